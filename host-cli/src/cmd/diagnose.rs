//! `propid diagnose`: the diagnosis as a command, around [`propid_science::diagnose::diagnose`].

use std::path::PathBuf;

use anyhow::Context;
use propid_science::diagnose::{diagnose, read_samples, report_figure, to_text, Options};

use crate::InputError;

/// Output format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// A readable report.
    Text,
    /// JSON.
    Json,
}

/// Arguments of `propid diagnose`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The recording (canonical TSV; `-` for standard input).
    pub file: PathBuf,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    pub format: Format,
    /// Write plots (measured vs simulated velocity before and after, residuals): .svg, .png, .html.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Largest number of effects to name.
    #[arg(long, default_value_t = 3)]
    pub max_effects: usize,
}

/// Runs `propid diagnose`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let (samples, skipped) = read_samples(&args.file)?;
    let mut report = diagnose(
        &samples,
        Options {
            max_effects: args.max_effects,
        },
    )
    .map_err(|e| InputError(format!("{}: {}", args.file.display(), e.0)))?;
    if skipped > 0 {
        report
            .notes
            .push(format!("{skipped} rows with missing values were skipped"));
    }
    if let Some(path) = &args.plot {
        crate::plot::write(path, &report_figure(&report))
            .with_context(|| format!("writing the plot {}", path.display()))?;
        eprintln!("plots written to {}", path.display());
    }
    let text = match args.format {
        Format::Text => to_text(&report, &args.file.display().to_string()),
        Format::Json => serde_json::to_string_pretty(&report)? + "\n",
    };
    use std::io::Write;
    std::io::stdout().write_all(text.as_bytes())?;
    Ok(())
}
