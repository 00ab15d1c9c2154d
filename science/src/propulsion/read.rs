//! A recording from propid's TSV: the seed's columns and the stand columns (`thrust`,
//! `voltage`, `current`, `command`).
//!
//! `force` is taken as the shaft torque (a load cell's, or the drive's estimate), `velocity` as
//! the mechanical speed unless the file's speed is electrical (divided by the pole pairs when
//! they are given). `command` is the duty only when the caller says so: a stand's throttle
//! signal or a drive's torque setpoint is not a duty, and taking one for it would give a wrong
//! Kv without a word. Rows without a time or a speed are dropped, as are rows whose time does not
//! increase; both are counted.

use std::io::BufRead;
use std::path::Path;

use propid_io::tsv::{StandColumn, TsvReader};
use propid_io::InputError;

use super::Recording;

/// How to read.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReadOptions {
    /// The speed column is electrical: divide it by these pole pairs.
    pub pole_pairs: Option<u32>,
    /// The `command` column is the ESC's duty (ratio 0–1).
    pub command_is_duty: bool,
}

/// What reading found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReadReport {
    /// Rows read.
    pub rows: usize,
    /// Rows dropped: no time or speed.
    pub without_speed: usize,
    /// Rows dropped: time not increasing.
    pub time_not_increasing: usize,
    /// The stand columns the file has.
    pub columns: Vec<&'static str>,
}

/// Reads a TSV into a [`Recording`].
pub fn read(
    input: impl BufRead,
    name: &str,
    options: &ReadOptions,
) -> Result<(Recording, ReadReport), InputError> {
    let mut reader = TsvReader::new(input, name)?;
    let has = |c: StandColumn| reader.has(c);
    let mut rec = Recording::default();
    let with = |yes: bool| yes.then(Vec::new);
    rec.torque = Some(Vec::new());
    rec.thrust = with(has(StandColumn::Thrust));
    rec.voltage = with(has(StandColumn::Voltage));
    rec.current = with(has(StandColumn::Current));
    rec.duty = with(has(StandColumn::Command) && options.command_is_duty);
    let mut report = ReadReport {
        columns: reader.stand_columns().iter().map(|c| c.name()).collect(),
        ..ReadReport::default()
    };
    let scale = 1.0 / f64::from(options.pole_pairs.unwrap_or(1).max(1));
    while let Some(row) = reader.next_row()? {
        report.rows += 1;
        let s = row.sample;
        if !(s.t.is_finite() && s.velocity.is_finite()) {
            report.without_speed += 1;
            continue;
        }
        if rec.time.last().is_some_and(|&last| s.t <= last) {
            report.time_not_increasing += 1;
            continue;
        }
        rec.time.push(s.t);
        rec.speed.push(s.velocity * scale);
        rec.acceleration.push(s.acceleration * scale);
        let push = |v: &mut Option<Vec<f64>>, x: f64| {
            if let Some(v) = v {
                v.push(x);
            }
        };
        push(&mut rec.torque, s.force);
        push(&mut rec.thrust, row.stand.thrust);
        push(&mut rec.voltage, row.stand.voltage);
        push(&mut rec.current, row.stand.current);
        push(&mut rec.duty, row.stand.command);
    }
    // A column with no value at all is not there.
    for c in [
        &mut rec.torque,
        &mut rec.thrust,
        &mut rec.voltage,
        &mut rec.current,
        &mut rec.duty,
    ] {
        if c.as_ref().is_some_and(|v| v.iter().all(|x| !x.is_finite())) {
            *c = None;
        }
    }
    Ok((rec, report))
}

/// [`read`] from a path (`-`: standard input).
pub fn read_path(
    path: &Path,
    options: &ReadOptions,
) -> Result<(Recording, ReadReport), InputError> {
    let name = path.display().to_string();
    if path == Path::new("-") {
        return read(std::io::stdin().lock(), "<stdin>", options);
    }
    let f =
        std::fs::File::open(path).map_err(|e| InputError::os(name.clone(), "cannot open", &e))?;
    read(std::io::BufReader::new(f), &name, options)
}
