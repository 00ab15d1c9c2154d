//! AutoQuad ESC32 telemetry, as the ESC32 Configuration Utility logs it.

use std::path::Path;

use super::{
    column, csv_error, csv_reader, describe_dropped, despike, differentiate, duplicates_warning,
    find_column, mean_sd, number, open_csv, DropReason, Dropped, Imported, UpdateRate,
};
use crate::input::LineLimit;
use crate::tsv::{Row, Sample, Stand, StandColumn};
use crate::InputError;

/// `YYYY-MM-DD HH:MM:SS:mmm` (the utility's PC timestamp) → seconds since the start of its day
/// count (days from the date, so midnight is crossed correctly). `None` if it is not that form.
fn pc_time(text: &str) -> Option<f64> {
    let (date, time) = text.trim().split_once(' ')?;
    let d: Vec<i64> = date
        .split('-')
        .map(|x| x.parse().ok())
        .collect::<Option<_>>()?;
    let t: Vec<f64> = time
        .split(':')
        .map(|x| x.parse().ok())
        .collect::<Option<_>>()?;
    if d.len() != 3 || t.len() != 4 {
        return None;
    }
    // A calendar date (the day count below would overflow on a year of sixteen digits).
    if !((1..=9999).contains(&d[0]) && (1..=12).contains(&d[1]) && (1..=31).contains(&d[2])) {
        return None;
    }
    // Days since a fixed epoch (civil calendar; exact for the Gregorian dates a log has).
    let (y, m) = if d[1] <= 2 {
        (d[0] - 1, d[1] + 9)
    } else {
        (d[0], d[1] - 3)
    };
    let days = 365 * y + y / 4 - y / 100 + y / 400 + (153 * m + 2) / 5 + d[2];
    Some(days as f64 * 86_400.0 + t[0] * 3600.0 + t[1] * 60.0 + t[2] + t[3] * 1e-3)
}

/// Imports an ESC32 log. `kv` [rpm/V] gives Kt = 60/(2π·kv); it must be finite and positive.
pub fn import_autoquad(path: &Path, kv: f64) -> Result<Imported, InputError> {
    import_autoquad_with(path, kv, false)
}

/// [`import_autoquad`], with velocity glitches set to NaN when `despike` (they are found and
/// reported either way).
pub fn import_autoquad_with(path: &Path, kv: f64, despike: bool) -> Result<Imported, InputError> {
    check_kv(kv)?;
    let (reader, headers, file) = open_csv(path)?;
    autoquad(reader, headers, file, kv, despike)
}

/// [`import_autoquad`] from any reader; `name` names it in messages.
pub fn read_autoquad(
    input: impl std::io::Read,
    name: &str,
    kv: f64,
) -> Result<Imported, InputError> {
    check_kv(kv)?;
    let (reader, headers, file) = csv_reader(Box::new(input), name.to_owned())?;
    autoquad(reader, headers, file, kv, false)
}

fn check_kv(kv: f64) -> Result<(), InputError> {
    if !kv.is_finite() || kv <= 0.0 {
        return Err(InputError::invalid(format!(
            "kv must be a finite positive number of rpm/V (got {kv})"
        )));
    }
    Ok(())
}

fn autoquad(
    mut reader: csv::Reader<LineLimit<Box<dyn std::io::Read + '_>>>,
    headers: csv::StringRecord,
    file: String,
    kv: f64,
    remove_spikes: bool,
) -> Result<Imported, InputError> {
    let (stamp, _) = column(&headers, &["Timestamp"], &file)?;
    let (amps, amps_name) = column(&headers, &["Amps"], &file)?;
    let (rpm, rpm_name) = column(&headers, &["RPM"], &file)?;
    let (duty, duty_name) = column(&headers, &["Duty"], &file)?;
    let volts = find_column(&headers, &["Batt. Volts"]);
    let kt = 60.0 / (std::f64::consts::TAU * kv);
    // (PC time, bus current, rpm, duty in %, bus voltage)
    let mut raw: Vec<(f64, f64, f64, f64, f64)> = Vec::new();
    // The log's line of each row, and the lines dropped as copies of the line before them (the
    // time is the row index, so a copy would also shift every later row's time).
    let mut lines = Vec::new();
    let mut dropped = Vec::new();
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
        lines.push(line);
        let text = record.get(stamp).unwrap_or("");
        let pc = pc_time(text).ok_or_else(|| {
            InputError::invalid(format!(
                "`{}` is not YYYY-MM-DD HH:MM:SS:mmm",
                text.chars().take(40).collect::<String>()
            ))
            .in_file(&file)
            .at_line(line)
            .in_column("Timestamp")
        })?;
        raw.push((
            pc,
            number(&record, amps, &amps_name, &file, line)?,
            number(&record, rpm, &rpm_name, &file, line)?,
            number(&record, duty, &duty_name, &file, line)?,
            match &volts {
                Some((i, name)) => number(&record, *i, name, &file, line)?,
                None => f64::NAN,
            },
        ));
        previous = record;
    }
    let n = raw.len();
    if n < 2 {
        return Err(
            InputError::invalid(format!("{n} data rows; at least 2 are needed")).in_file(&file),
        );
    }
    // The time base: the ESC logs at a fixed rate while the PC stamps rows in bursts, so the
    // row interval is the least-squares slope of PC time against row index.
    let (mi, mt) = (
        (n - 1) as f64 / 2.0,
        raw.iter().map(|r| r.0 - raw[0].0).sum::<f64>() / n as f64,
    );
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (k, r) in raw.iter().enumerate() {
        sxy += (k as f64 - mi) * (r.0 - raw[0].0 - mt);
        sxx += (k as f64 - mi).powi(2);
    }
    let dt = sxy / sxx;
    if !(1e-5..=1.0).contains(&dt) {
        return Err(InputError::invalid(format!(
            "the rows are {dt} s apart on average; an ESC logs every 10 µs to 1 s"
        ))
        .in_file(&file)
        .in_column("Timestamp"));
    }
    let scatter = raw
        .iter()
        .enumerate()
        .map(|(k, r)| (r.0 - raw[0].0 - mt - dt * (k as f64 - mi)).abs())
        .fold(0.0, f64::max);

    let mut rows = Vec::with_capacity(n);
    for (k, &(_, i_bus, r, d, v)) in raw.iter().enumerate() {
        let d = d / 100.0;
        // Phase current ≈ I_bus / duty; undefined at zero duty.
        let force = if d > 0.0 { kt * i_bus / d } else { f64::NAN };
        rows.push(Row {
            ts_local: f64::NAN,
            sample: Sample {
                t: k as f64 * dt,
                force,
                velocity: r * std::f64::consts::TAU / 60.0,
                acceleration: f64::NAN,
                position: f64::NAN,
            },
            stand: Stand {
                voltage: v,
                current: i_bus,
                command: d,
                ..Stand::NONE
            },
        });
    }
    let mut warnings = Vec::new();
    if !dropped.is_empty() {
        warnings.push(duplicates_warning(dropped.len(), n + dropped.len()));
    }
    despike(&mut rows, &lines, &rpm_name, remove_spikes, &mut warnings);
    differentiate(&mut rows);

    // What the signals do, measured.
    let rate = |col: usize| {
        UpdateRate::measure(
            raw.iter()
                .enumerate()
                .map(|(k, r)| (k as f64 * dt, [r.1, r.2, r.3, r.4][col])),
        )
        .describe(n)
    };
    let top = rows
        .iter()
        .map(|r| r.sample.velocity.abs())
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let rest: Vec<f64> = raw
        .iter()
        .filter(|r| r.2 == 0.0 && r.1.is_finite())
        .map(|r| r.1)
        .collect();
    let steady: Vec<f64> = rows
        .iter()
        .filter(|r| {
            r.sample.force.is_finite()
                && r.sample.velocity.abs() > 0.5 * top
                && r.sample.acceleration.abs() < 0.1 * top
        })
        .map(|r| r.sample.force * r.sample.velocity.signum())
        .collect();
    let steady_mean = if steady.is_empty() {
        f64::NAN
    } else {
        mean_sd(&steady).0
    };
    let sign = if steady_mean < 0.0 { -1.0 } else { 1.0 };
    for r in &mut rows {
        r.sample.force *= sign;
    }
    let mut assumptions = vec![
        format!(
            "time = row index × {:.4} ms: the least-squares slope of the PC timestamps against the row index over {n} rows ({:.1} s); the PC timestamps scatter by up to {:.0} ms around that line, so they are not used row by row",
            dt * 1e3,
            dt * (n - 1) as f64,
            scatter * 1e3
        ),
        format!("torque = Kt·I_bus/duty with Kt = 60/(2π·kv) = {kt:.4e} N·m/A (nominal, from kv): phase current ≈ bus current / duty; NaN at zero duty; this torque includes the motor's own friction"),
        format!("current = `{amps_name}` (the DC bus current the ESC reports) [A], kept as the TSV column `current`; it {}", rate(0)),
        format!("velocity = `{rpm_name}`·2π/60 (mechanical rpm from the commutation period); it {}", rate(1)),
        format!("command = `{duty_name}` / 100 (the duty the ESC applied, logged in %), kept as the TSV column `command` (ratio 0–1); it {}", rate(2)),
        "acceleration = central difference of the velocity (no smoothing)".into(),
    ];
    assumptions.push(if steady.is_empty() {
        "torque sign kept as logged: no sample at a steady speed above half the top speed to check it against".into()
    } else if sign < 0.0 {
        format!("torque sign flipped: at steady speed ({} samples) Kt·I_bus/duty averaged {steady_mean:.4} N·m against the rotation; drag opposes rotation, so the torque that holds the speed is taken as positive", steady.len())
    } else {
        format!("torque sign kept: at steady speed ({} samples) Kt·I_bus/duty averaged +{steady_mean:.4} N·m with the rotation, as drag requires", steady.len())
    });
    assumptions.push(if rest.len() >= 2 {
        let (m, sd) = mean_sd(&rest);
        format!(
            "zero offset: at zero speed ({} rows) the bus current reads {:+.1} ± {:.1} mA (mean ± s.d.); not subtracted",
            rest.len(),
            m * 1e3,
            sd * 1e3
        )
    } else {
        "zero offset: no rows at zero speed, so the current sensor's zero cannot be checked".into()
    });
    let mut stand_columns = vec![StandColumn::Current, StandColumn::Command];
    match &volts {
        Some((_, name)) => {
            assumptions.push(format!(
                "voltage = `{name}` (the DC bus voltage the ESC reports) [V], kept as the TSV column `voltage`; it {}",
                rate(3)
            ));
            stand_columns.insert(0, StandColumn::Voltage);
        }
        None => assumptions.push("voltage: no `Batt. Volts` column; no voltage column".into()),
    }
    assumptions.extend(describe_dropped(&dropped, n + dropped.len()));
    Ok(Imported {
        rows,
        stand_columns,
        extra: Vec::new(),
        assumptions,
        dropped,
        warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::pc_time;

    #[test]
    fn a_pc_time_outside_the_calendar_is_not_a_time() {
        // The fuzzer's input: a sixteen-digit year overflowed the day count.
        assert_eq!(pc_time("8888888888888888-11-05 17:14:08:947"), None);
        assert_eq!(pc_time("2019-13-05 17:14:08:947"), None);
        let t = pc_time("2019-11-05 17:14:08:947").unwrap();
        assert_eq!(pc_time("2019-11-05 17:14:09:947").unwrap() - t, 1.0);
    }
}
