//! `propid drive`: argument parsing, the signal handlers, progress lines and exit codes around
//! [`propid_drive::drive`].

use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use anyhow::Context;
use propid_drive::drive::{drive, DriveConfig, DriveEvent, StopReason, STOP_REPEATS};
use propid_drive::registers::{self, HostRegistry};
use propid_science::excitation::{Excitation, Pattern};

use crate::InputError;

/// Arguments of `propid drive`. Its settings are the seed's PyCyphal registers: defaults, then
/// `--register-file`, then the environment variables named after them (`UAVCAN__NODE__ID`,
/// `SETPOINT_RAT_LO_HI`, …), then `--register NAME=VALUE`, then the flags below.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// This node's ID (register uavcan.node.id).
    #[arg(long)]
    pub node_id: Option<u16>,
    /// The bus.
    #[command(flatten)]
    pub bus: crate::bus::BusArgs,
    /// Subject-ID of the readiness publisher; no readiness is published when unset
    /// (uavcan.pub.readiness.id).
    #[arg(long)]
    pub readiness_id: Option<u16>,
    /// Subject-ID of the ratiometric setpoint publisher (uavcan.pub.sp_rat.id).
    #[arg(long)]
    pub setpoint_id: Option<u16>,
    /// Subject-ID of the dynamics feedback subscriber (uavcan.sub.fb_dyn.id).
    #[arg(long)]
    pub feedback_id: Option<u16>,
    /// Setpoint range "LO HI", ratiometric in [-1, 1] (register setpoint_rat_lo_hi; default 0.1 0.9).
    #[arg(long)]
    pub setpoint_rat_lo_hi: Option<String>,
    /// Period of the sinusoid [s] (register period; default 2).
    #[arg(long)]
    pub period: Option<f64>,
    /// Duration of the pattern [s] (register pattern_duration; default 200).
    #[arg(long)]
    pub pattern_duration: Option<f64>,
    /// Duration of the initial run at the high setpoint [s] (register init_duration; default 5).
    #[arg(long)]
    pub init_duration: Option<f64>,
    /// Setpoint publication period [s] (register setpoint_period; default 0.005).
    #[arg(long)]
    pub setpoint_period: Option<f64>,
    /// A register file: `name: value` lines (`#` comments), applied before the environment.
    #[arg(long)]
    pub register_file: Option<PathBuf>,
    /// Set a register, NAME=VALUE (repeatable), after the environment.
    #[arg(long = "register", value_name = "NAME=VALUE")]
    pub registers: Vec<String>,
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
    /// Before engaging, find the drive on the bus (heartbeat, GetInfo), read its registers and
    /// refuse to run if they would spoil the data (feedback under 100 Hz, no local timestamps,
    /// feedback on another subject).
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    pub check_drive: bool,
}

impl Args {
    /// The registers these arguments, the environment and the register file describe.
    pub fn registers(&self) -> Result<HostRegistry, InputError> {
        let mut r = registers::drive_registers(None, self.register_file.is_some());
        if let Some(path) = &self.register_file {
            let text = std::fs::read_to_string(path)
                .map_err(|e| InputError(format!("cannot read {}: {e}", path.display())))?;
            registers::apply_file(&mut r, path, &text)?;
        }
        registers::apply_environment(&mut r, std::env::vars())?;
        for assignment in &self.registers {
            let (name, value) = assignment.split_once('=').ok_or_else(|| {
                InputError(format!("--register `{assignment}`: expected NAME=VALUE"))
            })?;
            registers::set_text(&mut r, name.trim(), value, &format!("--register {name}"))?;
        }
        let flags: [(&str, &str, Option<String>); 9] = [
            (
                "uavcan.node.id",
                "--node-id",
                self.node_id.map(|v| v.to_string()),
            ),
            (
                "uavcan.pub.readiness.id",
                "--readiness-id",
                self.readiness_id.map(|v| v.to_string()),
            ),
            (
                "uavcan.pub.sp_rat.id",
                "--setpoint-id",
                self.setpoint_id.map(|v| v.to_string()),
            ),
            (
                "uavcan.sub.fb_dyn.id",
                "--feedback-id",
                self.feedback_id.map(|v| v.to_string()),
            ),
            (
                "setpoint_rat_lo_hi",
                "--setpoint-rat-lo-hi",
                self.setpoint_rat_lo_hi
                    .as_ref()
                    .map(|v| v.replace(',', " ")),
            ),
            ("period", "--period", self.period.map(|v| v.to_string())),
            (
                "pattern_duration",
                "--pattern-duration",
                self.pattern_duration.map(|v| v.to_string()),
            ),
            (
                "init_duration",
                "--init-duration",
                self.init_duration.map(|v| v.to_string()),
            ),
            (
                "setpoint_period",
                "--setpoint-period",
                self.setpoint_period.map(|v| v.to_string()),
            ),
        ];
        for (name, flag, value) in flags {
            if let Some(v) = value {
                registers::set_text(&mut r, name, &v, flag)?;
            }
        }
        Ok(r)
    }

    /// The validated configuration these arguments (and the register variables) describe.
    pub fn config(&self) -> Result<DriveConfig, InputError> {
        let r = self.registers()?;
        registers::drive_config(&r, self.bus.mtu, self.pattern, self.deadman, self.fit)
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
    if args.check_drive {
        // Refuse, before anything moves, a drive whose settings would spoil the data.
        let listen = std::time::Duration::from_millis(1100);
        let drives = crate::cmd::telega::survey(
            transport.as_mut(),
            cfg.node_id,
            cfg.mtu,
            None,
            listen,
            Some(cfg.feedback_id),
        )?;
        for (id, name, problems) in &drives {
            if !problems.is_empty() {
                return Err(InputError(format!(
                    "refusing to engage drive {id} ({name}):\n{}",
                    crate::cmd::telega::explain(*id, problems)
                ))
                .into());
            }
        }
    }
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
