//! DSDL codecs: bit-exact serialization of the data types propid speaks.
//!
//! Every type implements [`DataType`]. Serialization writes into a caller-provided buffer;
//! deserialization follows the Cyphal rules: a short payload is implicitly zero-extended, a long
//! one implicitly truncated, and only an array length prefix over capacity is an error.

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
}

/// A DSDL composite type with a fixed serialized-size bound.
pub trait DataType: Sized {
    /// The DSDL extent in bytes (buffer size a receiver must reserve).
    const EXTENT_BYTES: usize;
    /// The largest serialized size in bytes.
    const MAX_SIZE_BYTES: usize;

    /// Serialize into `out` (at least [`Self::MAX_SIZE_BYTES`] long); returns the bytes written.
    fn serialize(&self, out: &mut [u8]) -> usize;

    /// Deserialize from a payload of any length (implicit zero extension and truncation).
    fn deserialize(payload: &[u8]) -> Result<Self, DecodeError>;
}
