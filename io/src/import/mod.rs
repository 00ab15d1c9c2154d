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

pub(crate) use crate::header::loose;
use crate::input::LineLimit;
use crate::tsv::{Row, StandColumn, TsvWriter};
use crate::{ErrorKind, InputError};

pub use autoquad::{import_autoquad, import_autoquad_with, read_autoquad};
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
    /// The log's lines not in the TSV, each with its reason.
    pub dropped: Vec<Dropped>,
    /// What a user should look at (duplicated rows, velocity glitches), one sentence each; the
    /// command prints them as warnings.
    pub warnings: Vec<String>,
}

/// A line of the log that is not in the TSV, and why: an importer drops only what is bad, one
/// row for one bad row, and lists each.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dropped {
    /// 1-based line of the log.
    pub line: u64,
    /// Why.
    pub reason: DropReason,
}

/// Why a row was dropped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum DropReason {
    /// The same line as the one before it, byte for byte (a log written twice).
    Duplicate,
    /// The time field is empty.
    NoTime,
    /// The time equals that of the row kept before it.
    RepeatedTime,
    /// The time is earlier than that of the row kept before it (the clock went back).
    TimeGoesBack,
    /// The time is later than that of the rows kept after it (a stale time: the next rows
    /// restart earlier).
    TimeAhead,
}

impl DropReason {
    /// In words.
    pub fn describe(self) -> &'static str {
        match self {
            DropReason::Duplicate => "the same as the line before it",
            DropReason::NoTime => "no time",
            DropReason::RepeatedTime => "the time repeats the row before",
            DropReason::TimeGoesBack => "the time is earlier than the row before",
            DropReason::TimeAhead => "the time is later than the rows after it (stale)",
        }
    }
}

/// Which rows to keep so that time increases strictly, dropping as few as possible: the longest
/// strictly increasing run of `times` (not necessarily contiguous), so one stale or out-of-order
/// row costs that row only, never the rows after it. Among runs of that length, the one keeping
/// the most `precious` rows (those with a sample of a slow sensor) wins; then the earlier rows.
/// Returns the kept indices, in order, and the reason for each dropped one (by index).
pub(crate) fn increasing_rows(
    times: &[f64],
    precious: &[bool],
) -> (Vec<usize>, Vec<(usize, DropReason)>) {
    let n = times.len();
    // Each row weighs more than all precious bonuses together: the count comes first.
    let weight = |i: usize| (n as u64 + 1) + u64::from(precious.get(i).copied().unwrap_or(false));
    // Ranks of the distinct times; a Fenwick tree over them holds, for each prefix of ranks,
    // the best (total weight, last index) of an increasing run ending below that rank.
    let mut sorted: Vec<f64> = times.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted.dedup();
    let mut tree: Vec<(u64, usize)> = vec![(0, usize::MAX); sorted.len() + 1];
    let mut prev = vec![usize::MAX; n];
    let mut best = (0u64, usize::MAX);
    for (i, &t) in times.iter().enumerate() {
        let rank = sorted.partition_point(|&x| x < t); // 0-based: ranks below are `< t`
        let mut below = (0u64, usize::MAX);
        let mut r = rank;
        while r > 0 {
            if tree[r].0 > below.0 {
                below = tree[r];
            }
            r &= r - 1;
        }
        let total = below.0 + weight(i);
        prev[i] = below.1;
        // Strictly better only: of equal totals the earlier row stays.
        let mut r = rank + 1;
        while r < tree.len() {
            if total > tree[r].0 {
                tree[r] = (total, i);
            }
            r += r & r.wrapping_neg();
        }
        if total > best.0 {
            best = (total, i);
        }
    }
    let mut kept = Vec::new();
    let mut i = best.1;
    while i != usize::MAX {
        kept.push(i);
        i = prev[i];
    }
    kept.reverse();
    let mut dropped = Vec::with_capacity(times.len() - kept.len());
    let mut next = 0;
    for (i, &t) in times.iter().enumerate() {
        if kept.get(next) == Some(&i) {
            next += 1;
            continue;
        }
        let before = next.checked_sub(1).map(|k| times[kept[k]]);
        let after = kept.get(next).map(|&k| times[k]);
        let reason = match (before, after) {
            (Some(b), _) if t == b => DropReason::RepeatedTime,
            (Some(b), _) if t < b => DropReason::TimeGoesBack,
            (_, Some(a)) if t == a => DropReason::RepeatedTime,
            _ => DropReason::TimeAhead,
        };
        dropped.push((i, reason));
    }
    (kept, dropped)
}

/// One sentence listing the dropped lines, grouped into runs of one reason (at most ten
/// groups shown).
pub(crate) fn describe_dropped(dropped: &[Dropped], rows: usize) -> Option<String> {
    if dropped.is_empty() {
        return None;
    }
    let mut groups: Vec<(u64, u64, DropReason)> = Vec::new();
    for d in dropped {
        match groups.last_mut() {
            Some((_, last, reason)) if *reason == d.reason && d.line == *last + 1 => *last = d.line,
            _ => groups.push((d.line, d.line, d.reason)),
        }
    }
    let shown: Vec<String> = groups
        .iter()
        .take(10)
        .map(|&(a, b, reason)| {
            if a == b {
                format!("line {a} ({})", reason.describe())
            } else {
                format!("lines {a}–{b} ({})", reason.describe())
            }
        })
        .collect();
    Some(format!(
        "{} of {} rows dropped, each for itself: {}{}",
        dropped.len(),
        rows,
        shown.join("; "),
        if groups.len() > 10 {
            format!("; and {} more groups", groups.len() - 10)
        } else {
            String::new()
        }
    ))
}

/// What to say about `n` rows dropped as copies of the line before them.
pub(crate) fn duplicates_warning(n: usize, rows: usize) -> String {
    format!(
        "{n} of {rows} lines repeat the line before them exactly (a log written twice, or rows copied): dropped; kept, each copy would count as another measurement and make every standard error too small (by √2 when every row is doubled)"
    )
}

/// Velocity glitches ([`crate::glitch`]) in `rows`: the rows' indices and the largest jump.
fn glitches(rows: &[Row]) -> (Vec<usize>, f64) {
    let v: Vec<f64> = rows.iter().map(|r| r.sample.velocity).collect();
    let found = crate::glitch::find(&v);
    (
        found.rows.into_iter().map(|k| k as usize).collect(),
        found.largest,
    )
}

/// Finds velocity glitches ([`crate::glitch`]) in `rows` (from the
/// log's `lines`), warns about them, and when `remove` sets their velocity to NaN (so neither
/// they nor the accelerations next to them are used; nothing is interpolated).
pub(crate) fn despike(
    rows: &mut [Row],
    lines: &[u64],
    speed_name: &str,
    remove: bool,
    warnings: &mut Vec<String>,
) {
    let (spikes, largest) = glitches(rows);
    if spikes.is_empty() {
        return;
    }
    let shown: Vec<String> = spikes
        .iter()
        .take(10)
        .map(|&k| lines[k].to_string())
        .collect();
    warnings.push(crate::glitch::sentence(
        speed_name,
        spikes.len(),
        &format!("{:.0} rpm", largest * 60.0 / std::f64::consts::TAU),
        &format!("lines {}", shown.join(", ")),
        if remove {
            "their velocity is NaN in the TSV (--despike), so neither they nor the accelerations beside them are used"
        } else {
            "kept: each puts a false pair of large accelerations into the data; --despike sets them to NaN"
        },
    ));
    if remove {
        for k in spikes {
            rows[k].sample.velocity = f64::NAN;
        }
    }
}

/// Velocity glitches in the rows of a TSV (`name`): what to tell the user, naming the rows by
/// their time, and, when `remove`, the rows left without them (a glitch's acceleration column is
/// the file's own, so the row is dropped whole). `None` when there are none.
pub fn tsv_glitches(name: &str, rows: &mut Vec<Row>, remove: bool) -> Option<String> {
    let (spikes, largest) = glitches(rows);
    if spikes.is_empty() {
        return None;
    }
    let times: Vec<String> = spikes
        .iter()
        .take(10)
        .map(|&k| format!("{:.4}", rows[k].sample.t))
        .collect();
    let sentence = crate::glitch::tsv_sentence(
        name,
        spikes.len(),
        largest,
        &format!("t = {} s", times.join(", ")),
        remove,
        "--despike",
    );
    if remove {
        let mut k = 0;
        let mut next = spikes.iter().peekable();
        rows.retain(|_| {
            let drop = next.next_if_eq(&&k).is_some();
            k += 1;
            !drop
        });
    }
    Some(sentence)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The fewest rows are dropped, each with its reason; of two equal times the first is kept.
    #[test]
    fn increasing_rows_drop_the_fewest() {
        let times = [9.0, 0.0, 0.0, 1.0, 2.0, 1.5, 3.0, 3.0, 4.0];
        let (kept, dropped) = increasing_rows(&times, &[]);
        // 2.0 then 1.5: either one is out of order; the earlier row is kept.
        assert_eq!(kept, [1, 3, 4, 6, 8]);
        assert_eq!(
            dropped,
            [
                (0, DropReason::TimeAhead),
                (2, DropReason::RepeatedTime),
                (5, DropReason::TimeGoesBack),
                (7, DropReason::RepeatedTime),
            ]
        );
        // …unless the later one holds a slow sensor's sample.
        let mut precious = [false; 9];
        precious[5] = true;
        let (kept, dropped) = increasing_rows(&times, &precious);
        assert_eq!(kept, [1, 3, 5, 6, 8]);
        assert_eq!(dropped[2], (4, DropReason::TimeAhead));
        // Never more rows dropped for a precious one.
        precious[0] = true;
        assert_eq!(increasing_rows(&times, &precious).0.len(), 5);
        assert_eq!(increasing_rows(&[], &[]).0, Vec::<usize>::new());
    }
}
