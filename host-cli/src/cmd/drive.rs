//! `propid drive`: argument parsing, the signal handlers, progress lines and exit codes around
//! [`propid_drive::drive::run_drive`].

use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use anyhow::Context;
use propid_core::can::{NodeId, SubjectId};
use propid_core::dsdl::Value;
use propid_drive::drive::{
    run_drive_machine, ConfigError, Drive, DriveConfig, DriveEvent, Progress,
};
use propid_drive::realtime::SystemClock;
use propid_drive::registers::{self, HostRegistry};
use propid_drive::StopReason;
use propid_science::excitation::{Excitation, Pattern};

use crate::InputError;

/// Arguments of `propid drive`. The seed's settings are registers (docs/REGISTERS.md): each
/// comes from its default, then the `--registers` file, then its environment variable (the
/// register's name as PyCyphal maps it, e.g. `SETPOINT_RAT_LO_HI`, `UAVCAN__NODE__ID`), then the
/// flag; the node serves them over uavcan.register.List/Access while it drives.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// This node's ID (register uavcan.node.id, UAVCAN__NODE__ID).
    #[arg(long)]
    pub node_id: Option<NodeId>,
    /// The bus.
    #[command(flatten)]
    pub bus: crate::bus::BusArgs,
    /// A register file: `name: value` lines (values as the environment variables take them),
    /// read before the environment and the flags; registers written over the bus are saved to it.
    #[arg(long, value_name = "FILE")]
    pub registers: Option<PathBuf>,
    /// Take the port-IDs from the drive's own registers (uavcan.pub.dynamics.id,
    /// uavcan.sub.setpoint_r_torq.id, uavcan.sub.readiness.id) and refuse to engage it when its
    /// configuration would spoil the data (see `propid telega`).
    #[arg(long, value_name = "NODE")]
    pub from_telega: Option<NodeId>,
    /// Print the registers (defaults, file, environment and flags applied and checked) in the
    /// register file's format, and exit without opening the bus.
    #[arg(long)]
    pub show_registers: bool,
    /// Subject-ID of the readiness publisher; no readiness is published when unset
    /// (uavcan.pub.readiness.id, UAVCAN__PUB__READINESS__ID).
    #[arg(long)]
    pub readiness_id: Option<SubjectId>,
    /// Subject-ID of the ratiometric setpoint publisher (uavcan.pub.sp_rat.id,
    /// UAVCAN__PUB__SP_RAT__ID).
    #[arg(long)]
    pub setpoint_id: Option<SubjectId>,
    /// Subject-ID of the dynamics feedback subscriber (uavcan.sub.fb_dyn.id,
    /// UAVCAN__SUB__FB_DYN__ID).
    #[arg(long)]
    pub feedback_id: Option<SubjectId>,
    /// Setpoint range "LO HI", ratiometric in [-1, 1] (register setpoint_rat_lo_hi,
    /// SETPOINT_RAT_LO_HI; default "0.1 0.9").
    #[arg(long)]
    pub setpoint_rat_lo_hi: Option<String>,
    /// Period of the sinusoid [s] (register period, PERIOD; default 2).
    #[arg(long)]
    pub period: Option<f64>,
    /// Duration of the pattern [s] (register pattern_duration, PATTERN_DURATION; default 200).
    #[arg(long)]
    pub pattern_duration: Option<f64>,
    /// Duration of the initial run at the high setpoint [s] (register init_duration,
    /// INIT_DURATION; default 5).
    #[arg(long)]
    pub init_duration: Option<f64>,
    /// Setpoint publication period [s] (register setpoint_period, SETPOINT_PERIOD; default
    /// 0.005).
    #[arg(long)]
    pub setpoint_period: Option<f64>,
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

fn n16(v: u16) -> Value {
    Value::natural16(&[v]).unwrap_or_default()
}

fn r64(v: f64) -> Value {
    Value::real64(&[v]).unwrap_or_default()
}

impl Args {
    /// The registers: defaults, then the register file, then the environment (`vars`), then
    /// the flags. A value that does not parse is refused naming its origin and register.
    pub fn registers(
        &self,
        vars: impl IntoIterator<Item = (String, String)>,
    ) -> Result<HostRegistry, InputError> {
        let mut r = registers::drive_defaults(self.registers.is_some());
        if let Some(path) = &self.registers {
            let text = std::fs::read_to_string(path).map_err(|e| {
                InputError::invalid(format!(
                    "cannot read the register file {}: {e}",
                    path.display()
                ))
            })?;
            registers::apply_file(&mut r, path, &text)?;
        }
        registers::apply_environment(&mut r, vars)?;
        let mut set = |name: &str, v: Option<Value>| {
            if let Some(v) = v {
                // The flags are typed: the conversion to the register's type cannot fail.
                let _ = r.set(name, &v);
            }
        };
        set(
            "uavcan.node.id",
            self.node_id.map(|id| n16(u16::from(id.get()))),
        );
        set(
            registers::DRIVE_READINESS_ID,
            self.readiness_id.map(|id| n16(id.get())),
        );
        set(
            registers::DRIVE_SETPOINT_ID,
            self.setpoint_id.map(|id| n16(id.get())),
        );
        set(
            registers::DRIVE_FEEDBACK_ID,
            self.feedback_id.map(|id| n16(id.get())),
        );
        set("period", self.period.map(r64));
        set("pattern_duration", self.pattern_duration.map(r64));
        set("init_duration", self.init_duration.map(r64));
        set("setpoint_period", self.setpoint_period.map(r64));
        if let Some(text) = &self.setpoint_rat_lo_hi {
            let (lo, hi) = parse_lo_hi(text)?;
            set("setpoint_rat_lo_hi", Value::real64(&[lo, hi]));
        }
        Ok(r)
    }

    /// The validated configuration these arguments, the register file and the environment
    /// (`vars`) describe, and the registers the drive will serve.
    pub fn config_with(
        &self,
        vars: impl IntoIterator<Item = (String, String)>,
    ) -> Result<(DriveConfig, HostRegistry), InputError> {
        let r = self.registers(vars)?;
        let until_rel_stderr = match self.until_stderr {
            Some(p) if p > 0.0 && p < 100.0 => Some(p / 100.0),
            Some(p) => {
                return Err(InputError::invalid(format!(
                    "--until-stderr must be a percentage in (0, 100) (got {p})"
                )))
            }
            None => None,
        };
        let mut cfg = DriveConfig::example(Excitation {
            lo: 0.1,
            hi: 0.9,
            period: 2.0,
            duration: 200.0,
            init_duration: 5.0,
            pattern: self.pattern,
        });
        cfg.mtu = self.bus.mtu;
        cfg.deadman = self.deadman;
        cfg.drive_node_id = self.drive_node_id;
        cfg.fit = self.fit || until_rel_stderr.is_some();
        cfg.until_rel_stderr = until_rel_stderr;
        let mut with_ids = r.clone();
        if self.from_telega.is_some() {
            // The port-IDs come from the drive later: check everything else now, before anything
            // is sent.
            for name in [registers::DRIVE_SETPOINT_ID, registers::DRIVE_FEEDBACK_ID] {
                if with_ids.get(name).and_then(|x| x.value.float_at(0))
                    == Some(f64::from(registers::UNSET))
                {
                    let _ = with_ids.set(name, &n16(0));
                }
            }
        }
        registers::apply_drive_registers(&with_ids, &mut cfg).map_err(flag_error)?;
        if let Some(path) = &self.pattern_file {
            cfg.excitation = crate::cmd::sim::read_pattern_file(path)?;
        }
        cfg.validate().map_err(flag_error)?;
        Ok((cfg, r))
    }

    /// [`Args::config_with`] the process's environment.
    pub fn config(&self) -> Result<(DriveConfig, HostRegistry), InputError> {
        self.config_with(std::env::vars())
    }
}

/// A configuration error in the words of the command line: the flag, the register and its
/// environment variable, and what is wrong.
pub fn flag_error(e: ConfigError) -> InputError {
    let (flag, register) = match e.setting {
        "node_id" | "uavcan.node.id" => ("--node-id", Some("uavcan.node.id")),
        "setpoint_id" | registers::DRIVE_SETPOINT_ID => {
            ("--setpoint-id", Some(registers::DRIVE_SETPOINT_ID))
        }
        "feedback_id" | registers::DRIVE_FEEDBACK_ID => {
            ("--feedback-id", Some(registers::DRIVE_FEEDBACK_ID))
        }
        "readiness_id" | registers::DRIVE_READINESS_ID => {
            ("--readiness-id", Some(registers::DRIVE_READINESS_ID))
        }
        "setpoint_lo" | "setpoint_hi" | "setpoint_rat_lo_hi" => {
            ("--setpoint-rat-lo-hi", Some("setpoint_rat_lo_hi"))
        }
        "period" => ("--period", Some("period")),
        "pattern_duration" => ("--pattern-duration", Some("pattern_duration")),
        "init_duration" => ("--init-duration", Some("init_duration")),
        "setpoint_period" => ("--setpoint-period", Some("setpoint_period")),
        "deadman" => ("--deadman", None),
        "drive_node_id" => ("--drive-node-id", None),
        "mtu" => ("--mtu", None),
        "interval" => ("--interval", None),
        "duration" => ("--duration", None),
        other => return InputError::invalid(format!("{other}: {}", e.problem)),
    };
    match register {
        Some(reg) => InputError::invalid(format!(
            "{flag} (register {reg}, {}) {}",
            registers::environment_name(reg),
            e.problem
        )),
        None => InputError::invalid(format!("{flag} {}", e.problem)),
    }
}

/// Parses the seed's `setpoint_rat_lo_hi` register: two numbers, space or comma separated.
pub fn parse_lo_hi(text: &str) -> Result<(f64, f64), InputError> {
    let bad = || InputError::invalid(format!("setpoint_rat_lo_hi `{text}` is not two numbers"));
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

/// A register written over the bus: kept in the register file (if one is used) for the next
/// run, and said on stderr.
fn save_written(
    file: Option<&std::path::Path>,
    regs: &mut HostRegistry,
    name: &str,
    value: &Value,
) {
    let shown = registers::show(value);
    let Some(path) = file else {
        eprintln!("drive: register {name} written over the bus: {shown} (no --registers file: not kept; this run keeps its values)");
        return;
    };
    let _ = regs.set(name, value);
    match std::fs::write(path, registers::render_file(regs)) {
        Ok(()) => eprintln!(
            "drive: register {name} written over the bus: {shown}, saved to {} for the next run",
            path.display()
        ),
        Err(e) => eprintln!(
            "drive: register {name} written over the bus: {shown}; cannot save it to {}: {e}",
            path.display()
        ),
    }
}

/// Runs `propid drive`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let (mut cfg, mut file_registers) = args.config()?;
    if args.show_registers {
        print!("{}", registers::render_file(&file_registers));
        return Ok(());
    }
    let mut transport = args.bus.open()?;
    if let Some(node) = args.from_telega {
        let ports =
            crate::cmd::telega::drive_ports(transport.as_mut(), cfg.node_id, cfg.mtu, node)?;
        let pick = |flag: Option<SubjectId>, theirs: Option<SubjectId>, name: &str, reg: &str| {
            match (flag, theirs) {
                (Some(f), Some(t)) if f != t => Err(InputError::invalid(format!(
                    "--{name} {f} but drive {node} has {reg} = {t}; drop the flag or change the register with propid telega"
                ))),
                (_, t) => Ok(t),
            }
        };
        let feedback = pick(
            args.feedback_id,
            ports.feedback,
            "feedback-id",
            registers::TELEGA_FEEDBACK_ID,
        )?;
        let setpoint = pick(
            args.setpoint_id,
            ports.setpoint,
            "setpoint-id",
            registers::TELEGA_SETPOINT_ID,
        )?;
        let readiness = pick(
            args.readiness_id,
            ports.readiness,
            "readiness-id",
            registers::TELEGA_READINESS_ID,
        )?;
        cfg.feedback_id = feedback.ok_or_else(|| {
            InputError::invalid(format!(
                "drive {node} has no {} set",
                registers::TELEGA_FEEDBACK_ID
            ))
        })?;
        cfg.setpoint_id = setpoint.ok_or_else(|| {
            InputError::invalid(format!(
                "drive {node} has no {} set",
                registers::TELEGA_SETPOINT_ID
            ))
        })?;
        cfg.readiness_id = readiness;
        cfg.drive_node_id = Some(node);
        eprintln!(
            "drive: drive {node} publishes feedback on {}, takes setpoints on {}, readiness on {}",
            cfg.feedback_id,
            cfg.setpoint_id,
            cfg.readiness_id.map_or("none".into(), |r| r.to_string())
        );
    }
    // What the node serves: the run's values, and the text registers as given.
    let mut served = registers::drive_registers(&cfg, args.registers.is_some());
    if let Some(d) = file_registers.get("uavcan.node.description") {
        let _ = served.set("uavcan.node.description", &d.value.clone());
    }
    let register_file = args.registers.clone();
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
    let drive = Drive::with_registers(
        cfg,
        &served,
        propid_drive::realtime::Clock::now(&SystemClock),
    );
    let outcome = run_drive_machine(
        drive,
        transport.as_mut(),
        &SystemClock,
        &stop,
        &mut out,
        &mut |e| {
            if let DriveEvent::RegisterWritten { name, value } = e {
                save_written(register_file.as_deref(), &mut file_registers, name, value);
            }
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
