//! Bit-level cursors over byte buffers, LSB-first as Cyphal packs fields.

/// Writes fields LSB-first into a byte buffer. Bits not written stay as they were, so callers
/// start from a zeroed buffer (void padding is then zero).
pub struct BitWriter<'a> {
    buf: &'a mut [u8],
    bit: usize,
}

impl<'a> BitWriter<'a> {
    /// A writer at the start of `buf`; the buffer is zeroed first.
    pub fn new(buf: &'a mut [u8]) -> Self {
        buf.fill(0);
        BitWriter { buf, bit: 0 }
    }

    /// Appends the low `bits` bits of `value` (`bits` ≤ 64). Bits that do not fit are dropped.
    pub fn write_uint(&mut self, value: u64, bits: u32) {
        let mut remaining = bits;
        let mut v = if bits >= 64 {
            value
        } else {
            value & ((1u64 << bits) - 1)
        };
        while remaining > 0 {
            let byte = self.bit / 8;
            let shift = (self.bit % 8) as u32;
            let take = (8 - shift).min(remaining);
            if let Some(b) = self.buf.get_mut(byte) {
                *b |= ((v as u8) & ((1u16 << take) - 1) as u8) << shift;
            }
            v >>= take;
            remaining -= take;
            self.bit += take as usize;
        }
    }

    /// Appends `bits` zero bits (void padding).
    pub fn skip(&mut self, bits: u32) {
        self.bit += bits as usize;
    }

    /// Advances to the next byte boundary (composite alignment).
    pub fn align(&mut self) {
        self.bit = self.bit.div_ceil(8) * 8;
    }

    /// Appends an IEEE-754 binary32.
    pub fn write_f32(&mut self, v: f32) {
        self.write_uint(u64::from(v.to_bits()), 32);
    }

    /// Appends a `saturated float16` (see [`f16_bits_saturated`]).
    pub fn write_f16_saturated(&mut self, v: f32) {
        self.write_uint(u64::from(f16_bits_saturated(v)), 16);
    }

    /// Appends an IEEE-754 binary64.
    pub fn write_f64(&mut self, v: f64) {
        self.write_uint(v.to_bits(), 64);
    }

    /// Appends a `bool`.
    pub fn write_bool(&mut self, v: bool) {
        self.write_uint(u64::from(v), 1);
    }

    /// Appends raw bytes (the writer must be on a byte boundary for them to land whole).
    pub fn write_bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_uint(u64::from(b), 8);
        }
    }

    /// Bits written so far.
    pub fn bit_len(&self) -> usize {
        self.bit
    }

    /// Bytes touched so far (the serialized length once writing is done).
    pub fn byte_len(&self) -> usize {
        self.bit.div_ceil(8)
    }
}

/// Reads fields LSB-first from a payload; bits past the end read as zero (implicit zero
/// extension).
pub struct BitReader<'a> {
    buf: &'a [u8],
    bit: usize,
}

impl<'a> BitReader<'a> {
    /// A reader at the start of `buf`.
    pub fn new(buf: &'a [u8]) -> Self {
        BitReader { buf, bit: 0 }
    }

    /// Reads `bits` bits (≤ 64) as an unsigned integer.
    pub fn read_uint(&mut self, bits: u32) -> u64 {
        let mut out = 0u64;
        let mut got = 0u32;
        while got < bits {
            let byte = self.buf.get(self.bit / 8).copied().unwrap_or(0);
            let shift = (self.bit % 8) as u32;
            let take = (8 - shift).min(bits - got);
            let chunk = (u64::from(byte) >> shift) & ((1u64 << take) - 1);
            out |= chunk << got;
            got += take;
            self.bit += take as usize;
        }
        out
    }

    /// Reads `bits` bits (1..=64) as a two's-complement signed integer.
    pub fn read_int(&mut self, bits: u32) -> i64 {
        let v = self.read_uint(bits);
        if bits < 64 && bits > 0 && (v >> (bits - 1)) & 1 == 1 {
            (v | !((1u64 << bits) - 1)) as i64
        } else {
            v as i64
        }
    }

    /// Reads a `bool`.
    pub fn read_bool(&mut self) -> bool {
        self.read_uint(1) == 1
    }

    /// Skips `bits` bits (void padding).
    pub fn skip(&mut self, bits: u32) {
        self.bit += bits as usize;
    }

    /// Advances to the next byte boundary.
    pub fn align(&mut self) {
        self.bit = self.bit.div_ceil(8) * 8;
    }

    /// Bits consumed so far (may run past the end of the payload: those read as zero).
    pub fn bit_position(&self) -> usize {
        self.bit
    }

    /// Bytes of payload left after the (byte-aligned) position; 0 once past the end.
    pub fn remaining_bytes(&self) -> usize {
        self.buf.len().saturating_sub(self.bit.div_ceil(8))
    }

    /// Reads an IEEE-754 binary64.
    pub fn read_f64(&mut self) -> f64 {
        f64::from_bits(self.read_uint(64))
    }

    /// Reads an IEEE-754 binary32.
    pub fn read_f32(&mut self) -> f32 {
        f32::from_bits(self.read_uint(32) as u32)
    }

    /// Reads an IEEE-754 binary16, widened to f32 exactly.
    pub fn read_f16(&mut self) -> f32 {
        f16_bits_to_f32(self.read_uint(16) as u16)
    }
}

/// The binary16 bits of `v` under the specification's `saturated` cast: finite values are
/// clamped to ±65504 (the largest finite binary16) and then rounded to nearest, ties to even;
/// NaN and ±∞ are kept. PyCyphal's numpy cast overflows finite |x| ≥ 65520 to ±∞ instead; we
/// follow the specification (and Nunavut's C output) here.
pub fn f16_bits_saturated(v: f32) -> u16 {
    const MAX: f32 = 65504.0;
    if v.is_nan() {
        // Keep sign and the top payload bits, quiet or signalling, so that a NaN read from the
        // wire is written back bit for bit (PyCyphal's numpy does the same).
        let bits = v.to_bits();
        let sign = ((bits >> 16) & 0x8000) as u16;
        let mantissa = match ((bits >> 13) & 0x3FF) as u16 {
            0 => 0x200,
            m => m,
        };
        return sign | 0x7C00 | mantissa;
    }
    let clamped = if v.is_finite() { v.clamp(-MAX, MAX) } else { v };
    half::f16::from_f32(clamped).to_bits()
}

/// Widens binary16 bits to f32 exactly; NaN payloads (including signalling NaNs) are kept
/// rather than quietened, so that decode → encode is the identity on the wire.
fn f16_bits_to_f32(bits: u16) -> f32 {
    if bits & 0x7C00 == 0x7C00 && bits & 0x03FF != 0 {
        let sign = u32::from(bits & 0x8000) << 16;
        return f32::from_bits(sign | 0x7F80_0000 | (u32::from(bits & 0x03FF) << 13));
    }
    half::f16::from_bits(bits).to_f32()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unaligned_fields_round_trip() {
        let mut buf = [0u8; 4];
        let mut w = BitWriter::new(&mut buf);
        w.write_uint(0b101, 3);
        w.write_uint(0x1FF, 9);
        w.write_uint(0xABCD, 16);
        assert_eq!(w.byte_len(), 4);
        // 3 bits 101, then 9 ones, then 0xABCD, LSB first.
        assert_eq!(buf, [0xFD, 0xDF, 0xBC, 0x0A]);
        let mut r = BitReader::new(&buf);
        assert_eq!(r.read_uint(3), 0b101);
        assert_eq!(r.read_uint(9), 0x1FF);
        assert_eq!(r.read_uint(16), 0xABCD);
        // Past the end: zeros.
        assert_eq!(r.read_uint(64), 0);
    }

    #[test]
    fn float16_saturates() {
        assert_eq!(f16_bits_saturated(1e5), 0x7BFF);
        assert_eq!(f16_bits_saturated(-3e38), 0xFBFF);
        assert_eq!(f16_bits_saturated(f32::INFINITY), 0x7C00);
        assert_eq!(f16_bits_saturated(f32::NEG_INFINITY), 0xFC00);
        assert!(half::f16::from_bits(f16_bits_saturated(f32::NAN)).is_nan());
        for nan in [0x7C01u16, 0x7E00, 0xFE00, 0x7FFF] {
            assert_eq!(f16_bits_saturated(f16_bits_to_f32(nan)), nan);
        }
        assert_eq!(f16_bits_saturated(-0.0), 0x8000);
        assert_eq!(f16_bits_saturated(1.0), 0x3C00);
    }
}
