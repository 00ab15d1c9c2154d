//! `uavcan.node.port.List.1.0` (fixed subject 7510): the ports a node uses, for introspection.
//!
//! Four delimited members, each preceded by a 4-byte delimiter header (its body length):
//! publishers and subscribers ([`SubjectIdList`], a union: a 8192-bit mask of 1024 bytes, a
//! sparse list of at most 255 subject-IDs, or "all"), clients and servers ([`ServiceIdList`], a
//! 512-bit mask of 64 bytes). The message is sealed; its largest form today (two masks) is 2194
//! bytes, and because its members are delimited a receiver must accept up to 8466 (the extent),
//! while a node with a few subjects sends the sparse form: 146 bytes plus 2 per subject-ID
//! (22 Classic CAN frames for a handful of ports).
//!
//! Decoding follows the DSDL rules for delimited types: a body shorter than its type reads as
//! zero-extended, a longer one is truncated, and a header that claims more bytes than remain (or
//! that is itself cut short) is rejected ([`DecodeError::DelimiterHeaderOverPayload`]).

use super::register::read_length;
use super::{BitReader, BitWriter, DataType, DecodeError};

/// `uavcan.node.port.SubjectIDList.1.0`: which subject-IDs (0..=8191) are in use.
#[derive(Clone, Debug, PartialEq, Eq)]
#[allow(clippy::large_enum_variant)] // the mask is the DSDL's fixed 1 KiB; no allocation by design
pub enum SubjectIdList {
    /// Tag 0: bit `i` (LSB-first) set means subject-ID `i` is used.
    Mask([u8; 1024]),
    /// Tag 1: at most 255 subject-IDs.
    SparseList(heapless::Vec<u16, 255>),
    /// Tag 2: every subject-ID is used.
    Total,
}

impl Default for SubjectIdList {
    fn default() -> Self {
        SubjectIdList::SparseList(heapless::Vec::new())
    }
}

impl SubjectIdList {
    /// Subject-IDs range 0..CAPACITY.
    pub const CAPACITY: usize = 8192;
    /// The delimited body's extent in bytes (`8 + 2**15` bits).
    pub const EXTENT_BYTES: usize = 4097;

    /// True if subject `id` is in the list.
    pub fn contains(&self, id: u16) -> bool {
        match self {
            SubjectIdList::Mask(m) => {
                usize::from(id) < Self::CAPACITY && m[usize::from(id) / 8] >> (id % 8) & 1 == 1
            }
            SubjectIdList::SparseList(l) => l.contains(&id),
            SubjectIdList::Total => true,
        }
    }

    fn body_len(&self) -> usize {
        match self {
            SubjectIdList::Mask(_) => 1025,
            SubjectIdList::SparseList(l) => 2 + 2 * l.len(),
            SubjectIdList::Total => 1,
        }
    }

    fn write(&self, w: &mut BitWriter<'_>) {
        w.write_uint(self.body_len() as u64, 32);
        match self {
            SubjectIdList::Mask(m) => {
                w.write_uint(0, 8);
                w.write_bytes(m);
            }
            SubjectIdList::SparseList(l) => {
                w.write_uint(1, 8);
                w.write_uint(l.len() as u64, 8);
                for &id in l {
                    // uavcan.node.port.SubjectID.1.0: uint13, a nested composite of 2 bytes.
                    w.write_uint(u64::from(id), 13);
                    w.align();
                }
            }
            SubjectIdList::Total => w.write_uint(2, 8),
        }
    }

    fn read(body: &[u8]) -> Result<Self, DecodeError> {
        let mut r = BitReader::new(body);
        Ok(match r.read_uint(8) as u8 {
            0 => {
                let mut m = [0u8; 1024];
                for b in &mut m {
                    *b = r.read_uint(8) as u8;
                }
                SubjectIdList::Mask(m)
            }
            1 => {
                let n = read_length(&mut r, 8, 255)?;
                let mut l = heapless::Vec::new();
                for _ in 0..n {
                    let _ = l.push(r.read_uint(13) as u16);
                    r.align();
                }
                SubjectIdList::SparseList(l)
            }
            2 => SubjectIdList::Total,
            tag => return Err(DecodeError::UnionTagOutOfRange { tag, members: 3 }),
        })
    }
}

/// `uavcan.node.port.ServiceIDList.1.0`: a 512-bit mask of service-IDs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ServiceIdList {
    /// Bit `i` (LSB-first) set means service-ID `i` is used.
    pub mask: [u8; 64],
}

impl Default for ServiceIdList {
    fn default() -> Self {
        ServiceIdList { mask: [0; 64] }
    }
}

impl ServiceIdList {
    /// Service-IDs range 0..CAPACITY.
    pub const CAPACITY: usize = 512;
    /// The delimited body's extent in bytes (1024 bits).
    pub const EXTENT_BYTES: usize = 128;

    /// Marks service `id` as used (ignored above 511).
    pub fn insert(&mut self, id: u16) {
        if usize::from(id) < Self::CAPACITY {
            self.mask[usize::from(id) / 8] |= 1 << (id % 8);
        }
    }

    /// True if service `id` is marked.
    pub fn contains(&self, id: u16) -> bool {
        usize::from(id) < Self::CAPACITY && self.mask[usize::from(id) / 8] >> (id % 8) & 1 == 1
    }

    fn write(&self, w: &mut BitWriter<'_>) {
        w.write_uint(64, 32);
        w.write_bytes(&self.mask);
    }

    fn read(body: &[u8]) -> Self {
        let mut mask = [0u8; 64];
        for (m, b) in mask.iter_mut().zip(body) {
            *m = *b;
        }
        ServiceIdList { mask }
    }
}

/// Reads a delimiter header at the reader's (byte-aligned) position and hands the body to
/// `read`; the reader then skips the whole body.
fn read_delimited<T>(
    r: &mut BitReader<'_>,
    payload: &[u8],
    read: impl FnOnce(&[u8]) -> Result<T, DecodeError>,
) -> Result<T, DecodeError> {
    let length = r.read_uint(32) as usize;
    let start = r.bit_position() / 8;
    // A header that itself runs past the end leaves a negative remainder: even a zero length is
    // then refused (PyCyphal's rule: `header * 8 > remaining_bit_length`, which can be negative).
    if start > payload.len() || length > payload.len() - start {
        return Err(DecodeError::DelimiterHeaderOverPayload {
            length,
            remaining: payload.len().saturating_sub(start),
        });
    }
    let body = if length == 0 {
        &[][..]
    } else {
        &payload[start..start + length]
    };
    let v = read(body)?;
    r.skip(length as u32 * 8);
    Ok(v)
}

/// `uavcan.node.port.List.1.0`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PortList {
    /// Subjects this node publishes.
    pub publishers: SubjectIdList,
    /// Subjects this node subscribes to.
    pub subscribers: SubjectIdList,
    /// Services this node calls.
    pub clients: ServiceIdList,
    /// Services this node serves.
    pub servers: ServiceIdList,
}

impl PortList {
    /// The fixed subject-ID.
    pub const FIXED_SUBJECT_ID: u16 = 7510;
    /// The longest time between two publications, seconds.
    pub const MAX_PUBLICATION_PERIOD_S: u64 = 10;
}

impl DataType for PortList {
    /// The delimited members may grow to their extents in later minor versions: 8466 bytes.
    const EXTENT_BYTES: usize = 8466;
    const MAX_SIZE_BYTES: usize = 2194;

    fn serialize(&self, out: &mut [u8]) -> usize {
        let mut w = BitWriter::new(&mut out[..Self::MAX_SIZE_BYTES]);
        self.publishers.write(&mut w);
        self.subscribers.write(&mut w);
        self.clients.write(&mut w);
        self.servers.write(&mut w);
        w.byte_len()
    }

    fn deserialize(payload: &[u8]) -> Result<Self, DecodeError> {
        let mut r = BitReader::new(payload);
        let publishers = read_delimited(&mut r, payload, SubjectIdList::read)?;
        let subscribers = read_delimited(&mut r, payload, SubjectIdList::read)?;
        let clients = read_delimited(&mut r, payload, |b| Ok(ServiceIdList::read(b)))?;
        let servers = read_delimited(&mut r, payload, |b| Ok(ServiceIdList::read(b)))?;
        Ok(PortList {
            publishers,
            subscribers,
            clients,
            servers,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sparse_form_round_trips_and_bad_headers_are_refused() {
        let mut p = PortList {
            publishers: SubjectIdList::SparseList(heapless::Vec::from_slice(&[7509, 1]).unwrap()),
            ..Default::default()
        };
        p.servers.insert(430);
        let mut buf = [0u8; 2194];
        let n = p.serialize(&mut buf);
        assert_eq!(n, 4 + 6 + 4 + 2 + 68 + 68);
        assert_eq!(&buf[..10], &[6, 0, 0, 0, 1, 2, 0x55, 0x1D, 1, 0]);
        let back = PortList::deserialize(&buf[..n]).unwrap();
        assert_eq!(back, p);
        assert!(back.servers.contains(430) && back.publishers.contains(7509));
        buf[0] = 0xFF;
        assert!(matches!(
            PortList::deserialize(&buf[..n]),
            Err(DecodeError::DelimiterHeaderOverPayload { .. })
        ));
    }
}
