//! `propid drive`: the seed's settings checked (flags, environment, register file), the signal
//! handlers, progress lines and exit codes around [`propid_drive_host::drive::run_drive`].

use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use anyhow::Context;
use propid_core::can::{NodeId, SubjectId};
use propid_core::dsdl::Value;
use propid_drive_host::drive::run_drive_machine;
use propid_drive_host::realtime::{Clock, SystemClock};
use propid_drive_host::register_file::render_file;
use propid_drive_host::stand::Played;
use propid_drive_proto::drive::{drive_registers, Drive, DriveConfig, DriveEvent, Progress};
use propid_drive_proto::excitation::Schedule;
use propid_drive_proto::limits::{Limits, SoftStart};
use propid_drive_proto::registers::{self, NODE_DESCRIPTION};
use propid_drive_proto::settings::{
    parse_speed, Deadman, InitDuration, MaxSpeed, PatternDuration, Period, RampDuration, Range,
    RangeError, RelativeError, SetpointPeriod, SetpointRange, SoftStartDuration, SoftStartSetpoint,
    WatchdogMargin, RAD_S_PER_RPM,
};
use propid_drive_proto::{HostRegistry, StopReason};
use propid_science::excitation::{Excitation, Pattern};

use crate::bus::{Bus, BusArgs};
use crate::settings::{
    checked, command_args, environment, fill, numbers, setpoint_range, setting, ConfigError,
    ConfigErrors, Names, Problem, RegisterFile,
};
use crate::InputError;

setting! {
    /// This node's ID.
    NodeIdSetting: Option<NodeId> =
        Names::register("node-id", registers::NODE_ID, "UAVCAN__NODE__ID"),
        "This node's ID",
        crate::settings::node_id;
    /// This node's description (register and environment only).
    Description: String = Names {
        flag: None,
        register: Some(NODE_DESCRIPTION),
        env: Some("UAVCAN__NODE__DESCRIPTION"),
    },
        "This node's description",
        |text: &str| Ok(text.to_string());
    /// The readiness publisher's subject.
    ReadinessId: Option<SubjectId> =
        Names::register("readiness-id", registers::DRIVE_READINESS_ID, "UAVCAN__PUB__READINESS__ID"),
        "Subject-ID of the readiness publisher; none is published when unset",
        crate::settings::subject_id;
    /// The setpoint publisher's subject.
    SetpointId: Option<SubjectId> =
        Names::register("setpoint-id", registers::DRIVE_SETPOINT_ID, "UAVCAN__PUB__SP_RAT__ID"),
        "Subject-ID of the ratiometric setpoint publisher",
        crate::settings::subject_id;
    /// The feedback subscriber's subject.
    FeedbackId: Option<SubjectId> =
        Names::register("feedback-id", registers::DRIVE_FEEDBACK_ID, "UAVCAN__SUB__FB_DYN__ID"),
        "Subject-ID of the dynamics feedback subscriber",
        crate::settings::subject_id;
    /// The setpoint range.
    LoHi: SetpointRange =
        Names::register("setpoint-rat-lo-hi", registers::SETPOINT_RAT_LO_HI, "SETPOINT_RAT_LO_HI"),
        "Setpoint range \"LO HI\", ratiometric, -1 ≤ LO < HI ≤ 1 [default: 0.1 0.9]",
        setpoint_range;
    /// The pattern's period.
    PeriodSetting: Period = Names::register("period", registers::PERIOD, "PERIOD"),
        "Period of the sinusoid [s] [default: 2]",
        within Period;
    /// The pattern's duration.
    PatternDurationSetting: PatternDuration =
        Names::register("pattern-duration", registers::PATTERN_DURATION, "PATTERN_DURATION"),
        "Duration of the pattern [s] [default: 200]",
        within PatternDuration;
    /// The init phase's duration.
    InitDurationSetting: InitDuration =
        Names::register("init-duration", registers::INIT_DURATION, "INIT_DURATION"),
        "Duration of the initial run at the high setpoint [s] [default: 5]",
        within InitDuration;
    /// The setpoint publication period.
    SetpointPeriodSetting: SetpointPeriod =
        Names::register("setpoint-period", registers::SETPOINT_PERIOD, "SETPOINT_PERIOD"),
        "Setpoint publication period [s] [default: 0.005]",
        within SetpointPeriod;
    /// The deadman timeout.
    DeadmanSetting: Deadman = Names::flag("deadman"),
        "Stop (commanding STANDBY) when no feedback arrives for this long during the pattern [s] [default: 0.5]",
        within Deadman;
    /// The drive whose heartbeat is watched.
    DriveNodeId: NodeId = Names::flag("drive-node-id"),
        "Node-ID of the drive, whose heartbeat is watched for a reboot (default: the publisher of the first feedback message)",
        |text: &str| text.parse::<NodeId>().map_err(Problem::Id);
    /// The precision to stop at.
    UntilStderr: RelativeError = Names::flag("until-stderr"),
        "Stop (with STANDBY, as always) once the relative standard errors of J and c2 are both at most this many percent; the pattern duration is then the longest the run may take",
        |text: &str| {
            let percent = Range { lo: 0.0, lo_open: true, hi: 100.0, hi_open: true, unit: "%" };
            let p = crate::settings::seconds_in(text, percent)?;
            RelativeError::new(p / 100.0).map_err(|_| Problem::Range(RangeError { range: percent, got: p }))
        };
    /// The highest speed allowed.
    MaxSpeedSetting: Option<MaxSpeed> =
        Names::register("max-speed", registers::MAX_SPEED, "MAX_SPEED"),
        "The highest speed the rotor may reach: rad/s, or rpm (12000rpm); 0: none [default: none: give your propeller's rated speed]",
        |text: &str| speed_or_none(text, MaxSpeed::new);
    /// The soft start's setpoint.
    SoftStartSetpointSetting: SoftStartSetpoint =
        Names::register("soft-start-setpoint", registers::SOFT_START_SETPOINT, "SOFT_START_SETPOINT"),
        "The soft start's setpoint: a ratiometric magnitude in (0, 1], applied in the direction of hi, at most |hi| [default: 0.1]",
        within SoftStartSetpoint;
    /// The soft start's duration.
    SoftStartDurationSetting: Option<SoftStartDuration> =
        Names::register("soft-start-duration", registers::SOFT_START_DURATION, "SOFT_START_DURATION"),
        "How long the soft start lasts before the init phase [s]; feedback must arrive and the rotor speed up the commanded way; 0: no soft start [default: 1]",
        |text: &str| seconds_or_none(text, SoftStartDuration::new);
    /// The ramp's duration.
    RampDurationSetting: Option<RampDuration> =
        Names::register("ramp-duration", registers::RAMP_DURATION, "RAMP_DURATION"),
        "A ramp from the soft start's setpoint to hi over this long [s], before the init phase; 0: none [default: 0]",
        |text: &str| seconds_or_none(text, RampDuration::new);
    /// The speed watchdog's margin.
    SpeedWatchdogSetting: Option<WatchdogMargin> =
        Names::register("speed-watchdog", registers::SPEED_WATCHDOG, "SPEED_WATCHDOG"),
        "The speed watchdog: how far the speed may run past what the reported torque can drive it, rad/s or rpm; 0: off [default: 50]",
        |text: &str| speed_or_none(text, WatchdogMargin::new);
}

/// What a speed's text must be.
const SPEED: &str = "speed in rad/s, or rpm (12000rpm)";

/// A speed (rad/s, or rpm), 0 for none, made into `make`'s type.
fn speed_or_none<T>(
    text: &str,
    make: fn(f64) -> Result<T, RangeError>,
) -> Result<Option<T>, Problem> {
    let v = parse_speed(text).ok_or_else(|| Problem::Type {
        text: text.to_string(),
        ty: SPEED,
    })?;
    if v == 0.0 {
        return Ok(None);
    }
    make(v).map(Some).map_err(Problem::Range)
}

/// Seconds, 0 for none, made into `make`'s type.
fn seconds_or_none<T>(
    text: &str,
    make: fn(f64) -> Result<T, RangeError>,
) -> Result<Option<T>, Problem> {
    let [v] = numbers::<1>(text)?;
    if v == 0.0 {
        return Ok(None);
    }
    make(v).map(Some).map_err(Problem::Range)
}

command_args! {
    /// Arguments of `propid drive`. The seed's settings are registers (docs/REGISTERS.md): each
    /// comes from its default, then the `--registers` file, then its environment variable (the
    /// register's name as PyCyphal maps it, e.g. `SETPOINT_RAT_LO_HI`, `UAVCAN__NODE__ID`), then
    /// the flag; the node serves them over uavcan.register.List/Access while it drives.
    pub struct Args {
        settings {
            node_id: NodeIdSetting as "ID",
            readiness_id: ReadinessId as "ID",
            setpoint_id: SetpointId as "ID",
            feedback_id: FeedbackId as "ID",
            setpoint_rat_lo_hi: LoHi as "LO HI",
            period: PeriodSetting as "S",
            pattern_duration: PatternDurationSetting as "S",
            init_duration: InitDurationSetting as "S",
            setpoint_period: SetpointPeriodSetting as "S",
            deadman: DeadmanSetting as "S",
            drive_node_id: DriveNodeId as "ID",
            until_stderr: UntilStderr as "PCT",
            max_speed: MaxSpeedSetting as "SPEED",
            soft_start_setpoint: SoftStartSetpointSetting as "SETPOINT",
            soft_start_duration: SoftStartDurationSetting as "S",
            ramp_duration: RampDurationSetting as "S",
            speed_watchdog: SpeedWatchdogSetting as "SPEED",
        }
        registers {
            description: Description,
        }
        nested {
            bus: BusArgs,
        }
        /// A register file: `name: value` lines (values as the environment variables take them),
        /// read before the environment and the flags; registers written over the bus are saved
        /// to it.
        #[arg(long, value_name = "FILE")]
        pub registers: Option<PathBuf>,
        /// Take the port-IDs from the drive's own registers (uavcan.pub.dynamics.id,
        /// uavcan.sub.setpoint_r_torq.id, uavcan.sub.readiness.id) and refuse to engage it when
        /// its configuration would spoil the data (see `propid telega`).
        #[arg(long, value_name = "NODE")]
        pub from_telega: Option<NodeId>,
        /// Print the registers (defaults, file, environment and flags applied and checked) in the
        /// register file's format, and exit without opening the bus.
        #[arg(long)]
        pub show_registers: bool,
        /// Pattern after the init phase (the seed: sine).
        #[arg(long, default_value_t = Pattern::Sine)]
        pub pattern: Pattern,
        /// Print the running estimate of J, c1, c2 on stderr while driving and, once the motor
        /// is at rest, the recording's Result (`propid diagnose`'s).
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
        /// Serve a live page of the run (plots, running estimate, bus health, a STOP button) on
        /// this address (loopback; the URL with its per-run token is printed on stderr).
        #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "127.0.0.1:8080")]
        pub live: Option<String>,
        /// Allow --live on an address other than loopback (anyone who can reach it and has the
        /// token can stop the drive).
        #[arg(long)]
        pub live_allow_remote: bool,
    }
}

/// `propid drive`'s arguments with the environment and the register file filled in, and what
/// was wrong on the way (a register file that cannot be read, lines that are not registers).
pub struct Raw {
    /// The arguments.
    pub args: Args,
    /// Errors so far.
    pub errors: ConfigErrors,
}

impl Args {
    /// These arguments with the environment (`vars`) and the register file filled in.
    pub fn raw(mut self, vars: &std::collections::HashMap<String, String>) -> Raw {
        let mut errors = ConfigErrors::default();
        let file = self
            .registers
            .as_deref()
            .and_then(|p| RegisterFile::read(p, &mut errors));
        // Served but not settings: the ports' `.type` registers.
        let defaults = registers::drive_defaults(false);
        let read_only: Vec<&str> = defaults
            .iter()
            .filter(|r| !r.mutable)
            .filter_map(|r| r.name.as_str())
            .collect();
        fill(&mut self, vars, file.as_ref(), &read_only, &mut errors);
        Raw { args: self, errors }
    }

    /// The checked settings of these arguments, the process's environment and the register file.
    pub fn settings(self) -> Result<Settings, ConfigErrors> {
        Settings::try_from(self.raw(&environment()))
    }
}

/// `propid drive`'s settings, checked: nothing here can be out of range.
#[derive(Clone, Debug)]
pub struct Settings {
    /// The bus.
    pub bus: Bus,
    /// This node's ID.
    pub node_id: NodeId,
    /// Its description.
    pub description: String,
    /// The register file, if any (written registers are saved to it).
    pub registers: Option<PathBuf>,
    /// Read the port-IDs from this drive.
    pub from_telega: Option<NodeId>,
    /// Print the registers and exit.
    pub show_registers: bool,
    /// Readiness subject.
    pub readiness_id: Option<SubjectId>,
    /// Setpoint subject (`None` only with `from_telega`: the drive's).
    pub setpoint_id: Option<SubjectId>,
    /// Feedback subject (`None` only with `from_telega`: the drive's).
    pub feedback_id: Option<SubjectId>,
    /// What to play.
    pub played: Played,
    /// Setpoint period.
    pub setpoint_period: SetpointPeriod,
    /// Deadman timeout.
    pub deadman: Deadman,
    /// The drive whose heartbeat is watched.
    pub drive_node_id: Option<NodeId>,
    /// Print the running estimate.
    pub fit: bool,
    /// Where the TSV goes (`None`: standard output).
    pub output: Option<PathBuf>,
    /// Progress lines.
    pub progress: bool,
    /// Stop once this precise.
    pub until: Option<RelativeError>,
    /// Serve the live page here.
    pub live: Option<String>,
    /// Even on a non-loopback address.
    pub live_allow_remote: bool,
    /// The limits that stop a runaway rotor.
    pub limits: Limits,
}

impl TryFrom<Raw> for Settings {
    type Error = ConfigErrors;

    /// Checks every setting and reports every error at once.
    fn try_from(raw: Raw) -> Result<Settings, ConfigErrors> {
        let Raw { args, mut errors } = raw;
        // Every field named: a setting added to Args and not checked here does not compile.
        let Args {
            node_id,
            description,
            bus,
            registers,
            from_telega,
            show_registers,
            readiness_id,
            setpoint_id,
            feedback_id,
            setpoint_rat_lo_hi,
            period,
            pattern_duration,
            init_duration,
            setpoint_period,
            pattern,
            deadman,
            drive_node_id,
            fit,
            output,
            progress,
            pattern_file,
            until_stderr,
            max_speed,
            soft_start_setpoint,
            soft_start_duration,
            ramp_duration,
            speed_watchdog,
            live,
            live_allow_remote,
        } = args;
        let e = &mut errors;
        let seed = Schedule::SEED;
        let node_id = e.required_id(node_id);
        let description = e.or(description, String::new());
        let bus = Bus::check(bus, e);
        let readiness_id = e.or(readiness_id, None);
        // With --from-telega the drive's own registers give the ports the settings leave out.
        let (setpoint_id, feedback_id) = match from_telega {
            Some(_) => (e.or(setpoint_id, None), e.or(feedback_id, None)),
            None => (
                e.required_id(setpoint_id).map(Some),
                e.required_id(feedback_id).map(Some),
            ),
        };
        let range = e.or(setpoint_rat_lo_hi, seed.range);
        let period = e.or(period, seed.period);
        let duration = e.or(pattern_duration, seed.duration);
        let init_duration = e.or(init_duration, seed.init_duration);
        let setpoint_period = e.or(setpoint_period, SetpointPeriod::SEED);
        let deadman = e.or(deadman, Deadman::DEFAULT);
        let drive_node_id = e.given(drive_node_id);
        let until = e.given(until_stderr);
        let defaults = Limits::DEFAULT;
        let max_speed = e.or(max_speed, defaults.max_speed);
        let soft_start_setpoint = e.or(soft_start_setpoint, SoftStart::DEFAULT.setpoint);
        let soft_start_duration = e.or(soft_start_duration, Some(SoftStart::DEFAULT.duration));
        let ramp = e.or(ramp_duration, defaults.ramp);
        let watchdog = e.or(speed_watchdog, defaults.watchdog);
        let from_file = pattern_file.map(|path| {
            crate::cmd::sim::read_pattern_file(&path)
                .map_err(|e| e.to_string())
                .and_then(|x| Played::try_from(x).map_err(|e| format!("{}: {e}", path.display())))
        });
        let from_file = match from_file {
            Some(Err(why)) => {
                e.push(ConfigError::Flag {
                    flag: "pattern-file",
                    why,
                });
                None
            }
            Some(Ok(played)) => Some(Some(played)),
            None => Some(None),
        };
        checked!(
            errors;
            node_id, description, bus, readiness_id, setpoint_id, feedback_id, range, period,
            duration, init_duration, setpoint_period, deadman, drive_node_id, until, from_file,
            max_speed, soft_start_setpoint, soft_start_duration, ramp, watchdog,
        );
        let played = from_file.unwrap_or_else(|| {
            let schedule = Schedule {
                range,
                period,
                duration,
                init_duration,
            };
            Played::new(schedule, pattern)
        });
        Ok(Settings {
            bus,
            node_id,
            description,
            registers,
            from_telega,
            show_registers,
            readiness_id,
            setpoint_id,
            feedback_id,
            played,
            setpoint_period,
            deadman,
            drive_node_id,
            fit: fit || until.is_some(),
            output,
            progress,
            until,
            live,
            live_allow_remote,
            limits: Limits {
                max_speed,
                soft_start: soft_start_duration.map(|duration| SoftStart {
                    setpoint: soft_start_setpoint,
                    duration,
                }),
                ramp,
                watchdog,
            },
        })
    }
}

impl Settings {
    /// The driver's configuration (ports the drive was to give are 0 until it has).
    pub fn drive_config(&self) -> DriveConfig {
        DriveConfig {
            node_id: self.node_id,
            mtu: self.bus.mtu,
            readiness_id: self.readiness_id,
            setpoint_id: self.setpoint_id.unwrap_or(SubjectId::from_const(0)),
            feedback_id: self.feedback_id.unwrap_or(SubjectId::from_const(0)),
            drive_node_id: self.drive_node_id,
            excitation: Arc::new(self.played),
            setpoint_period: self.setpoint_period,
            deadman: self.deadman,
            fit: self.fit,
            until_rel_stderr: self.until,
            limits: self.limits,
        }
    }

    /// The registers the drive serves: `cfg`'s values and the description.
    pub fn served(&self, cfg: &DriveConfig) -> HostRegistry {
        let mut served = drive_registers(cfg, self.registers.is_some());
        let description = registers::text(&self.description);
        let _ = served.set(NODE_DESCRIPTION, &description);
        served
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
        line += &format!(", {}", estimate_words(&e));
    }
    line
}

/// J and c2 of the running estimate with their standard errors, or "not identified yet" while
/// the data do not pin them down (a value on its bound has a standard error of 0, which would
/// read as perfect precision).
fn estimate_words(e: &propid_drive_proto::drive::Estimate) -> String {
    let one = |name: &str, value: f64, stderr: f64| {
        let limit = propid_science::plausibility::MAX_RELATIVE_STDERR * value.abs();
        if stderr > 0.0 && stderr <= limit {
            format!("{name} = {value:.4e} ± {stderr:.1e}")
        } else {
            format!("{name} not identified yet")
        }
    };
    format!(
        "{}, {}",
        one("J", e.j, e.j_stderr),
        one("c2", e.c2, e.c2_stderr)
    )
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
    let s = args.settings()?;
    let mut cfg = s.drive_config();
    if s.show_registers {
        print!("{}", render_file(&s.served(&cfg)));
        return Ok(());
    }
    let mut transport = s.bus.open()?;
    if let Some(node) = s.from_telega {
        let ports =
            crate::cmd::telega::drive_ports(transport.as_mut(), cfg.node_id, cfg.mtu, node)?;
        let pick = |ours: Option<SubjectId>, theirs: Option<SubjectId>, name: &str, reg: &str| {
            match (ours, theirs) {
                (Some(f), Some(t)) if f != t => Err(InputError::invalid(format!(
                    "--{name} {f} but drive {node} has {reg} = {t}; drop the setting or change the register with propid telega"
                ))),
                (_, t) => Ok(t),
            }
        };
        let feedback = pick(
            s.feedback_id,
            ports.feedback,
            "feedback-id",
            registers::TELEGA_FEEDBACK_ID,
        )?;
        let setpoint = pick(
            s.setpoint_id,
            ports.setpoint,
            "setpoint-id",
            registers::TELEGA_SETPOINT_ID,
        )?;
        let readiness = pick(
            s.readiness_id,
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
    // What the node serves (and saves to the register file): the run's values.
    let mut served = s.served(&cfg);
    let stop = Arc::new(AtomicBool::new(false));
    let _handlers = crate::signals::install(&stop)?;
    // With --fit the recording is diagnosed at the end: on standard output, a copy of the rows
    // goes to a temporary file for it.
    let copy = match (&s.output, s.fit) {
        (None, true) => Some(
            tempfile::NamedTempFile::new()
                .context("cannot create a temporary file for --fit's copy of the rows")?,
        ),
        _ => None,
    };
    let mut out: Box<dyn Write> = match (&s.output, &copy) {
        (Some(p), _) => Box::new(
            std::fs::File::create(p).with_context(|| format!("cannot create {}", p.display()))?,
        ),
        (None, Some(c)) => Box::new(Tee(
            std::io::stdout(),
            std::io::BufWriter::new(
                c.reopen()
                    .context("cannot write --fit's copy of the rows")?,
            ),
        )),
        (None, None) => Box::new(std::io::stdout()),
    };
    let excitation = *s.played.excitation();
    let readiness = cfg.readiness_id.is_some();
    let mut live = crate::live::start_for_drive(
        s.live.as_deref(),
        s.live_allow_remote,
        &stop,
        s.played,
        "propid drive",
    )?;
    eprintln!("drive: {}", limits_line(&cfg));
    let drive = Drive::with_registers(cfg, &served.clone(), SystemClock.now());
    let outcome = run_drive_machine(
        drive,
        transport.as_mut(),
        &SystemClock,
        &stop,
        &mut out,
        &mut |e| {
            if let DriveEvent::RegisterWritten { name, value } = e {
                save_written(s.registers.as_deref(), &mut served, name, value);
            }
            print_event(e, &excitation, s.progress);
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
    if let Some(e) = r.estimate.filter(|_| s.fit) {
        eprintln!("drive: running estimate {}", estimate_words(&e));
    }
    drop(out);
    if s.fit {
        // The motor is at rest (STANDBY and zero were sent above): the recording's Result, as
        // `propid diagnose` gives it.
        if let Some(path) = s.output.as_deref().or(copy.as_ref().map(|c| c.path())) {
            eprintln!(
                "drive: the motor is at rest; diagnosing the recording (seconds on a long run)"
            );
            eprint!("{}", result_of_recording(path));
        }
    }
    match &r.reason {
        StopReason::Completed | StopReason::Precise { .. }
            if outcome.standby_delivered(readiness) =>
        {
            Ok(())
        }
        StopReason::Completed => anyhow::bail!("the stop commands were not confirmed sent"),
        StopReason::Signal => Err(crate::Interrupted.into()),
        StopReason::Limit(limit) => Err(crate::LimitStopped(limit.to_string()).into()),
        reason => anyhow::bail!("{reason}"),
    }
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
            m.get() / RAD_S_PER_RPM
        )),
        None => parts.push(
            "no maximum speed (--max-speed: your propeller's rated speed, e.g. 12000rpm)".into(),
        ),
    }
    format!("limits: {}", parts.join("; "))
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
        "feedback: {} rows recorded, {} lost on the way ({share:.2} % kept): {} missing by the drive's timestamps (lost anywhere), {} by transfer-ID gaps (lost after the drive's queue: bus, adapter, kernel, reader); {} frames of damaged transfers",
        r.rows, l.lost(), l.by_timestamp, l.by_transfer_id, r.damaged_frames
    )
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

/// Writes to both.
struct Tee<A, B>(A, B);

impl<A: Write, B: Write> Write for Tee<A, B> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.write_all(buf)?;
        self.1.write_all(buf)?;
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.0.flush()?;
        self.1.flush()
    }
}

/// The Result of a recorded run (`drive --fit`'s last words): `propid diagnose`'s, or why there
/// is none. Never fails the command: the run itself is what its exit status reports.
fn result_of_recording(path: &std::path::Path) -> String {
    use propid_science::diagnose::Options;
    let diagnosed = super::DiagnosisInput::read(path, &Options::default().reading, false)
        .map_err(anyhow::Error::from)
        .and_then(|input| {
            let name = propid_io::error::display_name(path);
            super::diagnose::diagnose_input(input, Options::default(), None, &name, &|_| {})
        });
    match diagnosed {
        Err(e) => format!("drive: no Result: {e:#}\n"),
        Ok((_, Some(o))) => format!(
            "drive: the recording's Result (`propid diagnose` on the rows written; `--diameter` there adds C_Q):\n{}",
            o.to_text()
        ),
        Ok((report, None)) => format!(
            "drive: no Result: {}\n",
            report
                .verdict
                .cannot_judge_reasons()
                .unwrap_or_else(|| "the diagnosis could not judge".into())
        ),
    }
}
