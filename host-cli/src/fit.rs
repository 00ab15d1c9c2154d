//! `propid fit`: the seed regressor, exact and in constant memory.
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
use std::io::{BufRead, BufReader, Read, Seek, Write};
use std::path::{Path, PathBuf};

use anyhow::Context;
use propid_core::estimate::{LoadBounds, LoadEstimate, LoadEstimator, SolveError};
use serde::Serialize;

use crate::plot::{Figure, Panel, Series, Style};
use crate::tsv::{Sample, TsvReader};
use crate::InputError;

/// Output format of `propid fit`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// The seed's YAML keys (mass, c1, c2) with units, plus standard errors and the RMS.
    Yaml,
    /// The same as a JSON object.
    Json,
}

/// Arguments of `propid fit`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The TSV to fit (columns t, force, velocity, acceleration by header name); `-` or nothing
    /// reads standard input.
    pub file: Option<PathBuf>,
    /// Smallest (rotational) mass [kg] or [kg·m²].
    #[arg(long, default_value_t = 1e-9)]
    pub mass_min: f64,
    /// Largest (rotational) mass [kg] or [kg·m²].
    #[arg(long, default_value_t = 1e3)]
    pub mass_max: f64,
    /// Largest viscous coefficient c1 [N·s/m] or [N·m·s/rad]; 0 (the seed's default) forbids
    /// viscous friction.
    #[arg(long, default_value_t = 0.0)]
    pub c1_max: f64,
    /// Largest quadratic drag coefficient c2 [N·s²/m²] or [N·m·s²/rad²].
    #[arg(long, default_value_t = 1e2)]
    pub c2_max: f64,
    /// Propeller diameter [m]: also report the torque coefficient C_Q = 4π²·c2/(ρ·D⁵).
    #[arg(long)]
    pub diameter: Option<f64>,
    /// Air density [kg/m³] for C_Q.
    #[arg(long, default_value_t = 1.225)]
    pub density: f64,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Yaml)]
    pub format: Format,
    /// Write a plot of measured vs predicted acceleration and the force (.svg, .png or .html).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Show a progress bar on stderr (on by default for inputs over 50 MB).
    #[arg(long)]
    pub progress: bool,
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
pub fn find_window<R: BufRead>(reader: &mut TsvReader<R>) -> Result<Window, anyhow::Error> {
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

/// Fits a TSV file with the seed's trimming and bounds; `plot` gets a decimated copy of the data.
pub fn fit_path(path: &Path, args: &Args) -> anyhow::Result<(FitReport, Vec<Sample>)> {
    let name = path.display().to_string();
    let open = || -> anyhow::Result<TsvReader<BufReader<File>>> {
        let f = File::open(path).map_err(|e| InputError(format!("{name}: cannot open: {e}")))?;
        Ok(TsvReader::new(
            BufReader::with_capacity(1 << 16, f),
            name.clone(),
        )?)
    };
    let size = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    let mut reader = open()?;
    let window = find_window(&mut reader)?;
    let progress = (args.progress || size > 50 << 20).then(|| {
        let bar = indicatif::ProgressBar::new(size);
        bar.set_style(
            indicatif::ProgressStyle::with_template("fit {bar:40} {bytes}/{total_bytes} {eta}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar
    });
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
        if let Some(bar) = &progress {
            if i % 65536 == 0 {
                bar.set_position(reader.bytes_read());
            }
        }
    }
    if let Some(bar) = progress {
        bar.finish_and_clear();
    }
    let report = report_of(&estimator, args, window, &name)?;
    Ok((report, kept))
}

fn report_of(
    estimator: &LoadEstimator<f64>,
    args: &Args,
    window: Window,
    name: &str,
) -> anyhow::Result<FitReport> {
    let n = estimator.count() as u64;
    if n < 10 {
        return Err(InputError(format!(
            "{name}: only {n} usable samples after trimming (rows {}..={} of {}); at least 10 are needed",
            window.first + 1,
            window.last + 1,
            window.rows
        ))
        .into());
    }
    let bounds = LoadBounds {
        mass_min: args.mass_min,
        mass_max: args.mass_max,
        c1_max: args.c1_max,
        c2_max: args.c2_max,
    };
    if !(bounds.mass_min > 0.0
        && bounds.mass_min <= bounds.mass_max
        && bounds.c1_max >= 0.0
        && bounds.c2_max >= 0.0)
    {
        return Err(InputError(format!(
            "invalid bounds: need 0 < --mass-min ≤ --mass-max, --c1-max ≥ 0, --c2-max ≥ 0 (got {bounds:?})"
        ))
        .into());
    }
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

/// Runs `propid fit`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let from_stdin = args.file.as_deref().is_none_or(|p| p == Path::new("-"));
    // Standard input is spooled to a temporary file: two passes in constant memory.
    let spool;
    let path: &Path = if from_stdin {
        let mut tmp = tempfile::NamedTempFile::new().context("cannot create a temporary file")?;
        let mut stdin = std::io::stdin().lock();
        let mut buf = vec![0u8; 1 << 16];
        loop {
            let n = stdin.read(&mut buf).context("reading standard input")?;
            if n == 0 {
                break;
            }
            tmp.write_all(&buf[..n])
                .context("spooling standard input")?;
        }
        tmp.flush()?;
        tmp.as_file_mut().rewind()?;
        spool = tmp;
        spool.path()
    } else {
        args.file.as_deref().unwrap_or(Path::new("-"))
    };
    let (report, samples) = fit_path(path, &args).map_err(|e| {
        if from_stdin {
            // Name standard input, not the spool file, in messages.
            let message = format!("{e:#}").replace(&path.display().to_string(), "<stdin>");
            if crate::exit_status_for(&e) == 2 {
                InputError(message).into()
            } else {
                anyhow::anyhow!(message)
            }
        } else {
            e
        }
    })?;
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(plot) = &args.plot {
        crate::plot::write(plot, &figure(&report, &samples))?;
        eprintln!("plot written to {}", plot.display());
    }
    let text = match args.format {
        Format::Yaml => to_yaml(&report),
        Format::Json => serde_json::to_string_pretty(&report)? + "\n",
    };
    std::io::stdout().write_all(text.as_bytes())?;
    Ok(())
}
