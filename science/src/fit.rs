//! The seed regressor, exact and in constant memory.
//!
//! ## How data flows
//! ```text
//!  TSV file, memory-mapped (stdin: spooled to a temporary file first)
//!    one pass, a chunk of whole lines per thread: each chunk keeps its last run of complete rows
//!    as blocks of rows with their normal equations (LoadEstimator::update, fixed memory)
//!    ─► the chunks' runs joined into the file's last run, the seed's 10 % cut made (the block it
//!       falls in parsed again), the blocks merged (NormalEquations::merge)
//!    ─► LoadEstimator::estimate(bounds) ─► YAML/JSON on stdout; a plot parses the window again
//! ```
//! The window reproduces the seed exactly: the seed keeps the rows from the start of the last
//! run of rows whose every field is finite up to the last row where every column still has a
//! value, then drops the first `int(0.1 · (last − first))` rows. It checks every column of the
//! file (pandas reads them all); propid checks the columns it uses (t, force, velocity,
//! acceleration), which gives the same window on files whose other columns are complete.

mod columns;
mod report;
mod scan;

pub use columns::{fit_columns, Columns};
use report::report_of;
pub use report::{figure, to_yaml, yaml_float};

use std::fs::File;
use std::io::BufRead;
use std::path::Path;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::OnceLock;

use propid_core::estimate::LoadEstimator;
use serde::Serialize;

use propid_io::tsv::{row_of, Layout, RowError, Sample, TsvReader, Values, ALL_SLOTS};
use propid_io::InputError;

use crate::plausibility::Reading;

/// What a fit is asked to do (checked once by [`FitOptions::check`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitOptions {
    /// Smallest (rotational) mass [kg] or [kg·m²].
    pub mass_min: f64,
    /// Largest (rotational) mass.
    pub mass_max: f64,
    /// Largest viscous coefficient c1; 0 (the seed's default) forbids viscous friction, infinity
    /// leaves it unbounded.
    pub c1_max: f64,
    /// Largest quadratic drag coefficient c2 (infinity: unbounded).
    pub c2_max: f64,
    /// Propeller diameter [m], to report the torque coefficient C_Q.
    pub diameter: Option<f64>,
    /// Air density [kg/m³] for C_Q.
    pub density: f64,
    /// How the columns are read (a reversed torque sign, a velocity in rpm).
    pub reading: Reading,
}

impl Default for FitOptions {
    /// The seed's bounds, no C_Q.
    fn default() -> Self {
        FitOptions {
            mass_min: 1e-9,
            mass_max: 1e3,
            c1_max: 0.0,
            c2_max: 1e2,
            diameter: None,
            density: 1.225,
            reading: Reading::default(),
        }
    }
}

impl FitOptions {
    /// Checks the bounds and the propeller's geometry once, before any data is read.
    pub fn check(&self) -> Result<(), InputError> {
        let b = self;
        if !(b.mass_min > 0.0 && b.mass_min.is_finite() && b.mass_min <= b.mass_max) {
            return Err(InputError::invalid(format!(
                "mass bounds must satisfy 0 < mass_min ≤ mass_max (got {} and {})",
                b.mass_min, b.mass_max
            )));
        }
        for (name, v) in [("c1_max", b.c1_max), ("c2_max", b.c2_max)] {
            if v.is_nan() || v < 0.0 {
                return Err(InputError::invalid(format!("{name} must be ≥ 0 (got {v})")));
            }
        }
        if let Some(d) = b.diameter {
            if !(d > 0.0 && d.is_finite()) {
                return Err(InputError::invalid(format!(
                    "the propeller diameter must be a positive length in metres (got {d})"
                )));
            }
        }
        if !(b.density > 0.0 && b.density.is_finite()) {
            return Err(InputError::invalid(format!(
                "the air density must be positive (got {} kg/m³)",
                b.density
            )));
        }
        Ok(())
    }
}

/// Why a fit failed.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// The data or the options cannot give a fit, or the TSV is malformed or could not be read
    /// (the error names file, line, column or option).
    #[error(transparent)]
    Input(#[from] InputError),
}

/// The result of a fit, as printed.
#[derive(Clone, Debug, Serialize)]
pub struct FitReport {
    /// Inertia [kg·m²].
    pub mass: f64,
    /// Viscous coefficient [N·m·s/rad].
    pub c1: f64,
    /// Quadratic drag coefficient [N·m·s²/rad²].
    pub c2: f64,
    /// Standard error of mass.
    pub mass_stderr: f64,
    /// Standard error of c1.
    pub c1_stderr: f64,
    /// Standard error of c2.
    pub c2_stderr: f64,
    /// RMS of the acceleration residual [rad/s²].
    pub rms: f64,
    /// Samples fitted (after the seed's trimming).
    pub samples: u64,
    /// Rows read.
    pub rows: u64,
    /// Condition number of the scaled normal matrix.
    pub condition_number: f64,
    /// Parameters sitting on a bound.
    pub at_bound: Vec<&'static str>,
    /// Free parameters the data do not identify (on a bound, or a standard error above 30 % of
    /// the value): their values are not measurements. A parameter on a bound has the standard
    /// error of the fit without bounds, never the 0 of an active bound.
    pub not_identified: Vec<&'static str>,
    /// Torque coefficient, when a diameter was given.
    pub c_q: Option<f64>,
    /// Warnings about the data (also printed on stderr).
    pub warnings: Vec<String>,
}

/// The seed's window of rows to fit: `[first, last]`, 0-based data-row indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Window {
    /// First row fitted.
    pub first: u64,
    /// Last row fitted.
    pub last: u64,
    /// Data rows in the file.
    pub rows: u64,
    /// Rows with finite t, force, velocity and acceleration in the whole file.
    pub complete: u64,
    /// First row of the last run of complete rows (the seed keeps only that run).
    pub run_start: u64,
    /// The incomplete row that ended the previous run, if complete rows came before it:
    /// (1-based line, column name).
    pub breaker: Option<(u64, &'static str)>,
}

impl Window {
    /// Complete rows the seed's trimming drops because an incomplete row came after them.
    pub fn dropped_complete(&self) -> u64 {
        self.complete - (self.last - self.run_start + 1)
    }
}

/// The first of t, force, velocity, acceleration that is not finite.
fn first_non_finite(s: &Sample) -> &'static str {
    let names = ["t", "force", "velocity", "acceleration"];
    let v = [s.t, s.force, s.velocity, s.acceleration];
    (0..4)
        .find(|i| !v[*i].is_finite())
        .map_or("t", |i| names[i])
}

fn is_complete(s: &Sample) -> bool {
    s.is_finite()
}

/// Pass 1: the seed's window.
pub fn find_window<R: BufRead>(reader: &mut TsvReader<R>) -> Result<Window, FitError> {
    let name = reader.source_name().to_string();
    let rows = std::iter::from_fn(|| match reader.next_row() {
        Ok(Some(row)) => Some(Ok((reader.line_number(), row.sample))),
        Ok(None) => None,
        Err(e) => Some(Err(FitError::from(e))),
    });
    window_of(rows, &name)
}

/// The seed's window over rows given in order as (1-based line, sample); `name` is the source in
/// messages.
fn window_of(
    samples: impl Iterator<Item = Result<(u64, Sample), FitError>>,
    name: &str,
) -> Result<Window, FitError> {
    let mut rows = 0u64;
    // Last row where each used column had a value (pandas' last_valid_index: non-NaN).
    let mut last_valid = [None::<u64>; 4];
    let mut run_start = None::<u64>;
    let mut run_end = None::<u64>;
    let mut complete = 0u64;
    let mut last_incomplete = None::<(u64, &'static str)>;
    let mut breaker = None;
    for row in samples {
        let (line, s) = row?;
        let i = rows;
        rows += 1;
        for (slot, v) in last_valid
            .iter_mut()
            .zip([s.t, s.force, s.velocity, s.acceleration])
        {
            if !v.is_nan() {
                *slot = Some(i);
            }
        }
        if is_complete(&s) {
            if run_end != Some(i.wrapping_sub(1)) || run_start.is_none() {
                run_start = Some(i);
                breaker = if complete > 0 { last_incomplete } else { None };
            }
            run_end = Some(i);
            complete += 1;
        } else {
            last_incomplete = Some((line, first_non_finite(&s)));
        }
    }
    if rows == 0 {
        return Err(InputError::invalid(format!("{name}: no data rows after the header")).into());
    }
    let (Some(start), Some(end)) = (run_start, run_end) else {
        return Err(InputError::invalid(format!(
            "{name}: no row has finite t, force, velocity and acceleration"
        ))
        .into());
    };
    let max_valid = last_valid.iter().map(|v| v.unwrap_or(0)).min().unwrap_or(0);
    // All rows after max_valid lack a value, so the last complete run ends at or before it.
    let last = end.min(max_valid);
    let first = start + (0.1 * (last - start) as f64) as u64;
    Ok(Window {
        first,
        last,
        rows,
        complete,
        run_start: start,
        breaker,
    })
}

/// Fits a TSV file with the seed's trimming and bounds. Returns the report and a decimated copy
/// of the fitted rows (for a plot). `progress` is called now and then with (bytes read, file size).
pub fn fit_path(
    path: &Path,
    options: &FitOptions,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<(FitReport, Vec<Sample>), FitError> {
    fit_path_with(path, options, true, progress)
}

/// [`fit_path`], with the plot's rows only if `want_samples` (they cost a second parse of the
/// fitted rows). `path` must be a regular file (it is memory-mapped).
pub fn fit_path_with(
    path: &Path,
    options: &FitOptions,
    want_samples: bool,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<(FitReport, Vec<Sample>), FitError> {
    options.check()?;
    let name = path.display().to_string();
    let file = File::open(path).map_err(|e| InputError::os(name.clone(), "cannot open", &e))?;
    let size = file.metadata().map(|m| m.len()).unwrap_or(0);
    let map = if size == 0 {
        None
    } else {
        // SAFETY: a read-only map of a file propid never writes. Another process shrinking
        // the file while it is mapped would make a read fault (SIGBUS); that is the caveat
        // every memory-mapping reader accepts, and the file is read once, start to end.
        let map = unsafe { memmap2::Mmap::map(&file) }
            .map_err(|e| InputError::os(name.clone(), "cannot map", &e))?;
        // Read-ahead hint (Unix only; elsewhere the OS's default is fine).
        #[cfg(unix)]
        let _ = map.advise(memmap2::Advice::Sequential);
        Some(map)
    };
    let data: &[u8] = map.as_deref().unwrap_or(&[]);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let chunks = if data.len() < 1 << 20 {
        1
    } else {
        threads.min(data.len() / (512 << 10)).max(1)
    };
    fit_bytes(
        data,
        map.as_ref(),
        &name,
        options,
        want_samples,
        chunks,
        progress,
    )
}

/// The velocity-glitch test ([`propid_io::glitch`]) over the file: the chunks' first passes
/// merged in order; the second, over the file again, only when a glitch may be there. The
/// glitches' rows are their lines.
fn velocity_glitches(
    data: &[u8],
    header_len: usize,
    layout: &propid_io::tsv::Layout,
    chunks: &[scan::Chunk],
) -> Option<propid_io::glitch::Glitches> {
    let (first, rest) = chunks.split_first()?;
    let mut scatter = first.glitches.clone();
    for c in rest {
        scatter.merge(&c.glitches);
    }
    if !scatter.may_have_glitches() {
        return None;
    }
    let limit = scatter.limit();
    let mut triples = propid_io::glitch::Triples::default();
    let mut found = propid_io::glitch::Glitches::default();
    // The velocity: slot 3.
    scan::lines(data, header_len, data.len(), |line, bytes, _| {
        if let Ok(Some(v)) = layout.parse_line_converting(bytes, 0b1000) {
            if let Some(d) = triples.push(line + 1, v[3]) {
                found.check(&d, limit);
            }
        }
        true
    });
    Some(found)
}

/// What `fit` says of velocity glitches at these lines (none: nothing).
pub(crate) fn glitch_warning(name: &str, found: &propid_io::glitch::Glitches) -> Option<String> {
    if found.rows.is_empty() {
        return None;
    }
    let shown: Vec<String> = found.rows.iter().take(10).map(u64::to_string).collect();
    Some(propid_io::glitch::tsv_sentence(
        name,
        found.rows.len(),
        found.largest,
        &format!("lines {}", shown.join(", ")),
        false,
        "`propid diagnose --despike`",
    ))
}

/// Fits the TSV in `data` (named `name` in messages). `map` is the mapping `data` comes from, if
/// any: pages already scanned are released from it.
fn fit_bytes(
    data: &[u8],
    map: Option<&memmap2::Mmap>,
    name: &str,
    options: &FitOptions,
    want_samples: bool,
    chunks: usize,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<(FitReport, Vec<Sample>), FitError> {
    let reader = TsvReader::new(data, name)?;
    let layout = reader.layout().clone();
    let header_len = reader.bytes_read() as usize;
    // A last row without a line end was cut while the file was written: not fitted, announced.
    let (data, cut) = propid_io::tsv::without_cut_line(data, header_len);
    let size = data.len() as u64;
    let pieces = scan::split(data, header_len, chunks);
    let done = AtomicU64::new(header_len as u64);
    // Each thread takes the next piece not yet taken: a thread that starts late (its core
    // busy) leaves its piece to the others instead of being waited for. The pieces, and so the
    // sums, do not depend on which thread scans them.
    let next = AtomicUsize::new(0);
    let scanned: Vec<OnceLock<Result<scan::Chunk, (u64, RowError)>>> =
        pieces.iter().map(|_| OnceLock::new()).collect();
    let work = |tick: &mut dyn FnMut()| loop {
        let k = next.fetch_add(1, Ordering::Relaxed);
        let Some(&(a, b)) = pieces.get(k) else {
            break;
        };
        let _ = scanned[k].set(scan::scan(data, a, b, &layout, map, &done, &mut *tick));
    };
    std::thread::scope(|s| {
        for _ in 1..pieces.len() {
            s.spawn(|| work(&mut || {}));
        }
        // This thread reports the progress of all.
        work(&mut || progress(done.load(Ordering::Relaxed), size));
    });
    let results: Vec<Result<scan::Chunk, (u64, RowError)>> = scanned
        .into_iter()
        .map(|c| {
            c.into_inner()
                .expect("every piece is scanned before the scope ends")
        })
        .collect();
    progress(size, size);
    // Chunk k's lines start after line_base[k]; its rows after row_base[k].
    let mut chunks = Vec::with_capacity(results.len());
    let (mut line_base, mut row_base) = (vec![], vec![]);
    let (mut lines, mut rows, mut complete) = (1u64, 0u64, 0u64);
    let mut copies = (0u64, None);
    for r in results {
        let c = r.map_err(|(line, e)| e.at(name, lines + line))?;
        copies.0 += c.copies.0;
        if copies.1.is_none() {
            copies.1 = c.copies.1.map(|l| lines + l);
        }
        line_base.push(lines);
        row_base.push(rows);
        lines += c.lines;
        rows += c.rows;
        complete += c.complete;
        chunks.push(c);
    }
    if rows == 0 {
        return Err(InputError::invalid(format!("{name}: no data rows after the header")).into());
    }
    let Some(last_chunk) = chunks.iter().rposition(|c| c.run_rows > 0) else {
        return Err(InputError::invalid(format!(
            "{name}: no row has finite t, force, velocity and acceleration"
        ))
        .into());
    };
    // The file's last run: the last chunk's, joined with the runs of the chunks before it as
    // long as they reach across the boundary.
    let mut parts = vec![last_chunk];
    let mut breaker = None;
    let mut k = last_chunk;
    while chunks[k].run_open_at_start {
        let Some(j) = (0..k).rev().find(|j| chunks[*j].rows > 0) else {
            break;
        };
        if chunks[j].last_row_complete {
            parts.push(j);
            k = j;
        } else {
            breaker = chunks[j]
                .last_incomplete
                .map(|(l, c)| (line_base[j] + l, c));
            break;
        }
    }
    if !chunks[k].run_open_at_start {
        breaker = chunks[k].breaker.map(|(l, c)| (line_base[k] + l, c));
    }
    parts.reverse();
    let run_start = row_base[parts[0]] + chunks[parts[0]].run_first_row;
    let run_rows: u64 = parts.iter().map(|k| chunks[*k].run_rows).sum();
    let last = run_start + run_rows - 1;
    let first = run_start + (0.1 * (last - run_start) as f64) as u64;
    let glitches = velocity_glitches(data, header_len, &layout, &chunks)
        .and_then(|found| glitch_warning(name, &found));
    let notes = |mut report: FitReport| {
        report.warnings.extend(glitches.clone());
        if cut {
            report
                .warnings
                .push(propid_io::tsv::cut_line_note(name, lines + 1));
        }
        if let (n @ 1.., Some(first)) = copies {
            report
                .warnings
                .push(propid_io::tsv::copies_note(name, n, first));
        }
        report
    };
    // A slow sensor (a load cell logged in one row of ten, NaN between) leaves the complete rows
    // one or two at a time, and the seed's window — the last run of them — a sample or two.
    // Then the complete rows are fitted instead, as diagnose uses them.
    let runs: u64 = chunks.iter().map(|c| c.runs).sum();
    if 2 * runs > complete && 2 * run_rows < complete {
        let sparse = Sparse {
            rows,
            complete,
            run_rows,
        };
        let (report, kept) = fit_sparse(
            data,
            header_len,
            &layout,
            name,
            options,
            sparse,
            want_samples,
        )?;
        return Ok((notes(report), kept));
    }
    let window = Window {
        first,
        last,
        rows,
        complete,
        run_start,
        breaker: if complete > run_rows { breaker } else { None },
    };
    // The sums of rows first..=last: the block the cut falls in is parsed again.
    let blocks = parts
        .iter()
        .flat_map(|k| chunks[*k].run.blocks.iter().map(|b| (line_base[*k], b)));
    let resum = |b: &scan::Block, skip: u64| {
        let mut est = LoadEstimator::new();
        walk(
            data,
            b.offset,
            skip,
            b.rows - skip,
            &layout,
            scan::FIT_SLOTS,
            |_, v| {
                est.update(v[2], v[3], v[4]);
            },
        );
        est
    };
    let (total, start) = scan::sums_from(blocks, first - run_start, resum).unzip();
    let start = start.unwrap_or((0, 0, 0)); // (offset, line, rows to skip there)
    let estimator = total.unwrap_or_default();
    let n = last - first + 1;
    // Rows of the window, in order, with their line numbers.
    let window_rows = |convert: u16, f: &mut dyn FnMut(u64, &Values)| {
        let (offset, line, skip) = start;
        walk(data, offset, skip, n, &layout, convert, |l, v| {
            f(line + l - 1, v)
        });
    };
    if !sums_finite(&estimator) {
        let mut est = LoadEstimator::new();
        let mut overflow = None;
        window_rows(scan::FIT_SLOTS, &mut |line, v| {
            est.update(v[2], v[3], v[4]);
            if overflow.is_none() && !sums_finite(&est) {
                overflow = Some((line, row_of(v).sample));
            }
        });
        if let Some((line, s)) = overflow {
            return Err(overflow_error(name, line, &s).into());
        }
    }
    // The plausibility gate's stretch of rows: the window's first GATE_ROWS, in order.
    let mut gate = Vec::new();
    let (offset, _, skip) = start;
    walk(
        data,
        offset,
        skip,
        n.min(GATE_ROWS),
        &layout,
        ALL_SLOTS,
        |_, v| gate.push(row_of(v).sample),
    );
    let report = notes(report_of(&estimator, options, window, name, &gate)?);
    let mut kept = Vec::new();
    if want_samples {
        let keep_every = (n / 4000).max(1);
        let mut i = 0u64;
        window_rows(ALL_SLOTS, &mut |_, v| {
            if i % keep_every == 0 {
                let mut sample = row_of(v).sample;
                options.reading.apply(&mut sample);
                kept.push(sample);
            }
            i += 1;
        });
    }
    Ok((report, kept))
}

/// What [`fit_sparse`] needs to know of the file's first pass.
struct Sparse {
    rows: u64,
    complete: u64,
    run_rows: u64,
}

/// The fit of a file whose complete rows come one or two at a time (a slow sensor): every
/// complete row after the seed's 10 % cut (of the complete rows), in one more pass, with a
/// warning that says so.
fn fit_sparse(
    data: &[u8],
    from: usize,
    layout: &Layout,
    name: &str,
    options: &FitOptions,
    sparse: Sparse,
    want_samples: bool,
) -> Result<(FitReport, Vec<Sample>), FitError> {
    let first = (0.1 * (sparse.complete - 1) as f64) as u64;
    let keep_every = ((sparse.complete - first) / 4000).max(1);
    let mut estimator = LoadEstimator::new();
    let (mut row, mut complete, mut first_row, mut last_row) = (0u64, 0u64, 0u64, 0u64);
    let mut overflow = None;
    let mut kept = Vec::new();
    scan::lines(data, from, data.len(), |line, bytes, _| {
        // Every line parsed without error in the first pass.
        let Ok(Some(v)) = layout.parse_line_converting(bytes, ALL_SLOTS) else {
            return true;
        };
        row += 1;
        if scan::incomplete(&v).is_some() {
            return true;
        }
        complete += 1;
        if complete <= first {
            return true;
        }
        if complete == first + 1 {
            first_row = row - 1;
        }
        last_row = row - 1;
        estimator.update(v[2], v[3], v[4]);
        if overflow.is_none() && !sums_finite(&estimator) {
            overflow = Some((line + 1, row_of(&v).sample));
        }
        if want_samples && (complete - 1 - first) % keep_every == 0 {
            let mut sample = row_of(&v).sample;
            options.reading.apply(&mut sample);
            kept.push(sample);
        }
        true
    });
    if let Some((line, s)) = overflow {
        return Err(overflow_error(name, line, &s).into());
    }
    let window = Window {
        first: first_row,
        last: last_row,
        rows: sparse.rows,
        complete: sparse.complete,
        run_start: first_row,
        breaker: None,
    };
    // Rows one or two at a time are no stretch to integrate the acceleration over: only the
    // torque sign is checked.
    let mut report = report_of(&estimator, options, window, name, &[])?;
    report.warnings.insert(
        0,
        format!(
            "{name}: only {} of {} rows have t, force, velocity and acceleration, and they come one or two at a time (a slow sensor such as a load cell, NaN between its samples): the seed's window, the last run of complete rows, would hold {} row(s); fitted instead are the {} complete rows after the seed's 10 % cut, as diagnose uses them",
            sparse.complete,
            sparse.rows,
            sparse.run_rows,
            sparse.complete - first
        ),
    );
    Ok((report, kept))
}

/// Calls `f(local line, values)` for `rows` rows after the first `skip` rows from `offset`
/// (blank lines skipped; the rows were parsed once already, so none fails; the skipped ones are
/// not parsed again), converting the slots in `convert` ([`Layout::parse_line_converting`]).
fn walk(
    data: &[u8],
    offset: usize,
    skip: u64,
    rows: u64,
    layout: &Layout,
    convert: u16,
    mut f: impl FnMut(u64, &Values),
) {
    let (mut skip, mut left) = (skip, rows);
    if left == 0 {
        return;
    }
    scan::lines(data, offset, data.len(), |line, bytes, _| {
        if skip > 0 {
            skip -= u64::from(Layout::is_row(bytes));
            return true;
        }
        if let Ok(Some(v)) = layout.parse_line_converting(bytes, convert) {
            f(line, &v);
            left -= 1;
        }
        left > 0
    });
}

/// True if every sum of the normal equations is finite.
fn sums_finite(estimator: &LoadEstimator<f64>) -> bool {
    let e = estimator.equations();
    e.matrix().iter().flatten().all(|v| v.is_finite())
        && e.vector().iter().all(|v| v.is_finite())
        && e.sum_y_squared().is_finite()
}

/// The error for the row at which the sums stop being finite.
fn overflow_error(name: &str, line: u64, s: &Sample) -> InputError {
    InputError::invalid(format!(
        "{name}: line {line}: the sums of squares overflow a 64-bit float at this row \
         (force {:e}, velocity {:e}, acceleration {:e}): a value this large is not a measurement; \
         remove the row or rescale the data",
        s.force, s.velocity, s.acceleration
    ))
}

/// Rows of the window the plausibility gate integrates the acceleration over (the first ones):
/// enough for any unit mistake, cheap beside a multi-million-row fit.
const GATE_ROWS: u64 = 100_000;

#[cfg(test)]
mod tests {
    use super::*;

    /// The two-pass streaming reference (the seed's window found first, then summed in order).
    fn reference(text: &str) -> Result<(Window, LoadEstimator<f64>), String> {
        let mut r = TsvReader::new(text.as_bytes(), "mem").map_err(|e| e.to_string())?;
        let w = find_window(&mut r).map_err(|e| e.to_string())?;
        let mut r = TsvReader::new(text.as_bytes(), "mem").unwrap();
        let mut est = LoadEstimator::new();
        let mut i = 0;
        while let Some(row) = r.next_row().unwrap() {
            if i >= w.first && i <= w.last {
                est.update(
                    row.sample.force,
                    row.sample.velocity,
                    row.sample.acceleration,
                );
            }
            i += 1;
        }
        Ok((w, est))
    }

    /// The one-pass chunked scan gives the two-pass answer whatever the chunks, with incomplete
    /// rows and blank lines anywhere (head, middle, chunk borders, tail).
    #[test]
    fn chunked_scan_matches_the_two_pass_reference() {
        let holes: [&[usize]; 7] = [
            &[],
            &[0, 1, 2],
            &[700],
            &[100, 3000, 3001, 5900],
            &[5999],
            &[2000, 2001, 2002, 2003, 4000],
            &[5, 6, 5997, 5998, 5999],
        ];
        let options = FitOptions {
            c1_max: f64::INFINITY,
            ..FitOptions::default()
        };
        for (h, hole) in holes.iter().enumerate() {
            let mut text = String::from("t\tforce\tvelocity\tacceleration\n");
            let mut w = 3.0f64;
            for i in 0..6000usize {
                let q = 1.0 + (i as f64 * 0.01).sin();
                let a = (q - 0.1 * w - 0.02 * w * w.abs()) / 0.5 + (i as f64 * 7.7).sin() * 0.01;
                // t in seconds, as the velocity is integrated (the plausibility gate checks it).
                let t = i as f64 * 0.005;
                if hole.contains(&i) {
                    text += &format!("{t}\t{q}\tnan\t{a}\n");
                } else {
                    text += &format!("{t}\t{q}\t{w}\t{a}\n");
                }
                if i % 977 == 0 {
                    text += "\n \t\n";
                }
                w += a * 0.005;
            }
            let (want_window, want) = reference(&text).unwrap();
            for chunks in [1, 2, 3, 5, 8, 64] {
                let (report, samples) = fit_bytes(
                    text.as_bytes(),
                    None,
                    "mem",
                    &options,
                    true,
                    chunks,
                    &mut |_, _| {},
                )
                .unwrap();
                let got = report_of(&want, &options, want_window, "mem", &[]).unwrap();
                assert_eq!(report.samples, want_window.last - want_window.first + 1);
                assert_eq!(report.rows, 6000);
                assert_eq!(report.warnings, got.warnings, "holes {h}, {chunks} chunks");
                // Sums equal to rounding (compensated in both, added in another order); the
                // solve amplifies that by at most the condition number.
                let tol = got.condition_number * 1e-15;
                for (a, b) in [
                    (report.mass, got.mass),
                    (report.c1, got.c1),
                    (report.c2, got.c2),
                ] {
                    assert!(
                        (a - b).abs() <= tol * b.abs(),
                        "holes {h}, {chunks} chunks: {a} vs {b} (condition number {})",
                        got.condition_number
                    );
                }
                assert!(!samples.is_empty());
            }
        }
    }

    /// YAML 1.1's float pattern (the one PyYAML resolves), by hand:
    /// `[-+]?([0-9][0-9_]*)?\.[0-9.]*([eE][-+][0-9]+)?`, or `[-+]?\.(inf|Inf|INF)`, `\.(nan|NaN|NAN)`.
    fn yaml11_float(s: &str) -> bool {
        if matches!(s, ".nan" | ".NaN" | ".NAN") {
            return true;
        }
        let s = s.strip_prefix(['-', '+']).unwrap_or(s);
        if matches!(s, ".inf" | ".Inf" | ".INF") {
            return true;
        }
        let (mantissa, exponent) = match s.find(['e', 'E']) {
            Some(i) => (&s[..i], Some(&s[i + 1..])),
            None => (s, None),
        };
        let Some(dot) = mantissa.find('.') else {
            return false;
        };
        let (int, frac) = (&mantissa[..dot], &mantissa[dot + 1..]);
        let int_ok = int.is_empty()
            || (int.as_bytes()[0].is_ascii_digit()
                && int.bytes().all(|b| b.is_ascii_digit() || b == b'_'));
        let frac_ok = frac.bytes().all(|b| b.is_ascii_digit() || b == b'.');
        let exp_ok = exponent.is_none_or(|e| {
            let digits = e.strip_prefix(['-', '+']);
            digits.is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
        });
        int_ok && frac_ok && exp_ok
    }

    #[test]
    fn yaml_floats_match_the_yaml_1_1_float_pattern_and_round_trip() {
        assert!(
            !yaml11_float("2.827626e2"),
            "the old output is a string in YAML 1.1"
        );
        assert!(!yaml11_float("0.000000000e0"));
        assert!(yaml11_float("2.827626e+02"));
        for v in [
            0.0,
            -0.0,
            282.7626,
            -1e-9,
            1.5e-8,
            1e300,
            f64::MIN_POSITIVE,
            f64::MAX,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            7.0,
        ] {
            for digits in [0, 3, 6, 9] {
                let text = yaml_float(v, digits);
                assert!(yaml11_float(&text), "{v} → `{text}`");
                if v.is_finite() {
                    let back: f64 = text.parse().unwrap();
                    let want: f64 = format!("{v:.digits$e}").parse().unwrap();
                    assert_eq!(back, want, "{v} → `{text}`");
                }
            }
        }
        assert_eq!(yaml_float(282.7626, 6), "2.827626e+02");
        assert_eq!(yaml_float(0.0, 9), "0.000000000e+00");
        assert_eq!(yaml_float(-0.0, 3), "0.000e+00");
        assert_eq!(yaml_float(2e-5, 3), "2.000e-05");
        assert_eq!(yaml_float(1e300, 3), "1.000e+300");
    }
}
