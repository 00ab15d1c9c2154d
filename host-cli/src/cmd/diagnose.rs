//! `propid diagnose`: the diagnosis as a command, around [`propid_science::diagnose::diagnose`].

use std::path::PathBuf;

use propid_science::diagnose::{
    diagnose_rows, read_rows, report_figure, to_text, Options, Verdict,
};

use crate::{CannotJudge, InputError};

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
#[command(
    after_help = "Exit status: 0 a verdict (nothing wrong, effects named, or structure left \
unexplained); 2 bad input (unreadable file, time going backwards); 3 cannot judge: the data cannot \
support a verdict (all-zero force, an absurd value such as 1e300, time not in seconds, no excitation, \
too few samples, non-finite fitted parameters); the report says why; 1 any other error."
)]
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
    let (rows, skipped) = read_rows(&args.file)?;
    let mut report = diagnose_rows(
        &rows,
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
    let cannot_judge = match &report.verdict {
        Verdict::CannotJudge { reasons } => Some(
            reasons
                .iter()
                .map(|w| w.to_string())
                .collect::<Vec<_>>()
                .join("; "),
        ),
        _ => None,
    };
    if let Some(path) = args.plot.as_ref().filter(|_| cannot_judge.is_none()) {
        crate::plot::write(path, &report_figure(&report))?;
        eprintln!("plots written to {}", path.display());
    }
    let text = match args.format {
        Format::Text => to_text(&report, &args.file.display().to_string()),
        Format::Json => serde_json::to_string_pretty(&report)? + "\n",
    };
    use std::io::Write;
    std::io::stdout().write_all(text.as_bytes())?;
    match cannot_judge {
        Some(why) => {
            Err(CannotJudge(format!("{}: cannot judge: {why}", args.file.display())).into())
        }
        None => Ok(()),
    }
}
