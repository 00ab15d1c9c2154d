//! `propid import`: measured logs from other test stands into propid's TSV.
//!
//! ```text
//!  AutoQuad ESC32 telemetry (CSV) ─► t = row × 10 ms, ω = rpm·2π/60, Q = Kt·I_bus/duty ─┐
//!  RCbenchmark log (CSV)          ─► t, ω = rpm·2π/60, Q = load-cell torque (sparse)  ─┴─► TSV
//!                                    acceleration = central difference of ω (both)
//! ```
//! Importers convert units and say what they assume, on stderr and in `docs/REAL_DATA.md`. They
//! never smooth, shift or filter a signal, so what `diagnose` finds is in the data. The one
//! derived column is the acceleration, a plain central difference of the measured velocity
//! ((ω[k+1] − ω[k−1]) / (t[k+1] − t[k−1])), because neither stand logs one.

mod autoquad;
mod rcbench;

use std::path::{Path, PathBuf};

use anyhow::Context;

use crate::tsv::{Row, TsvWriter};
use crate::InputError;

pub use autoquad::import_autoquad;
pub use rcbench::import_rcbench;

/// The importers.
#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// AutoQuad ESC32 telemetry (duty, bus current, rpm): torque = Kt·I_bus/duty, Kt = 60/(2π·kv).
    Autoquad {
        /// The ESC32 Configuration Utility CSV.
        file: PathBuf,
        /// The motor's kv [rpm/V] (gives Kt = 60/(2π·kv) N·m/A).
        #[arg(long)]
        kv: f64,
        /// Output TSV (standard output if omitted).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// RCbenchmark (Tyto Robotics) stand log: load-cell torque and electrical rpm.
    Rcbench {
        /// The RCbenchmark CSV export.
        file: PathBuf,
        /// Output TSV (standard output if omitted).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
}

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

fn write(imported: &Imported, output: Option<&Path>) -> anyhow::Result<()> {
    for a in &imported.assumptions {
        eprintln!("import: {a}");
    }
    let out: Box<dyn std::io::Write> = match output {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p).with_context(|| format!("cannot create {}", p.display()))?,
        )),
        None => Box::new(std::io::BufWriter::new(std::io::stdout().lock())),
    };
    let mut w = TsvWriter::new(out, false)?;
    for r in &imported.rows {
        w.write(r)?;
    }
    w.into_inner()?;
    eprintln!("import: {} rows", imported.rows.len());
    Ok(())
}

/// Runs an importer.
pub fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Autoquad { file, kv, output } => {
            write(&import_autoquad(&file, kv)?, output.as_deref())
        }
        Command::Rcbench { file, output } => write(&import_rcbench(&file)?, output.as_deref()),
    }
}
