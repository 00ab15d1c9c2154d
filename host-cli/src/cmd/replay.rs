//! `propid replay`: a candump log back into the TSV, around [`propid_io::candump::replay`].

use std::path::PathBuf;

use anyhow::Context;
use propid_core::can::RxError;
use propid_io::candump::{replay, ReplayError, ReplayOptions, ReplaySummary};
use propid_io::output::Output;

use crate::InputError;

/// Arguments of `propid replay`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The candump log (`candump -L` format); `-` for standard input.
    pub file: PathBuf,
    /// Subject-ID of the dynamics feedback (0 to 8191).
    #[arg(long, env = "UAVCAN__SUB__FB_DYN__ID")]
    pub feedback_id: propid_core::can::SubjectId,
    /// Only the feedback of this node-ID (0 to 127). Without it, the first node seen on the subject
    /// is used, and a second node there is an error.
    #[arg(long)]
    pub source_node: Option<propid_core::can::NodeId>,
    /// Output TSV (standard output if omitted).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

fn node(n: Option<u8>) -> String {
    n.map_or("anonymous".into(), |n| n.to_string())
}

/// The summary printed on stderr: what was written, and everything skipped, by kind.
pub fn describe(s: &ReplaySummary, name: &str, feedback_id: u16) -> Vec<String> {
    let mut out = vec![format!(
        "replay: {name}: {} lines, {} feedback messages on subject {feedback_id}{} written",
        s.lines,
        s.rows,
        s.source
            .map(|n| format!(" from node {n}"))
            .unwrap_or_default()
    )];
    let mut skipped = Vec::new();
    for (n, what) in [
        (s.malformed, "malformed lines"),
        (s.error_frames, "error frames"),
        (s.remote_frames, "remote frames"),
        (s.base_frames, "11-bit frames"),
        (s.undecodable, "transfers that are not DoF3rdTs"),
    ] {
        if n > 0 {
            skipped.push(format!("{n} {what}"));
        }
    }
    for (why, what) in [
        (RxError::BadCrc, "CRC mismatch"),
        (RxError::BadToggle, "toggle error"),
        (RxError::WrongTransferId, "wrong transfer-ID"),
        (RxError::MissingStart, "missing start of transfer"),
        (RxError::DuplicateTransfer, "duplicate transfer"),
        (RxError::NotCyphal, "not Cyphal (no tail byte)"),
        (RxError::OutOfSessions, "out of sessions"),
        (RxError::AnonymousMultiFrame, "anonymous multi-frame"),
    ] {
        let n = s.dropped(why);
        if n > 0 {
            skipped.push(format!("{n} frames dropped by the reassembler: {what}"));
        }
    }
    if !s.other_sources.is_empty() {
        let list: Vec<String> = s
            .other_sources
            .iter()
            .map(|&(n, frames)| format!("node {} ({frames} frames)", node(n)))
            .collect();
        skipped.push(format!("the feedback of {}", list.join(", ")));
    }
    if !skipped.is_empty() {
        out.push(format!("replay: skipped {}", skipped.join(", ")));
    }
    for (line, why) in &s.malformed_first {
        out.push(format!("replay: {name}: line {line}: {why}"));
    }
    if s.malformed > s.malformed_first.len() as u64 {
        out.push(format!(
            "replay: … and {} more malformed lines",
            s.malformed - s.malformed_first.len() as u64
        ));
    }
    out
}

/// Every subject seen and its nodes, for a message when nothing matched.
fn seen(s: &ReplaySummary) -> String {
    if s.subjects.is_empty() {
        return "no Cyphal message frames at all".into();
    }
    s.subjects
        .iter()
        .map(|(subject, nodes, frames)| {
            format!(
                "subject {subject} ({frames} frames from node {})",
                nodes
                    .iter()
                    .map(|&n| node(n))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// Runs `propid replay`. The log is read through [`propid_io::input::open`] (gzip read through,
/// lines bounded); the TSV goes to standard output or through an
/// [`AtomicOutput`](propid_io::output::AtomicOutput), never over the log. A read error midway
/// still keeps the rows before it (they are whole), then fails.
pub fn run(args: Args) -> anyhow::Result<()> {
    let mut out = Output::create(args.output.as_deref(), &[&args.file])?;
    let input = propid_io::input::open(&args.file)?;
    let name = input.name().to_owned();
    let options = ReplayOptions {
        feedback_id: args.feedback_id.get(),
        source_node: args.source_node.map(|n| n.get()),
    };
    let out_name = out.name();
    let result = replay(input, &name, &options, std::io::BufWriter::new(&mut out));
    let summary = match result {
        Ok(summary) => summary,
        Err(ReplayError::Write(io)) => {
            return Err(anyhow::Error::new(io).context(format!("writing {out_name}")))
        }
        Err(other) => {
            out.finish()
                .with_context(|| format!("writing {out_name}"))?;
            return Err(other.into());
        }
    };
    out.finish()
        .with_context(|| format!("writing {out_name}"))?;
    for line in describe(&summary, &name, args.feedback_id.get()) {
        eprintln!("{line}");
    }
    if summary.rows == 0 {
        let why = match args.source_node {
            Some(n) => format!("subject {} from node {n}", args.feedback_id),
            None => format!("subject {}", args.feedback_id),
        };
        return Err(InputError::invalid(format!(
            "{name}: no feedback transfers on {why}; the log has {}",
            seen(&summary)
        ))
        .into());
    }
    if args.source_node.is_none() && !summary.other_sources.is_empty() {
        let list: Vec<String> = summary
            .other_sources
            .iter()
            .map(|&(n, frames)| format!("node {} ({frames} frames)", node(n)))
            .collect();
        return Err(InputError::invalid(format!(
            "{name}: subject {} carries feedback from several nodes: node {} (written) and {}; \
             they are not merged: choose one with --source-node",
            args.feedback_id,
            node(summary.source),
            list.join(", ")
        ))
        .into());
    }
    Ok(())
}
