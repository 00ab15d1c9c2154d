//! `propid drive`: argument parsing, the signal handlers, progress lines and exit codes around
//! [`propid_drive::drive`].

use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use anyhow::Context;
use propid_drive::drive::{drive, DriveConfig, DriveEvent, StopReason, STOP_REPEATS};
use propid_science::excitation::{Excitation, Pattern};

use crate::InputError;

/// Arguments of `propid drive` (each also read from the PyCyphal register variable named).
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// This node's ID (register uavcan.node.id).
    #[arg(long, env = "UAVCAN__NODE__ID")]
    pub node_id: Option<u8>,
    /// The bus.
    #[command(flatten)]
    pub bus: crate::bus::BusArgs,
    /// Subject-ID of the readiness publisher; no readiness is published when unset
    /// (uavcan.pub.readiness.id).
    #[arg(long, env = "UAVCAN__PUB__READINESS__ID")]
    pub readiness_id: Option<u16>,
    /// Subject-ID of the ratiometric setpoint publisher (uavcan.pub.sp_rat.id).
    #[arg(long, env = "UAVCAN__PUB__SP_RAT__ID")]
    pub setpoint_id: Option<u16>,
    /// Subject-ID of the dynamics feedback subscriber (uavcan.sub.fb_dyn.id).
    #[arg(long, env = "UAVCAN__SUB__FB_DYN__ID")]
    pub feedback_id: Option<u16>,
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
    /// Print the running estimate of J, c1, c2 on stderr while driving.
    #[arg(long)]
    pub fit: bool,
    /// Write the TSV here instead of standard output.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Progress on stderr once a second.
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    pub progress: bool,
}

impl Args {
    /// The validated configuration these arguments (and the register variables) describe.
    pub fn config(&self) -> Result<DriveConfig, InputError> {
        let need = |v: Option<u16>, flag: &str, var: &str, what: &str| {
            v.ok_or_else(|| InputError(format!("{what} is not set: give --{flag} or {var}")))
        };
        let node_id = self.node_id.ok_or_else(|| {
            InputError("node id is not set: give --node-id or UAVCAN__NODE__ID".into())
        })?;
        let setpoint_id = need(
            self.setpoint_id,
            "setpoint-id",
            "UAVCAN__PUB__SP_RAT__ID",
            "setpoint subject-ID",
        )?;
        let feedback_id = need(
            self.feedback_id,
            "feedback-id",
            "UAVCAN__SUB__FB_DYN__ID",
            "feedback subject-ID",
        )?;
        let (lo, hi) = parse_lo_hi(&self.setpoint_rat_lo_hi)?;
        let cfg = DriveConfig {
            node_id,
            mtu: self.bus.mtu,
            readiness_id: self.readiness_id,
            setpoint_id,
            feedback_id,
            excitation: Excitation {
                lo,
                hi,
                period: self.period,
                duration: self.pattern_duration,
                init_duration: self.init_duration,
                pattern: self.pattern,
            },
            setpoint_period: self.setpoint_period,
            deadman: self.deadman,
            fit: self.fit,
        };
        cfg.validate()?;
        Ok(cfg)
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

/// Prints a drive's events on stderr (`progress` off: only the start of the pattern).
pub fn print_event(event: DriveEvent, excitation: &Excitation, progress: bool) {
    match event {
        DriveEvent::PatternStarted => {
            if progress {
                eprintln!(
                    "drive: pattern commenced ({}, {} s)",
                    excitation.pattern, excitation.duration
                );
            }
        }
        DriveEvent::Progress {
            elapsed,
            feedback_per_s,
            dropped_transfers,
            estimate,
        } => {
            if progress {
                let mut line = format!(
                    "drive: pattern {elapsed:.1}/{:.0} s, feedback {feedback_per_s} /s, dropped transfers {dropped_transfers}",
                    excitation.duration
                );
                if let Some((j, _, c2)) = estimate {
                    line += &format!(", J = {j:.4e}, c2 = {c2:.4e}");
                }
                eprintln!("{line}");
            }
        }
    }
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
    let outcome = drive(&cfg, transport.as_mut(), &mut out, &stop, &mut |e| {
        print_event(e, &excitation, args.progress)
    });
    let why = match &outcome.reason {
        StopReason::Completed => "the pattern is complete".to_string(),
        StopReason::Signal => "interrupted by a signal".to_string(),
        StopReason::LostFeedback => format!("no feedback for {} s (deadman)", cfg.deadman),
        StopReason::Error(e) => format!("error: {e}"),
    };
    eprintln!(
        "drive: stopped ({why}); STANDBY and a zero setpoint sent {STOP_REPEATS} times; {} rows written",
        outcome.rows
    );
    if let Some((m, c1, c2)) = outcome.estimate.filter(|_| cfg.fit) {
        eprintln!("drive: running estimate J = {m:.6e}, c1 = {c1:.3e}, c2 = {c2:.6e}");
    }
    match outcome.reason {
        StopReason::Completed => Ok(()),
        StopReason::Signal => std::process::exit(130),
        StopReason::LostFeedback => anyhow::bail!("feedback lost"),
        StopReason::Error(e) => anyhow::bail!(e),
    }
}
