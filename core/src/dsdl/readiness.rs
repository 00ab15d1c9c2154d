//! `zubax.service.Readiness.1.0`: the drive's arming state command (sealed, 1 byte).

use super::{BitReader, BitWriter, DataType, DecodeError};

/// `zubax.service.Readiness.1.0`: `truncated uint2 value`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Readiness {
    /// One of [`Readiness::SLEEP`], [`Readiness::STANDBY`], [`Readiness::ENGAGED`] (1 is
    /// undefined but representable). Serialization keeps the low two bits (truncated cast).
    pub value: u8,
}

impl Readiness {
    /// Lowest power; the drive may be unresponsive.
    pub const SLEEP: u8 = 0;
    /// Ready but not producing torque: what the driver commands whenever it stops.
    pub const STANDBY: u8 = 2;
    /// Producing torque as commanded.
    pub const ENGAGED: u8 = 3;
}

impl DataType for Readiness {
    const EXTENT_BYTES: usize = 1;
    const MAX_SIZE_BYTES: usize = 1;

    fn serialize(&self, out: &mut [u8]) -> usize {
        let mut w = BitWriter::new(&mut out[..Self::MAX_SIZE_BYTES]);
        w.write_uint(u64::from(self.value), 2);
        1
    }

    fn deserialize(payload: &[u8]) -> Result<Self, DecodeError> {
        let mut r = BitReader::new(payload);
        Ok(Readiness {
            value: r.read_uint(2) as u8,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_emit() {
        let mut buf = [0xAA; 1];
        assert_eq!(
            Readiness {
                value: Readiness::ENGAGED
            }
            .serialize(&mut buf),
            1
        );
        assert_eq!(buf, [0x03]);
        assert_eq!(Readiness { value: 5 }.serialize(&mut buf), 1);
        assert_eq!(buf, [0x01]);
        assert_eq!(Readiness::deserialize(&[0xFE]).unwrap().value, 2);
        assert_eq!(Readiness::deserialize(&[]).unwrap().value, 0);
    }
}
