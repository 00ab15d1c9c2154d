//! `propid import`: measured logs of other stands into propid's TSV, around [`propid_io::import`].

use std::path::{Path, PathBuf};

use anyhow::Context;
use propid_io::import::{import_autoquad, import_rcbench, write_tsv, Imported, RcbenchOptions};

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
        /// Output TSV (standard output if omitted).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
}

fn write(imported: &Imported, output: Option<&Path>) -> anyhow::Result<()> {
    for a in &imported.assumptions {
        eprintln!("import: {a}");
    }
    let out: Box<dyn std::io::Write> = match output {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p).with_context(|| format!("cannot create {}", p.display()))?,
        )),
        None => Box::new(std::io::BufWriter::new(std::io::stdout().lock())),
    };
    write_tsv(imported, out).with_context(|| {
        format!(
            "writing {}",
            output.map_or("standard output".into(), |p| p.display().to_string())
        )
    })?;
    eprintln!("import: {} rows", imported.rows.len());
    Ok(())
}

/// Runs an importer.
pub fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Autoquad { file, kv, output } => {
            let imported = import_autoquad(&file, kv)
                .map_err(|e| crate::InputError(e.0.replace("kv must", "--kv must")))?;
            write(&imported, output.as_deref())
        }
        Command::Rcbench {
            file,
            subtract_zero_offset,
            output,
        } => write(
            &import_rcbench(
                &file,
                &RcbenchOptions {
                    subtract_zero_offset,
                },
            )?,
            output.as_deref(),
        ),
    }
}
