//! DSDL codecs: bit-exact serialization of the data types propid speaks.
//!
//! Every type implements [`DataType`]: `serialize` writes into a caller-provided buffer (no
//! allocation), `deserialize` reads from a payload of any length.
//!
//! ## The rules, as the Cyphal specification states them
//! - **Bit order**: fields are packed LSB-first, little-endian; a field that does not start on a
//!   byte boundary continues in the next byte's low bits ([`BitWriter`], [`BitReader`]).
//! - **Nested composites** start on a byte boundary and occupy whole bytes (a `uavcan.node.Health`
//!   inside `Heartbeat` takes one byte although it holds two bits).
//! - **Implicit zero extension**: a payload shorter than the type reads as if padded with zero
//!   bits; a variable-length array whose length prefix points past the end gets zero elements.
//! - **Implicit truncation**: bytes past the end of the type are ignored, sealed types included.
//! - **Rejection**: a variable-length array prefix over the array's capacity
//!   ([`DecodeError::ArrayLengthOverCapacity`]), a union tag past the last member
//!   ([`DecodeError::UnionTagOutOfRange`]), a delimiter header longer than what remains
//!   ([`DecodeError::DelimiterHeaderOverPayload`]).
//! - **Delimited** (non-sealed) composites nested in another type carry a 4-byte length header;
//!   their body is zero-extended or truncated to their own type independently.
//! - **`truncated` integers** keep the low bits (`Readiness` 5 → 1; a `uint53` timestamp keeps
//!   its low 53 bits). Void padding is written as zero and ignored on read.
//! - **`saturated float16`**: finite values clamp to ±65504 and then round to nearest even; NaN
//!   and ±∞ are kept. PyCyphal differs here (its numpy cast overflows finite |x| ≥ 65520 to ±∞);
//!   propid follows the specification, as Nunavut's C does for clamping.
//!
//! The golden vectors produced by PyCyphal (see `core/tests/data/payloads.json`) pin all of this.

mod bits;
mod dof3rdts;
mod execute_command;
mod get_info;
mod heartbeat;
mod port_list;
mod readiness;
mod register;
mod vector31;

pub use bits::{f16_bits_saturated, BitReader, BitWriter};
pub use dof3rdts::{DoF2ndKinematics, DoF3rdDynamics, DoF3rdKinematics, DoF3rdTs, Timestamp};
pub use execute_command::{
    ExecuteCommandRequest, ExecuteCommandResponse, EXECUTE_COMMAND_SERVICE_ID,
};
pub use get_info::{GetInfoRequest, GetInfoResponse, Version, GET_INFO_SERVICE_ID};
pub use heartbeat::Heartbeat;
pub use port_list::{PortList, ServiceIdList, SubjectIdList};
pub use readiness::Readiness;
pub use register::{
    AccessRequest, AccessResponse, BitArray, ListRequest, ListResponse, Name, Value,
    ACCESS_SERVICE_ID, LIST_SERVICE_ID,
};
pub use vector31::Vector31;

/// Why a payload could not be deserialized.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DecodeError {
    /// A variable-length array's length prefix exceeds the array's capacity.
    ArrayLengthOverCapacity {
        /// The length the prefix claimed.
        length: usize,
        /// The capacity the DSDL definition allows.
        capacity: usize,
    },
    /// A union's tag names no member.
    UnionTagOutOfRange {
        /// The tag read.
        tag: u8,
        /// How many members the union has.
        members: u8,
    },
    /// A delimited composite's header claims more bytes than the payload has left.
    DelimiterHeaderOverPayload {
        /// The length the header claimed.
        length: usize,
        /// The bytes left after the header.
        remaining: usize,
    },
}

impl core::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DecodeError::ArrayLengthOverCapacity { length, capacity } => write!(
                f,
                "array length prefix {length} exceeds the capacity {capacity}"
            ),
            DecodeError::UnionTagOutOfRange { tag, members } => {
                write!(
                    f,
                    "union tag {tag} names no member (the union has {members})"
                )
            }
            DecodeError::DelimiterHeaderOverPayload { length, remaining } => write!(
                f,
                "delimiter header claims {length} bytes but only {remaining} remain"
            ),
        }
    }
}

/// A DSDL composite type with a fixed serialized-size bound.
pub trait DataType: Sized {
    /// The DSDL extent in bytes (buffer size a receiver must reserve).
    const EXTENT_BYTES: usize;
    /// The largest serialized size in bytes.
    const MAX_SIZE_BYTES: usize;

    /// Serialize into `out` (at least [`Self::MAX_SIZE_BYTES`] long); returns the bytes written.
    ///
    /// # Panics
    /// If `out` is shorter than [`Self::MAX_SIZE_BYTES`].
    fn serialize(&self, out: &mut [u8]) -> usize;

    /// Deserialize from a payload of any length (implicit zero extension and truncation).
    fn deserialize(payload: &[u8]) -> Result<Self, DecodeError>;
}
