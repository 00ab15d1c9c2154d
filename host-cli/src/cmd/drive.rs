//! `propid drive`: argument parsing, the signal handlers, progress lines and exit codes around
//! [`propid_drive::drive::run_drive`].

use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use anyhow::Context;
use propid_core::can::{NodeId, SubjectId};
use propid_drive::drive::{run_drive, ConfigError, DriveConfig, DriveEvent, Progress};
use propid_drive::realtime::SystemClock;
use propid_drive::StopReason;
use propid_science::excitation::{Excitation, Pattern};

use crate::InputError;

/// Arguments of `propid drive` (each also read from the PyCyphal register variable named).
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// This node's ID (register uavcan.node.id).
    #[arg(long, env = "UAVCAN__NODE__ID")]
    pub node_id: Option<NodeId>,
    /// The bus.
    #[command(flatten)]
    pub bus: crate::bus::BusArgs,
    /// Subject-ID of the readiness publisher; no readiness is published when unset
    /// (uavcan.pub.readiness.id).
    #[arg(long, env = "UAVCAN__PUB__READINESS__ID")]
    pub readiness_id: Option<SubjectId>,
    /// Subject-ID of the ratiometric setpoint publisher (uavcan.pub.sp_rat.id).
    #[arg(long, env = "UAVCAN__PUB__SP_RAT__ID")]
    pub setpoint_id: Option<SubjectId>,
    /// Subject-ID of the dynamics feedback subscriber (uavcan.sub.fb_dyn.id).
    #[arg(long, env = "UAVCAN__SUB__FB_DYN__ID")]
    pub feedback_id: Option<SubjectId>,
    /// Setpoint range "LO HI", ratiometric in [-1, 1] (register setpoint_rat_lo_hi).
    #[arg(long, env = "SETPOINT_RAT_LO_HI", default_value = "0.1 0.9")]
    pub setpoint_rat_lo_hi: String,
    /// Period of the sinusoid [s] (register period).
    #[arg(long, env = "PERIOD", default_value_t = 2.0)]
    pub period: f64,
    /// Duration of the pattern [s] (register pattern_duration).
    #[arg(long, env = "PATTERN_DURATION", default_value_t = 200.0)]
    pub pattern_duration: f64,
    /// Duration of the initial run at the high setpoint [s] (register init_duration).
    #[arg(long, env = "INIT_DURATION", default_value_t = 5.0)]
    pub init_duration: f64,
    /// Setpoint publication period [s] (register setpoint_period).
    #[arg(long, env = "SETPOINT_PERIOD", default_value_t = 0.005)]
    pub setpoint_period: f64,
    /// Pattern after the init phase (the seed: sine).
    #[arg(long, default_value_t = Pattern::Sine)]
    pub pattern: Pattern,
    /// Stop (commanding STANDBY) when no feedback arrives for this long during the pattern [s].
    #[arg(long, default_value_t = 0.5)]
    pub deadman: f64,
    /// Node-ID of the drive, whose heartbeat is watched for a reboot (default: the publisher of
    /// the first feedback message).
    #[arg(long)]
    pub drive_node_id: Option<NodeId>,
    /// Print the running estimate of J, c1, c2 on stderr while driving.
    #[arg(long)]
    pub fit: bool,
    /// Write the TSV here instead of standard output.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Progress on stderr once a second.
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    pub progress: bool,
    /// Play a pattern file from `propid plan` (its range, period and duration) instead of
    /// --pattern, --period and the setpoint range.
    #[arg(long)]
    pub pattern_file: Option<PathBuf>,
    /// Stop (with STANDBY, as always) once the relative standard errors of J and c2 are both at
    /// most this many percent; the pattern duration is then the longest the run may take.
    #[arg(long, value_name = "PCT")]
    pub until_stderr: Option<f64>,
    /// Serve a live page of the run (plots, running estimate, bus health, a STOP button) on this
    /// address (loopback; the URL with its per-run token is printed on stderr).
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "127.0.0.1:8080")]
    pub live: Option<String>,
    /// Allow --live on an address other than loopback (anyone who can reach it and has the token
    /// can stop the drive).
    #[arg(long)]
    pub live_allow_remote: bool,
}

impl Args {
    /// The validated configuration these arguments (and the register variables) describe.
    pub fn config(&self) -> Result<DriveConfig, InputError> {
        let need = |v: Option<SubjectId>, flag: &str, var: &str, what: &str| {
            v.ok_or_else(|| InputError(format!("{what} is not set: give --{flag} or {var}")))
        };
        let node_id = self.node_id.ok_or_else(|| {
            InputError("node id is not set: give --node-id or UAVCAN__NODE__ID".into())
        })?;
        let setpoint_id = need(
            self.setpoint_id,
            "setpoint-id",
            "UAVCAN__PUB__SP_RAT__ID",
            "setpoint id",
        )?;
        let feedback_id = need(
            self.feedback_id,
            "feedback-id",
            "UAVCAN__SUB__FB_DYN__ID",
            "feedback id",
        )?;
        let (lo, hi) = parse_lo_hi(&self.setpoint_rat_lo_hi)?;
        let excitation = match &self.pattern_file {
            Some(path) => crate::cmd::sim::read_pattern_file(path)?,
            None => Excitation {
                lo,
                hi,
                period: self.period,
                duration: self.pattern_duration,
                init_duration: self.init_duration,
                pattern: self.pattern,
            },
        };
        let until_rel_stderr = match self.until_stderr {
            Some(p) if p > 0.0 && p < 100.0 => Some(p / 100.0),
            Some(p) => {
                return Err(InputError(format!(
                    "--until-stderr must be a percentage in (0, 100) (got {p})"
                )))
            }
            None => None,
        };
        let cfg = DriveConfig {
            node_id,
            mtu: self.bus.mtu,
            readiness_id: self.readiness_id,
            setpoint_id,
            feedback_id,
            excitation,
            setpoint_period: self.setpoint_period,
            deadman: self.deadman,
            drive_node_id: self.drive_node_id,
            fit: self.fit || until_rel_stderr.is_some(),
            until_rel_stderr,
        };
        cfg.validate().map_err(flag_error)?;
        Ok(cfg)
    }
}

/// A configuration error in the words of the command line: the flag (and its register
/// variable, where it has one) and what is wrong.
pub fn flag_error(e: ConfigError) -> InputError {
    let (flag, var) = match e.setting {
        "node_id" => ("--node-id", Some("UAVCAN__NODE__ID")),
        "setpoint_id" => ("--setpoint-id", Some("UAVCAN__PUB__SP_RAT__ID")),
        "feedback_id" => ("--feedback-id", Some("UAVCAN__SUB__FB_DYN__ID")),
        "readiness_id" => ("--readiness-id", Some("UAVCAN__PUB__READINESS__ID")),
        "setpoint_lo" | "setpoint_hi" | "setpoint_rat_lo_hi" => {
            ("--setpoint-rat-lo-hi", Some("SETPOINT_RAT_LO_HI"))
        }
        "period" => ("--period", Some("PERIOD")),
        "pattern_duration" => ("--pattern-duration", Some("PATTERN_DURATION")),
        "init_duration" => ("--init-duration", Some("INIT_DURATION")),
        "setpoint_period" => ("--setpoint-period", Some("SETPOINT_PERIOD")),
        "deadman" => ("--deadman", None),
        "drive_node_id" => ("--drive-node-id", None),
        "mtu" => ("--mtu", None),
        "interval" => ("--interval", None),
        "duration" => ("--duration", None),
        other => return InputError(format!("{other}: {}", e.problem)),
    };
    match var {
        Some(var) => InputError(format!("{flag} ({var}) {}", e.problem)),
        None => InputError(format!("{flag} {}", e.problem)),
    }
}

/// Parses the seed's `setpoint_rat_lo_hi` register: two numbers, space or comma separated.
pub fn parse_lo_hi(text: &str) -> Result<(f64, f64), InputError> {
    let bad = || InputError(format!("setpoint_rat_lo_hi `{text}` is not two numbers"));
    let values: Vec<f64> = text
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    match values[..] {
        [lo, hi] => Ok((lo, hi)),
        _ => Err(bad()),
    }
}

/// Prints a drive's events on stderr (`progress` off: only the stop).
pub fn print_event(event: &DriveEvent, excitation: &Excitation, progress: bool) {
    match event {
        DriveEvent::PatternStarted if progress => eprintln!(
            "drive: pattern commenced ({}, {} s)",
            excitation.pattern, excitation.duration
        ),
        DriveEvent::Progress(p) if progress => eprintln!("{}", progress_line(p, excitation)),
        DriveEvent::Stopping(reason) => {
            eprintln!("drive: stopping ({reason}): STANDBY and a zero setpoint first in line")
        }
        _ => {}
    }
}

fn progress_line(p: &Progress, excitation: &Excitation) -> String {
    let mut line = format!(
        "drive: pattern {:.1}/{:.0} s, feedback {} /s, dropped transfers {}, frames dropped {}",
        p.elapsed, excitation.duration, p.feedback_per_s, p.dropped_transfers, p.tx.dropped
    );
    if p.tx.would_block > 0 {
        line += &format!(
            " (link busy {} times, {} setpoints superseded)",
            p.tx.would_block, p.tx.superseded
        );
    }
    if let Some(e) = p.estimate {
        line += &format!(
            ", J = {:.4e} ± {:.1e}, c2 = {:.4e} ± {:.1e}",
            e.j, e.j_stderr, e.c2, e.c2_stderr
        );
    }
    line
}

/// Runs `propid drive`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let cfg = args.config()?;
    let mut transport = args.bus.open()?;
    let stop = Arc::new(AtomicBool::new(false));
    crate::signals::install(&stop)?;
    let mut out: Box<dyn Write> = match &args.output {
        Some(p) => Box::new(
            std::fs::File::create(p).with_context(|| format!("cannot create {}", p.display()))?,
        ),
        None => Box::new(std::io::stdout()),
    };
    let excitation = cfg.excitation;
    let readiness = cfg.readiness_id.is_some();
    let fit = cfg.fit;
    let mut live = crate::live::start_for_drive(
        args.live.as_deref(),
        args.live_allow_remote,
        &stop,
        excitation,
        "propid drive",
    )?;
    let outcome = run_drive(
        cfg,
        transport.as_mut(),
        &SystemClock,
        &stop,
        &mut out,
        &mut |e| {
            print_event(e, &excitation, args.progress);
            if let Some((_, view)) = live.as_mut() {
                view.on_event(e);
            }
        },
    );
    let r = &outcome.report;
    let delivered = if outcome.standby_delivered(readiness) {
        format!(
            "STANDBY and a zero setpoint sent ({} and {} times)",
            r.standby_sent, r.zero_setpoints_sent
        )
    } else {
        format!(
            "STANDBY and a zero setpoint NOT confirmed sent ({} and {} handed to the link{})",
            r.standby_sent,
            r.zero_setpoints_sent,
            outcome
                .link
                .link_fault
                .as_ref()
                .map(|f| format!(
                    "; the link failed: {f}; {} frames after that never written",
                    outcome.link.lost_to_fault
                ))
                .unwrap_or_default()
        )
    };
    eprintln!(
        "drive: stopped ({}); {delivered}; {} rows written; frames dropped {} (link busy {} times, {} setpoints superseded, {} refused by a full queue)",
        r.reason, r.rows, r.tx.dropped, r.tx.would_block, r.tx.superseded, r.tx.refused
    );
    if let Some(e) = r.estimate.filter(|_| fit) {
        eprintln!(
            "drive: running estimate J = {:.6e} ± {:.1e}, c1 = {:.3e}, c2 = {:.6e} ± {:.1e}",
            e.j, e.j_stderr, e.c1, e.c2, e.c2_stderr
        );
    }
    match &r.reason {
        StopReason::Completed | StopReason::Precise { .. }
            if outcome.standby_delivered(readiness) =>
        {
            Ok(())
        }
        StopReason::Completed => anyhow::bail!("the stop commands were not confirmed sent"),
        StopReason::Signal => std::process::exit(130),
        reason => anyhow::bail!("{reason}"),
    }
}
