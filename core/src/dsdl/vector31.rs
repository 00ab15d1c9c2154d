//! `zubax.primitive.real16.Vector31.1.0`: the ratiometric setpoint vector (sealed, 62 bytes).

use super::{BitReader, BitWriter, DataType, DecodeError};

/// `zubax.primitive.real16.Vector31.1.0`: `float16[31] value` (saturated).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Vector31 {
    /// The elements; serialized as binary16 with the saturated cast.
    pub value: [f32; 31],
}

impl Vector31 {
    /// All 31 elements set to `v` (how the driver commands one setpoint to every drive).
    pub fn splat(v: f32) -> Self {
        Vector31 { value: [v; 31] }
    }
}

impl DataType for Vector31 {
    const EXTENT_BYTES: usize = 62;
    const MAX_SIZE_BYTES: usize = 62;

    fn serialize(&self, out: &mut [u8]) -> usize {
        let mut w = BitWriter::new(&mut out[..Self::MAX_SIZE_BYTES]);
        for v in self.value {
            w.write_f16_saturated(v);
        }
        Self::MAX_SIZE_BYTES
    }

    fn deserialize(payload: &[u8]) -> Result<Self, DecodeError> {
        let mut r = BitReader::new(payload);
        let mut value = [0f32; 31];
        for v in &mut value {
            *v = r.read_f16();
        }
        Ok(Vector31 { value })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_emit() {
        let mut v = Vector31::splat(0.0);
        v.value[0] = 1.0;
        v.value[1] = -2.0;
        v.value[30] = 1e6; // saturates to 65504
        let mut buf = [0u8; 62];
        assert_eq!(v.serialize(&mut buf), 62);
        assert_eq!(&buf[..4], &[0x00, 0x3C, 0x00, 0xC0]);
        assert_eq!(&buf[60..], &[0xFF, 0x7B]);
        let back = Vector31::deserialize(&buf).unwrap();
        assert_eq!(back.value[30], 65504.0);
        // 61 bytes: the last element's high byte reads as zero.
        let short = Vector31::deserialize(&buf[..61]).unwrap();
        assert_eq!(short.value[30], half::f16::from_bits(0x00FF).to_f32());
    }
}
