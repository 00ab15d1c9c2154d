//! `uavcan.node.GetInfo.1.0`: who a node is (request empty; response up to 313 bytes, extent
//! 448).

use super::{BitReader, BitWriter, DataType, DecodeError};

/// The fixed service-ID of `uavcan.node.GetInfo.1.0`.
pub const GET_INFO_SERVICE_ID: u16 = 430;

/// `uavcan.node.Version.1.0`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Version {
    /// Major version.
    pub major: u8,
    /// Minor version.
    pub minor: u8,
}

/// `uavcan.node.GetInfo.1.0` request: empty.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GetInfoRequest;

impl DataType for GetInfoRequest {
    const EXTENT_BYTES: usize = 0;
    const MAX_SIZE_BYTES: usize = 0;

    fn serialize(&self, _out: &mut [u8]) -> usize {
        0
    }

    fn deserialize(_payload: &[u8]) -> Result<Self, DecodeError> {
        Ok(GetInfoRequest)
    }
}

/// `uavcan.node.GetInfo.1.0` response.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GetInfoResponse {
    /// Cyphal protocol version the node implements.
    pub protocol_version: Version,
    /// Hardware version.
    pub hardware_version: Version,
    /// Software version.
    pub software_version: Version,
    /// Version-control revision of the software (0 if unknown).
    pub software_vcs_revision_id: u64,
    /// 128-bit unique ID.
    pub unique_id: [u8; 16],
    /// Node name, reverse-domain style (e.g. `org.propid.drive`), at most 50 bytes.
    pub name: heapless::Vec<u8, 50>,
    /// CRC-64-WE of the software image, if known.
    pub software_image_crc: Option<u64>,
    /// Certificate of authenticity, at most 222 bytes.
    pub certificate_of_authenticity: heapless::Vec<u8, 222>,
}

impl GetInfoResponse {
    /// The fixed service-ID of GetInfo.
    pub const FIXED_SERVICE_ID: u16 = GET_INFO_SERVICE_ID;
}

fn read_bytes<const N: usize>(r: &mut BitReader<'_>) -> Result<heapless::Vec<u8, N>, DecodeError> {
    let length = r.read_uint(8) as usize;
    if length > N {
        return Err(DecodeError::ArrayLengthOverCapacity {
            length,
            capacity: N,
        });
    }
    let mut v = heapless::Vec::new();
    for _ in 0..length {
        // Cannot fail: length ≤ N was checked above.
        let _ = v.push(r.read_uint(8) as u8);
    }
    Ok(v)
}

impl DataType for GetInfoResponse {
    const EXTENT_BYTES: usize = 448;
    const MAX_SIZE_BYTES: usize = 313;

    fn serialize(&self, out: &mut [u8]) -> usize {
        let mut w = BitWriter::new(&mut out[..Self::MAX_SIZE_BYTES]);
        for v in [
            self.protocol_version,
            self.hardware_version,
            self.software_version,
        ] {
            w.write_uint(u64::from(v.major), 8);
            w.write_uint(u64::from(v.minor), 8);
        }
        w.write_uint(self.software_vcs_revision_id, 64);
        for b in self.unique_id {
            w.write_uint(u64::from(b), 8);
        }
        w.write_uint(self.name.len() as u64, 8);
        for &b in &self.name {
            w.write_uint(u64::from(b), 8);
        }
        match self.software_image_crc {
            Some(crc) => {
                w.write_uint(1, 8);
                w.write_uint(crc, 64);
            }
            None => w.write_uint(0, 8),
        }
        w.write_uint(self.certificate_of_authenticity.len() as u64, 8);
        for &b in &self.certificate_of_authenticity {
            w.write_uint(u64::from(b), 8);
        }
        w.byte_len()
    }

    fn deserialize(payload: &[u8]) -> Result<Self, DecodeError> {
        let mut r = BitReader::new(payload);
        let mut version = || Version {
            major: r.read_uint(8) as u8,
            minor: r.read_uint(8) as u8,
        };
        let protocol_version = version();
        let hardware_version = version();
        let software_version = version();
        let software_vcs_revision_id = r.read_uint(64);
        let mut unique_id = [0u8; 16];
        for b in &mut unique_id {
            *b = r.read_uint(8) as u8;
        }
        let name = read_bytes::<50>(&mut r)?;
        let crc_len = r.read_uint(8) as usize;
        let software_image_crc = match crc_len {
            0 => None,
            1 => Some(r.read_uint(64)),
            length => {
                return Err(DecodeError::ArrayLengthOverCapacity {
                    length,
                    capacity: 1,
                })
            }
        };
        let certificate_of_authenticity = read_bytes::<222>(&mut r)?;
        Ok(GetInfoResponse {
            protocol_version,
            hardware_version,
            software_version,
            software_vcs_revision_id,
            unique_id,
            name,
            software_image_crc,
            certificate_of_authenticity,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_emit() {
        let mut r = GetInfoResponse {
            protocol_version: Version { major: 1, minor: 0 },
            software_vcs_revision_id: 0x0102_0304_0506_0708,
            software_image_crc: Some(0xAA),
            ..Default::default()
        };
        r.name.extend_from_slice(b"ab").unwrap();
        let mut buf = [0u8; 313];
        let n = r.serialize(&mut buf);
        assert_eq!(n, 30 + 1 + 2 + 1 + 8 + 1);
        assert_eq!(&buf[..2], &[1, 0]);
        assert_eq!(&buf[6..14], &[8, 7, 6, 5, 4, 3, 2, 1]);
        assert_eq!(&buf[30..33], &[2, b'a', b'b']);
        assert_eq!(buf[33], 1);
        assert_eq!(GetInfoResponse::deserialize(&buf[..n]).unwrap(), r);
    }

    #[test]
    fn rejects_length_over_capacity() {
        let mut buf = [0u8; 40];
        buf[30] = 51;
        assert_eq!(
            GetInfoResponse::deserialize(&buf),
            Err(DecodeError::ArrayLengthOverCapacity {
                length: 51,
                capacity: 50
            })
        );
        buf[30] = 0;
        buf[31] = 2;
        assert!(GetInfoResponse::deserialize(&buf).is_err());
    }
}
