//! `propid import`: measured logs of other stands into propid's TSV, around [`propid_io::import`].

use std::path::PathBuf;

use anyhow::Context;
use propid_io::import::{
    import_autoquad_with, import_rcbench, write_tsv, Imported, RcbenchOptions,
};
use propid_io::output::Output;
use propid_io::ErrorKind;

/// The importers.
#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// AutoQuad ESC32 telemetry (duty, bus current, rpm): torque = Kt·I_bus/duty, Kt = 60/(2π·kv).
    Autoquad {
        /// The ESC32 Configuration Utility CSV.
        file: PathBuf,
        /// The motor's kv [rpm/V] (gives Kt = 60/(2π·kv) N·m/A); finite and positive.
        #[arg(long)]
        kv: f64,
        /// Set the velocity of samples found to be glitches (a jump away and straight back) to
        /// NaN; without it they are reported and kept.
        #[arg(long)]
        despike: bool,
        /// Output TSV (standard output if omitted).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// RCbenchmark or Tyto Robotics stand log: load-cell torque, optical or electrical rpm, ESC signal.
    Rcbench {
        /// The RCbenchmark / Tyto CSV export.
        file: PathBuf,
        /// Subtract the torque measured at zero speed (the load cell's zero offset) from every sample.
        #[arg(long)]
        subtract_zero_offset: bool,
        /// Set the velocity of samples found to be glitches (a jump away and straight back) to
        /// NaN; without it they are reported and kept.
        #[arg(long)]
        despike: bool,
        /// Output TSV (standard output if omitted).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
}

/// Prints what the importer measured and writes the TSV.
fn write(imported: &Imported, out: Output) -> anyhow::Result<()> {
    for a in &imported.assumptions {
        eprintln!("import: {a}");
    }
    for w in &imported.warnings {
        eprintln!("warning: {w}");
    }
    let name = out.name();
    let out = write_tsv(imported, std::io::BufWriter::new(out))
        .and_then(|w| w.into_inner().map_err(|e| e.into_error()))
        .with_context(|| format!("writing {name}"))?;
    out.finish().with_context(|| format!("writing {name}"))?;
    eprintln!("import: {} rows", imported.rows.len());
    Ok(())
}

/// Runs an importer. The output goes to standard output, or to `-o FILE` through an
/// [`AtomicOutput`](propid_io::output::AtomicOutput): checked before the input is read (never
/// the input itself), and written whole or not at all.
pub fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Autoquad {
            file,
            kv,
            despike,
            output,
        } => {
            let out = Output::create(output.as_deref(), &[&file])?;
            let imported = import_autoquad_with(&file, kv, despike).map_err(|mut e| {
                // The library checks a value; here it is a flag.
                if let ErrorKind::Invalid(message) = &mut e.kind {
                    *message = message.replace("kv must", "--kv must");
                }
                e
            })?;
            write(&imported, out)
        }
        Command::Rcbench {
            file,
            subtract_zero_offset,
            despike,
            output,
        } => {
            let out = Output::create(output.as_deref(), &[&file])?;
            let options = RcbenchOptions {
                subtract_zero_offset,
                despike,
            };
            write(&import_rcbench(&file, &options)?, out)
        }
    }
}
