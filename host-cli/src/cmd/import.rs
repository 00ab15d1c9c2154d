//! `propid import`: measured logs of other stands into propid's TSV, around [`propid_io::import`].

use std::path::{Path, PathBuf};

use anyhow::Context;
use propid_io::import::{import_autoquad, import_rcbench, write_tsv, Imported};

/// The importers.
#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// AutoQuad ESC32 telemetry (duty, bus current, rpm): torque = Kt·I_bus/duty, Kt = 60/(2π·kv).
    Autoquad {
        /// The ESC32 Configuration Utility CSV.
        file: PathBuf,
        /// The motor's kv [rpm/V] (gives Kt = 60/(2π·kv) N·m/A).
        #[arg(long)]
        kv: f64,
        /// Output TSV (standard output if omitted).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// RCbenchmark (Tyto Robotics) stand log: load-cell torque and electrical rpm.
    Rcbench {
        /// The RCbenchmark CSV export.
        file: PathBuf,
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
    write_tsv(imported, out)?;
    eprintln!("import: {} rows", imported.rows.len());
    Ok(())
}

/// Runs an importer.
pub fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Autoquad { file, kv, output } => {
            write(&import_autoquad(&file, kv)?, output.as_deref())
        }
        Command::Rcbench { file, output } => write(&import_rcbench(&file)?, output.as_deref()),
    }
}
