//! Importers: measured logs from other test stands into propid's TSV.
//!
//! ```text
//!  AutoQuad ESC32 telemetry (CSV) ─► t = row × 10 ms, ω = rpm·2π/60, Q = Kt·I_bus/duty ─┐
//!  RCbenchmark log (CSV)          ─► t, ω = rpm·2π/60, Q = load-cell torque (sparse)  ─┴─► TSV
//!                                    acceleration = central difference of ω (both)
//! ```
//! Importers convert units and say what they assume (in [`Imported::assumptions`], which the command prints). They
//! never smooth, shift or filter a signal, so what `diagnose` finds is in the data. The one
//! derived column is the acceleration, a plain central difference of the measured velocity
//! ((ω[k+1] − ω[k−1]) / (t[k+1] − t[k−1])), because neither stand logs one.

mod autoquad;
mod rcbench;

use std::path::Path;

use crate::tsv::{Row, TsvWriter};
use crate::InputError;

pub use autoquad::import_autoquad;
pub use rcbench::import_rcbench;

/// An imported recording: the rows and what was assumed.
pub struct Imported {
    /// Rows in time order.
    pub rows: Vec<Row>,
    /// Assumptions and conversions, one sentence each.
    pub assumptions: Vec<String>,
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

/// Opens a CSV log: the reader, its header and the file name for messages.
pub(crate) fn open_csv(
    path: &Path,
) -> Result<(csv::Reader<std::fs::File>, csv::StringRecord, String), InputError> {
    let file = path.display().to_string();
    let mut reader = csv::ReaderBuilder::new()
        .flexible(true)
        .from_path(path)
        .map_err(|e| InputError(format!("{file}: cannot open: {e}")))?;
    let headers = reader
        .headers()
        .map_err(|e| InputError(format!("{file}: line 1: {e}")))?
        .clone();
    Ok((reader, headers, file))
}

/// Finds a column by exact header name (a UTF-8 byte-order mark on the first is ignored).
pub(crate) fn column(
    headers: &csv::StringRecord,
    name: &str,
    file: &str,
) -> Result<usize, InputError> {
    headers
        .iter()
        .position(|h| h.trim_start_matches('\u{feff}').trim() == name)
        .ok_or_else(|| {
            InputError(format!(
                "{file}: line 1: no column `{name}` (columns: {})",
                headers
                    .iter()
                    .map(|h| h.trim_start_matches('\u{feff}'))
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })
}

/// Parses a CSV field: a number, or NaN when empty.
pub(crate) fn number(
    record: &csv::StringRecord,
    index: usize,
    name: &str,
    file: &str,
    line: u64,
) -> Result<f64, InputError> {
    let text = record.get(index).unwrap_or("").trim();
    if text.is_empty() {
        return Ok(f64::NAN);
    }
    text.parse().map_err(|_| {
        InputError(format!(
            "{file}: line {line}, column `{name}`: `{text}` is not a number"
        ))
    })
}

/// Writes an imported recording as propid's TSV.
pub fn write_tsv<W: std::io::Write>(imported: &Imported, out: W) -> std::io::Result<W> {
    let mut w = TsvWriter::new(out, false)?;
    for r in &imported.rows {
        w.write(r)?;
    }
    w.into_inner()
}
