//! `propid drive`: argument parsing, the signal handlers, progress lines and exit codes around
//! [`propid_drive_host::drive::run_drive`].

use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use anyhow::Context;
use propid_core::can::{Mtu, NodeId, SubjectId};
use propid_core::dsdl::Value;
use propid_drive_host::drive::run_drive_machine;
use propid_drive_host::realtime::SystemClock;
use propid_drive_host::register_file::{self, parse_text, render_file};
use propid_drive_host::stand::Played;
use propid_drive_proto::drive::{drive_registers, Drive, DriveConfig, DriveEvent, Progress};
use propid_drive_proto::excitation::Schedule;
use propid_drive_proto::limits::{Limits, SoftStart};
use propid_drive_proto::registers::{self, subject_register};
use propid_drive_proto::settings::{
    parse_speed, Deadman, InitDuration, MaxSpeed, PatternDuration, Period, RampDuration,
    RelativeError, SetpointPeriod, SetpointRange, SoftStartDuration, SoftStartSetpoint,
    WatchdogMargin,
};
use propid_drive_proto::{HostRegistry, StopReason};
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
    /// The highest speed the rotor may reach: rad/s, or rpm with `rpm` (`12000rpm`); 0: none
    /// (register max_speed, MAX_SPEED; default none: set your propeller's rated speed).
    #[arg(long, value_name = "SPEED", value_parser = speed_arg)]
    pub max_speed: Option<f64>,
    /// The soft start's setpoint, a ratiometric magnitude in (0, 1] applied in the direction of
    /// hi (register soft_start_setpoint, SOFT_START_SETPOINT; default 0.1).
    #[arg(long, value_name = "SETPOINT")]
    pub soft_start_setpoint: Option<f64>,
    /// How long the soft start lasts [s]; 0: none (register soft_start_duration,
    /// SOFT_START_DURATION; default 1).
    #[arg(long, value_name = "SECONDS")]
    pub soft_start_duration: Option<f64>,
    /// A ramp from the soft start's setpoint to hi over this long [s], before the init phase; 0:
    /// none (register ramp_duration, RAMP_DURATION; default 0).
    #[arg(long, value_name = "SECONDS")]
    pub ramp_duration: Option<f64>,
    /// The speed watchdog's margin: how far the speed may run past what the reported torque can
    /// explain, rad/s or rpm; 0: off (register speed_watchdog, SPEED_WATCHDOG; default 50).
    #[arg(long, value_name = "SPEED", value_parser = speed_arg)]
    pub speed_watchdog: Option<f64>,
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
                InputError(format!(
                    "cannot read the register file {}: {e}",
                    path.display()
                ))
            })?;
            let (entries, errors) = register_file::read_entries(&text);
            if let Some(e) = errors.first() {
                return Err(InputError(format!("{}:{}: {e}", path.display(), e.line)));
            }
            for e in entries {
                let origin = format!("{}:{}", path.display(), e.line);
                set_text(&mut r, &e.name, &e.value, &origin)?;
            }
        }
        let vars: Vec<(String, String)> = vars.into_iter().collect();
        let names: Vec<String> = r
            .iter()
            .filter(|x| x.mutable)
            .filter_map(|x| x.name.as_str().map(String::from))
            .collect();
        for name in names {
            let var = registers::environment_name(&name);
            if let Some((_, value)) = vars.iter().find(|(k, _)| *k == var) {
                set_text(&mut r, &name, value, &format!("environment variable {var}"))?;
            }
        }
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
        set(registers::MAX_SPEED, self.max_speed.map(r64));
        set(
            registers::SOFT_START_SETPOINT,
            self.soft_start_setpoint.map(r64),
        );
        set(
            registers::SOFT_START_DURATION,
            self.soft_start_duration.map(r64),
        );
        set(registers::RAMP_DURATION, self.ramp_duration.map(r64));
        set(registers::SPEED_WATCHDOG, self.speed_watchdog.map(r64));
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
            Some(p) => Some(RelativeError::new(p / 100.0).map_err(|_| {
                InputError(format!(
                    "--until-stderr must be a percentage in (0, 100) (got {p})"
                ))
            })?),
            None => None,
        };
        let first = |name: &str| r.get(name).and_then(|x| x.value.float_at(0));
        let number = |name: &'static str| first(name).unwrap_or(f64::NAN);
        let node_id = match first(registers::NODE_ID) {
            Some(v) if v < f64::from(registers::UNSET) => {
                Some(NodeId::try_from(v as u64).map_err(|e| flag_error(registers::NODE_ID, e))?)
            }
            _ => None,
        }
        .ok_or_else(|| flag_error(registers::NODE_ID, "is not set"))?;
        let port = |name: &'static str, required: bool| match subject_register(&r, name)
            .map_err(|e| flag_error(name, e))?
        {
            None if required && self.from_telega.is_none() => Err(flag_error(name, "is not set")),
            id => Ok(id),
        };
        let setpoint_id = port(registers::DRIVE_SETPOINT_ID, true)?;
        let feedback_id = port(registers::DRIVE_FEEDBACK_ID, true)?;
        let readiness_id = port(registers::DRIVE_READINESS_ID, false)?;
        let lohi = r.get(registers::SETPOINT_RAT_LO_HI).map(|x| &x.value);
        let (lo, hi) = (
            lohi.and_then(|v| v.float_at(0)).unwrap_or(f64::NAN),
            lohi.and_then(|v| v.float_at(1)).unwrap_or(f64::NAN),
        );
        let schedule = Schedule {
            range: SetpointRange::new(lo, hi)
                .map_err(|e| flag_error(registers::SETPOINT_RAT_LO_HI, e))?,
            period: Period::new(number(registers::PERIOD))
                .map_err(|e| flag_error(registers::PERIOD, e))?,
            duration: PatternDuration::new(number(registers::PATTERN_DURATION))
                .map_err(|e| flag_error(registers::PATTERN_DURATION, e))?,
            init_duration: InitDuration::new(number(registers::INIT_DURATION))
                .map_err(|e| flag_error(registers::INIT_DURATION, e))?,
        };
        let played = match &self.pattern_file {
            Some(path) => Played::try_from(crate::cmd::sim::read_pattern_file(path)?)
                .map_err(|e| InputError(format!("{}: {e}", path.display())))?,
            None => Played::new(schedule, self.pattern),
        };
        let cfg = DriveConfig {
            node_id,
            mtu: Mtu::from_bytes(self.bus.mtu).ok_or_else(|| {
                InputError(format!("--mtu must be 8 or 64 (got {})", self.bus.mtu))
            })?,
            readiness_id,
            // Zero until --from-telega reads the drive's.
            setpoint_id: setpoint_id.unwrap_or(SubjectId::from_const(0)),
            feedback_id: feedback_id.unwrap_or(SubjectId::from_const(0)),
            drive_node_id: self.drive_node_id,
            excitation: std::sync::Arc::new(played),
            setpoint_period: SetpointPeriod::new(number(registers::SETPOINT_PERIOD))
                .map_err(|e| flag_error(registers::SETPOINT_PERIOD, e))?,
            deadman: Deadman::new(self.deadman).map_err(|e| flag_error("deadman", e))?,
            fit: self.fit || until_rel_stderr.is_some(),
            until_rel_stderr,
            limits: limits_of(&number)?,
        };
        Ok((cfg, r))
    }

    /// [`Args::config_with`] the process's environment.
    pub fn config(&self) -> Result<(DriveConfig, HostRegistry), InputError> {
        self.config_with(std::env::vars())
    }
}

/// A speed flag: rad/s, or rpm with `rpm`.
fn speed_arg(text: &str) -> Result<f64, String> {
    parse_speed(text)
        .ok_or_else(|| format!("`{text}` is not a speed: give rad/s (1256.6) or rpm (12000rpm)"))
}

/// The limits the registers hold (0: off), each checked.
fn limits_of(number: &dyn Fn(&'static str) -> f64) -> Result<Limits, InputError> {
    let positive = |name: &'static str| Some(number(name)).filter(|v| *v != 0.0);
    let soft_start = match positive(registers::SOFT_START_DURATION) {
        None => None,
        Some(d) => Some(SoftStart {
            setpoint: SoftStartSetpoint::new(number(registers::SOFT_START_SETPOINT))
                .map_err(|e| flag_error(registers::SOFT_START_SETPOINT, e))?,
            duration: SoftStartDuration::new(d)
                .map_err(|e| flag_error(registers::SOFT_START_DURATION, e))?,
        }),
    };
    Ok(Limits {
        max_speed: positive(registers::MAX_SPEED)
            .map(MaxSpeed::new)
            .transpose()
            .map_err(|e| flag_error(registers::MAX_SPEED, e))?,
        soft_start,
        ramp: positive(registers::RAMP_DURATION)
            .map(RampDuration::new)
            .transpose()
            .map_err(|e| flag_error(registers::RAMP_DURATION, e))?,
        watchdog: positive(registers::SPEED_WATCHDOG)
            .map(WatchdogMargin::new)
            .transpose()
            .map_err(|e| flag_error(registers::SPEED_WATCHDOG, e))?,
    })
}

/// Sets one register from text; the error names `origin`. Speed registers also take rpm.
fn set_text(r: &mut HostRegistry, name: &str, text: &str, origin: &str) -> Result<(), InputError> {
    let current = r
        .get(name)
        .ok_or_else(|| InputError(format!("{origin}: no register named {name}")))?;
    let converted;
    let text = if [registers::MAX_SPEED, registers::SPEED_WATCHDOG].contains(&name) {
        match parse_speed(text) {
            Some(v) => {
                converted = v.to_string();
                converted.as_str()
            }
            None => text,
        }
    } else {
        text
    };
    let value = parse_text(&current.value, text).ok_or_else(|| {
        InputError(format!(
            "{origin}: `{text}` is not a valid {} for register {name}",
            registers::describe(&current.value)
        ))
    })?;
    r.set(name, &value)
        .map_err(|e| InputError(format!("{origin}: {name}: {e}")))
}

/// A configuration error in the words of the command line: the flag, the register and its
/// environment variable, and what is wrong.
pub fn flag_error(setting: &str, problem: impl ToString) -> InputError {
    let problem = problem.to_string();
    let (flag, register) = match setting {
        registers::NODE_ID => ("--node-id", Some(registers::NODE_ID)),
        registers::DRIVE_SETPOINT_ID => ("--setpoint-id", Some(registers::DRIVE_SETPOINT_ID)),
        registers::DRIVE_FEEDBACK_ID => ("--feedback-id", Some(registers::DRIVE_FEEDBACK_ID)),
        registers::DRIVE_READINESS_ID => ("--readiness-id", Some(registers::DRIVE_READINESS_ID)),
        registers::SETPOINT_RAT_LO_HI => {
            ("--setpoint-rat-lo-hi", Some(registers::SETPOINT_RAT_LO_HI))
        }
        registers::PERIOD => ("--period", Some(registers::PERIOD)),
        registers::PATTERN_DURATION => ("--pattern-duration", Some(registers::PATTERN_DURATION)),
        registers::INIT_DURATION => ("--init-duration", Some(registers::INIT_DURATION)),
        registers::SETPOINT_PERIOD => ("--setpoint-period", Some(registers::SETPOINT_PERIOD)),
        registers::MAX_SPEED => ("--max-speed", Some(registers::MAX_SPEED)),
        registers::SOFT_START_SETPOINT => (
            "--soft-start-setpoint",
            Some(registers::SOFT_START_SETPOINT),
        ),
        registers::SOFT_START_DURATION => (
            "--soft-start-duration",
            Some(registers::SOFT_START_DURATION),
        ),
        registers::RAMP_DURATION => ("--ramp-duration", Some(registers::RAMP_DURATION)),
        registers::SPEED_WATCHDOG => ("--speed-watchdog", Some(registers::SPEED_WATCHDOG)),
        other => return InputError(format!("--{} {problem}", other.replace('_', "-"))),
    };
    match register {
        Some(reg) => InputError(format!(
            "{flag} (register {reg}, {}) {problem}",
            registers::environment_name(reg)
        )),
        None => InputError(format!("{flag} {problem}")),
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
        DriveEvent::SoftStartPassed(p) if progress => eprintln!(
            "drive: soft start passed: {} feedback messages, the rotor went from {:.1} to {:.1} rad/s the commanded way",
            p.messages, p.from, p.to
        ),
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
    match std::fs::write(path, render_file(regs)) {
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
        print!("{}", render_file(&file_registers));
        return Ok(());
    }
    let mut transport = args.bus.open()?;
    if let Some(node) = args.from_telega {
        let ports =
            crate::cmd::telega::drive_ports(transport.as_mut(), cfg.node_id, cfg.mtu, node)?;
        let pick = |flag: Option<SubjectId>, theirs: Option<SubjectId>, name: &str, reg: &str| {
            match (flag, theirs) {
                (Some(f), Some(t)) if f != t => Err(InputError(format!(
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
            InputError(format!(
                "drive {node} has no {} set",
                registers::TELEGA_FEEDBACK_ID
            ))
        })?;
        cfg.setpoint_id = setpoint.ok_or_else(|| {
            InputError(format!(
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
    let mut served = drive_registers(&cfg, args.registers.is_some());
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
    let played = played_of(&args, &cfg)?;
    let excitation = *played.excitation();
    let readiness = cfg.readiness_id.is_some();
    let fit = cfg.fit;
    let mut live = crate::live::start_for_drive(
        args.live.as_deref(),
        args.live_allow_remote,
        &stop,
        played,
        "propid drive",
    )?;
    eprintln!("drive: {}", limits_line(&cfg));
    let drive = Drive::with_registers(
        cfg,
        &served,
        propid_drive_host::realtime::Clock::now(&SystemClock),
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
    eprintln!("drive: {}", feedback_line(r));
    eprintln!("drive: {}", priority_line(&outcome.link.priority));
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
        StopReason::Limit(limit) => Err(crate::LimitStopped(limit.to_string()).into()),
        reason => anyhow::bail!("{reason}"),
    }
}

/// How much feedback was lost on its way during the recording, and where it was seen missing.
pub fn feedback_line(r: &propid_drive_proto::drive::StopReport) -> String {
    let l = r.feedback_lost;
    let expected = r.rows + l.lost();
    let share = if expected == 0 {
        100.0
    } else {
        100.0 * r.rows as f64 / expected as f64
    };
    format!(
        "feedback: {} rows recorded, {} lost on the way ({share:.2} % kept): {} missing by the drive's timestamps (lost anywhere), {} by transfer-ID gaps (lost after the drive's queue: bus, adapter, kernel, reader); {} frames rejected by the reassembler",
        r.rows, l.lost(), l.by_timestamp, l.by_transfer_id, r.dropped_transfers
    )
}

/// The limits in force, said before the run.
pub fn limits_line(cfg: &DriveConfig) -> String {
    let l = &cfg.limits;
    let hi = cfg.excitation.schedule().range.hi();
    let mut parts = Vec::new();
    match l.soft_start {
        Some(s) => parts.push(format!(
            "soft start at {:+} for {} s (feedback and the direction checked before any high torque)",
            s.setpoint.get().min(hi.abs()).copysign(if hi < 0.0 { -1.0 } else { 1.0 }),
            s.duration
        )),
        None => parts.push("no soft start".into()),
    }
    if let Some(r) = l.ramp {
        parts.push(format!("a {r} s ramp to {hi}"));
    }
    match l.watchdog {
        Some(w) => parts.push(format!("speed watchdog, margin {w} rad/s")),
        None => parts.push("no speed watchdog".into()),
    }
    match l.max_speed {
        Some(m) => parts.push(format!(
            "maximum speed {m} rad/s ({:.0} rpm)",
            m.get() / propid_drive_proto::settings::RAD_S_PER_RPM
        )),
        None => parts.push(
            "no maximum speed (--max-speed: your propeller's rated speed, e.g. 12000rpm)".into(),
        ),
    }
    format!("limits: {}", parts.join("; "))
}

/// The loop's scheduling priority, and how to get a real-time one where it was refused.
pub fn priority_line(p: &propid_transport::priority::ThreadPriority) -> String {
    if p.is_realtime() {
        format!("the control loop and the serial reader ran at {p}")
    } else {
        format!(
            "the control loop ran at {p}; on a busy machine it can wait for a CPU long enough to lose feedback (docs/TRANSPORTS.md); on Linux `sudo setcap cap_sys_nice+ep \"$(command -v propid)\"` lets it take a real-time priority"
        )
    }
}

/// What `cfg` plays, as the science describes it (for the progress lines and the live page).
fn played_of(args: &Args, cfg: &DriveConfig) -> Result<Played, InputError> {
    match &args.pattern_file {
        Some(path) => Played::try_from(crate::cmd::sim::read_pattern_file(path)?)
            .map_err(|e| InputError(format!("{}: {e}", path.display()))),
        None => Ok(Played::new(cfg.excitation.schedule(), args.pattern)),
    }
}
