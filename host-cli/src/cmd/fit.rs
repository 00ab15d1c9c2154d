//! `propid fit`: the seed regressor as a command, around [`propid_science::fit::fit_path`].

use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

use anyhow::Context;
use propid_science::fit::{figure, fit_path, to_yaml, FitOptions};

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

impl Args {
    /// The fit's options.
    pub fn options(&self) -> FitOptions {
        FitOptions {
            mass_min: self.mass_min,
            mass_max: self.mass_max,
            c1_max: self.c1_max,
            c2_max: self.c2_max,
            diameter: self.diameter,
            density: self.density,
        }
    }
}

fn size_of(path: &Path) -> u64 {
    std::fs::metadata(path).map(|m| m.len()).unwrap_or(0)
}

fn progress_bar() -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template("fit {bar:40} {bytes}/{total_bytes} {eta}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
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
    let options = args.options();
    let bar = (args.progress || size_of(path) > 50 << 20).then(progress_bar);
    let mut on_progress = |done: u64, total: u64| {
        if let Some(bar) = &bar {
            bar.set_length(total);
            bar.set_position(done);
        }
    };
    let result = fit_path(path, &options, &mut on_progress);
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    let (report, samples) = result.map_err(anyhow::Error::from).map_err(|e| {
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
