//! Node-, subject- and service-IDs as types (canadensis style): a value out of range cannot be
//! built, so the framing, the reassembler and the node never check a range again.
//!
//! Each type is made once, where the number enters: `TryFrom` an integer (from a register or a
//! configuration), `FromStr` (from text, with a message that names the range), or `from_const` in
//! a constant (an out-of-range constant does not compile).

use core::fmt;
use core::str::FromStr;

/// Which kind of ID an [`IdError`] is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum IdKind {
    /// A Cyphal/CAN node-ID, 0..=127.
    Node,
    /// A subject-ID, 0..=8191.
    Subject,
    /// A service-ID, 0..=511.
    Service,
}

impl IdKind {
    /// What the ID is called.
    pub const fn name(self) -> &'static str {
        match self {
            IdKind::Node => "node-ID",
            IdKind::Subject => "subject-ID",
            IdKind::Service => "service-ID",
        }
    }

    /// The largest valid value.
    pub const fn max(self) -> u16 {
        match self {
            IdKind::Node => NodeId::MAX as u16,
            IdKind::Subject => SubjectId::MAX,
            IdKind::Service => ServiceId::MAX,
        }
    }
}

/// A number that is not a valid ID of its kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct IdError {
    /// The kind of ID.
    pub kind: IdKind,
    /// The value given, when it was an integer (`None`: text that is not a non-negative integer).
    pub value: Option<i128>,
}

impl fmt::Display for IdError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (name, max) = (self.kind.name(), self.kind.max());
        match self.value {
            Some(v) => write!(f, "{name} {v} is out of range: it must be from 0 to {max}"),
            None => write!(f, "a {name} must be an integer from 0 to {max}"),
        }
    }
}

impl core::error::Error for IdError {}

macro_rules! id_type {
    ($(#[$doc:meta])* $name:ident, $repr:ty, $max:expr, $kind:expr) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub struct $name($repr);

        impl $name {
            /// The largest valid value.
            pub const MAX: $repr = $max;

            /// The ID, or `None` if `value` is out of range.
            pub const fn new(value: $repr) -> Option<Self> {
                if value <= Self::MAX {
                    Some($name(value))
                } else {
                    None
                }
            }

            /// The ID for a constant; an out-of-range constant fails to compile when used in a
            /// `const` (and panics otherwise).
            pub const fn from_const(value: $repr) -> Self {
                match Self::new(value) {
                    Some(id) => id,
                    None => panic!("ID out of range"),
                }
            }

            /// The numeric value.
            pub const fn get(self) -> $repr {
                self.0
            }
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                fmt::Display::fmt(&self.0, f)
            }
        }

        impl From<$name> for $repr {
            fn from(id: $name) -> $repr {
                id.0
            }
        }

        impl FromStr for $name {
            type Err = IdError;

            /// Parses a decimal integer in range.
            fn from_str(s: &str) -> Result<Self, IdError> {
                let v: u64 = s.trim().parse().map_err(|_| IdError {
                    kind: $kind,
                    value: s.trim().parse::<i128>().ok(),
                })?;
                $name::try_from(v)
            }
        }

        id_type!(@try_from $name, $repr, $kind, u8 u16 u32 u64 usize i8 i16 i32 i64 isize);
    };
    (@try_from $name:ident, $repr:ty, $kind:expr, $($int:ty)*) => {
        $(
            impl TryFrom<$int> for $name {
                type Error = IdError;

                fn try_from(value: $int) -> Result<Self, IdError> {
                    <$repr>::try_from(value)
                        .ok()
                        .and_then($name::new)
                        .ok_or(IdError {
                            kind: $kind,
                            value: Some(value as i128),
                        })
                }
            }
        )*
    };
}

id_type!(
    /// A Cyphal/CAN node-ID, 0..=127.
    NodeId,
    u8,
    127,
    IdKind::Node
);
id_type!(
    /// A subject-ID, 0..=8191.
    SubjectId,
    u16,
    8191,
    IdKind::Subject
);
id_type!(
    /// A service-ID, 0..=511.
    ServiceId,
    u16,
    511,
    IdKind::Service
);

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::string::ToString;

    #[test]
    fn ranges_conversions_and_messages() {
        assert_eq!(NodeId::try_from(127u8).map(NodeId::get), Ok(127));
        assert_eq!(SubjectId::try_from(8191u32).map(u16::from), Ok(8191));
        assert_eq!(
            ServiceId::new(511).map(|s| s.to_string()),
            Some("511".into())
        );
        let e = NodeId::try_from(200u16).unwrap_err();
        assert_eq!(
            e.to_string(),
            "node-ID 200 is out of range: it must be from 0 to 127"
        );
        assert!(SubjectId::try_from(-1i32).is_err());
        assert!(ServiceId::try_from(512usize).is_err());
        assert_eq!("  42 ".parse::<NodeId>(), Ok(NodeId::from_const(42)));
        assert_eq!(
            "9000".parse::<SubjectId>().unwrap_err().to_string(),
            "subject-ID 9000 is out of range: it must be from 0 to 8191"
        );
        assert_eq!(
            "-3".parse::<ServiceId>().unwrap_err().to_string(),
            "service-ID -3 is out of range: it must be from 0 to 511"
        );
        assert_eq!(
            "x7".parse::<NodeId>().unwrap_err().to_string(),
            "a node-ID must be an integer from 0 to 127"
        );
        const HEARTBEAT: SubjectId = SubjectId::from_const(7509);
        assert_eq!(HEARTBEAT.get(), 7509);
    }
}
