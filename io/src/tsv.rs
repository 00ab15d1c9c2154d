//! The TSV currency: every producer of samples (drive, replay, sim, importers) writes it and every
//! consumer (fit, diagnose, plot) reads it.
//!
//! Columns, by header name (order free, extra columns ignored):
//! `ts_local` (host receive time, s, optional), `t` (device time, s), `force` (N·m), `velocity`
//! (rad/s), `acceleration` (rad/s²), `position` (rad, optional). This is the seed driver's output
//! plus `position`. Empty fields and `nan` read as NaN (the seed's pandas does the same).

use std::io::{BufRead, Write};

/// One measurement of the drive's dynamics feedback.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Device time [s].
    pub t: f64,
    /// Torque (the drive's estimate) [N·m].
    pub force: f64,
    /// Angular velocity [rad/s].
    pub velocity: f64,
    /// Angular acceleration [rad/s²].
    pub acceleration: f64,
    /// Rotor angle [rad], when the source has it (NaN otherwise).
    pub position: f64,
}

impl Sample {
    /// True if time, force, velocity and acceleration are all finite (position may be NaN).
    pub fn is_finite(&self) -> bool {
        self.t.is_finite()
            && self.force.is_finite()
            && self.velocity.is_finite()
            && self.acceleration.is_finite()
    }
}

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

/// Streams rows from a TSV in constant memory.
pub struct TsvReader<R> {
    input: R,
    source_name: String,
    line_no: u64,
    line: String,
    /// Field indices of ts_local, t, force, velocity, acceleration, position.
    idx: [Option<usize>; 6],
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
            line: String::new(),
            idx,
            bytes_read: n as u64,
        })
    }

    /// True if the file has a `position` column.
    pub fn has_position(&self) -> bool {
        self.idx[5].is_some()
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
                .read_line(&mut self.line)
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
            let text = self.line.trim_end_matches(['\r', '\n']);
            if text.trim().is_empty() {
                continue;
            }
            let mut values = [f64::NAN; 6];
            let mut found = 0usize;
            for (field_index, field) in text.split('\t').enumerate() {
                found = field_index + 1;
                if let Some(slot) = self.idx.iter().position(|i| *i == Some(field_index)) {
                    values[slot] = parse_field(field).ok_or_else(|| TsvError::NotANumber {
                        source_name: self.source_name.clone(),
                        line: self.line_no,
                        column: HEADER[slot].to_string(),
                        text: field.chars().take(40).collect(),
                    })?;
                }
            }
            for (slot, name) in HEADER.iter().enumerate().take(5).skip(1) {
                let needed = self.idx[slot].unwrap_or(0) + 1;
                if needed > found {
                    return Err(TsvError::ShortRow {
                        source_name: self.source_name.clone(),
                        line: self.line_no,
                        column: (*name).to_string(),
                        found,
                        needed,
                    });
                }
            }
            return Ok(Some(Row {
                ts_local: values[0],
                sample: Sample {
                    t: values[1],
                    force: values[2],
                    velocity: values[3],
                    acceleration: values[4],
                    position: values[5],
                },
            }));
        }
    }
}

/// Parses one field: a float, `nan`/`inf` in any case, or empty (NaN).
fn parse_field(field: &str) -> Option<f64> {
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
}

impl<W: Write> TsvWriter<W> {
    /// Writes the header line.
    pub fn new(mut out: W, flush_each_row: bool) -> std::io::Result<Self> {
        writeln!(out, "{}", HEADER.join("\t"))?;
        if flush_each_row {
            out.flush()?;
        }
        Ok(TsvWriter {
            out,
            flush_each_row,
        })
    }

    /// Writes one row. NaN is written as `nan` (the seed's Python prints the same).
    pub fn write(&mut self, row: &Row) -> std::io::Result<()> {
        let s = &row.sample;
        let fields = [
            row.ts_local,
            s.t,
            s.force,
            s.velocity,
            s.acceleration,
            s.position,
        ];
        let mut line = String::with_capacity(96);
        for (i, v) in fields.iter().enumerate() {
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
