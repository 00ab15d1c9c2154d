//! RCbenchmark (Tyto Robotics) stand logs.

use std::path::Path;

use super::{column, differentiate, number, open_csv, Imported};
use crate::tsv::{Row, Sample};
use crate::InputError;

/// Imports an RCbenchmark CSV: velocity from the electrical rpm at every row, `force` = the
/// load-cell torque where it was sampled (NaN elsewhere: never interpolated), its sign made
/// positive for a torque that resists the rotation.
pub fn import_rcbench(path: &Path) -> Result<Imported, InputError> {
    let (mut reader, headers, file) = open_csv(path)?;
    let time = column(&headers, "Time (s)", &file)?;
    let torque = column(&headers, "Torque (N·m)", &file)?;
    let rpm = column(&headers, "Motor Electrical Speed (RPM)", &file)?;
    let mut rows: Vec<Row> = Vec::new();
    for (k, record) in reader.records().enumerate() {
        let line = k as u64 + 2;
        let record = record.map_err(|e| InputError(format!("{file}: line {line}: {e}")))?;
        let t = number(&record, time, "Time (s)", &file, line)?;
        let q = number(&record, torque, "Torque (N·m)", &file, line)?;
        let r = number(&record, rpm, "Motor Electrical Speed (RPM)", &file, line)?;
        // The first rows repeat t = 0: keep time strictly increasing, as the TSV promises.
        if rows.last().is_some_and(|p| t <= p.sample.t) {
            continue;
        }
        rows.push(Row {
            ts_local: f64::NAN,
            sample: Sample {
                t,
                force: q,
                velocity: r * std::f64::consts::TAU / 60.0,
                acceleration: f64::NAN,
                position: f64::NAN,
            },
        });
    }
    if rows.is_empty() {
        return Err(InputError(format!("{file}: no data rows")));
    }
    // Sign: the load cell reads the reaction torque, whose sign follows the direction of
    // rotation (positive in one run, negative in others). Make the torque at speed positive.
    let (mut sum, mut n) = (0.0, 0);
    let top = rows.iter().map(|r| r.sample.velocity).fold(0.0, f64::max);
    for r in &rows {
        if r.sample.force.is_finite() && r.sample.velocity > 0.5 * top {
            sum += r.sample.force;
            n += 1;
        }
    }
    let sign = if n > 0 && sum < 0.0 { -1.0 } else { 1.0 };
    for r in &mut rows {
        r.sample.force *= sign;
    }
    differentiate(&mut rows);
    Ok(Imported {
        rows,
        assumptions: vec![
            "velocity = Motor Electrical Speed (RPM)·2π/60 (mechanical rpm, from the phase frequency and the pole count set in the RCbenchmark software)".into(),
            format!(
                "force = the load-cell torque, sampled at ~6.7 Hz (NaN between samples, not interpolated), sign {}: the motor sits on the load cell, so it reads Q_aero + J·dω/dt (motor friction excluded), with a zero offset of up to ±1.5 mN·m",
                if sign < 0.0 { "flipped so that the torque at speed is positive" } else { "kept (positive at speed)" }
            ),
            "rows repeating an earlier time (the log starts with several t = 0) are dropped".into(),
            "acceleration = central difference of the velocity at the full row rate (no smoothing)".into(),
        ],
    })
}
