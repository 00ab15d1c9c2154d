//! AutoQuad ESC32 telemetry, as the ESC32 Configuration Utility logs it.

use std::path::Path;

use super::{column, differentiate, number, open_csv, Imported};
use crate::tsv::{Row, Sample};
use crate::InputError;

/// Imports an ESC32 log. `kv` [rpm/V] gives Kt = 60/(2π·kv).
pub fn import_autoquad(path: &Path, kv: f64) -> Result<Imported, InputError> {
    if kv.is_nan() || kv <= 0.0 {
        return Err(InputError(format!("--kv must be positive (got {kv})")));
    }
    let (mut reader, headers, file) = open_csv(path)?;
    let (amps, rpm, duty) = (
        column(&headers, "Amps", &file)?,
        column(&headers, "RPM", &file)?,
        column(&headers, "Duty", &file)?,
    );
    let kt = 60.0 / (std::f64::consts::TAU * kv);
    let mut rows = Vec::new();
    for (k, record) in reader.records().enumerate() {
        let line = k as u64 + 2;
        let record = record.map_err(|e| InputError(format!("{file}: line {line}: {e}")))?;
        let i_bus = number(&record, amps, "Amps", &file, line)?;
        let r = number(&record, rpm, "RPM", &file, line)?;
        let d = number(&record, duty, "Duty", &file, line)? / 100.0;
        // Phase current ≈ I_bus / duty; undefined at zero duty.
        let force = if d > 0.0 { kt * i_bus / d } else { f64::NAN };
        rows.push(Row {
            ts_local: f64::NAN,
            sample: Sample {
                t: k as f64 * 0.010,
                force,
                velocity: r * std::f64::consts::TAU / 60.0,
                acceleration: f64::NAN,
                position: f64::NAN,
            },
        });
    }
    if rows.is_empty() {
        return Err(InputError(format!("{file}: no data rows")));
    }
    differentiate(&mut rows);
    Ok(Imported {
        rows,
        assumptions: vec![
            "time = row index × 10.00 ms (the PC timestamp jitters by ±0.1 s; a fit of time against index gives 10.00 ms per row)".into(),
            format!("torque = Kt·I_bus/duty with Kt = 60/(2π·kv) = {kt:.4e} N·m/A: phase current ≈ bus current / duty; NaN at zero duty; this torque includes the motor's own friction"),
            "velocity = RPM·2π/60 (mechanical rpm from the commutation period)".into(),
            "acceleration = central difference of the velocity (no smoothing)".into(),
        ],
    })
}
