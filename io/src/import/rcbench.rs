//! RCbenchmark and Tyto Robotics stand logs (the GUI's CSV export, any version).

use std::path::Path;

use super::{
    column, csv_reader, differentiate, find_column, mean_sd, number, open_csv, Imported, UpdateRate,
};
use crate::tsv::{Row, Sample};
use crate::InputError;

/// What to do beyond reading.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RcbenchOptions {
    /// Subtract the mean torque seen at zero speed (the load cell's zero offset) from every
    /// torque sample. Off by default: the offset is measured and reported, never removed
    /// silently.
    pub subtract_zero_offset: bool,
}

/// Column names seen in RCbenchmark and Tyto exports, compared loosely (case, `µ`/`u`,
/// `N·m`/`N-m`).
const TIME_S: &[&str] = &["Time (s)", "Time"];
const TIME_MS: &[&str] = &["Time (ms)"];
const TORQUE: &[&str] = &["Torque (N·m)", "Torque (Nm)"];
const OPTICAL: &[&str] = &["Motor Optical Speed (RPM)"];
const ELECTRICAL: &[&str] = &["Motor Electrical Speed (RPM)"];
const GENERIC_RPM: &[&str] = &["Motor Speed (RPM)", "RPM"];
const COMMAND: &[&str] = &["ESC signal (µs)", "ESC signal (us)"];

/// Imports an RCbenchmark or Tyto CSV: velocity from the optical rpm when that probe logged
/// anything, else the electrical rpm; `force` = the load-cell torque where it was sampled (NaN
/// elsewhere: never interpolated), with the sign that makes the torque at steady speed oppose
/// drag; the ESC signal as the `command` column when it was logged.
pub fn import_rcbench(path: &Path, options: &RcbenchOptions) -> Result<Imported, InputError> {
    let (reader, headers, file) = open_csv(path)?;
    rcbench(reader, headers, file, options)
}

/// [`import_rcbench`] from any reader; `name` names it in messages.
pub fn read_rcbench(
    input: impl std::io::Read,
    name: &str,
    options: &RcbenchOptions,
) -> Result<Imported, InputError> {
    let (reader, headers, file) = csv_reader(Box::new(input), name.to_owned())?;
    rcbench(reader, headers, file, options)
}

fn rcbench(
    mut reader: csv::Reader<Box<dyn std::io::Read + '_>>,
    headers: csv::StringRecord,
    file: String,
    options: &RcbenchOptions,
) -> Result<Imported, InputError> {
    let (time, time_name, time_scale) = match find_column(&headers, TIME_MS) {
        Some((i, n)) => (i, n, 1e-3),
        None => {
            let (i, n) = column(&headers, TIME_S, &file)?;
            (i, n, 1.0)
        }
    };
    let (torque, torque_name) = column(&headers, TORQUE, &file)?;
    let speeds: Vec<(usize, String)> = [OPTICAL, ELECTRICAL, GENERIC_RPM]
        .iter()
        .filter_map(|names| find_column(&headers, names))
        .collect();
    if speeds.is_empty() {
        column(
            &headers,
            &[OPTICAL[0], ELECTRICAL[0], GENERIC_RPM[0]],
            &file,
        )?;
    }
    let command = find_column(&headers, COMMAND);

    // Read everything: (line, t, torque, [speeds], command).
    struct Raw {
        t: f64,
        q: f64,
        speeds: Vec<f64>,
        command: f64,
    }
    let mut raw: Vec<Raw> = Vec::new();
    let mut dropped_lines = Vec::new();
    for (k, record) in reader.records().enumerate() {
        let line = k as u64 + 2;
        let record = record.map_err(|e| InputError(format!("{file}: line {line}: {e}")))?;
        let t = number(&record, time, &time_name, &file, line)? * time_scale;
        let q = number(&record, torque, &torque_name, &file, line)?;
        let speeds = speeds
            .iter()
            .map(|(i, n)| number(&record, *i, n, &file, line))
            .collect::<Result<Vec<f64>, _>>()?;
        let command = match &command {
            Some((i, n)) => number(&record, *i, n, &file, line)?,
            None => f64::NAN,
        };
        if !t.is_finite() {
            return Err(InputError(format!(
                "{file}: line {line}, column `{time_name}`: no time"
            )));
        }
        // Time must increase strictly, as the TSV promises: a row repeating an earlier time
        // is dropped and counted.
        if raw.last().is_some_and(|p| t <= p.t) {
            dropped_lines.push(line);
            continue;
        }
        raw.push(Raw {
            t,
            q,
            speeds,
            command,
        });
    }
    if raw.len() < 2 {
        return Err(InputError(format!(
            "{file}: {} data rows with increasing time; at least 2 are needed",
            raw.len()
        )));
    }
    let n = raw.len();
    let mut assumptions = Vec::new();

    // The time base: the median row interval must be plausible for a test stand.
    let mut dts: Vec<f64> = raw.windows(2).map(|w| w[1].t - w[0].t).collect();
    let dt = super::median(&mut dts).unwrap_or(f64::NAN);
    if !(1e-5..=1.0).contains(&dt) {
        return Err(InputError(format!(
            "{file}: column `{time_name}`: the median interval between rows is {dt} {}; a stand logs every 10 µs to 1 s — is the unit right?",
            if time_scale == 1.0 { "s" } else { "s (after ms → s)" }
        )));
    }
    assumptions.push(format!(
        "time = `{time_name}`{}: {n} rows over {:.1} s, median row interval {:.2} ms ({:.1} rows/s)",
        if time_scale == 1.0 { " in seconds" } else { " in milliseconds, converted to seconds" },
        raw[n - 1].t - raw[0].t,
        dt * 1e3,
        1.0 / dt
    ));
    if !dropped_lines.is_empty() {
        assumptions.push(format!(
            "{} rows whose time does not increase were dropped (lines {}{})",
            dropped_lines.len(),
            dropped_lines
                .iter()
                .take(5)
                .map(u64::to_string)
                .collect::<Vec<_>>()
                .join(", "),
            if dropped_lines.len() > 5 { ", …" } else { "" }
        ));
    }

    // The speed: the first of optical, electrical, generic that logged a non-zero value.
    let chosen = (0..speeds.len()).find(|&s| {
        raw.iter()
            .any(|r| r.speeds[s].is_finite() && r.speeds[s] != 0.0)
    });
    let Some(chosen) = chosen else {
        return Err(InputError(format!(
            "{file}: no speed column has a non-zero value ({})",
            speeds
                .iter()
                .map(|s| format!("`{}`", s.1))
                .collect::<Vec<_>>()
                .join(", ")
        )));
    };
    let speed_name = &speeds[chosen].1;
    let others: Vec<String> = speeds
        .iter()
        .enumerate()
        .filter(|&(s, _)| s != chosen)
        .map(|(_, (_, name))| format!("`{name}` is zero or empty throughout"))
        .collect();
    let kind = if OPTICAL
        .iter()
        .any(|o| super::loose(o) == super::loose(speed_name))
    {
        "the optical probe: mechanical rpm if the number of reflective marks is set right in the stand's software"
    } else if ELECTRICAL
        .iter()
        .any(|o| super::loose(o) == super::loose(speed_name))
    {
        "the electrical probe: mechanical rpm computed from the phase frequency and the pole count set in the stand's software"
    } else {
        "a speed column of unknown origin, taken as mechanical rpm"
    };
    let rate = UpdateRate::measure(raw.iter().map(|r| (r.t, r.speeds[chosen])));
    assumptions.push(format!(
        "velocity = `{speed_name}`·2π/60 ({kind}){}; it {}",
        if others.is_empty() {
            String::new()
        } else {
            format!(" — used because {}", others.join(", "))
        },
        rate.describe(n)
    ));

    let mut rows: Vec<Row> = raw
        .iter()
        .map(|r| Row {
            ts_local: f64::NAN,
            sample: Sample {
                t: r.t,
                force: r.q,
                velocity: r.speeds[chosen] * std::f64::consts::TAU / 60.0,
                acceleration: f64::NAN,
                position: f64::NAN,
            },
        })
        .collect();
    differentiate(&mut rows);

    // The torque: how often it updates, its zero at rest, its sign at speed.
    let rate = UpdateRate::measure(rows.iter().map(|r| (r.sample.t, r.sample.force)));
    if rate.present == 0 {
        return Err(InputError(format!(
            "{file}: column `{torque_name}` is empty in every row"
        )));
    }
    let top = rows
        .iter()
        .map(|r| r.sample.velocity.abs())
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let at_rest: Vec<f64> = rows
        .iter()
        .filter(|r| {
            // At rest: below 1 % of the top speed and not starting or stopping.
            r.sample.force.is_finite()
                && r.sample.velocity.abs() <= 0.01 * top
                && r.sample.acceleration.abs() <= 0.01 * top
        })
        .map(|r| r.sample.force)
        .collect();
    let offset = (at_rest.len() >= 2).then(|| mean_sd(&at_rest));
    // Steady speed: above half the top speed and changing by less than 10 % of it per second.
    let steady: Vec<f64> = rows
        .iter()
        .filter(|r| {
            r.sample.force.is_finite()
                && r.sample.velocity.abs() > 0.5 * top
                && r.sample.acceleration.abs() < 0.1 * top
        })
        .map(|r| (r.sample.force - offset.map_or(0.0, |o| o.0)) * r.sample.velocity.signum())
        .collect();
    let (steady_mean, _) = if steady.is_empty() {
        (f64::NAN, 0.0)
    } else {
        mean_sd(&steady)
    };
    let sign = if steady_mean < 0.0 { -1.0 } else { 1.0 };
    let subtract = if options.subtract_zero_offset {
        offset.map_or(0.0, |o| o.0)
    } else {
        0.0
    };
    for r in &mut rows {
        r.sample.force = sign * (r.sample.force - subtract);
    }
    assumptions.push(format!(
        "force = `{torque_name}` (the load-cell torque; NaN between its samples, never interpolated); it {}",
        rate.describe(n)
    ));
    assumptions.push(if steady.is_empty() {
        "torque sign kept as logged: no torque sample at a steady speed above half the top speed to check it against".into()
    } else if sign < 0.0 {
        format!(
            "torque sign flipped: at steady speed ({} samples above half the top speed of {:.0} rad/s) the logged torque averaged {:.4} N·m against the direction of rotation; drag opposes rotation, so the torque that holds the speed is taken as positive",
            steady.len(),
            top,
            steady_mean
        )
    } else {
        format!(
            "torque sign kept: at steady speed ({} samples above half the top speed of {:.0} rad/s) the logged torque averaged +{:.4} N·m with the direction of rotation, as drag requires",
            steady.len(),
            top,
            steady_mean
        )
    });
    assumptions.push(match offset {
        Some((m, sd)) => format!(
            "zero offset: at zero speed ({} torque samples) the load cell reads {:+.2} ± {:.2} mN·m (mean ± s.d., in the sign above); {}",
            at_rest.len(),
            sign * m * 1e3,
            sd * 1e3,
            if options.subtract_zero_offset {
                "subtracted from every sample"
            } else {
                "not subtracted"
            }
        ),
        None => "zero offset: no torque samples at zero speed, so the load cell's zero cannot be checked".into(),
    });
    assumptions.push("the motor sits on the load cell, so the torque is the aerodynamic torque plus J_prop·dω/dt; the motor's own friction is inside the measurement and not seen".into());
    assumptions.push(
        "acceleration = central difference of the velocity at the full row rate (no smoothing)"
            .into(),
    );

    // The command, kept as a column when it was logged.
    let command = match &command {
        Some((_, name)) => {
            let values: Vec<f64> = raw.iter().map(|r| r.command).collect();
            let rate = UpdateRate::measure(raw.iter().map(|r| (r.t, r.command)));
            if rate.present == 0 {
                assumptions.push(format!(
                    "command: `{name}` is empty in every row; no command column"
                ));
                None
            } else {
                assumptions.push(format!(
                    "command = `{name}` (the ESC signal the stand gave), kept as the TSV column `command`; it {}",
                    rate.describe(n)
                ));
                Some(values)
            }
        }
        None => {
            assumptions.push("command: no ESC signal column; no command column".into());
            None
        }
    };
    Ok(Imported {
        rows,
        command,
        assumptions,
    })
}
