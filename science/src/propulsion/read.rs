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

use propid_io::tsv::{Row, StandColumn, TsvReader};
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
    let mut builder = Builder::new(
        &reader.stand_columns(),
        options,
        ReadReport {
            columns: reader.stand_columns().iter().map(|c| c.name()).collect(),
            ..ReadReport::default()
        },
    );
    while let Some(row) = reader.next_row()? {
        builder.push(&row);
    }
    Ok(builder.finish())
}

/// A [`Recording`] of rows already read (`columns`: the stand columns their file has), as
/// [`read`] makes it.
pub fn from_rows(rows: &[Row], columns: &[StandColumn], options: &ReadOptions) -> Recording {
    let mut builder = Builder::new(columns, options, ReadReport::default());
    for row in rows {
        builder.push(row);
    }
    builder.finish().0
}

/// The time, speed and thrust of rows already read, for a Result's C_T
/// ([`crate::result::Outcome::add_thrust`]): `None` when their file has no `thrust` column
/// (`columns`). The speed is read as `reading` says (`--velocity-unit`).
pub fn thrust_of_rows(
    rows: &[Row],
    columns: &[StandColumn],
    reading: &crate::plausibility::Reading,
) -> Option<Recording> {
    if !columns.contains(&StandColumn::Thrust) {
        return None;
    }
    let mut rec = from_rows(rows, &[StandColumn::Thrust], &ReadOptions::default());
    rec.torque = None;
    let (_, speed) = reading.factors();
    // The acceleration column stays in rad/s² (as the Reading documents).
    for x in &mut rec.speed {
        *x *= speed;
    }
    rec.thrust.is_some().then_some(rec)
}

/// A recording made row by row: rows without a time or a speed, or whose time does not
/// increase, are dropped and counted; a channel with no value at all is absent.
struct Builder {
    rec: Recording,
    report: ReadReport,
    scale: f64,
}

impl Builder {
    fn new(columns: &[StandColumn], options: &ReadOptions, report: ReadReport) -> Builder {
        let with = |c: StandColumn| columns.contains(&c).then(Vec::new);
        let rec = Recording {
            torque: Some(Vec::new()),
            thrust: with(StandColumn::Thrust),
            voltage: with(StandColumn::Voltage),
            current: with(StandColumn::Current),
            duty: with(StandColumn::Command).filter(|_| options.command_is_duty),
            ..Recording::default()
        };
        Builder {
            rec,
            report,
            scale: 1.0 / f64::from(options.pole_pairs.unwrap_or(1).max(1)),
        }
    }

    fn push(&mut self, row: &Row) {
        let (rec, report) = (&mut self.rec, &mut self.report);
        report.rows += 1;
        let s = row.sample;
        if !(s.t.is_finite() && s.velocity.is_finite()) {
            report.without_speed += 1;
            return;
        }
        if rec.time.last().is_some_and(|&last| s.t <= last) {
            report.time_not_increasing += 1;
            return;
        }
        rec.time.push(s.t);
        rec.speed.push(s.velocity * self.scale);
        rec.acceleration.push(s.acceleration * self.scale);
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

    fn finish(mut self) -> (Recording, ReadReport) {
        let rec = &mut self.rec;
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
        (self.rec, self.report)
    }
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
