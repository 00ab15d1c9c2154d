//! `uavcan.node.Heartbeat.1.0`: every node's 1 Hz liveness message (7 bytes, extent 12).

use super::{BitReader, BitWriter, DataType, DecodeError};

/// `uavcan.node.Heartbeat.1.0` with `uavcan.node.Health.1.0` and `uavcan.node.Mode.1.0`
/// flattened to their values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Heartbeat {
    /// Seconds since the node started.
    pub uptime: u32,
    /// `uavcan.node.Health.1.0` value (2 bits): [`Heartbeat::HEALTH_NOMINAL`] ….
    pub health: u8,
    /// `uavcan.node.Mode.1.0` value (3 bits): [`Heartbeat::MODE_OPERATIONAL`] ….
    pub mode: u8,
    /// Vendor-defined status.
    pub vendor_specific_status_code: u8,
}

impl Heartbeat {
    /// The fixed subject-ID of Heartbeat.
    pub const FIXED_SUBJECT_ID: u16 = 7509;
    /// Health: all is well.
    pub const HEALTH_NOMINAL: u8 = 0;
    /// Health: a minor problem.
    pub const HEALTH_ADVISORY: u8 = 1;
    /// Health: degraded.
    pub const HEALTH_CAUTION: u8 = 2;
    /// Health: cannot perform its function.
    pub const HEALTH_WARNING: u8 = 3;
    /// Mode: normal operation.
    pub const MODE_OPERATIONAL: u8 = 0;
    /// Mode: starting up.
    pub const MODE_INITIALIZATION: u8 = 1;
    /// Mode: maintenance.
    pub const MODE_MAINTENANCE: u8 = 2;
    /// Mode: being updated.
    pub const MODE_SOFTWARE_UPDATE: u8 = 3;
}

impl DataType for Heartbeat {
    const EXTENT_BYTES: usize = 12;
    const MAX_SIZE_BYTES: usize = 7;

    fn serialize(&self, out: &mut [u8]) -> usize {
        let mut w = BitWriter::new(&mut out[..Self::MAX_SIZE_BYTES]);
        w.write_uint(u64::from(self.uptime), 32);
        w.write_uint(u64::from(self.health), 2);
        w.align();
        w.write_uint(u64::from(self.mode), 3);
        w.align();
        w.write_uint(u64::from(self.vendor_specific_status_code), 8);
        Self::MAX_SIZE_BYTES
    }

    fn deserialize(payload: &[u8]) -> Result<Self, DecodeError> {
        let mut r = BitReader::new(payload);
        let uptime = r.read_uint(32) as u32;
        let health = r.read_uint(2) as u8;
        r.align();
        let mode = r.read_uint(3) as u8;
        r.align();
        let vendor_specific_status_code = r.read_uint(8) as u8;
        Ok(Heartbeat {
            uptime,
            health,
            mode,
            vendor_specific_status_code,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_emit() {
        let hb = Heartbeat {
            uptime: 0x0102_0304,
            health: Heartbeat::HEALTH_CAUTION,
            mode: Heartbeat::MODE_MAINTENANCE,
            vendor_specific_status_code: 0xAB,
        };
        let mut buf = [0u8; 7];
        assert_eq!(hb.serialize(&mut buf), 7);
        assert_eq!(buf, [0x04, 0x03, 0x02, 0x01, 0x02, 0x02, 0xAB]);
        assert_eq!(Heartbeat::deserialize(&buf).unwrap(), hb);
        // Padding bits in the health byte are ignored.
        assert_eq!(
            Heartbeat::deserialize(&[0, 0, 0, 0, 0xFD]).unwrap().health,
            1
        );
    }
}
