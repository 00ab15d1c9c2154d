//! The seed regressor, exact and in constant memory.
//!
//! ## How data flows
//! ```text
//!  TSV file (or stdin, spooled to a temporary file)
//!    pass 1: count rows, find the seed's window (last complete run of rows, minus its first 10 %)
//!    pass 2: rows in the window ─► LoadEstimator::update (fixed memory) + a decimated copy for the plot
//!    ─► LoadEstimator::estimate(bounds) ─► YAML/JSON on stdout, plot to a file
//! ```
//! The window reproduces the seed exactly: the seed keeps the rows from the start of the last
//! run of rows whose every field is finite up to the last row where every column still has a
//! value, then drops the first `int(0.1 · (last − first))` rows. It checks every column of the
//! file (pandas reads them all); propid checks the columns it uses (t, force, velocity,
//! acceleration), which gives the same window on files whose other columns are complete.

use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::Path;

use propid_core::estimate::{LoadBounds, LoadEstimate, LoadEstimator, SolveError};
use serde::Serialize;

use propid_io::tsv::{Sample, TsvError, TsvReader};
use propid_io::InputError;

use crate::figure::{Figure, Panel, Series, Style};

/// What a fit is asked to do (checked once by [`FitOptions::check`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitOptions {
    /// Smallest (rotational) mass [kg] or [kg·m²].
    pub mass_min: f64,
    /// Largest (rotational) mass.
    pub mass_max: f64,
    /// Largest viscous coefficient c1; 0 (the seed's default) forbids viscous friction.
    pub c1_max: f64,
    /// Largest quadratic drag coefficient c2.
    pub c2_max: f64,
    /// Propeller diameter [m], to report the torque coefficient C_Q.
    pub diameter: Option<f64>,
    /// Air density [kg/m³] for C_Q.
    pub density: f64,
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
        }
    }
}

impl FitOptions {
    /// Checks the bounds and the propeller's geometry once, before any data is read.
    pub fn check(&self) -> Result<(), InputError> {
        let b = self;
        if !(b.mass_min > 0.0 && b.mass_min <= b.mass_max && !b.mass_max.is_nan()) {
            return Err(InputError(format!(
                "mass bounds must satisfy 0 < mass_min ≤ mass_max (got {} and {})",
                b.mass_min, b.mass_max
            )));
        }
        for (name, v) in [("c1_max", b.c1_max), ("c2_max", b.c2_max)] {
            if v.is_nan() || v < 0.0 {
                return Err(InputError(format!("{name} must be ≥ 0 (got {v})")));
            }
        }
        if let Some(d) = b.diameter {
            if !(d > 0.0 && d.is_finite()) {
                return Err(InputError(format!(
                    "the propeller diameter must be a positive length in metres (got {d})"
                )));
            }
        }
        if !(b.density > 0.0 && b.density.is_finite()) {
            return Err(InputError(format!(
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
    /// The data or the options cannot give a fit (the message names file, line or option).
    #[error(transparent)]
    Input(#[from] InputError),
    /// The TSV is malformed or could not be read.
    #[error(transparent)]
    Tsv(#[from] TsvError),
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
}

fn is_complete(s: &Sample) -> bool {
    s.is_finite()
}

/// Pass 1: the seed's window.
pub fn find_window<R: BufRead>(reader: &mut TsvReader<R>) -> Result<Window, FitError> {
    let mut rows = 0u64;
    // Last row where each used column had a value (pandas' last_valid_index: non-NaN).
    let mut last_valid = [None::<u64>; 4];
    let mut run_start = None::<u64>;
    let mut run_end = None::<u64>;
    while let Some(row) = reader.next_row()? {
        let i = rows;
        rows += 1;
        let s = row.sample;
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
            }
            run_end = Some(i);
        }
    }
    if rows == 0 {
        return Err(InputError(format!(
            "{}: no data rows after the header",
            reader.source_name()
        ))
        .into());
    }
    let (Some(start), Some(end)) = (run_start, run_end) else {
        return Err(InputError(format!(
            "{}: no row has finite t, force, velocity and acceleration",
            reader.source_name()
        ))
        .into());
    };
    let max_valid = last_valid.iter().map(|v| v.unwrap_or(0)).min().unwrap_or(0);
    // All rows after max_valid lack a value, so the last complete run ends at or before it.
    let last = end.min(max_valid);
    let first = start + (0.1 * (last - start) as f64) as u64;
    Ok(Window { first, last, rows })
}

/// Fits a TSV file with the seed's trimming and bounds. Returns the report and a decimated copy
/// of the fitted rows (for a plot). `progress` is called now and then with (bytes read, file size)
/// during the second pass.
pub fn fit_path(
    path: &Path,
    options: &FitOptions,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<(FitReport, Vec<Sample>), FitError> {
    options.check()?;
    let name = path.display().to_string();
    let open = || -> Result<TsvReader<BufReader<File>>, FitError> {
        let f = File::open(path).map_err(|e| InputError(format!("{name}: cannot open: {e}")))?;
        Ok(TsvReader::new(
            BufReader::with_capacity(1 << 16, f),
            name.clone(),
        )?)
    };
    let size = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    let mut reader = open()?;
    let window = find_window(&mut reader)?;
    let mut reader = open()?;
    let mut estimator = LoadEstimator::<f64>::new();
    let keep_every = ((window.last - window.first + 1) / 4000).max(1);
    let mut kept = Vec::new();
    let mut i = 0u64;
    while let Some(row) = reader.next_row()? {
        if i >= window.first && i <= window.last {
            let s = row.sample;
            estimator.update(s.force, s.velocity, s.acceleration);
            if (i - window.first) % keep_every == 0 {
                kept.push(s);
            }
        }
        i += 1;
        if i > window.last {
            break;
        }
        if i % 65536 == 0 {
            progress(reader.bytes_read(), size);
        }
    }
    progress(size, size);
    let report = report_of(&estimator, options, window, &name)?;
    Ok((report, kept))
}

fn report_of(
    estimator: &LoadEstimator<f64>,
    args: &FitOptions,
    window: Window,
    name: &str,
) -> Result<FitReport, InputError> {
    let n = estimator.count() as u64;
    if n < 10 {
        return Err(InputError(format!(
            "{name}: only {n} usable samples after trimming (rows {}..={} of {}); at least 10 are needed",
            window.first + 1,
            window.last + 1,
            window.rows
        )));
    }
    let bounds = LoadBounds {
        mass_min: args.mass_min,
        mass_max: args.mass_max,
        c1_max: args.c1_max,
        c2_max: args.c2_max,
    };
    let names = ["force", "velocity", "velocity·|velocity|"];
    let est: LoadEstimate<f64> = estimator.estimate(&bounds).map_err(|e| match e {
        SolveError::NoExcitation { regressor } => InputError(format!(
            "{name}: `{}` is zero in every sample: the data cannot identify {}",
            names[regressor],
            ["the mass", "c1", "c2"][regressor]
        )),
        SolveError::TooFewSamples => InputError(format!("{name}: too few samples")),
        SolveError::Singular => InputError(format!(
            "{name}: the regressors are linearly dependent: the excitation does not identify mass, c1 and c2"
        )),
        SolveError::Infeasible => InputError(format!("{name}: the bounds admit no solution")),
    })?;
    let mut warnings = Vec::new();
    if est.condition_number > 1e8 {
        let rel = [
            est.mass_stderr / est.mass.abs(),
            est.c1_stderr / est.c1.abs().max(f64::MIN_POSITIVE),
            est.c2_stderr / est.c2.abs().max(f64::MIN_POSITIVE),
        ];
        let worst = (0..3)
            .max_by(|a, b| rel[*a].total_cmp(&rel[*b]))
            .unwrap_or(0);
        warnings.push(format!(
            "poor excitation (condition number {:.3e}): the data can hardly identify {}",
            est.condition_number,
            ["mass", "c1", "c2"][worst]
        ));
    }
    let at_bound = ["mass", "c1", "c2"]
        .iter()
        .zip(est.at_bound)
        .filter(|(_, b)| *b)
        .map(|(n, _)| *n)
        .collect();
    let c_q = args
        .diameter
        .map(|d| 4.0 * std::f64::consts::PI.powi(2) * est.c2 / (args.density * d.powi(5)));
    Ok(FitReport {
        mass: est.mass,
        c1: est.c1,
        c2: est.c2,
        mass_stderr: est.mass_stderr,
        c1_stderr: est.c1_stderr,
        c2_stderr: est.c2_stderr,
        rms: est.rms,
        samples: n,
        rows: window.rows,
        condition_number: est.condition_number,
        at_bound,
        c_q,
        warnings,
    })
}

/// The report as the seed's YAML (same keys and unit comments), plus propid's extras.
pub fn to_yaml(r: &FitReport) -> String {
    let mut s = String::new();
    s += &format!("mass: {:.9e} # [kg] | [kg*m^2]\n", r.mass + 0.0);
    s += &format!("c1:   {:.9e} # [N*s/m] | [N*m*s/rad]\n", r.c1 + 0.0);
    s += &format!("c2:   {:.9e} # [N*s^2/m^2] | [N*m*s^2/rad^2]\n", r.c2);
    s += &format!("mass_stderr: {:.3e}\n", r.mass_stderr);
    s += &format!("c1_stderr: {:.3e}\n", r.c1_stderr);
    s += &format!("c2_stderr: {:.3e}\n", r.c2_stderr);
    s += &format!(
        "rms: {:.6e} # acceleration residual [m/s^2] | [rad/s^2]\n",
        r.rms
    );
    s += &format!("samples: {}\n", r.samples);
    s += &format!("condition_number: {:.3e}\n", r.condition_number);
    s += &format!("at_bound: [{}]\n", r.at_bound.join(", "));
    if let Some(cq) = r.c_q {
        s += &format!("c_q: {cq:.6e} # propeller torque coefficient\n");
    }
    s
}

/// The plot: measured vs predicted acceleration, and the force, over time.
pub fn figure(r: &FitReport, samples: &[Sample]) -> Figure {
    let t: Vec<f64> = samples.iter().map(|s| s.t).collect();
    let predicted = samples
        .iter()
        .map(|s| (s.force - r.c1 * s.velocity - r.c2 * s.velocity * s.velocity.abs()) / r.mass)
        .collect();
    Figure {
        title: format!(
            "propid fit: J = {:.4e} kg·m², c1 = {:.3e}, c2 = {:.4e} (RMS {:.3e} rad/s²)",
            r.mass, r.c1, r.c2, r.rms
        ),
        x_label: "t [s]".into(),
        panels: vec![
            Panel {
                title: "acceleration: measured vs model".into(),
                y_label: "dω/dt [rad/s²]".into(),
                series: vec![
                    Series {
                        name: "measured".into(),
                        x: t.clone(),
                        y: samples.iter().map(|s| s.acceleration).collect(),
                        style: Style::Points,
                    },
                    Series {
                        name: "model (F − c1·ω − c2·ω|ω|)/J".into(),
                        x: t.clone(),
                        y: predicted,
                        style: Style::Line,
                    },
                ],
            },
            Panel {
                title: "force (torque)".into(),
                y_label: "Q [N·m]".into(),
                series: vec![Series {
                    name: "force".into(),
                    x: t,
                    y: samples.iter().map(|s| s.force).collect(),
                    style: Style::Line,
                }],
            },
        ],
    }
}
