//! The TSV currency: every producer of samples (drive, replay, sim, importers) writes it and every
//! consumer (fit, diagnose, plot) reads it.
//!
//! Columns, by header name (order free, extra columns ignored):
//! `ts_local` (host receive time, s, optional), `t` (device time, s), `force` (N·m), `velocity`
//! (rad/s), `acceleration` (rad/s²), `position` (rad, optional). This is the seed driver's output
//! plus `position`. Empty fields and `nan` read as NaN (the seed's pandas does the same).

use std::io::{BufRead, Write};

pub use propid_core::sample::Sample;

/// A TSV row: the sample plus the host's receive time, if the file has it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    /// Host monotonic receive time [s] (NaN if the file has no `ts_local` column).
    pub ts_local: f64,
    /// The measurement.
    pub sample: Sample,
}

/// The header `propid` writes.
pub const HEADER: [&str; 6] = [
    "ts_local",
    "t",
    "force",
    "velocity",
    "acceleration",
    "position",
];

/// Why a TSV could not be read. Every variant names where.
#[derive(Debug, thiserror::Error)]
pub enum TsvError {
    /// The input has no header line.
    #[error("{source_name}: empty input (no header line)")]
    Empty {
        /// File name or `<stdin>`.
        source_name: String,
    },
    /// A required column is missing from the header.
    #[error("{source_name}: line 1: missing column `{column}` (header has: {header})")]
    MissingColumn {
        /// File name or `<stdin>`.
        source_name: String,
        /// The missing column.
        column: &'static str,
        /// The header as found.
        header: String,
    },
    /// A field is not a number.
    #[error("{source_name}: line {line}, column `{column}`: `{text}` is not a number")]
    NotANumber {
        /// File name or `<stdin>`.
        source_name: String,
        /// 1-based line number.
        line: u64,
        /// Column name.
        column: String,
        /// The offending text (shortened).
        text: String,
    },
    /// A row has fewer fields than a required column's index.
    #[error(
        "{source_name}: line {line}: row has {found} fields, column `{column}` is field {needed}"
    )]
    ShortRow {
        /// File name or `<stdin>`.
        source_name: String,
        /// 1-based line number.
        line: u64,
        /// Column name.
        column: String,
        /// Fields present.
        found: usize,
        /// 1-based index of the column.
        needed: usize,
    },
    /// Reading failed.
    #[error("{source_name}: line {line}: {source}")]
    Io {
        /// File name or `<stdin>`.
        source_name: String,
        /// 1-based line number where reading failed.
        line: u64,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
}

/// Where the columns are in a row, found from the header: the byte-level row parser behind
/// [`TsvReader`], also usable on a memory-mapped file split among threads (lines are
/// independent).
#[derive(Clone, Debug)]
pub struct Layout {
    /// Field indices of ts_local, t, force, velocity, acceleration, position.
    idx: [Option<usize>; 6],
    /// For each field index up to the last used one, the slot it fills (`NONE` if unused).
    slot_of: Vec<u8>,
}

const NONE: u8 = u8::MAX;

/// Why one row could not be parsed (the caller adds the file and line: [`RowError::at`]).
#[derive(Clone, Debug, PartialEq)]
pub enum RowError {
    /// A used field is not a number.
    NotANumber {
        /// Slot in [`HEADER`].
        slot: usize,
        /// The offending text (shortened).
        text: String,
    },
    /// The row ends before a required column.
    ShortRow {
        /// Slot in [`HEADER`].
        slot: usize,
        /// Fields present.
        found: usize,
        /// 1-based index of the column.
        needed: usize,
    },
}

impl RowError {
    /// The error with its place.
    pub fn at(self, source_name: &str, line: u64) -> TsvError {
        match self {
            RowError::NotANumber { slot, text } => TsvError::NotANumber {
                source_name: source_name.to_string(),
                line,
                column: HEADER[slot].to_string(),
                text,
            },
            RowError::ShortRow {
                slot,
                found,
                needed,
            } => TsvError::ShortRow {
                source_name: source_name.to_string(),
                line,
                column: HEADER[slot].to_string(),
                found,
                needed,
            },
        }
    }
}

/// The bytes `str::trim` removes that are ASCII (Unicode White_Space below 0x80).
fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\n' | 0x0B | 0x0C | b'\r')
}

fn trim_bytes(mut f: &[u8]) -> &[u8] {
    while let [first, rest @ ..] = f {
        if !is_space(*first) {
            break;
        }
        f = rest;
    }
    while let [rest @ .., last] = f {
        if !is_space(*last) {
            break;
        }
        f = rest;
    }
    f
}

/// Parses one field's bytes like [`parse_field`] (the same values are accepted and the same
/// floats result: fast-float2 rounds correctly, as std does; anything it refuses, such as
/// Unicode spaces around a number, goes through std).
fn parse_field_bytes(field: &[u8]) -> Option<f64> {
    let f = trim_bytes(field);
    if f.is_empty() {
        return Some(f64::NAN);
    }
    match fast_float2::parse::<f64, _>(f) {
        Ok(v) => Some(v),
        Err(_) => parse_field(std::str::from_utf8(field).ok()?),
    }
}

/// Every slot of [`HEADER`], for [`Layout::parse_line_converting`].
pub const ALL_SLOTS: u8 = 0b11_1111;

/// The line without the `\r`s (and `\n`s) at its end.
#[inline]
fn strip_cr(line: &[u8]) -> &[u8] {
    match line {
        [.., b'\r'] => {
            let mut l = line;
            while let [rest @ .., b'\r' | b'\n'] = l {
                l = rest;
            }
            l
        }
        _ => line,
    }
}

/// The number of ASCII digits `b` starts with, eight bytes at a time.
#[inline]
fn leading_digits(b: &[u8]) -> usize {
    const ONES: u64 = 0x0101_0101_0101_0101;
    let mut n = 0;
    while let Some(chunk) = b.get(n..).and_then(|r| r.first_chunk::<8>()) {
        // Byte by byte, z = byte ^ '0' is below 10 exactly for a digit; (z & 0x7f) + 0x76 has
        // its top bit set for z & 0x7f ≥ 10 (and cannot carry into the next byte), z itself
        // for z ≥ 0x80. The lowest flagged byte is the first non-digit.
        let z = u64::from_le_bytes(*chunk) ^ (0x30 * ONES);
        let flags = (((z & (0x7f * ONES)) + 0x76 * ONES) | z) & (0x80 * ONES);
        if flags != 0 {
            return n + (flags.trailing_zeros() / 8) as usize;
        }
        n += 8;
    }
    while b.get(n).is_some_and(u8::is_ascii_digit) {
        n += 1;
    }
    n
}

/// The length of the plain decimal number (`-?[0-9]+(.[0-9]+)?`, at most 300 bytes, so finite)
/// that `field` starts with, if it ends at a tab or at the end of `field`.
#[inline]
fn plain_decimal(field: &[u8]) -> Option<usize> {
    let sign = usize::from(field.first() == Some(&b'-'));
    let int = leading_digits(&field[sign..]);
    if int == 0 {
        return None;
    }
    let mut end = sign + int;
    if field.get(end) == Some(&b'.') {
        let frac = leading_digits(&field[end + 1..]);
        if frac == 0 {
            return None;
        }
        end += 1 + frac;
    }
    (end <= 300 && matches!(field.get(end), None | Some(b'\t'))).then_some(end)
}

impl Layout {
    fn new(idx: [Option<usize>; 6]) -> Self {
        let last = idx.iter().flatten().copied().max().unwrap_or(0);
        let mut slot_of = vec![NONE; last + 1];
        for (slot, i) in idx.iter().enumerate() {
            if let Some(i) = i {
                slot_of[*i] = slot as u8;
            }
        }
        Layout { idx, slot_of }
    }

    /// True if the line holds nothing but white space (such lines are skipped, as pandas does).
    pub fn is_blank(line: &[u8]) -> bool {
        match std::str::from_utf8(line) {
            Ok(text) => text.trim().is_empty(),
            Err(_) => false,
        }
    }

    /// True if the line (without its `\n`) is a row, false if [`Layout::parse_line`] skips it as
    /// blank.
    #[inline]
    pub fn is_row(line: &[u8]) -> bool {
        let line = strip_cr(line);
        !(line.first().is_none_or(|b| is_space(*b) || *b >= 0x80) && Self::is_blank(line))
    }

    /// Parses one line (without its `\n`) into ts_local, t, force, velocity, acceleration,
    /// position (NaN where empty or absent); `None` for a blank line.
    pub fn parse_line(&self, line: &[u8]) -> Result<Option<[f64; 6]>, RowError> {
        self.parse_line_converting(line, ALL_SLOTS)
    }

    /// [`Layout::parse_line`], converting only the slots whose bit (`1 << slot`, slots in
    /// [`HEADER`] order) is set in `convert`. The other fields are checked all the same (the
    /// same text is the same error) and read as `0.0` when they are a plain decimal number
    /// (`-?[0-9]+(.[0-9]+)?`, at most 300 bytes: always finite), without the cost of a float
    /// conversion; any other text is converted as `parse_line` does. So in every slot
    /// `is_finite()` is what `parse_line` gives, and the converted slots hold its exact values.
    #[inline]
    pub fn parse_line_converting(
        &self,
        line: &[u8],
        convert: u8,
    ) -> Result<Option<[f64; 6]>, RowError> {
        let line = strip_cr(line);
        if line.first().is_none_or(|b| is_space(*b) || *b >= 0x80) && Self::is_blank(line) {
            return Ok(None);
        }
        let mut values = [f64::NAN; 6];
        let mut found = 0usize;
        let mut rest = line;
        for (field_index, &slot) in self.slot_of.iter().enumerate() {
            found = field_index + 1;
            // The common case: a plain number right up to the tab (or the line's end), parsed
            // without looking for the tab first.
            if slot != NONE && convert & (1 << slot) == 0 {
                // Checked, not converted: a plain decimal number ends at the tab or the line.
                if let Some(used) = plain_decimal(rest) {
                    values[slot as usize] = 0.0;
                    match rest.get(used + 1..) {
                        None => break,
                        Some(next) => {
                            rest = next;
                            continue;
                        }
                    }
                }
            } else if slot != NONE {
                if let Ok((v, used)) = fast_float2::parse_partial::<f64, _>(rest) {
                    match rest.get(used) {
                        None => {
                            values[slot as usize] = v;
                            break;
                        }
                        Some(b'\t') => {
                            values[slot as usize] = v;
                            rest = &rest[used + 1..];
                            continue;
                        }
                        Some(_) => {}
                    }
                }
            }
            let (field, next) = match memchr::memchr(b'\t', rest) {
                Some(i) => (&rest[..i], Some(&rest[i + 1..])),
                None => (rest, None),
            };
            if slot != NONE {
                let slot = slot as usize;
                values[slot] = parse_field_bytes(field).ok_or_else(|| RowError::NotANumber {
                    slot,
                    text: String::from_utf8_lossy(field).chars().take(40).collect(),
                })?;
            }
            match next {
                Some(n) => rest = n,
                None => break,
            }
        }
        for slot in 1..5 {
            let needed = self.idx[slot].unwrap_or(0) + 1;
            if needed > found {
                return Err(RowError::ShortRow {
                    slot,
                    found,
                    needed,
                });
            }
        }
        Ok(Some(values))
    }
}

/// A row from the six values of [`Layout::parse_line`].
pub fn row_of(v: &[f64; 6]) -> Row {
    Row {
        ts_local: v[0],
        sample: Sample {
            t: v[1],
            force: v[2],
            velocity: v[3],
            acceleration: v[4],
            position: v[5],
        },
    }
}

/// Streams rows from a TSV in constant memory.
pub struct TsvReader<R> {
    input: R,
    source_name: String,
    line_no: u64,
    line: Vec<u8>,
    layout: Layout,
    bytes_read: u64,
}

impl<R: BufRead> TsvReader<R> {
    /// Reads the header. `source_name` is used in error messages (file path or `<stdin>`).
    pub fn new(mut input: R, source_name: impl Into<String>) -> Result<Self, TsvError> {
        let source_name = source_name.into();
        let mut header = String::new();
        let n = input.read_line(&mut header).map_err(|e| TsvError::Io {
            source_name: source_name.clone(),
            line: 1,
            source: e,
        })?;
        let header_trimmed = header
            .trim_end_matches(['\r', '\n'])
            .trim_start_matches('\u{feff}');
        if n == 0 || header_trimmed.trim().is_empty() {
            return Err(TsvError::Empty { source_name });
        }
        let names: Vec<&str> = header_trimmed.split('\t').map(str::trim).collect();
        let mut idx = [None; 6];
        for (slot, want) in idx.iter_mut().zip(HEADER) {
            *slot = names.iter().position(|n| *n == want);
        }
        for (i, want) in HEADER.iter().enumerate().take(5).skip(1) {
            if idx[i].is_none() {
                return Err(TsvError::MissingColumn {
                    source_name,
                    column: want,
                    header: names.join(", "),
                });
            }
        }
        Ok(TsvReader {
            input,
            source_name,
            line_no: 1,
            line: Vec::new(),
            layout: Layout::new(idx),
            bytes_read: n as u64,
        })
    }

    /// True if the file has a `position` column.
    pub fn has_position(&self) -> bool {
        self.layout.idx[5].is_some()
    }

    /// The column layout (to parse further lines of the same file elsewhere).
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// Bytes consumed so far (for progress reporting).
    pub fn bytes_read(&self) -> u64 {
        self.bytes_read
    }

    /// The 1-based number of the line last read.
    pub fn line_number(&self) -> u64 {
        self.line_no
    }

    /// The name used in error messages.
    pub fn source_name(&self) -> &str {
        &self.source_name
    }

    /// The next row, `None` at the end. Blank lines are skipped.
    pub fn next_row(&mut self) -> Result<Option<Row>, TsvError> {
        loop {
            self.line.clear();
            let n = self
                .input
                .read_until(b'\n', &mut self.line)
                .map_err(|e| TsvError::Io {
                    source_name: self.source_name.clone(),
                    line: self.line_no + 1,
                    source: e,
                })?;
            if n == 0 {
                return Ok(None);
            }
            self.bytes_read += n as u64;
            self.line_no += 1;
            let line = self.line.strip_suffix(b"\n").unwrap_or(&self.line);
            match self.layout.parse_line(line) {
                Ok(None) => continue,
                Ok(Some(v)) => return Ok(Some(row_of(&v))),
                Err(e) => return Err(e.at(&self.source_name, self.line_no)),
            }
        }
    }
}

/// Parses one field: a float, `nan`/`inf` in any case, or empty (NaN).
pub fn parse_field(field: &str) -> Option<f64> {
    let s = field.trim();
    if s.is_empty() {
        return Some(f64::NAN);
    }
    s.parse::<f64>().ok()
}

/// Writes the canonical TSV, optionally flushing after every row (so that nothing is lost if the
/// process is killed).
pub struct TsvWriter<W: Write> {
    out: W,
    flush_each_row: bool,
    extra_columns: usize,
}

impl<W: Write> TsvWriter<W> {
    /// Writes the header line.
    pub fn new(out: W, flush_each_row: bool) -> std::io::Result<Self> {
        Self::with_extra_columns(out, flush_each_row, &[])
    }

    /// Writes the header line with `extra` columns after the standard ones (for example the
    /// `command` an importer keeps); the reader ignores columns it does not know. Rows then go
    /// through [`TsvWriter::write_with`].
    pub fn with_extra_columns(
        mut out: W,
        flush_each_row: bool,
        extra: &[&str],
    ) -> std::io::Result<Self> {
        let mut header = HEADER.join("\t");
        for name in extra {
            header.push('\t');
            header.push_str(name);
        }
        writeln!(out, "{header}")?;
        if flush_each_row {
            out.flush()?;
        }
        Ok(TsvWriter {
            out,
            flush_each_row,
            extra_columns: extra.len(),
        })
    }

    /// Writes one row. NaN is written as `nan` (the seed's Python prints the same).
    pub fn write(&mut self, row: &Row) -> std::io::Result<()> {
        self.write_with(row, &[])
    }

    /// Writes one row and the values of the extra columns (NaN where one is missing).
    pub fn write_with(&mut self, row: &Row, extra: &[f64]) -> std::io::Result<()> {
        let s = &row.sample;
        let fields = [
            row.ts_local,
            s.t,
            s.force,
            s.velocity,
            s.acceleration,
            s.position,
        ];
        let extra = (0..self.extra_columns).map(|k| extra.get(k).copied().unwrap_or(f64::NAN));
        let mut line = String::with_capacity(96);
        for (i, v) in fields.into_iter().chain(extra).enumerate() {
            if i > 0 {
                line.push('\t');
            }
            if v.is_nan() {
                line.push_str("nan");
            } else {
                line.push_str(&format!("{v}"));
            }
        }
        line.push('\n');
        self.out.write_all(line.as_bytes())?;
        if self.flush_each_row {
            self.out.flush()?;
        }
        Ok(())
    }

    /// Flushes and returns the inner writer.
    pub fn into_inner(mut self) -> std::io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The byte-level parser accepts exactly what std's accepts, with the same values.
    #[test]
    fn fast_fields_agree_with_std() {
        let cases = [
            "0",
            "-0",
            "+1",
            "1.",
            ".5",
            "-.5",
            "1e5",
            "1E-5",
            "1.e3",
            "1e+3",
            "1e",
            "e5",
            ".",
            "-",
            "+",
            "1.2.3",
            "0x10",
            "1_000",
            "inf",
            "-inf",
            "+inf",
            "Infinity",
            "-INFINITY",
            "infin",
            "nan",
            "NaN",
            "-nan",
            "+nan",
            "1e400",
            "-1e400",
            "1e-400",
            "4.9e-324",
            "2.5e-324",
            "0.30000000000000004",
            "123456789012345678901234567890",
            " 7 ",
            "\u{a0}8",
            "9\u{a0}",
            "1,5",
            "1 2",
            "--1",
            "+-1",
            "1e5e5",
            "0.000000000e0",
            "2.827626e2",
            "١",
            "",
            "   ",
            "\r",
            "1d3",
            "1f",
            "0e0",
            "00012",
            "1e0001",
        ];
        for c in cases {
            let want = parse_field(c);
            let got = parse_field_bytes(c.as_bytes());
            match (want, got) {
                (Some(a), Some(b)) => {
                    assert!(
                        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                        "`{c}`"
                    )
                }
                (None, None) => {}
                _ => panic!("`{c}`: std {want:?}, fast {got:?}"),
            }
            // The same through a whole line (the parser's shortcut before the tab).
            let line = format!("t\tforce\tvelocity\tacceleration\n{c}\t2\t{c}\t{c}");
            let mut r = TsvReader::new(line.as_bytes(), "mem").unwrap();
            match (want, r.next_row()) {
                (Some(a), Ok(Some(row))) => {
                    for b in [row.sample.t, row.sample.velocity, row.sample.acceleration] {
                        assert!(
                            a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                            "`{c}`"
                        );
                    }
                }
                (None, Err(TsvError::NotANumber { .. })) => {}
                (Some(_), Ok(None)) if c.trim().is_empty() => {}
                (w, g) => panic!("`{c}` in a line: std {w:?}, reader {g:?}"),
            }
            // Converting some slots only: the same rows, errors and finiteness everywhere, the
            // same values in the converted slots.
            let layout = r.layout().clone();
            let cases_in_line = [
                format!("{c}\t{c}\t{c}\t{c}\t{c}\t{c}"),
                format!("1.5\t{c}\t-2\t{c}\t0.25\t{c}"),
                format!("{c}\t1\t2\t3\t4\t{c}"),
                format!("{c}\t1\t2\t3\t4"),
                format!("{c}\t1\t2\t3\t4\t"),
                format!("{c}\t1\t2"),
            ];
            for text in &cases_in_line {
                let full = layout.parse_line(text.as_bytes());
                for convert in [0u8, 0b1_1100, 0b10_0001, ALL_SLOTS] {
                    let part = layout.parse_line_converting(text.as_bytes(), convert);
                    match (&full, &part) {
                        (Ok(Some(a)), Ok(Some(b))) => {
                            for slot in 0..6 {
                                assert_eq!(a[slot].is_finite(), b[slot].is_finite(), "`{text}`");
                                if convert & (1 << slot) != 0 {
                                    assert!(
                                        a[slot].to_bits() == b[slot].to_bits()
                                            || (a[slot].is_nan() && b[slot].is_nan()),
                                        "`{text}`"
                                    );
                                }
                            }
                        }
                        (a, b) => assert_eq!(a, b, "`{text}`"),
                    }
                    assert_eq!(
                        Layout::is_row(text.as_bytes()),
                        matches!(full, Ok(Some(_)) | Err(_)),
                        "`{text}`"
                    );
                }
            }
        }
    }

    /// The digit scan eight bytes at a time finds the first non-digit wherever it is.
    #[test]
    fn leading_digits_and_plain_decimals() {
        for len in 0..40 {
            for stop in [b'.', b'\t', b'/', b':', b' ', 0x80, 0xb0, 0xff, b'a'] {
                let mut b = vec![b'7'; len];
                b.push(stop);
                b.extend_from_slice(b"123456789");
                assert_eq!(leading_digits(&b), len, "{len} {stop}");
                assert_eq!(leading_digits(&b[..len]), len);
            }
        }
        assert_eq!(plain_decimal(b"12.5\tx"), Some(4));
        assert_eq!(plain_decimal(b"-0.000000000000000001"), Some(21));
        assert_eq!(plain_decimal(b"7"), Some(1));
        for no in [
            &b"1."[..],
            b".5",
            b"-",
            b"1e5",
            b"1.5 ",
            b"+1",
            b"nan",
            b"1.2.3",
            b"",
        ] {
            assert_eq!(plain_decimal(no), None, "{}", String::from_utf8_lossy(no));
        }
        assert_eq!(plain_decimal(&[b'9'; 300]), Some(300));
        assert_eq!(plain_decimal(&[b'9'; 301]), None);
    }

    #[test]
    fn lines_with_crlf_blank_and_unicode_space() {
        let text = "t\tforce\tvelocity\tacceleration\r\n1\t2\t3\t4\r\n \t \r\n\u{a0}\n5\t6\t7\t8";
        let mut r = TsvReader::new(text.as_bytes(), "mem").unwrap();
        assert_eq!(r.next_row().unwrap().unwrap().sample.acceleration, 4.0);
        assert_eq!(r.next_row().unwrap().unwrap().sample.t, 5.0);
        assert_eq!(r.line_number(), 5);
        assert!(r.next_row().unwrap().is_none());
    }

    #[test]
    fn round_trip_and_errors() {
        let row = Row {
            ts_local: 1.5,
            sample: Sample {
                t: 0.25,
                force: -0.125,
                velocity: 300.0,
                acceleration: f64::NAN,
                position: 1e-7,
            },
        };
        let mut w = TsvWriter::new(Vec::new(), false).unwrap();
        w.write(&row).unwrap();
        let bytes = w.into_inner().unwrap();
        let mut r = TsvReader::new(&bytes[..], "mem").unwrap();
        let back = r.next_row().unwrap().unwrap();
        assert_eq!(back.sample.t, 0.25);
        assert_eq!(back.sample.position, 1e-7);
        assert!(back.sample.acceleration.is_nan());
        assert!(r.next_row().unwrap().is_none());

        // Header order free, extra columns ignored, position optional.
        let text = "x\tacceleration\tvelocity\tforce\tt\n9\t1\t2\t3\t4\n";
        let mut r = TsvReader::new(text.as_bytes(), "mem").unwrap();
        assert!(!r.has_position());
        let s = r.next_row().unwrap().unwrap().sample;
        assert_eq!(
            (s.t, s.force, s.velocity, s.acceleration),
            (4.0, 3.0, 2.0, 1.0)
        );
        assert!(s.position.is_nan());

        let err = TsvReader::new("t\tforce\tvelocity\n".as_bytes(), "f.tsv")
            .err()
            .unwrap();
        assert!(
            err.to_string().contains("missing column `acceleration`"),
            "{err}"
        );
        let mut r = TsvReader::new(
            "t\tforce\tvelocity\tacceleration\n1\t2\tabc\t4\n".as_bytes(),
            "f.tsv",
        )
        .unwrap();
        let err = r.next_row().err().unwrap().to_string();
        assert!(
            err.contains("line 2") && err.contains("`velocity`") && err.contains("abc"),
            "{err}"
        );
        assert!(matches!(
            TsvReader::new(&b""[..], "e"),
            Err(TsvError::Empty { .. })
        ));
    }
}
