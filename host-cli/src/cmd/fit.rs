//! `propid fit`: the seed regressor as a command, around [`propid_science::fit::fit_path`].

use std::io::Write;
use std::path::{Path, PathBuf};

use propid_science::fit::{figure, fit_path_with, to_yaml, FitError, FitOptions};
use propid_science::result::Outcome;

use propid_io::input::Mappable;

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
    #[arg(long, default_value_t = 1e-9, allow_negative_numbers = true)]
    pub mass_min: f64,
    /// Largest (rotational) mass [kg] or [kg·m²].
    #[arg(long, default_value_t = 1e3, allow_negative_numbers = true)]
    pub mass_max: f64,
    /// Largest viscous coefficient c1 [N·s/m] or [N·m·s/rad]; 0 (the seed's default) forbids
    /// viscous friction.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub c1_max: f64,
    /// Largest quadratic drag coefficient c2 [N·s²/m²] or [N·m·s²/rad²].
    #[arg(long, default_value_t = 1e2, allow_negative_numbers = true)]
    pub c2_max: f64,
    /// The propeller and air: also report the torque coefficient C_Q = 4π²·c2/(ρ·D⁵).
    #[command(flatten)]
    pub propeller: super::PropellerArgs,
    /// How the columns are read.
    #[command(flatten)]
    pub reading: super::ReadingArgs,
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
    /// The fit's options (a bare diameter outside 0.02–3 m is refused).
    pub fn options(&self) -> Result<FitOptions, propid_io::InputError> {
        let (diameter, density) = self.propeller.resolve()?;
        Ok(FitOptions {
            mass_min: self.mass_min,
            mass_max: self.mass_max,
            c1_max: self.c1_max,
            c2_max: self.c2_max,
            diameter,
            density,
            reading: self.reading.reading(),
        })
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

/// The file's time, speed and thrust when it has a `thrust` column (read again: the fit itself
/// keeps no rows), for the Result's C_T.
fn thrust(
    path: &Path,
    reading: &propid_science::plausibility::Reading,
) -> Result<Option<propid_science::propulsion::Recording>, propid_io::InputError> {
    let input = propid_io::input::open(path)?;
    let name = input.name().to_owned();
    let header = propid_io::tsv::TsvReader::new(input, name)?;
    if !header.has(propid_io::tsv::StandColumn::Thrust) {
        return Ok(None);
    }
    let table = propid_io::tsv::read_rows(path, |_| true)?;
    Ok(propid_science::propulsion::read::thrust_of_rows(
        &table.rows,
        &table.stand_columns,
        reading,
    ))
}

/// Runs `propid fit`.
pub fn run(args: Args) -> anyhow::Result<()> {
    // Flags first: a bad bound or geometry is reported before any input is read.
    let options = args.options()?;
    options.check()?;
    // A regular uncompressed file is mapped as it is. Anything else — standard input, a pipe
    // (`<(…)`, a FIFO), a gzip file — is spooled through propid_io::input (decompressed, its
    // lines bounded, so `/dev/zero` stops at once) to a temporary file, then mapped.
    let input = Mappable::new(args.file.as_deref().unwrap_or(Path::new("-")))?;
    let path = input.path();
    let bar = (args.progress || size_of(path) > 50 << 20).then(progress_bar);
    let mut on_progress = |done: u64, total: u64| {
        if let Some(bar) = &bar {
            bar.set_length(total);
            bar.set_position(done);
        }
    };
    let result = fit_path_with(path, &options, args.plot.is_some(), &mut on_progress);
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    let (report, samples) = result.map_err(|FitError::Input(e)| input.rename(e))?;
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(plot) = &args.plot {
        crate::plot::write(plot, &figure(&report, &samples))?;
        eprintln!("plot written to {}", plot.display());
    }
    // The Result, for a person, after the warnings; standard output keeps the seed's keys.
    let mut outcome = Outcome::from_fit(&report, options.c1_max > 0.0, args.propeller.air()?);
    if let Some(rec) = thrust(path, &options.reading).map_err(|e| input.rename(e))? {
        outcome.add_thrust(&rec);
    }
    for w in outcome
        .warnings
        .iter()
        .filter(|w| !report.warnings.contains(w))
    {
        eprintln!("warning: {w}");
    }
    eprint!("{}", outcome.to_text());
    let text = match args.format {
        Format::Yaml => to_yaml(&report),
        Format::Json => serde_json::to_string_pretty(&report)? + "\n",
    };
    std::io::stdout().write_all(text.as_bytes())?;
    Ok(())
}
