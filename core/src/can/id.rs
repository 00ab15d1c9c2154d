//! The 29-bit Cyphal/CAN identifier, parsed into a plain representation and emitted back.
//!
//! ```text
//! message: prio[28:26] 0[25] anon[24] 0[23] 11[22:21] subject[20:8] 0[7] source[6:0]
//! service: prio[28:26] 1[25] req[24]  0[23] service[22:14] destination[13:7] source[6:0]
//! ```
//! Bits 22..21 of a message ID are reserved and sent as 1 (as PyCyphal does); receivers ignore
//! them. A message frame with bit 23 or bit 7 set is not Cyphal and is dropped.

use super::{NodeId, ServiceId, SubjectId, TransferKind};

/// Transfer priority, 0 (exceptional) … 7 (optional); 4 is nominal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Priority(u8);

impl Priority {
    /// Exceptional (highest).
    pub const EXCEPTIONAL: Priority = Priority(0);
    /// Immediate.
    pub const IMMEDIATE: Priority = Priority(1);
    /// Fast.
    pub const FAST: Priority = Priority(2);
    /// High.
    pub const HIGH: Priority = Priority(3);
    /// Nominal (the default).
    pub const NOMINAL: Priority = Priority(4);
    /// Low.
    pub const LOW: Priority = Priority(5);
    /// Slow.
    pub const SLOW: Priority = Priority(6);
    /// Optional (lowest).
    pub const OPTIONAL: Priority = Priority(7);

    /// A priority from its numeric level; `None` above 7.
    pub const fn new(level: u8) -> Option<Priority> {
        if level <= 7 {
            Some(Priority(level))
        } else {
            None
        }
    }

    /// The numeric level.
    pub const fn level(self) -> u8 {
        self.0
    }
}

/// A parsed Cyphal/CAN identifier.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CanId {
    /// Priority.
    pub priority: Priority,
    /// Message or service, port and destination.
    pub kind: TransferKind,
    /// Source node-ID (`None` for anonymous messages).
    pub source: Option<NodeId>,
}

impl CanId {
    /// Parses a 29-bit ID; `None` if it is not a valid Cyphal/CAN ID.
    pub fn parse(id: u32) -> Option<CanId> {
        if id > 0x1FFF_FFFF {
            return None;
        }
        let priority = Priority((id >> 26) as u8 & 7);
        // Masked to their field widths, so always in range.
        let source = NodeId::from_const((id & 0x7F) as u8);
        if id & (1 << 25) == 0 {
            if id & (1 << 23) != 0 || id & (1 << 7) != 0 {
                return None;
            }
            let anonymous = id & (1 << 24) != 0;
            Some(CanId {
                priority,
                kind: TransferKind::Message {
                    subject_id: SubjectId::from_const(((id >> 8) & 0x1FFF) as u16),
                },
                source: if anonymous { None } else { Some(source) },
            })
        } else {
            if id & (1 << 23) != 0 {
                return None;
            }
            let service_id = ServiceId::from_const(((id >> 14) & 0x1FF) as u16);
            let destination = NodeId::from_const(((id >> 7) & 0x7F) as u8);
            if destination == source {
                return None;
            }
            let kind = if id & (1 << 24) != 0 {
                TransferKind::Request {
                    service_id,
                    destination,
                }
            } else {
                TransferKind::Response {
                    service_id,
                    destination,
                }
            };
            Some(CanId {
                priority,
                kind,
                source: Some(source),
            })
        }
    }

    /// Emits the 29-bit ID. For anonymous messages `pseudo_id` fills the source field (the
    /// specification asks for a pseudo-random value; PyCyphal uses the payload byte sum).
    /// `None` for an anonymous service transfer, which does not exist; every field is in range
    /// by type.
    pub fn emit(&self, pseudo_id: u8) -> Option<u32> {
        let prio = u32::from(self.priority.0) << 26;
        match self.kind {
            TransferKind::Message { subject_id } => {
                let (anon, src) = match self.source {
                    Some(s) => (0, u32::from(s.get())),
                    None => (1 << 24, u32::from(pseudo_id & 0x7F)),
                };
                Some(prio | anon | (3 << 21) | (u32::from(subject_id.get()) << 8) | src)
            }
            TransferKind::Request {
                service_id,
                destination,
            }
            | TransferKind::Response {
                service_id,
                destination,
            } => {
                let src = self.source?;
                let req = if matches!(self.kind, TransferKind::Request { .. }) {
                    1 << 24
                } else {
                    0
                };
                Some(
                    prio | (1 << 25)
                        | req
                        | (u32::from(service_id.get()) << 14)
                        | (u32::from(destination.get()) << 7)
                        | u32::from(src.get()),
                )
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_emit_examples_from_the_vectors() {
        // Priority 4, subject 100, node 42.
        let m = CanId::parse(0x1060_642A).unwrap();
        assert_eq!(m.priority, Priority::NOMINAL);
        assert_eq!(
            m.kind,
            TransferKind::Message {
                subject_id: SubjectId::from_const(100)
            }
        );
        assert_eq!(m.source, Some(NodeId::from_const(42)));
        assert_eq!(m.emit(0), Some(0x1060_642A));
        // GetInfo request 10 → 42 and its response.
        let req = CanId::parse(0x136B_950A).unwrap();
        assert_eq!(
            req.kind,
            TransferKind::Request {
                service_id: ServiceId::from_const(430),
                destination: NodeId::from_const(42)
            }
        );
        assert_eq!(req.source, Some(NodeId::from_const(10)));
        assert_eq!(req.emit(0), Some(0x136B_950A));
        let resp = CanId::parse(0x126B_852A).unwrap();
        assert_eq!(
            resp.kind,
            TransferKind::Response {
                service_id: ServiceId::from_const(430),
                destination: NodeId::from_const(10)
            }
        );
        assert_eq!(resp.emit(0), Some(0x126B_852A));
    }

    #[test]
    fn reserved_bits() {
        // Bits 22..21 clear: still accepted.
        assert!(CanId::parse(0x1000_642A).is_some());
        // Bit 23 or bit 7 set on a message: not Cyphal.
        assert!(CanId::parse(0x1060_642A | 1 << 23).is_none());
        assert!(CanId::parse(0x1060_642A | 1 << 7).is_none());
        assert!(CanId::parse(0x136B_950A | 1 << 23).is_none());
        // Anonymous.
        let a = CanId::parse(0x1160_6455).unwrap();
        assert_eq!(a.source, None);
        // Out-of-range fields cannot be built; an anonymous service transfer is refused.
        assert_eq!(SubjectId::new(8192), None);
        let bad = CanId {
            priority: Priority::NOMINAL,
            kind: TransferKind::Request {
                service_id: ServiceId::from_const(1),
                destination: NodeId::from_const(2),
            },
            source: None,
        };
        assert_eq!(bad.emit(0), None);
    }
}
