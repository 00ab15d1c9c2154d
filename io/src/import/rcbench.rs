//! RCbenchmark and Tyto Robotics stand logs (the GUI's CSV export, any version).

use std::path::Path;

use super::{
    column, csv_error, csv_reader, describe_dropped, despike, differentiate, duplicates_warning,
    find_column, increasing_rows, loose, mean_sd, number, open_csv, DropReason, Dropped,
    ExtraColumn, Imported, UpdateRate,
};
use crate::input::LineLimit;
use crate::tsv::{Row, Sample, StandColumn};
use crate::InputError;

/// What to do beyond reading.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RcbenchOptions {
    /// Subtract the mean torque (and thrust) seen at zero speed (the load cells' zero offsets)
    /// from every torque (and thrust) sample. Off by default: the offsets are measured and
    /// reported, never removed silently.
    pub subtract_zero_offset: bool,
    /// Set the velocity of the samples found to be glitches (a jump away and straight back) to
    /// NaN. Off by default: glitches are found and reported, never removed silently.
    pub despike: bool,
}

/// Column names seen in RCbenchmark and Tyto exports, compared loosely (case, `µ`/`u`,
/// `N·m`/`N-m`).
const TIME_S: &[&str] = &["Time (s)", "Time"];
const TIME_MS: &[&str] = &["Time (ms)"];
const TORQUE: &[&str] = &["Torque (N·m)", "Torque (Nm)"];
const OPTICAL: &[&str] = &["Motor Optical Speed (RPM)"];
const ELECTRICAL: &[&str] = &["Motor Electrical Speed (RPM)"];
const GENERIC_RPM: &[&str] = &["Motor Speed (RPM)", "RPM"];
const COMMAND_US: &[&str] = &["ESC signal (µs)", "ESC signal (us)", "ESC (µs)"];
const COMMAND_PERCENT: &[&str] = &["ESC signal (%)", "ESC (%)", "Throttle (%)"];
const VOLTAGE: &[&str] = &["Voltage (V)"];
const CURRENT: &[&str] = &["Current (A)"];
const ELECTRICAL_POWER: &[&str] = &["Electrical Power (W)"];
const MECHANICAL_POWER: &[&str] = &["Mechanical Power (W)"];
/// Thrust units a header may name, in newtons per unit (standard gravity 9.80665 m/s²; the
/// pound-force and ounce-force as defined from the avoirdupois pound).
const THRUST_UNITS: &[(&str, f64)] = &[
    ("n", 1.0),
    ("gf", 9.806_65e-3),
    ("g", 9.806_65e-3),
    ("kgf", 9.806_65),
    ("kg", 9.806_65),
    ("lbf", 4.448_221_615_260_5),
    ("lb", 4.448_221_615_260_5),
    ("ozf", 0.278_013_850_953_781_2),
    ("oz", 0.278_013_850_953_781_2),
];

/// Where a kept column goes.
#[derive(Clone, Copy, PartialEq)]
enum Kept {
    Stand(StandColumn),
    Extra(&'static str),
}

/// A column kept beside the dynamics: `value = (logged − offset) · scale`.
struct KeptColumn {
    to: Kept,
    index: usize,
    name: String,
    offset: f64,
    scale: f64,
    /// How the logged value becomes the kept one, for the assumptions.
    how: String,
}

/// The thrust column, if any, with its scale to newtons from the unit its header names.
fn thrust_column(
    headers: &csv::StringRecord,
    file: &str,
) -> Result<Option<KeptColumn>, InputError> {
    let Some(index) = headers.iter().position(|h| loose(h).starts_with("thrust")) else {
        return Ok(None);
    };
    let name = headers[index]
        .trim_start_matches('\u{feff}')
        .trim()
        .to_owned();
    let unit = loose(&name)
        .strip_prefix("thrust")
        .map(|u| u.trim_start_matches('(').trim_end_matches(')').to_owned())
        .unwrap_or_default();
    let Some(&(_, scale)) = THRUST_UNITS.iter().find(|(u, _)| *u == unit) else {
        return Err(InputError::invalid(format!(
            "the thrust's unit {} is not one propid converts (gf, kgf, N, lbf, ozf); rename the column to say its unit, e.g. `Thrust (gf)`",
            if unit.is_empty() { "is not given".to_string() } else { format!("`{unit}`") }
        ))
        .in_file(file)
        .at_line(1)
        .in_column(name));
    };
    Ok(Some(KeptColumn {
        to: Kept::Stand(StandColumn::Thrust),
        index,
        how: if scale == 1.0 {
            format!("`{name}` in N")
        } else {
            format!("`{name}` × {scale} N per unit")
        },
        name,
        offset: 0.0,
        scale,
    }))
}

/// The columns kept beside the dynamics that this log has.
fn kept_columns(headers: &csv::StringRecord, file: &str) -> Result<Vec<KeptColumn>, InputError> {
    let mut kept: Vec<KeptColumn> = thrust_column(headers, file)?.into_iter().collect();
    let plain = |to: Kept, names: &[&str], unit: &str| {
        find_column(headers, names).map(|(index, name)| KeptColumn {
            to,
            index,
            how: format!("`{name}` in {unit}"),
            name,
            offset: 0.0,
            scale: 1.0,
        })
    };
    kept.extend(plain(
        Kept::Stand(StandColumn::Voltage),
        VOLTAGE,
        "V (the DC supply the stand measures)",
    ));
    kept.extend(plain(
        Kept::Stand(StandColumn::Current),
        CURRENT,
        "A (the DC supply the stand measures)",
    ));
    if let Some((index, name)) = find_column(headers, COMMAND_US) {
        kept.push(KeptColumn {
            to: Kept::Stand(StandColumn::Command),
            index,
            how: format!("(`{name}` − 1000 µs) / 1000 µs: the standard 1000–2000 µs servo signal range (an ESC calibrated to other end points maps differently; the logged µs are kept as `esc_signal_us`)"),
            name: name.clone(),
            offset: 1000.0,
            scale: 1e-3,
        });
        kept.push(KeptColumn {
            to: Kept::Extra("esc_signal_us"),
            index,
            how: format!("`{name}` as logged [µs]"),
            name,
            offset: 0.0,
            scale: 1.0,
        });
    } else if let Some((index, name)) = find_column(headers, COMMAND_PERCENT) {
        kept.push(KeptColumn {
            to: Kept::Stand(StandColumn::Command),
            index,
            how: format!("`{name}` / 100"),
            name,
            offset: 0.0,
            scale: 1e-2,
        });
    }
    kept.extend(plain(
        Kept::Extra("electrical_power"),
        ELECTRICAL_POWER,
        "W (computed by the stand's software)",
    ));
    kept.extend(plain(
        Kept::Extra("mechanical_power"),
        MECHANICAL_POWER,
        "W (computed by the stand's software)",
    ));
    Ok(kept)
}

/// A load cell's reading at rest (mean ± s.d. and count) and at steady speed (each sample times
/// the sign of the rotation), from rows already differentiated.
struct LoadCell {
    at_rest: Option<(f64, f64)>,
    rest_samples: usize,
    steady: Vec<f64>,
}

impl LoadCell {
    fn measure(rows: &[Row], value: impl Fn(&Row) -> f64) -> LoadCell {
        let top = top_speed(rows);
        let at_rest: Vec<f64> = rows
            .iter()
            .filter(|r| {
                // At rest: below 1 % of the top speed and not starting or stopping.
                value(r).is_finite()
                    && r.sample.velocity.abs() <= 0.01 * top
                    && r.sample.acceleration.abs() <= 0.01 * top
            })
            .map(&value)
            .collect();
        let offset = (at_rest.len() >= 2).then(|| mean_sd(&at_rest));
        // Steady speed: above half the top speed and changing by less than 10 % of it per second.
        let steady = rows
            .iter()
            .filter(|r| {
                value(r).is_finite()
                    && r.sample.velocity.abs() > 0.5 * top
                    && r.sample.acceleration.abs() < 0.1 * top
            })
            .map(|r| (value(r) - offset.map_or(0.0, |o| o.0)) * r.sample.velocity.signum())
            .collect();
        LoadCell {
            at_rest: offset,
            rest_samples: at_rest.len(),
            steady,
        }
    }

    /// The mean at steady speed, NaN without samples.
    fn steady_mean(&self) -> f64 {
        if self.steady.is_empty() {
            f64::NAN
        } else {
            mean_sd(&self.steady).0
        }
    }

    /// −1 when the reading opposes the rotation at steady speed, else 1.
    fn sign(&self) -> f64 {
        if self.steady_mean() < 0.0 {
            -1.0
        } else {
            1.0
        }
    }
}

/// The largest finite |ω| of the rows.
fn top_speed(rows: &[Row]) -> f64 {
    rows.iter()
        .map(|r| r.sample.velocity.abs())
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max)
}

/// Imports an RCbenchmark or Tyto CSV: velocity from the optical rpm when that probe logged
/// anything, else the electrical rpm; `force` = the load-cell torque where it was sampled (NaN
/// elsewhere: never interpolated), with the sign that makes the torque at steady speed oppose
/// drag; the stand columns from the thrust (in N, positive at speed), voltage, current and ESC
/// signal (ratio 0–1) it logged; the stand's power columns as extra columns.
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
    mut reader: csv::Reader<LineLimit<Box<dyn std::io::Read + '_>>>,
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
    let kept = kept_columns(&headers, &file)?;

    // Read everything: t, torque, [speeds], [kept columns].
    struct Raw {
        t: f64,
        q: f64,
        speeds: Vec<f64>,
        kept: Vec<f64>,
    }
    // Every row is read; then only the bad ones are dropped, each for itself.
    let mut read: Vec<(u64, Raw)> = Vec::new();
    let mut dropped: Vec<Dropped> = Vec::new();
    let mut previous = csv::StringRecord::new();
    for (k, record) in reader.records().enumerate() {
        let line = k as u64 + 2;
        let record = record.map_err(|e| csv_error(&file, &e, line))?;
        if k > 0 && record.iter().eq(previous.iter()) {
            dropped.push(Dropped {
                line,
                reason: DropReason::Duplicate,
            });
            continue;
        }
        let t = number(&record, time, &time_name, &file, line)? * time_scale;
        let q = number(&record, torque, &torque_name, &file, line)?;
        let speeds = speeds
            .iter()
            .map(|(i, n)| number(&record, *i, n, &file, line))
            .collect::<Result<Vec<f64>, _>>()?;
        let kept = kept
            .iter()
            .map(|c| Ok((number(&record, c.index, &c.name, &file, line)? - c.offset) * c.scale))
            .collect::<Result<Vec<f64>, InputError>>()?;
        previous = record;
        if !t.is_finite() {
            dropped.push(Dropped {
                line,
                reason: DropReason::NoTime,
            });
            continue;
        }
        read.push((line, Raw { t, q, speeds, kept }));
    }
    let rows_in_log = read.len() + dropped.len();
    let duplicates = dropped
        .iter()
        .filter(|d| d.reason == DropReason::Duplicate)
        .count();
    // Time must increase strictly, as the TSV promises: the fewest rows are dropped that make
    // it so (a stale time costs its own row, not the rows until the clock passes it).
    let times: Vec<f64> = read.iter().map(|(_, r)| r.t).collect();
    // Of equally few, the rows dropped are those without a load-cell sample.
    let thrust = kept
        .iter()
        .position(|c| c.to == Kept::Stand(StandColumn::Thrust));
    let precious: Vec<bool> = read
        .iter()
        .map(|(_, r)| r.q.is_finite() || thrust.is_some_and(|k| r.kept[k].is_finite()))
        .collect();
    let (keep, out_of_order) = increasing_rows(&times, &precious);
    dropped.extend(out_of_order.iter().map(|&(i, reason)| Dropped {
        line: read[i].0,
        reason,
    }));
    dropped.sort_by_key(|d| d.line);
    let mut read: Vec<Option<(u64, Raw)>> = read.into_iter().map(Some).collect();
    let (lines, raw): (Vec<u64>, Vec<Raw>) = keep.iter().filter_map(|&i| read[i].take()).unzip();
    if raw.len() < 2 {
        return Err(InputError::invalid(format!(
            "{} data rows with increasing time; at least 2 are needed",
            raw.len()
        ))
        .in_file(&file));
    }
    let n = raw.len();
    let mut assumptions = Vec::new();

    // The time base: the median row interval must be plausible for a test stand.
    let mut dts: Vec<f64> = raw.windows(2).map(|w| w[1].t - w[0].t).collect();
    let dt = super::median(&mut dts).unwrap_or(f64::NAN);
    if !(1e-5..=1.0).contains(&dt) {
        return Err(InputError::invalid(format!(
            "the median interval between rows is {dt} {}; a stand logs every 10 µs to 1 s — is the unit right?",
            if time_scale == 1.0 { "s" } else { "s (after ms → s)" }
        ))
        .in_file(&file)
        .in_column(&time_name));
    }
    assumptions.push(format!(
        "time = `{time_name}`{}: {n} rows over {:.1} s, median row interval {:.2} ms ({:.1} rows/s)",
        if time_scale == 1.0 { " in seconds" } else { " in milliseconds, converted to seconds" },
        raw[n - 1].t - raw[0].t,
        dt * 1e3,
        1.0 / dt
    ));
    assumptions.extend(describe_dropped(&dropped, rows_in_log));
    let mut warnings = Vec::new();
    if duplicates > 0 {
        warnings.push(duplicates_warning(duplicates, rows_in_log));
    }

    // The speed: the first of optical, electrical, generic that logged a non-zero value.
    let chosen = (0..speeds.len()).find(|&s| {
        raw.iter()
            .any(|r| r.speeds[s].is_finite() && r.speeds[s] != 0.0)
    });
    let Some(chosen) = chosen else {
        return Err(InputError::invalid(format!(
            "no speed column has a non-zero value ({})",
            speeds
                .iter()
                .map(|s| format!("`{}`", s.1))
                .collect::<Vec<_>>()
                .join(", ")
        ))
        .in_file(&file));
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
        .map(|r| {
            let mut row = Row::new(
                f64::NAN,
                Sample {
                    t: r.t,
                    force: r.q,
                    velocity: r.speeds[chosen] * std::f64::consts::TAU / 60.0,
                    acceleration: f64::NAN,
                    position: f64::NAN,
                },
            );
            for (c, v) in kept.iter().zip(&r.kept) {
                if let Kept::Stand(column) = c.to {
                    *row.stand.get_mut(column) = *v;
                }
            }
            row
        })
        .collect();
    despike(
        &mut rows,
        &lines,
        speed_name,
        options.despike,
        &mut warnings,
    );
    differentiate(&mut rows);
    let top = top_speed(&rows);

    // The torque: how often it updates, its zero at rest, its sign at speed.
    let rate = UpdateRate::measure(rows.iter().map(|r| (r.sample.t, r.sample.force)));
    if rate.present == 0 {
        return Err(InputError::invalid("empty in every row".into())
            .in_file(&file)
            .in_column(&torque_name));
    }
    let cell = LoadCell::measure(&rows, |r| r.sample.force);
    let sign = cell.sign();
    let subtract = |cell: &LoadCell| {
        if options.subtract_zero_offset {
            cell.at_rest.map_or(0.0, |o| o.0)
        } else {
            0.0
        }
    };
    let zero = subtract(&cell);
    for r in &mut rows {
        r.sample.force = sign * (r.sample.force - zero);
    }
    assumptions.push(format!(
        "force = `{torque_name}` (the load-cell torque; NaN between its samples, never interpolated); it {}",
        rate.describe(n)
    ));
    assumptions.extend(sign_and_offset(
        "torque",
        "drag opposes rotation, so the torque that holds the speed is taken as positive",
        "N·m",
        &cell,
        top,
        options,
    ));
    assumptions.push("the motor sits on the load cell, so the torque is the aerodynamic torque plus J_prop·dω/dt; the motor's own friction is inside the measurement and not seen".into());
    assumptions.push(
        "acceleration = central difference of the velocity at the full row rate (no smoothing)"
            .into(),
    );

    // The rest of the stand: thrust (signed like the torque: positive at speed), voltage,
    // current, command, power.
    let mut stand_columns = Vec::new();
    let mut extra = Vec::new();
    for (k, c) in kept.iter().enumerate() {
        let rate = UpdateRate::measure(raw.iter().map(|r| (r.t, r.kept[k])));
        let (what, column) = match c.to {
            Kept::Stand(column) => (format!("{} = {}", column.name(), c.how), column.name()),
            Kept::Extra(name) => (format!("{name} = {}", c.how), name),
        };
        if rate.present == 0 {
            assumptions.push(format!(
                "{}: `{}` is empty in every row; no {column} column",
                column, c.name
            ));
            continue;
        }
        assumptions.push(format!(
            "{what}, kept as the TSV column `{column}`; it {}",
            rate.describe(n)
        ));
        match c.to {
            Kept::Stand(StandColumn::Thrust) => {
                let cell = LoadCell::measure(&rows, |r| r.stand.thrust);
                let (sign, zero) = (cell.sign(), subtract(&cell));
                for r in &mut rows {
                    r.stand.thrust = sign * (r.stand.thrust - zero);
                }
                assumptions.extend(sign_and_offset(
                    "thrust",
                    "the propeller's thrust at speed is taken as positive",
                    "N",
                    &cell,
                    top,
                    options,
                ));
                stand_columns.push(StandColumn::Thrust);
            }
            Kept::Stand(column) => stand_columns.push(column),
            Kept::Extra(name) => extra.push(ExtraColumn {
                name,
                values: raw.iter().map(|r| r.kept[k]).collect(),
            }),
        }
    }
    if !kept
        .iter()
        .any(|c| c.to == Kept::Stand(StandColumn::Command))
    {
        assumptions.push("command: no ESC signal column; no command column".into());
    }
    stand_columns.sort_by_key(|c| c.slot());
    Ok(Imported {
        rows,
        stand_columns,
        extra,
        assumptions,
        dropped,
        warnings,
    })
}

/// What a load cell's sign and zero were found to be, a sentence each. `flipped` says why a
/// reading against the rotation is flipped.
fn sign_and_offset(
    what: &str,
    flipped: &str,
    unit: &str,
    cell: &LoadCell,
    top: f64,
    options: &RcbenchOptions,
) -> [String; 2] {
    let sign = cell.sign();
    let small = if unit == "N·m" { "mN·m" } else { "mN" };
    let sign_text = if cell.steady.is_empty() {
        format!("{what} sign kept as logged: no {what} sample at a steady speed above half the top speed to check it against")
    } else if sign < 0.0 {
        format!(
            "{what} sign flipped: at steady speed ({} samples above half the top speed of {top:.0} rad/s) the logged {what} averaged {:.4} {unit} against the direction of rotation; {flipped}",
            cell.steady.len(),
            cell.steady_mean()
        )
    } else {
        format!(
            "{what} sign kept: at steady speed ({} samples above half the top speed of {top:.0} rad/s) the logged {what} averaged +{:.4} {unit} with the direction of rotation",
            cell.steady.len(),
            cell.steady_mean()
        )
    };
    // "zero offset" for the torque, as the seed's readers know it; "thrust zero offset" else.
    let label = if what == "torque" {
        "zero offset".to_string()
    } else {
        format!("{what} zero offset")
    };
    let zero_text = match cell.at_rest {
        Some((m, sd)) => format!(
            "{label}: at zero speed ({} {what} samples) the load cell reads {:+.2} ± {:.2} {small} (mean ± s.d., in the sign above); {}",
            cell.rest_samples,
            sign * m * 1e3,
            sd * 1e3,
            if options.subtract_zero_offset {
                "subtracted from every sample"
            } else {
                "not subtracted"
            }
        ),
        None => format!("{label}: no {what} samples at zero speed, so the load cell's zero cannot be checked"),
    };
    [sign_text, zero_text]
}
