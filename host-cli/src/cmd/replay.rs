//! `propid replay`: a candump log back into the TSV, around [`propid_io::candump::replay`].

use std::io::{BufRead, Write};
use std::path::PathBuf;

use anyhow::Context;
use propid_io::candump::replay;

use crate::InputError;

/// Arguments of `propid replay`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The candump log (`candump -L` format); `-` for standard input.
    pub file: PathBuf,
    /// Subject-ID of the dynamics feedback.
    #[arg(long, env = "UAVCAN__SUB__FB_DYN__ID")]
    pub feedback_id: u16,
    /// Output TSV (standard output if omitted).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

/// Runs `propid replay`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let name = args.file.display().to_string();
    let input: Box<dyn BufRead> = if name == "-" {
        Box::new(std::io::BufReader::new(std::io::stdin()))
    } else {
        let f = std::fs::File::open(&args.file)
            .map_err(|e| InputError(format!("{name}: cannot open: {e}")))?;
        Box::new(std::io::BufReader::new(f))
    };
    let out: Box<dyn Write> = match &args.output {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p).with_context(|| format!("cannot create {}", p.display()))?,
        )),
        None => Box::new(std::io::BufWriter::new(std::io::stdout().lock())),
    };
    let rows = replay(input, &name, args.feedback_id, out)?;
    eprintln!(
        "replay: {rows} feedback messages on subject {}",
        args.feedback_id
    );
    Ok(())
}
