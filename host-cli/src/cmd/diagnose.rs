//! `propid diagnose`: the diagnosis as a command, around [`propid_science::diagnose::diagnose`].

use std::path::PathBuf;

use propid_science::diagnose::{diagnose_rows_observed, report_figure, to_text, Options, Stage};

use propid_science::result::Outcome;

use crate::CannotJudge;

/// Output format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// The Result, then the diagnosis, for a person.
    Text,
    /// The diagnosis as JSON, its Result under `result`.
    Json,
    /// The Result as YAML (the keys of the JSON's `result`).
    Yaml,
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
    /// Largest number of effects to name (at least 1; the seed's model alone is `propid fit`).
    #[arg(long, default_value_t = 3, value_parser = at_least_one)]
    pub max_effects: usize,
    /// A model to fit and score beside the one the diagnosis names: effects separated by commas
    /// (force_sensor_lag,drag_exponent). Each is tuned and fitted as the search would, and the
    /// report says which of the two models the held-out data prefer, or that they cannot tell
    /// them apart.
    #[arg(long, value_name = "EFFECTS")]
    pub compare: Option<propid_science::diagnose::EffectSet>,
    /// How the columns are read.
    #[command(flatten)]
    pub reading: super::ReadingArgs,
    /// Leave out the rows whose velocity is a glitch (a sample that jumps away from both
    /// neighbours and straight back, as an optical probe's missed mark does); without it they are
    /// announced and kept.
    #[arg(long)]
    pub despike: bool,
    /// The propeller and air, for C_Q.
    #[command(flatten)]
    pub propeller: super::PropellerArgs,
}

/// `--max-effects`: a count of at least one.
fn at_least_one(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(0) => Err("0 tries no effect, so nothing could be concluded about the seed's model: give 1 or more (the seed's model alone is `propid fit`)".into()),
        Ok(n) => Ok(n),
        Err(_) => Err(format!("`{text}` is not a whole number of effects (1 or more)")),
    }
}

/// Lets glibc give every large buffer back to the system when it is freed. By default glibc
/// raises its mmap threshold after the first large free (up to 32 MiB), so the diagnosis's
/// 16 MB columns of a 2-million-row log then come from the heap and stay resident after they
/// are dropped: the peak RSS was 279 MB for a live peak of about 220 MB.
fn return_large_buffers_to_the_system() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets an allocator parameter; it is called before any thread of this
    // command starts, takes plain integers, and M_MMAP_THRESHOLD = 1 MiB is within its range
    // (at most HEAP_MAX_SIZE / 2 = 32 MiB on 64-bit). A refusal returns 0 and changes nothing.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 1 << 20);
    }
}

/// Runs `propid diagnose`.
pub fn run(args: Args) -> anyhow::Result<()> {
    // Flags first: a bad diameter is reported before any input is read.
    let air = args.propeller.air()?;
    return_large_buffers_to_the_system();
    // Progress on stderr (drawn only when it is a terminal): reading and each selection round
    // take seconds on an hour-long log.
    let bar = indicatif::ProgressBar::new_spinner();
    bar.set_style(
        indicatif::ProgressStyle::with_template("diagnose {spinner} {msg} {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    bar.set_message(format!("reading {}", args.file.display()));
    let input = super::DiagnosisInput::read(&args.file, &args.reading.reading(), args.despike)?;
    let max_effects = args.max_effects;
    let progress = |stage: Stage| {
        bar.set_message(match stage {
            Stage::Base => "base model and its residuals".to_string(),
            Stage::Candidates { round, done, of } => {
                format!("effect {round} of at most {max_effects}: {done}/{of} candidates tried")
            }
            Stage::Extended => "extended model".to_string(),
        })
    };
    let diagnosed = diagnose_input(
        input,
        args.options(),
        air,
        &propid_io::error::display_name(&args.file),
        &progress,
    );
    bar.finish_and_clear();
    let (report, outcome) = diagnosed?;
    let cannot_judge = report.verdict.cannot_judge_reasons();
    if let Some(path) = args.plot.as_ref().filter(|_| cannot_judge.is_none()) {
        crate::plot::write(path, &report_figure(&report))?;
        eprintln!("plots written to {}", path.display());
    }
    let text = match (args.format, &outcome) {
        (Format::Text, _) => text(&report, outcome.as_ref(), &args.file.display().to_string()),
        (Format::Json, _) => {
            serde_json::to_string_pretty(&json(&report, outcome.as_ref())?)? + "\n"
        }
        (Format::Yaml, Some(o)) => o.to_yaml(),
        (Format::Yaml, None) => String::new(),
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

impl Args {
    /// The diagnosis's options these flags ask for.
    pub fn options(&self) -> Options {
        Options {
            max_effects: self.max_effects,
            reading: self.reading.reading(),
            compare: self.compare.unwrap_or_default(),
        }
    }
}

/// The diagnosis of what was read (`name` in messages), with its Result (C_Q and C_T with
/// `air`'s diameter and density, when given): what `propid diagnose` prints, the end of
/// `drive --fit` and the Python package's `diagnose` return. What C_T's identification says
/// joins the report's notes.
pub fn diagnose_input(
    input: super::DiagnosisInput,
    options: Options,
    air: Option<propid_science::result::Air>,
    name: &str,
    progress: &(dyn Fn(Stage) + Sync),
) -> anyhow::Result<(propid_science::diagnose::Report, Option<Outcome>)> {
    let super::DiagnosisInput {
        rows,
        skipped,
        notes,
        thrust,
    } = input;
    let mut report =
        diagnose_rows_observed(rows, options, progress).map_err(|e| e.in_file(name))?;
    if skipped > 0 {
        report
            .notes
            .push(format!("{skipped} rows with missing values were skipped"));
    }
    report.notes.extend(notes);
    let mut outcome = Outcome::from_diagnosis(&report, skipped as u64, air);
    if let (Some(o), Some(rec)) = (outcome.as_mut(), &thrust) {
        let before = o.warnings.len();
        o.add_thrust(rec);
        report.notes.extend(o.warnings[before..].iter().cloned());
    }
    Ok((report, outcome))
}

/// The diagnosis as `--format json` writes it: the report, with its Result under `result` (the
/// Python package's `diagnose` gives the same).
pub fn json(
    report: &propid_science::diagnose::Report,
    outcome: Option<&Outcome>,
) -> serde_json::Result<serde_json::Value> {
    let mut v = serde_json::to_value(report)?;
    if let (Some(o), Some(map)) = (outcome, v.as_object_mut()) {
        map.insert("result".into(), serde_json::to_value(o)?);
    }
    Ok(v)
}

/// The diagnosis as the text format writes it: the Result first, then the report (the Python
/// package's `str(diagnosis)` gives the same).
pub fn text(
    report: &propid_science::diagnose::Report,
    outcome: Option<&Outcome>,
    source: &str,
) -> String {
    match outcome {
        Some(o) => o.to_text() + "\n" + &to_text(report, source),
        None => to_text(report, source),
    }
}
