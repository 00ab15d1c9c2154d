//! Importers: measured logs from other test stands into propid's TSV.
//!
//! ```text
//!  AutoQuad ESC32 telemetry (CSV)  ─► t = row × (fitted row interval), ω = rpm·2π/60, Q = Kt·I_bus/duty ─┐
//!  RCbenchmark / Tyto log (CSV)    ─► t, ω = rpm·2π/60 (optical or electrical), Q = load-cell torque    ─┴─► TSV
//!                                     acceleration = central difference of ω; command kept as a column
//! ```
//! Importers convert units and report what they measured and assumed (in
//! [`Imported::assumptions`], which the command prints): how often each signal really updates,
//! the torque's sign convention (at steady speed drag opposes rotation), the torque seen at zero
//! speed (a zero offset, reported and subtracted only when asked), the time base. No message
//! states a fact of one particular data set: every figure in them is computed from the file.
//! They never smooth, shift or filter a signal, so what `diagnose` finds is in the data. The one
//! derived column is the acceleration, a plain central difference of the measured velocity
//! ((ω[k+1] − ω[k−1]) / (t[k+1] − t[k−1])), because neither stand logs one. What else the stand
//! measured is kept in the TSV's stand columns ([`crate::tsv::Stand`]): thrust (converted to N
//! from the unit its header names), DC bus voltage and current, and the command the stand gave
//! (ESC signal, duty) as a ratio 0–1 — the input is evidence too. Other measured columns worth
//! keeping (the stand's electrical and mechanical power, the raw ESC signal in µs) become extra
//! TSV columns ([`Imported::extra`]). Each kept column's update rate is measured and reported.
//!
//! Bad input is an [`InputError`] naming the file, the line and the column: a field that is not
//! a number, or a row too short to have the column at all. An empty field is a missing sample
//! (NaN): stands log sensors at different rates and leave the others empty.

mod autoquad;
mod rcbench;

use std::path::Path;

use crate::error::Importer;
use crate::input::LineLimit;
use crate::tsv::{Row, StandColumn, TsvWriter};
use crate::{ErrorKind, InputError};

pub use autoquad::{import_autoquad, read_autoquad};
pub use rcbench::{import_rcbench, read_rcbench, RcbenchOptions};

/// An imported recording: the rows, what the stand measured beside them and what was measured
/// and assumed.
pub struct Imported {
    /// Rows in time order, with [`Row::stand`] filled from the log's thrust, voltage, current and
    /// command columns (NaN where not logged).
    pub rows: Vec<Row>,
    /// The stand columns the log has (written to the TSV), in [`StandColumn::ALL`] order. Their
    /// units and conversions are stated in [`Imported::assumptions`].
    pub stand_columns: Vec<StandColumn>,
    /// Other measured columns kept as extra TSV columns, one value per row.
    pub extra: Vec<ExtraColumn>,
    /// Measurements, assumptions and conversions, one sentence each.
    pub assumptions: Vec<String>,
}

/// A column an importer keeps beyond the TSV's known ones (readers ignore it).
pub struct ExtraColumn {
    /// The TSV header name (`electrical_power`, …), with its unit in the name or the
    /// importer's assumptions.
    pub name: &'static str,
    /// One value per row (NaN where not logged).
    pub values: Vec<f64>,
}

impl Imported {
    /// The values of one stand column, one per row.
    pub fn stand(&self, column: StandColumn) -> Vec<f64> {
        self.rows.iter().map(|r| r.stand.get(column)).collect()
    }
}

/// Fills the acceleration column with the central difference of the velocity (one-sided at the
/// ends); NaN where a neighbour is missing.
pub(crate) fn differentiate(rows: &mut [Row]) {
    let n = rows.len();
    let vel: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| (r.sample.t, r.sample.velocity))
        .collect();
    for (k, row) in rows.iter_mut().enumerate() {
        let (lo, hi) = (k.saturating_sub(1), (k + 1).min(n - 1));
        let dt = vel[hi].0 - vel[lo].0;
        row.sample.acceleration = if dt > 0.0 {
            (vel[hi].1 - vel[lo].1) / dt
        } else {
            f64::NAN
        };
    }
}

/// How often a signal really updates: the samples present and the median interval between
/// consecutive changes of value. `None` for the interval when it never changes twice.
pub(crate) struct UpdateRate {
    /// Rows where the signal has a value.
    pub present: usize,
    /// Median time between changes of value [s].
    pub interval: Option<f64>,
}

impl UpdateRate {
    pub(crate) fn measure(samples: impl Iterator<Item = (f64, f64)>) -> UpdateRate {
        let mut present = 0;
        let mut last: Option<(f64, f64)> = None;
        let mut intervals = Vec::new();
        for (t, v) in samples {
            if !v.is_finite() {
                continue;
            }
            present += 1;
            match last {
                Some((_, lv)) if lv == v => {}
                Some((lt, _)) => {
                    intervals.push(t - lt);
                    last = Some((t, v));
                }
                None => last = Some((t, v)),
            }
        }
        UpdateRate {
            present,
            interval: median(&mut intervals),
        }
    }

    /// "updates at 44.8 Hz (median interval 22.3 ms), in 812 of 4814 rows (17 %)".
    pub(crate) fn describe(&self, rows: usize) -> String {
        let share = format!(
            "{} of {rows} rows ({:.0} %)",
            self.present,
            100.0 * self.present as f64 / rows.max(1) as f64
        );
        match self.interval {
            Some(dt) if dt > 0.0 => format!(
                "updates at {:.3} Hz (median interval between changes {:.1} ms), present in {share}",
                1.0 / dt,
                dt * 1e3
            ),
            _ => format!("never changes value; present in {share}"),
        }
    }
}

/// The median (NaN-free input), `None` when empty.
pub(crate) fn median(x: &mut [f64]) -> Option<f64> {
    if x.is_empty() {
        return None;
    }
    x.sort_by(f64::total_cmp);
    let n = x.len();
    Some(if n % 2 == 1 {
        x[n / 2]
    } else {
        0.5 * (x[n / 2 - 1] + x[n / 2])
    })
}

/// Mean and sample standard deviation.
pub(crate) fn mean_sd(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let var = x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (m, var.sqrt())
}

/// A CSV reader over some input, its header line, and the input's name for messages.
pub(crate) type Csv<'a> = (
    csv::Reader<LineLimit<Box<dyn std::io::Read + 'a>>>,
    csv::StringRecord,
    String,
);

/// Opens a CSV log ([`crate::input::open`]: gzip read through, lines bounded, OS errors with the
/// path): the reader, its header and the file name for messages.
pub(crate) fn open_csv(path: &Path) -> Result<Csv<'static>, InputError> {
    let input = crate::input::open(path)?;
    let name = input.name().to_owned();
    csv_reader(Box::new(input), name)
}

/// A CSV reader over any input (named `name` in messages), with its header; lines bounded.
pub(crate) fn csv_reader(
    input: Box<dyn std::io::Read + '_>,
    name: String,
) -> Result<Csv<'_>, InputError> {
    let mut reader = csv::ReaderBuilder::new()
        .flexible(true)
        .from_reader(LineLimit::new(input));
    let headers = reader
        .headers()
        .map_err(|e| csv_error(&name, &e, 1))?
        .clone();
    Ok((reader, headers, name))
}

/// A CSV reader's error at `line` of `name`, typed.
pub(crate) fn csv_error(name: &str, e: &csv::Error, line: u64) -> InputError {
    match e.kind() {
        csv::ErrorKind::Io(io) => crate::input::error_of(name, io, line),
        csv::ErrorKind::Utf8 { .. } => InputError::new(ErrorKind::NotText)
            .in_file(name)
            .at_line(line),
        _ => InputError::invalid(e.to_string())
            .in_file(name)
            .at_line(line),
    }
}

/// The importer for a file whose first line is `header`, when it is a stand's own export (what a
/// TSV reader tells a user who gave it one).
pub fn recognise(header: &str) -> Option<Importer> {
    let names: Vec<String> = header.split(',').map(loose).collect();
    if names.len() < 3 {
        return None;
    }
    let has = |n: &str| names.iter().any(|h| *h == loose(n));
    let starts = |n: &str| names.iter().any(|h| h.starts_with(&loose(n)));
    if has("Timestamp") && has("Amps") && has("RPM") && has("Duty") {
        Some(Importer::Autoquad)
    } else if (starts("Time (") || has("Time")) && (starts("Torque (") || starts("Thrust (")) {
        Some(Importer::Rcbench)
    } else {
        None
    }
}

/// A header name compared loosely: no byte-order mark, lower case, `µ`/`μ` as `u`, and no
/// spaces, `·`, `-` or `.` (so `Torque (N·m)`, `Torque (N-m)` and `torque (Nm)` are one name).
pub(crate) fn loose(name: &str) -> String {
    name.trim_start_matches('\u{feff}')
        .to_lowercase()
        .replace(['µ', 'μ'], "u")
        .chars()
        .filter(|c| !matches!(c, ' ' | '·' | '-' | '.' | '\u{22c5}'))
        .collect()
}

/// The first of `names` (compared loosely) that the header has: its index and the header's own
/// spelling.
pub(crate) fn find_column(headers: &csv::StringRecord, names: &[&str]) -> Option<(usize, String)> {
    names.iter().find_map(|name| {
        let want = loose(name);
        headers.iter().position(|h| loose(h) == want).map(|i| {
            (
                i,
                headers[i].trim_start_matches('\u{feff}').trim().to_owned(),
            )
        })
    })
}

/// Finds a column by name (see [`find_column`]) or says which columns the file has.
pub(crate) fn column(
    headers: &csv::StringRecord,
    names: &[&str],
    file: &str,
) -> Result<(usize, String), InputError> {
    find_column(headers, names).ok_or_else(|| {
        InputError::new(ErrorKind::MissingColumn {
            wanted: names.join("` or `"),
            columns: headers
                .iter()
                .map(|h| h.trim_start_matches('\u{feff}'))
                .collect::<Vec<_>>()
                .join(", "),
        })
        .in_file(file)
        .at_line(1)
    })
}

/// Parses a CSV field: a number, or NaN when empty. A row too short to have the field is an
/// error, like a field that is not a number.
pub(crate) fn number(
    record: &csv::StringRecord,
    index: usize,
    name: &str,
    file: &str,
    line: u64,
) -> Result<f64, InputError> {
    let at = |kind| {
        InputError::new(kind)
            .in_file(file)
            .at_line(line)
            .in_column(name)
    };
    let Some(text) = record.get(index) else {
        return Err(at(ErrorKind::ShortRow {
            found: record.len(),
            needed: index + 1,
        }));
    };
    let text = text.trim();
    if text.is_empty() {
        return Ok(f64::NAN);
    }
    text.parse().map_err(|_| {
        at(ErrorKind::NotANumber {
            text: text.chars().take(40).collect(),
        })
    })
}

/// Writes an imported recording as propid's TSV: the seed's columns, the stand columns the log
/// has, then the extra columns.
pub fn write_tsv<W: std::io::Write>(imported: &Imported, out: W) -> std::io::Result<W> {
    let names: Vec<&str> = imported.extra.iter().map(|c| c.name).collect();
    let mut w = TsvWriter::with_columns(out, false, &imported.stand_columns, &names)?;
    let mut extra = vec![f64::NAN; names.len()];
    for (k, r) in imported.rows.iter().enumerate() {
        for (v, c) in extra.iter_mut().zip(&imported.extra) {
            *v = c.values.get(k).copied().unwrap_or(f64::NAN);
        }
        w.write_with(r, &extra)?;
    }
    w.into_inner()
}
