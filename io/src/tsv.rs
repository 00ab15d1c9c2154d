//! The TSV currency: every producer of samples (drive, replay, sim, importers) writes it and every
//! consumer (fit, diagnose, plot) reads it.
//!
//! Columns, by header name (order free, other columns ignored):
//! `ts_local` (host receive time, s, optional), `t` (device time, s), `force` (N·m), `velocity`
//! (rad/s), `acceleration` (rad/s²), `position` (rad, optional). This is the seed driver's output
//! plus `position`. Empty fields and `nan` read as NaN (the seed's pandas does the same).
//!
//! A test stand measures more than the drive reports; four optional columns carry it, in
//! [`Row::stand`] ([`Stand`]): `thrust` (N), `voltage` (the DC bus, V), `current` (the DC bus,
//! A), `command` (what the stand asked of the ESC or drive, as a ratio: 0 = nothing, 1 = full;
//! an importer states how it converted the logged unit). Absent columns and empty fields read as
//! NaN, like `position`: a value is either measured in this row or NaN, never filled in. A writer
//! writes the seed's six columns, then the stand columns it is given ([`TsvWriter::with_columns`]),
//! then any named extra columns (for example an importer's `electrical_power`), which readers
//! ignore.

use std::io::{BufRead, Write};

use crate::error::{Compression, ErrorKind, InputError};

pub use propid_core::sample::Sample;

/// What a test stand measures beside the drive's dynamics feedback, in the same row. Each is NaN
/// where the source has no such column or no sample in this row (a slow load cell leaves most
/// rows empty): never interpolated, never held. Two `Stand`s are equal when each value is equal
/// or both are absent (NaN), so rows of the seed's columns compare as they did before.
#[derive(Clone, Copy, Debug)]
pub struct Stand {
    /// Thrust [N] (a propeller pushing air: positive along its thrust axis).
    pub thrust: f64,
    /// DC bus voltage [V].
    pub voltage: f64,
    /// DC bus current [A].
    pub current: f64,
    /// The command given to the ESC or drive as a ratio: 0 nothing, 1 full (a duty, a PWM
    /// signal mapped onto its range, a ratiometric setpoint); the producer states its mapping.
    pub command: f64,
}

impl Stand {
    /// Nothing measured: every value NaN.
    pub const NONE: Stand = Stand {
        thrust: f64::NAN,
        voltage: f64::NAN,
        current: f64::NAN,
        command: f64::NAN,
    };

    /// The value of one column.
    pub fn get(&self, column: StandColumn) -> f64 {
        match column {
            StandColumn::Thrust => self.thrust,
            StandColumn::Voltage => self.voltage,
            StandColumn::Current => self.current,
            StandColumn::Command => self.command,
        }
    }

    /// The value of one column, to set.
    pub fn get_mut(&mut self, column: StandColumn) -> &mut f64 {
        match column {
            StandColumn::Thrust => &mut self.thrust,
            StandColumn::Voltage => &mut self.voltage,
            StandColumn::Current => &mut self.current,
            StandColumn::Command => &mut self.command,
        }
    }
}

impl PartialEq for Stand {
    fn eq(&self, other: &Stand) -> bool {
        StandColumn::ALL.iter().all(|c| {
            let (a, b) = (self.get(*c), other.get(*c));
            a == b || (a.is_nan() && b.is_nan())
        })
    }
}

impl Default for Stand {
    /// [`Stand::NONE`].
    fn default() -> Self {
        Stand::NONE
    }
}

/// One of the optional stand columns of the TSV.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StandColumn {
    /// `thrust` [N].
    Thrust,
    /// `voltage` [V], the DC bus.
    Voltage,
    /// `current` [A], the DC bus.
    Current,
    /// `command` [ratio 0–1].
    Command,
}

impl StandColumn {
    /// Every stand column, in the order they are written.
    pub const ALL: [StandColumn; 4] = [
        StandColumn::Thrust,
        StandColumn::Voltage,
        StandColumn::Current,
        StandColumn::Command,
    ];

    /// The column's header name.
    pub fn name(self) -> &'static str {
        COLUMNS[self.slot()]
    }

    /// The column's unit as documents print it.
    pub fn unit(self) -> &'static str {
        match self {
            StandColumn::Thrust => "N",
            StandColumn::Voltage => "V",
            StandColumn::Current => "A",
            StandColumn::Command => "ratio 0–1",
        }
    }

    /// Its slot in [`COLUMNS`] (and in [`Layout::parse_line`]'s values).
    pub fn slot(self) -> usize {
        match self {
            StandColumn::Thrust => 6,
            StandColumn::Voltage => 7,
            StandColumn::Current => 8,
            StandColumn::Command => 9,
        }
    }
}

/// A TSV row: the sample, the host's receive time and what a stand measured beside it, each
/// NaN where the file does not have it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    /// Host monotonic receive time [s] (NaN if the file has no `ts_local` column).
    pub ts_local: f64,
    /// The measurement.
    pub sample: Sample,
    /// The stand's other measurements ([`Stand::NONE`] for a drive's own feedback).
    pub stand: Stand,
}

impl Row {
    /// A row of the seed's columns (no stand measurements).
    pub const fn new(ts_local: f64, sample: Sample) -> Row {
        Row {
            ts_local,
            sample,
            stand: Stand::NONE,
        }
    }
}

/// The header `propid` writes by default: the seed driver's columns plus `position`.
pub const HEADER: [&str; 6] = [
    "ts_local",
    "t",
    "force",
    "velocity",
    "acceleration",
    "position",
];

/// Number of columns the reader knows ([`COLUMNS`]).
pub const SLOTS: usize = 10;

/// Every column the reader knows, by slot: [`HEADER`], then the stand columns.
pub const COLUMNS: [&str; SLOTS] = [
    "ts_local",
    "t",
    "force",
    "velocity",
    "acceleration",
    "position",
    "thrust",
    "voltage",
    "current",
    "command",
];

/// The values of one line, by slot of [`COLUMNS`] (NaN where empty or absent).
pub type Values = [f64; SLOTS];

/// Where the columns are in a row, found from the header: the byte-level row parser behind
/// [`TsvReader`], also usable on a memory-mapped file split among threads (lines are
/// independent).
#[derive(Clone, Debug)]
pub struct Layout {
    /// Field index of each column of [`COLUMNS`] in the file.
    idx: [Option<usize>; SLOTS],
    /// For each field index up to the last used one, the slot it fills (`NONE` if unused).
    slot_of: Vec<u8>,
}

const NONE: u8 = u8::MAX;

/// Why one row could not be parsed (the caller adds the file and line: [`RowError::at`]).
#[derive(Clone, Debug, PartialEq)]
pub enum RowError {
    /// A used field is not a number.
    NotANumber {
        /// Slot in [`COLUMNS`].
        slot: usize,
        /// The offending text (shortened).
        text: String,
    },
    /// The line is longer than [`MAX_LINE`] bytes.
    LineTooLong,
    /// The row ends before a required column.
    ShortRow {
        /// Slot in [`COLUMNS`].
        slot: usize,
        /// Fields present.
        found: usize,
        /// 1-based index of the column.
        needed: usize,
    },
}

impl RowError {
    /// The error with its place.
    pub fn at(self, source_name: &str, line: u64) -> InputError {
        let e = match self {
            RowError::NotANumber { slot, text } => {
                InputError::new(ErrorKind::NotANumber { text }).in_column(COLUMNS[slot])
            }
            RowError::LineTooLong => InputError::new(ErrorKind::LineTooLong { limit: MAX_LINE }),
            RowError::ShortRow {
                slot,
                found,
                needed,
            } => InputError::new(ErrorKind::ShortRow { found, needed }).in_column(COLUMNS[slot]),
        };
        e.in_file(source_name).at_line(line)
    }
}

/// The longest line a reader accepts [bytes]: a row of a log is a few hundred bytes, so a longer
/// "line" is another kind of file, and reading it whole could take any amount of memory.
pub const MAX_LINE: usize = 64 << 10;

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

/// Every slot of [`COLUMNS`], for [`Layout::parse_line_converting`].
pub const ALL_SLOTS: u16 = (1 << SLOTS) - 1;

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
    fn new(idx: [Option<usize>; SLOTS]) -> Self {
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

    /// Parses one line (without its `\n`) into the values of [`COLUMNS`] (NaN where empty or
    /// absent); `None` for a blank line.
    pub fn parse_line(&self, line: &[u8]) -> Result<Option<Values>, RowError> {
        self.parse_line_converting(line, ALL_SLOTS)
    }

    /// [`Layout::parse_line`], converting only the slots whose bit (`1 << slot`, slots in
    /// [`COLUMNS`] order) is set in `convert`. The other fields are checked all the same (the
    /// same text is the same error) and read as `0.0` when they are a plain decimal number
    /// (`-?[0-9]+(.[0-9]+)?`, at most 300 bytes: always finite), without the cost of a float
    /// conversion; any other text is converted as `parse_line` does. So in every slot
    /// `is_finite()` is what `parse_line` gives, and the converted slots hold its exact values.
    #[inline]
    pub fn parse_line_converting(
        &self,
        line: &[u8],
        convert: u16,
    ) -> Result<Option<Values>, RowError> {
        let line = strip_cr(line);
        if line.first().is_none_or(|b| is_space(*b) || *b >= 0x80) && Self::is_blank(line) {
            return Ok(None);
        }
        if line.len() > MAX_LINE {
            return Err(RowError::LineTooLong);
        }
        let mut values = [f64::NAN; SLOTS];
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

/// A row from the values of [`Layout::parse_line`].
pub fn row_of(v: &Values) -> Row {
    Row {
        ts_local: v[0],
        sample: Sample {
            t: v[1],
            force: v[2],
            velocity: v[3],
            acceleration: v[4],
            position: v[5],
        },
        stand: Stand {
            thrust: v[6],
            voltage: v[7],
            current: v[8],
            command: v[9],
        },
    }
}

/// Streams rows from a TSV in constant memory: lines longer than [`MAX_LINE`] are an error
/// (never read whole), a compressed or binary input is named as such, and a last line without a
/// line end — a file cut while it was written — is not used but reported
/// ([`TsvReader::truncated_line`]).
pub struct TsvReader<R> {
    input: R,
    source_name: String,
    line_no: u64,
    line: Vec<u8>,
    layout: Layout,
    bytes_read: u64,
    truncated: Option<u64>,
    previous_t: f64,
    repeated_times: u64,
    first_repeated_time: Option<u64>,
}

/// Reads one line into `buf` (its `\n` included if it has one), at most `limit` bytes of it:
/// `Ok(None)` at the end of the input, `Ok(Some(false))` for a line longer than `limit` (the
/// bytes beyond it are not read).
fn read_line_bounded<R: BufRead>(
    input: &mut R,
    buf: &mut Vec<u8>,
    limit: usize,
) -> std::io::Result<Option<bool>> {
    buf.clear();
    loop {
        let available = match input.fill_buf() {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if available.is_empty() {
            return Ok((!buf.is_empty()).then_some(true));
        }
        let (take, done) = match memchr::memchr(b'\n', available) {
            Some(i) => (i + 1, true),
            None => (available.len(), false),
        };
        if buf.len() + take > limit + 2 {
            // Room for a `\r\n` after `limit` bytes of text.
            let room = (limit + 2).saturating_sub(buf.len());
            buf.extend_from_slice(&available[..room.min(take)]);
            input.consume(room.min(take));
            return Ok(Some(false));
        }
        buf.extend_from_slice(&available[..take]);
        input.consume(take);
        if done {
            return Ok(Some(true));
        }
    }
}

/// Why the first bytes of a TSV are not its header: compressed, or not text.
fn not_text(head: &[u8]) -> Option<ErrorKind> {
    if let Some(c) = Compression::sniff(head) {
        return Some(ErrorKind::Compressed(c));
    }
    // A multi-byte character cut by the end of `head` is not an error (`error_len` is None).
    let invalid = std::str::from_utf8(head).is_err_and(|e| e.error_len().is_some());
    (head.contains(&0) || invalid).then_some(ErrorKind::NotText)
}

impl<R: BufRead> TsvReader<R> {
    /// Reads the header. `source_name` is used in error messages (file path or `<stdin>`).
    pub fn new(mut input: R, source_name: impl Into<String>) -> Result<Self, InputError> {
        let source_name = source_name.into();
        let at = |kind: ErrorKind| {
            InputError::new(kind)
                .in_file(source_name.clone())
                .at_line(1)
        };
        let mut header = Vec::new();
        let read = read_line_bounded(&mut input, &mut header, MAX_LINE)
            .map_err(|e| InputError::os(source_name.clone(), "cannot read", &e).at_line(1))?;
        if let Some(kind) = not_text(&header[..header.len().min(64)]) {
            return Err(at(kind));
        }
        match read {
            None => return Err(InputError::new(ErrorKind::Empty).in_file(source_name)),
            Some(false) => return Err(at(ErrorKind::LineTooLong { limit: MAX_LINE })),
            Some(true) => {}
        }
        let Ok(header_text) = std::str::from_utf8(&header) else {
            return Err(at(ErrorKind::NotText));
        };
        let header_trimmed = header_text
            .trim_end_matches(['\r', '\n'])
            .trim_start_matches('\u{feff}');
        if header_trimmed.trim().is_empty() {
            let mut e = at(ErrorKind::Empty);
            e.place.line = None;
            return Err(e);
        }
        let names: Vec<&str> = header_trimmed.split('\t').map(str::trim).collect();
        let mut idx = [None; SLOTS];
        for (slot, want) in idx.iter_mut().zip(COLUMNS) {
            *slot = names.iter().position(|n| *n == want);
        }
        for (i, want) in COLUMNS.iter().enumerate().take(5).skip(1) {
            if idx[i].is_none() {
                if let Some(importer) = crate::header::recognise(header_trimmed) {
                    return Err(at(ErrorKind::ForeignFormat(importer)));
                }
                return Err(at(ErrorKind::MissingColumn {
                    wanted: (*want).into(),
                    columns: shorten_list(&names),
                }));
            }
        }
        Ok(TsvReader {
            input,
            source_name,
            line_no: 1,
            line: Vec::new(),
            layout: Layout::new(idx),
            bytes_read: header.len() as u64,
            truncated: None,
            previous_t: f64::NAN,
            repeated_times: 0,
            first_repeated_time: None,
        })
    }

    /// True if the file has a `position` column.
    pub fn has_position(&self) -> bool {
        self.layout.idx[5].is_some()
    }

    /// True if the file has this stand column.
    pub fn has(&self, column: StandColumn) -> bool {
        self.layout.idx[column.slot()].is_some()
    }

    /// The stand columns the file has, in [`StandColumn::ALL`] order.
    pub fn stand_columns(&self) -> Vec<StandColumn> {
        StandColumn::ALL
            .into_iter()
            .filter(|c| self.has(*c))
            .collect()
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

    /// The line that ended the input without a line end, if any: a file cut while it was
    /// written (its last number may be cut short), so it was not returned as a row. Known once
    /// [`TsvReader::next_row`] has returned `None`.
    pub fn truncated_line(&self) -> Option<u64> {
        self.truncated
    }

    /// Rows whose time `t` equals the previous row's, and the line of the first: a log written
    /// twice, or rows duplicated, which make every standard error too small.
    pub fn repeated_times(&self) -> (u64, Option<u64>) {
        (self.repeated_times, self.first_repeated_time)
    }

    /// The next row, `None` at the end. Blank lines are skipped.
    pub fn next_row(&mut self) -> Result<Option<Row>, InputError> {
        loop {
            let read =
                read_line_bounded(&mut self.input, &mut self.line, MAX_LINE).map_err(|e| {
                    InputError::os(self.source_name.clone(), "cannot read", &e)
                        .at_line(self.line_no + 1)
                })?;
            let Some(terminated) = read else {
                return Ok(None);
            };
            self.bytes_read += self.line.len() as u64;
            self.line_no += 1;
            if !terminated {
                return Err(RowError::LineTooLong.at(&self.source_name, self.line_no));
            }
            let (line, ends) = match self.line.strip_suffix(b"\n") {
                Some(l) => (l, true),
                None => (&self.line[..], false),
            };
            match self.layout.parse_line(line) {
                Ok(None) => continue,
                Ok(Some(_)) if !ends => {
                    self.truncated = Some(self.line_no);
                    return Ok(None);
                }
                Ok(Some(v)) => {
                    let t = v[1];
                    if t == self.previous_t {
                        self.repeated_times += 1;
                        self.first_repeated_time.get_or_insert(self.line_no);
                    }
                    self.previous_t = t;
                    return Ok(Some(row_of(&v)));
                }
                // A cut last line may be cut inside a number or before a column: it is
                // reported as cut, not as a bad field.
                Err(_) if !ends => {
                    self.truncated = Some(self.line_no);
                    return Ok(None);
                }
                Err(e) => return Err(e.at(&self.source_name, self.line_no)),
            }
        }
    }
}

/// A whole TSV read into memory, with what the reader noticed on the way.
pub struct Table {
    /// The file's name for messages (`<stdin>` for `-`).
    pub name: String,
    /// The rows kept.
    pub rows: Vec<Row>,
    /// Rows read but not kept (see [`read_rows`]).
    pub skipped: usize,
    /// The stand columns the file has.
    pub stand_columns: Vec<StandColumn>,
    /// The last line, cut without a line end, that was not used ([`TsvReader::truncated_line`]).
    pub truncated_line: Option<u64>,
    /// Rows repeating the previous row's time, and the first's line
    /// ([`TsvReader::repeated_times`]).
    pub repeated_times: (u64, Option<u64>),
}

impl Table {
    /// What a command should tell its user about the file, one sentence each: a cut last line,
    /// repeated times.
    pub fn notes(&self) -> Vec<String> {
        let mut notes = Vec::new();
        if let Some(line) = self.truncated_line {
            notes.push(cut_line_note(&self.name, line));
        }
        if let (n @ 1.., Some(first)) = self.repeated_times {
            notes.push(format!(
                "{}: {n} rows repeat the previous row's time (the first at line {first}): duplicated rows count twice and make every standard error too small (by √2 when every row is doubled); remove them if they are copies",
                self.name
            ));
        }
        notes
    }
}

/// What to tell a user about `n` rows that are copies of the row before them (the first at
/// `first`).
pub fn copies_note(name: &str, n: u64, first: u64) -> String {
    format!(
        "{name}: {n} rows are copies of the row before them (the first at line {first}): each copy counts as another measurement, which makes every standard error too small (by √2 when every row is doubled); remove them if the log was written twice"
    )
}

/// What to tell a user about a last line cut without a line end ([`TsvReader::truncated_line`]).
pub fn cut_line_note(name: &str, line: u64) -> String {
    format!(
        "{name}: line {line} has no line end (the file was cut while it was written, perhaps inside a number): that line is not used"
    )
}

/// `data` without its last line if that line has no line end and is a row (not blank), and
/// whether it was cut off; lines before `from` (the header) and lines longer than [`MAX_LINE`]
/// (an error wherever they are) are never cut. The same rule as
/// [`TsvReader`]'s, for readers of a whole file in memory.
pub fn without_cut_line(data: &[u8], from: usize) -> (&[u8], bool) {
    if data.len() <= from || data.last() == Some(&b'\n') {
        return (data, false);
    }
    let start = memchr::memrchr(b'\n', &data[from..]).map_or(from, |i| from + i + 1);
    // A line past the bound is that error, whether it ends or not.
    if data.len() - start <= MAX_LINE && Layout::is_row(&data[start..]) {
        (&data[..start], true)
    } else {
        (data, false)
    }
}

/// Reads the TSV at `path` ([`crate::input::open`]: `-` is standard input, gzip is read
/// through, lines are bounded) and keeps the rows for which `keep` is true.
pub fn read_rows(path: &std::path::Path, keep: impl Fn(&Row) -> bool) -> Result<Table, InputError> {
    let input = crate::input::open(path)?;
    let name = input.name().to_owned();
    let mut reader = TsvReader::new(input, name.clone())?;
    let (mut rows, mut skipped) = (Vec::new(), 0);
    while let Some(row) = reader.next_row()? {
        if keep(&row) {
            rows.push(row);
        } else {
            skipped += 1;
        }
    }
    Ok(Table {
        name,
        rows,
        skipped,
        stand_columns: reader.stand_columns(),
        truncated_line: reader.truncated_line(),
        repeated_times: reader.repeated_times(),
    })
}

/// The names joined with `, `, shortened to about 200 characters (a header can be anything).
fn shorten_list(names: &[&str]) -> String {
    let mut out = String::new();
    for (k, name) in names.iter().enumerate() {
        if out.len() + name.len() > 200 {
            out += &format!(", … ({} more)", names.len() - k);
            break;
        }
        if k > 0 {
            out += ", ";
        }
        out.extend(name.chars().take(40));
    }
    out
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
    stand: Vec<StandColumn>,
    extra_columns: usize,
    line: String,
}

impl<W: Write> TsvWriter<W> {
    /// Writes the header line of the seed's columns ([`HEADER`]).
    pub fn new(out: W, flush_each_row: bool) -> std::io::Result<Self> {
        Self::with_columns(out, flush_each_row, &[], &[])
    }

    /// Writes the header line: [`HEADER`], the `stand` columns (in the order given), then
    /// `extra` named columns (for example an importer's `electrical_power`; readers ignore
    /// columns they do not know). Rows with extra values go through [`TsvWriter::write_with`].
    pub fn with_columns(
        mut out: W,
        flush_each_row: bool,
        stand: &[StandColumn],
        extra: &[&str],
    ) -> std::io::Result<Self> {
        let mut header = HEADER.join("\t");
        for name in stand.iter().map(|c| c.name()).chain(extra.iter().copied()) {
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
            stand: stand.to_vec(),
            extra_columns: extra.len(),
            line: String::with_capacity(128),
        })
    }

    /// Writes one row (NaN in any extra column). NaN is written as `nan` (the seed's Python
    /// prints the same).
    pub fn write(&mut self, row: &Row) -> std::io::Result<()> {
        self.write_with(row, &[])
    }

    /// Writes one row and the values of the extra columns (NaN where one is missing).
    pub fn write_with(&mut self, row: &Row, extra: &[f64]) -> std::io::Result<()> {
        use std::fmt::Write as _;
        let s = &row.sample;
        let fields = [
            row.ts_local,
            s.t,
            s.force,
            s.velocity,
            s.acceleration,
            s.position,
        ];
        let stand = self.stand.iter().map(|c| row.stand.get(*c));
        let extra = (0..self.extra_columns).map(|k| extra.get(k).copied().unwrap_or(f64::NAN));
        let line = &mut self.line;
        line.clear();
        for (i, v) in fields.into_iter().chain(stand).chain(extra).enumerate() {
            if i > 0 {
                line.push('\t');
            }
            if v.is_nan() {
                line.push_str("nan");
            } else {
                // Writing into a String cannot fail.
                let _ = write!(line, "{v}");
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
            let line = format!("t\tforce\tvelocity\tacceleration\n{c}\t2\t{c}\t{c}\n");
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
                (
                    None,
                    Err(InputError {
                        kind: ErrorKind::NotANumber { .. },
                        ..
                    }),
                ) => {}
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
                for convert in [0u16, 0b1_1100, 0b10_0001, ALL_SLOTS] {
                    let part = layout.parse_line_converting(text.as_bytes(), convert);
                    match (&full, &part) {
                        (Ok(Some(a)), Ok(Some(b))) => {
                            for slot in 0..SLOTS {
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
        let text =
            "t\tforce\tvelocity\tacceleration\r\n1\t2\t3\t4\r\n \t \r\n\u{a0}\n5\t6\t7\t8\r\n";
        let mut r = TsvReader::new(text.as_bytes(), "mem").unwrap();
        assert_eq!(r.next_row().unwrap().unwrap().sample.acceleration, 4.0);
        assert_eq!(r.next_row().unwrap().unwrap().sample.t, 5.0);
        assert_eq!(r.line_number(), 5);
        assert!(r.next_row().unwrap().is_none());
        assert_eq!(r.truncated_line(), None);
    }

    /// A last line without a line end was cut while the file was written: not a row, reported
    /// (whether it still parses or was cut inside a number or before a column); a blank one is
    /// nothing.
    #[test]
    fn a_cut_last_line_is_reported_not_used() {
        for last in ["5\t6\t7\t8", "5\t6\t7\t8.2e", "5\t6\t7", "5\t6\t7\t8\r"] {
            let text = format!("t\tforce\tvelocity\tacceleration\n1\t2\t3\t4\n{last}");
            let mut r = TsvReader::new(text.as_bytes(), "mem").unwrap();
            assert_eq!(r.next_row().unwrap().unwrap().sample.t, 1.0);
            assert!(r.next_row().unwrap().is_none(), "{last:?}");
            assert_eq!(r.truncated_line(), Some(3), "{last:?}");
        }
        let text = "t\tforce\tvelocity\tacceleration\n1\t2\t3\t4\n \t";
        let mut r = TsvReader::new(text.as_bytes(), "mem").unwrap();
        assert!(r.next_row().unwrap().is_some());
        assert!(r.next_row().unwrap().is_none());
        assert_eq!(r.truncated_line(), None);
    }

    /// A line longer than MAX_LINE is an error naming it, read no further than the bound; the
    /// header likewise; compressed and binary input is named as such.
    #[test]
    fn long_lines_compressed_and_binary_input() {
        struct Endless(u8);
        impl std::io::Read for Endless {
            fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
                buf.fill(self.0);
                Ok(buf.len())
            }
        }
        let e = TsvReader::new(std::io::BufReader::new(Endless(b'7')), "<stdin>")
            .err()
            .unwrap();
        assert_eq!(e.kind, ErrorKind::LineTooLong { limit: MAX_LINE });
        assert_eq!(e.place.line, Some(1));
        assert!(e
            .to_string()
            .starts_with("<stdin>: line 1: the line is longer than 64 KiB"));
        let e = TsvReader::new(std::io::BufReader::new(Endless(0)), "<stdin>")
            .err()
            .unwrap();
        assert_eq!(e.kind, ErrorKind::NotText, "{e}");
        let head = "t\tforce\tvelocity\tacceleration\n1\t2\t3\t4\n";
        let input = std::io::Read::chain(head.as_bytes(), Endless(b'1'));
        let mut r = TsvReader::new(std::io::BufReader::new(input), "big.tsv").unwrap();
        assert!(r.next_row().unwrap().is_some());
        let e = r.next_row().err().unwrap();
        assert_eq!(
            (e.kind.clone(), e.place.line),
            (ErrorKind::LineTooLong { limit: MAX_LINE }, Some(3))
        );
        assert!(r.line.len() <= MAX_LINE + 2);
        let e = TsvReader::new(&[0x1f, 0x8b, 8, 0, 0, 0][..], "run.tsv.gz")
            .err()
            .unwrap();
        assert_eq!(e.kind, ErrorKind::Compressed(Compression::Gzip));
        assert_eq!(e.place.file.as_deref(), Some("run.tsv.gz"));
        // A header cut inside a multi-byte character at 64 bytes is still text.
        let header = format!("{}µ\tt\tforce\tvelocity\tacceleration\n", "x".repeat(63));
        assert!(TsvReader::new(header.as_bytes(), "m").is_ok());
    }

    /// Rows repeating the previous row's time are counted (a log written twice).
    #[test]
    fn repeated_times_are_counted() {
        let text = "t\tforce\tvelocity\tacceleration\n1\t2\t3\t4\n1\t2\t3\t4\n2\t2\t3\t4\n2\t2\t3\t4\n3\t0\t0\t0\n";
        let mut r = TsvReader::new(text.as_bytes(), "m").unwrap();
        while r.next_row().unwrap().is_some() {}
        assert_eq!(r.repeated_times(), (2, Some(3)));
    }

    #[test]
    fn round_trip_and_errors() {
        let row = Row::new(
            1.5,
            Sample {
                t: 0.25,
                force: -0.125,
                velocity: 300.0,
                acceleration: f64::NAN,
                position: 1e-7,
            },
        );
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
            err.to_string().contains("no column `acceleration`"),
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
            Err(InputError {
                kind: ErrorKind::Empty,
                ..
            })
        ));
    }

    /// The stand columns: written when asked for, in the order asked, read by name wherever
    /// they are, NaN where absent; the seed's columns and extra columns stay where they were.
    #[test]
    fn stand_columns_round_trip() {
        let mut row = Row::new(
            f64::NAN,
            Sample {
                t: 1.0,
                force: 0.1,
                velocity: 200.0,
                acceleration: 3.0,
                position: f64::NAN,
            },
        );
        row.stand = Stand {
            thrust: 4.5,
            voltage: 16.0,
            current: f64::NAN,
            command: 0.25,
        };
        let columns = [
            StandColumn::Command,
            StandColumn::Thrust,
            StandColumn::Voltage,
        ];
        let mut w = TsvWriter::with_columns(Vec::new(), false, &columns, &["power"]).unwrap();
        w.write_with(&row, &[7.0]).unwrap();
        let text = String::from_utf8(w.into_inner().unwrap()).unwrap();
        assert_eq!(
            text,
            "ts_local\tt\tforce\tvelocity\tacceleration\tposition\tcommand\tthrust\tvoltage\tpower\n\
             nan\t1\t0.1\t200\t3\tnan\t0.25\t4.5\t16\t7\n"
        );
        let mut r = TsvReader::new(text.as_bytes(), "mem").unwrap();
        assert_eq!(
            r.stand_columns(),
            [
                StandColumn::Thrust,
                StandColumn::Voltage,
                StandColumn::Command
            ]
        );
        assert!(!r.has(StandColumn::Current));
        let back = r.next_row().unwrap().unwrap();
        let s = back.sample;
        assert_eq!(
            (s.t, s.force, s.velocity, s.acceleration),
            (1.0, 0.1, 200.0, 3.0)
        );
        assert!(s.position.is_nan());
        assert_eq!(
            (back.stand.thrust, back.stand.voltage, back.stand.command),
            (4.5, 16.0, 0.25)
        );
        assert!(back.stand.current.is_nan());
        // A file of the seed's columns only: every stand value NaN.
        let mut r = TsvReader::new(
            "t\tforce\tvelocity\tacceleration\n1\t2\t3\t4\n".as_bytes(),
            "m",
        )
        .unwrap();
        assert!(r.stand_columns().is_empty());
        let back = r.next_row().unwrap().unwrap();
        assert!(StandColumn::ALL.iter().all(|c| back.stand.get(*c).is_nan()));
        // A stand column that is not a number is named.
        let mut r = TsvReader::new(
            "t\tforce\tvelocity\tacceleration\tthrust\n1\t2\t3\t4\t5 gf\n".as_bytes(),
            "m.tsv",
        )
        .unwrap();
        let e = r.next_row().err().unwrap().to_string();
        assert!(
            e.contains("line 2") && e.contains("`thrust`") && e.contains("5 gf"),
            "{e}"
        );
    }
}
