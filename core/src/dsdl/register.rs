//! `uavcan.register.*`: the named, typed configuration values every Cyphal node may expose.
//!
//! - [`Name`] (`uavcan.register.Name.1.0`): `uint8[<256]`, 1..=256 bytes.
//! - [`Value`] (`uavcan.register.Value.1.0`): a sealed union, one tag byte and one of fifteen
//!   `uavcan.primitive.*` members (at most 258 bytes), so 1..=259 bytes.
//! - [`AccessRequest`] / [`AccessResponse`] (`uavcan.register.Access.1.0`, service 384): name and
//!   value to write (empty: only read), answered with a timestamp, the mutable/persistent flags and
//!   the value read back (empty: no such register). Request ≤ 515 bytes, response ≤ 267.
//! - [`ListRequest`] / [`ListResponse`] (`uavcan.register.List.1.0`, service 385): the name at an
//!   index (empty past the end).
//!
//! All are sealed: extent = maximum size, no delimiter headers.

use super::{f16_bits_saturated, BitReader, BitWriter, DataType, DecodeError};

/// The fixed service-ID of `uavcan.register.Access.1.0`.
pub const ACCESS_SERVICE_ID: u16 = 384;
/// The fixed service-ID of `uavcan.register.List.1.0`.
pub const LIST_SERVICE_ID: u16 = 385;

/// Reads a length prefix of `bits` bits and checks it against `capacity`.
pub(crate) fn read_length(
    r: &mut BitReader<'_>,
    bits: u32,
    capacity: usize,
) -> Result<usize, DecodeError> {
    let length = r.read_uint(bits) as usize;
    if length > capacity {
        return Err(DecodeError::ArrayLengthOverCapacity { length, capacity });
    }
    Ok(length)
}

/// `uavcan.register.Name.1.0`: a register name, UTF-8, at most 255 bytes.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Name {
    /// The name's bytes (UTF-8; the DSDL does not enforce it).
    pub name: heapless::Vec<u8, 255>,
}

impl Name {
    /// The name, or `None` if longer than 255 bytes.
    pub fn new(name: &str) -> Option<Name> {
        Some(Name {
            name: heapless::Vec::from_slice(name.as_bytes()).ok()?,
        })
    }

    /// The name as text, if it is UTF-8.
    pub fn as_str(&self) -> Option<&str> {
        core::str::from_utf8(&self.name).ok()
    }

    /// True for the empty name (List: past the last register).
    pub fn is_empty(&self) -> bool {
        self.name.is_empty()
    }

    fn write(&self, w: &mut BitWriter<'_>) {
        w.write_uint(self.name.len() as u64, 8);
        w.write_bytes(&self.name);
    }

    fn read(r: &mut BitReader<'_>) -> Result<Name, DecodeError> {
        let n = read_length(r, 8, 255)?;
        let mut name = heapless::Vec::new();
        for _ in 0..n {
            // Cannot fail: n ≤ 255.
            let _ = name.push(r.read_uint(8) as u8);
        }
        Ok(Name { name })
    }
}

impl DataType for Name {
    const EXTENT_BYTES: usize = 256;
    const MAX_SIZE_BYTES: usize = 256;

    fn serialize(&self, out: &mut [u8]) -> usize {
        let mut w = BitWriter::new(&mut out[..Self::MAX_SIZE_BYTES]);
        self.write(&mut w);
        w.byte_len()
    }

    fn deserialize(payload: &[u8]) -> Result<Self, DecodeError> {
        Name::read(&mut BitReader::new(payload))
    }
}

/// `uavcan.primitive.array.Bit.1.0`'s `bool[<=2048]`, packed eight to a byte.
#[derive(Clone, Debug)]
pub struct BitArray {
    len: u16,
    bits: [u8; 256],
}

impl BitArray {
    /// The largest number of bits.
    pub const CAPACITY: usize = 2048;

    /// No bits.
    pub const fn new() -> Self {
        BitArray {
            len: 0,
            bits: [0; 256],
        }
    }

    /// From a slice of at most 2048 booleans (`None` if longer).
    pub fn from_bools(bools: &[bool]) -> Option<Self> {
        let mut a = BitArray::new();
        for &b in bools {
            a.push(b).ok()?;
        }
        Some(a)
    }

    /// Number of bits.
    pub fn len(&self) -> usize {
        usize::from(self.len)
    }

    /// True if there are no bits.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Bit `i` (false past the end).
    pub fn get(&self, i: usize) -> bool {
        i < self.len() && self.bits[i / 8] >> (i % 8) & 1 == 1
    }

    /// Sets bit `i` (ignored past the end).
    pub fn set(&mut self, i: usize, v: bool) {
        if i < self.len() {
            let m = 1u8 << (i % 8);
            if v {
                self.bits[i / 8] |= m;
            } else {
                self.bits[i / 8] &= !m;
            }
        }
    }

    /// Appends a bit; `Err` when full.
    #[allow(clippy::result_unit_err)]
    pub fn push(&mut self, v: bool) -> Result<(), ()> {
        if self.len() >= Self::CAPACITY {
            return Err(());
        }
        self.len += 1;
        self.set(self.len() - 1, v);
        Ok(())
    }

    /// The bits in order.
    pub fn iter(&self) -> impl Iterator<Item = bool> + '_ {
        (0..self.len()).map(|i| self.get(i))
    }
}

impl Default for BitArray {
    fn default() -> Self {
        BitArray::new()
    }
}

impl PartialEq for BitArray {
    fn eq(&self, other: &Self) -> bool {
        self.len == other.len && self.iter().eq(other.iter())
    }
}

impl Eq for BitArray {}

#[cfg(feature = "defmt")]
impl defmt::Format for BitArray {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "BitArray({=usize} bits)", self.len())
    }
}

/// `uavcan.register.Value.1.0`: the union of every register type. Numeric members are arrays
/// (a scalar is an array of one); capacities are the DSDL's. `Real16` elements are kept as
/// binary16 ([`half::f16`]), bit for bit as on the wire; [`Value::real16`] converts from `f32`
/// with the specification's `saturated` cast.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Value {
    /// Tag 0: no value (a read-only Access request; a nonexistent register in a response).
    #[default]
    Empty,
    /// Tag 1: UTF-8 text, at most 256 bytes.
    String(heapless::Vec<u8, 256>),
    /// Tag 2: raw bytes, at most 256.
    Unstructured(heapless::Vec<u8, 256>),
    /// Tag 3: at most 2048 bits.
    Bit(BitArray),
    /// Tag 4: `int64[<=32]`.
    Integer64(heapless::Vec<i64, 32>),
    /// Tag 5: `int32[<=64]`.
    Integer32(heapless::Vec<i32, 64>),
    /// Tag 6: `int16[<=128]`.
    Integer16(heapless::Vec<i16, 128>),
    /// Tag 7: `int8[<=256]`.
    Integer8(heapless::Vec<i8, 256>),
    /// Tag 8: `uint64[<=32]`.
    Natural64(heapless::Vec<u64, 32>),
    /// Tag 9: `uint32[<=64]`.
    Natural32(heapless::Vec<u32, 64>),
    /// Tag 10: `uint16[<=128]`.
    Natural16(heapless::Vec<u16, 128>),
    /// Tag 11: `uint8[<=256]`.
    Natural8(heapless::Vec<u8, 256>),
    /// Tag 12: `float64[<=32]`.
    Real64(heapless::Vec<f64, 32>),
    /// Tag 13: `float32[<=64]`.
    Real32(heapless::Vec<f32, 64>),
    /// Tag 14: `float16[<=128]`.
    Real16(heapless::Vec<half::f16, 128>),
}

#[cfg(feature = "defmt")]
impl defmt::Format for Value {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "Value::{=str}[{=usize}]", self.type_name(), self.len())
    }
}

/// Reads `n` elements with `read` into a heapless vector (length already checked).
fn read_vec<T, const N: usize>(
    r: &mut BitReader<'_>,
    prefix_bits: u32,
    mut read: impl FnMut(&mut BitReader<'_>) -> T,
) -> Result<heapless::Vec<T, N>, DecodeError> {
    let n = read_length(r, prefix_bits, N)?;
    let mut v = heapless::Vec::new();
    for _ in 0..n {
        // Cannot fail: n ≤ N.
        let _ = v.push(read(r));
    }
    Ok(v)
}

impl Value {
    /// The largest serialized size: the tag and 258 bytes.
    pub const MAX_SIZE_BYTES: usize = 259;

    /// The union tag (0..=14).
    pub fn tag(&self) -> u8 {
        match self {
            Value::Empty => 0,
            Value::String(_) => 1,
            Value::Unstructured(_) => 2,
            Value::Bit(_) => 3,
            Value::Integer64(_) => 4,
            Value::Integer32(_) => 5,
            Value::Integer16(_) => 6,
            Value::Integer8(_) => 7,
            Value::Natural64(_) => 8,
            Value::Natural32(_) => 9,
            Value::Natural16(_) => 10,
            Value::Natural8(_) => 11,
            Value::Real64(_) => 12,
            Value::Real32(_) => 13,
            Value::Real16(_) => 14,
        }
    }

    /// The member's name as the DSDL spells it (`natural16`, `real32`, …).
    pub fn type_name(&self) -> &'static str {
        [
            "empty",
            "string",
            "unstructured",
            "bit",
            "integer64",
            "integer32",
            "integer16",
            "integer8",
            "natural64",
            "natural32",
            "natural16",
            "natural8",
            "real64",
            "real32",
            "real16",
        ][usize::from(self.tag())]
    }

    /// True for [`Value::Empty`].
    pub fn is_empty(&self) -> bool {
        matches!(self, Value::Empty)
    }

    /// Number of elements (bytes for strings and unstructured, 0 for empty).
    pub fn len(&self) -> usize {
        match self {
            Value::Empty => 0,
            Value::String(v) | Value::Unstructured(v) | Value::Natural8(v) => v.len(),
            Value::Bit(v) => v.len(),
            Value::Integer64(v) => v.len(),
            Value::Integer32(v) => v.len(),
            Value::Integer16(v) => v.len(),
            Value::Integer8(v) => v.len(),
            Value::Natural64(v) => v.len(),
            Value::Natural32(v) => v.len(),
            Value::Natural16(v) => v.len(),
            Value::Real64(v) => v.len(),
            Value::Real32(v) => v.len(),
            Value::Real16(v) => v.len(),
        }
    }

    /// True for the numeric members (bit, integer*, natural*, real*).
    pub fn is_numeric(&self) -> bool {
        self.tag() >= 3
    }

    /// A string value (`None` if longer than 256 bytes).
    pub fn string(s: &str) -> Option<Value> {
        Some(Value::String(heapless::Vec::from_slice(s.as_bytes()).ok()?))
    }

    /// A `natural16` array (`None` if longer than 128): how port-IDs and node-IDs are stored.
    pub fn natural16(v: &[u16]) -> Option<Value> {
        Some(Value::Natural16(heapless::Vec::from_slice(v).ok()?))
    }

    /// A `real32` array (`None` if longer than 64).
    pub fn real32(v: &[f32]) -> Option<Value> {
        Some(Value::Real32(heapless::Vec::from_slice(v).ok()?))
    }

    /// A `real64` array (`None` if longer than 32).
    pub fn real64(v: &[f64]) -> Option<Value> {
        Some(Value::Real64(heapless::Vec::from_slice(v).ok()?))
    }

    /// A `real16` array from `f32` with the saturated cast (`None` if longer than 128).
    pub fn real16(v: &[f32]) -> Option<Value> {
        let mut out = heapless::Vec::new();
        for &x in v {
            out.push(half::f16::from_bits(f16_bits_saturated(x))).ok()?;
        }
        Some(Value::Real16(out))
    }

    /// A `bit` array (`None` if longer than 2048).
    pub fn bit(v: &[bool]) -> Option<Value> {
        BitArray::from_bools(v).map(Value::Bit)
    }

    /// Element `i` of a numeric value as `f64` (`bit` as 0/1); `None` for text, empty, or past
    /// the end.
    pub fn float_at(&self, i: usize) -> Option<f64> {
        if i >= self.len() {
            return None;
        }
        Some(match self {
            Value::Empty | Value::String(_) | Value::Unstructured(_) => return None,
            Value::Bit(v) => f64::from(u8::from(v.get(i))),
            Value::Integer64(v) => v[i] as f64,
            Value::Integer32(v) => f64::from(v[i]),
            Value::Integer16(v) => f64::from(v[i]),
            Value::Integer8(v) => f64::from(v[i]),
            Value::Natural64(v) => v[i] as f64,
            Value::Natural32(v) => f64::from(v[i]),
            Value::Natural16(v) => f64::from(v[i]),
            Value::Natural8(v) => f64::from(v[i]),
            Value::Real64(v) => v[i],
            Value::Real32(v) => f64::from(v[i]),
            Value::Real16(v) => f64::from(v[i].to_f32()),
        })
    }

    /// The text of a string or unstructured value (if UTF-8).
    pub fn as_str(&self) -> Option<&str> {
        match self {
            Value::String(v) | Value::Unstructured(v) => core::str::from_utf8(v).ok(),
            _ => None,
        }
    }

    pub(crate) fn write(&self, w: &mut BitWriter<'_>) {
        w.write_uint(u64::from(self.tag()), 8);
        match self {
            Value::Empty => {}
            Value::String(v) | Value::Unstructured(v) => {
                w.write_uint(v.len() as u64, 16);
                w.write_bytes(v);
            }
            Value::Bit(v) => {
                w.write_uint(v.len() as u64, 16);
                for b in v.iter() {
                    w.write_bool(b);
                }
                w.align();
            }
            Value::Integer64(v) => {
                w.write_uint(v.len() as u64, 8);
                v.iter().for_each(|&x| w.write_uint(x as u64, 64));
            }
            Value::Integer32(v) => {
                w.write_uint(v.len() as u64, 8);
                v.iter().for_each(|&x| w.write_uint(x as u64, 32));
            }
            Value::Integer16(v) => {
                w.write_uint(v.len() as u64, 8);
                v.iter().for_each(|&x| w.write_uint(x as u64, 16));
            }
            Value::Integer8(v) => {
                w.write_uint(v.len() as u64, 16);
                v.iter().for_each(|&x| w.write_uint(x as u64, 8));
            }
            Value::Natural64(v) => {
                w.write_uint(v.len() as u64, 8);
                v.iter().for_each(|&x| w.write_uint(x, 64));
            }
            Value::Natural32(v) => {
                w.write_uint(v.len() as u64, 8);
                v.iter().for_each(|&x| w.write_uint(u64::from(x), 32));
            }
            Value::Natural16(v) => {
                w.write_uint(v.len() as u64, 8);
                v.iter().for_each(|&x| w.write_uint(u64::from(x), 16));
            }
            Value::Natural8(v) => {
                w.write_uint(v.len() as u64, 16);
                w.write_bytes(v);
            }
            Value::Real64(v) => {
                w.write_uint(v.len() as u64, 8);
                v.iter().for_each(|&x| w.write_f64(x));
            }
            Value::Real32(v) => {
                w.write_uint(v.len() as u64, 8);
                v.iter().for_each(|&x| w.write_f32(x));
            }
            Value::Real16(v) => {
                w.write_uint(v.len() as u64, 8);
                v.iter()
                    .for_each(|&x| w.write_uint(u64::from(x.to_bits()), 16));
            }
        }
    }

    pub(crate) fn read(r: &mut BitReader<'_>) -> Result<Value, DecodeError> {
        let tag = r.read_uint(8) as u8;
        Ok(match tag {
            0 => Value::Empty,
            1 => Value::String(read_vec(r, 16, |r| r.read_uint(8) as u8)?),
            2 => Value::Unstructured(read_vec(r, 16, |r| r.read_uint(8) as u8)?),
            3 => {
                let n = read_length(r, 16, BitArray::CAPACITY)?;
                let mut a = BitArray::new();
                for _ in 0..n {
                    let _ = a.push(r.read_bool());
                }
                r.align();
                Value::Bit(a)
            }
            4 => Value::Integer64(read_vec(r, 8, |r| r.read_int(64))?),
            5 => Value::Integer32(read_vec(r, 8, |r| r.read_int(32) as i32)?),
            6 => Value::Integer16(read_vec(r, 8, |r| r.read_int(16) as i16)?),
            7 => Value::Integer8(read_vec(r, 16, |r| r.read_int(8) as i8)?),
            8 => Value::Natural64(read_vec(r, 8, |r| r.read_uint(64))?),
            9 => Value::Natural32(read_vec(r, 8, |r| r.read_uint(32) as u32)?),
            10 => Value::Natural16(read_vec(r, 8, |r| r.read_uint(16) as u16)?),
            11 => Value::Natural8(read_vec(r, 16, |r| r.read_uint(8) as u8)?),
            12 => Value::Real64(read_vec(r, 8, |r| r.read_f64())?),
            13 => Value::Real32(read_vec(r, 8, |r| r.read_f32())?),
            14 => Value::Real16(read_vec(r, 8, |r| {
                half::f16::from_bits(r.read_uint(16) as u16)
            })?),
            tag => return Err(DecodeError::UnionTagOutOfRange { tag, members: 15 }),
        })
    }
}

impl DataType for Value {
    const EXTENT_BYTES: usize = 259;
    const MAX_SIZE_BYTES: usize = 259;

    fn serialize(&self, out: &mut [u8]) -> usize {
        let mut w = BitWriter::new(&mut out[..Self::MAX_SIZE_BYTES]);
        self.write(&mut w);
        w.byte_len()
    }

    fn deserialize(payload: &[u8]) -> Result<Self, DecodeError> {
        Value::read(&mut BitReader::new(payload))
    }
}

/// `uavcan.register.Access.1.0` request: write `value` (unless empty) to `name`, then read it.
#[derive(Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AccessRequest {
    /// The register.
    pub name: Name,
    /// The value to write; [`Value::Empty`] to only read.
    pub value: Value,
}

impl DataType for AccessRequest {
    const EXTENT_BYTES: usize = 515;
    const MAX_SIZE_BYTES: usize = 515;

    fn serialize(&self, out: &mut [u8]) -> usize {
        let mut w = BitWriter::new(&mut out[..Self::MAX_SIZE_BYTES]);
        self.name.write(&mut w);
        self.value.write(&mut w);
        w.byte_len()
    }

    fn deserialize(payload: &[u8]) -> Result<Self, DecodeError> {
        let mut r = BitReader::new(payload);
        let name = Name::read(&mut r)?;
        let value = Value::read(&mut r)?;
        Ok(AccessRequest { name, value })
    }
}

/// `uavcan.register.Access.1.0` response: the register as read after the write (if any).
#[derive(Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AccessResponse {
    /// `uavcan.time.SynchronizedTimestamp.1.0` of the read, µs (truncated to 56 bits; 0 =
    /// unknown).
    pub timestamp_us: u64,
    /// The register can be written.
    pub mutable: bool,
    /// The register keeps its value across restarts.
    pub persistent: bool,
    /// The value read; [`Value::Empty`] if there is no such register.
    pub value: Value,
}

impl DataType for AccessResponse {
    const EXTENT_BYTES: usize = 267;
    const MAX_SIZE_BYTES: usize = 267;

    fn serialize(&self, out: &mut [u8]) -> usize {
        let mut w = BitWriter::new(&mut out[..Self::MAX_SIZE_BYTES]);
        w.write_uint(self.timestamp_us, 56);
        w.write_bool(self.mutable);
        w.write_bool(self.persistent);
        w.skip(6);
        self.value.write(&mut w);
        w.byte_len()
    }

    fn deserialize(payload: &[u8]) -> Result<Self, DecodeError> {
        let mut r = BitReader::new(payload);
        let timestamp_us = r.read_uint(56);
        let mutable = r.read_bool();
        let persistent = r.read_bool();
        r.skip(6);
        let value = Value::read(&mut r)?;
        Ok(AccessResponse {
            timestamp_us,
            mutable,
            persistent,
            value,
        })
    }
}

/// `uavcan.register.List.1.0` request: the name of the register at `index`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ListRequest {
    /// Index from 0; iterate until the response's name is empty.
    pub index: u16,
}

impl DataType for ListRequest {
    const EXTENT_BYTES: usize = 2;
    const MAX_SIZE_BYTES: usize = 2;

    fn serialize(&self, out: &mut [u8]) -> usize {
        let mut w = BitWriter::new(&mut out[..Self::MAX_SIZE_BYTES]);
        w.write_uint(u64::from(self.index), 16);
        2
    }

    fn deserialize(payload: &[u8]) -> Result<Self, DecodeError> {
        Ok(ListRequest {
            index: BitReader::new(payload).read_uint(16) as u16,
        })
    }
}

/// `uavcan.register.List.1.0` response: a name, empty past the last register.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ListResponse {
    /// The register's name.
    pub name: Name,
}

impl DataType for ListResponse {
    const EXTENT_BYTES: usize = 256;
    const MAX_SIZE_BYTES: usize = 256;

    fn serialize(&self, out: &mut [u8]) -> usize {
        self.name.serialize(out)
    }

    fn deserialize(payload: &[u8]) -> Result<Self, DecodeError> {
        Ok(ListResponse {
            name: Name::deserialize(payload)?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn natural16_scalar_and_access_round_trip() {
        let req = AccessRequest {
            name: Name::new("uavcan.node.id").unwrap(),
            value: Value::natural16(&[42]).unwrap(),
        };
        let mut buf = [0u8; 515];
        let n = req.serialize(&mut buf);
        assert_eq!(&buf[..1], &[14]);
        assert_eq!(&buf[15..n], &[10, 1, 42, 0]);
        assert_eq!(AccessRequest::deserialize(&buf[..n]).unwrap(), req);
    }

    #[test]
    fn bits_pack_lsb_first_and_rejects() {
        let v = Value::bit(&[true, false, true, true, false, false, false, false, true]).unwrap();
        let mut buf = [0u8; 259];
        let n = v.serialize(&mut buf);
        assert_eq!(&buf[..n], &[3, 9, 0, 0b0000_1101, 1]);
        assert_eq!(Value::deserialize(&buf[..n]).unwrap(), v);
        assert_eq!(
            Value::deserialize(&[15]),
            Err(DecodeError::UnionTagOutOfRange {
                tag: 15,
                members: 15
            })
        );
        assert!(Value::deserialize(&[3, 0x01, 0x08]).is_err());
        assert_eq!(
            Value::deserialize(&[4, 1, 0xFF]).unwrap().float_at(0),
            Some(255.0)
        );
        assert_eq!(
            Value::deserialize(&[5, 1, 0xFF, 0xFF, 0xFF, 0xFF]).unwrap(),
            Value::Integer32(heapless::Vec::from_slice(&[-1]).unwrap())
        );
    }
}
