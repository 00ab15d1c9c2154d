//! `propid drive`: the seed's driver as a Cyphal node.
//!
//! ```text
//!  DriveConfig (PyCyphal register env vars or flags) ─► validate before anything is sent
//!  loop (HostClock):
//!    every setpoint period: Readiness ENGAGED + Vector31 setpoint ─► Node::publish ─► transport
//!    transport.receive ─► Node::handle_frame ─► DoF3rdTs ─► TSV row (flushed) [+ running fit]
//!    Node::poll_transmit ─► transport.send   (heartbeat 1 Hz, GetInfo answers)
//!  phases: init at hi (feedback ignored) → header → pattern (sine | steps | chirp) → stop
//!  stop (end, error, SIGINT/SIGTERM, feedback silent > deadman): STANDBY + zero setpoint, several
//!  times, then exit, saying why on stderr
//! ```

use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use anyhow::Context;
use propid_core::can::{Mtu, Priority};
use propid_core::dsdl::{DataType, DoF3rdTs, Readiness, Vector31};
use propid_core::estimate::{LoadBounds, LoadEstimator};
use propid_core::node::{Event, Node, NodeConfig};
use propid_core::time::Instant;
use propid_transport::{CanTransport, HostClock};

use crate::sim::{Excitation, Pattern};
use crate::tsv::{Row, Sample, TsvWriter};
use crate::InputError;

/// The node type of the host tools: 8 ports, 16 sessions, 512-byte transfers, 256 queued frames.
pub type HostNode = Node<8, 16, 512, 256>;

/// How many times the stop command (STANDBY + zero setpoint) is sent.
pub const STOP_REPEATS: usize = 5;

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
    #[arg(long, value_enum, default_value_t = Pattern::Sine)]
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

/// A validated configuration.
#[derive(Clone, Debug)]
pub struct DriveConfig {
    /// Node-ID.
    pub node_id: u8,
    /// MTU (8 or 64).
    pub mtu: usize,
    /// Readiness subject, if any.
    pub readiness_id: Option<u16>,
    /// Setpoint subject.
    pub setpoint_id: u16,
    /// Feedback subject.
    pub feedback_id: u16,
    /// The excitation.
    pub excitation: Excitation,
    /// Setpoint period [s].
    pub setpoint_period: f64,
    /// Deadman timeout [s].
    pub deadman: f64,
    /// Running fit on stderr.
    pub fit: bool,
    /// Progress on stderr.
    pub progress: bool,
}

impl DriveConfig {
    /// The seed document's example set-up: node 10, readiness on subject 10, setpoint on 24,
    /// feedback on 110, Classic CAN, a setpoint every 5 ms, a 0.5 s deadman, no progress lines.
    pub fn example(excitation: Excitation) -> Self {
        DriveConfig {
            node_id: 10,
            mtu: 8,
            readiness_id: Some(10),
            setpoint_id: 24,
            feedback_id: 110,
            excitation,
            setpoint_period: 0.005,
            deadman: 0.5,
            fit: false,
            progress: false,
        }
    }
}

impl Args {
    /// Checks everything before anything is sent.
    pub fn config(&self) -> Result<DriveConfig, InputError> {
        let need = |v: Option<u16>, what: &str, var: &str| {
            v.ok_or_else(|| {
                InputError(format!(
                    "{what} is not set: give --{} or {var}",
                    what.replace(' ', "-")
                ))
            })
        };
        let node_id = self.node_id.ok_or_else(|| {
            InputError("node id is not set: give --node-id or UAVCAN__NODE__ID".into())
        })?;
        if node_id > 127 {
            return Err(InputError(format!(
                "node id must be 0..=127 (got {node_id})"
            )));
        }
        let setpoint_id = need(self.setpoint_id, "setpoint id", "UAVCAN__PUB__SP_RAT__ID")?;
        let feedback_id = need(self.feedback_id, "feedback id", "UAVCAN__SUB__FB_DYN__ID")?;
        for (name, id) in [
            ("setpoint", Some(setpoint_id)),
            ("feedback", Some(feedback_id)),
            ("readiness", self.readiness_id),
        ] {
            if id.is_some_and(|id| id > 8191) {
                return Err(InputError(format!(
                    "{name} subject-ID must be 0..=8191 (got {})",
                    id.unwrap_or(0)
                )));
            }
        }
        let lohi: Vec<f64> = self
            .setpoint_rat_lo_hi
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
            .map(|s| s.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| {
                InputError(format!(
                    "setpoint_rat_lo_hi `{}` is not two numbers",
                    self.setpoint_rat_lo_hi
                ))
            })?;
        let [lo, hi] = lohi[..] else {
            return Err(InputError(format!(
                "setpoint_rat_lo_hi `{}` is not two numbers",
                self.setpoint_rat_lo_hi
            )));
        };
        let excitation = Excitation {
            lo,
            hi,
            period: self.period,
            duration: self.pattern_duration,
            init_duration: self.init_duration,
            pattern: self.pattern,
        };
        excitation.validate()?;
        if !(self.setpoint_period > 0.0 && self.setpoint_period < 1.0) {
            return Err(InputError(format!(
                "setpoint_period must be in (0, 1) s (got {})",
                self.setpoint_period
            )));
        }
        if self.deadman.is_nan() || self.deadman <= 0.0 {
            return Err(InputError(format!(
                "--deadman must be positive (got {})",
                self.deadman
            )));
        }
        if self.bus.mtu != 8 && self.bus.mtu != 64 {
            return Err(InputError(format!(
                "MTU must be 8 or 64 (got {})",
                self.bus.mtu
            )));
        }
        Ok(DriveConfig {
            node_id,
            mtu: self.bus.mtu,
            readiness_id: self.readiness_id,
            setpoint_id,
            feedback_id,
            excitation,
            setpoint_period: self.setpoint_period,
            deadman: self.deadman,
            fit: self.fit,
            progress: self.progress,
        })
    }
}

/// Why the drive stopped.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum StopReason {
    /// The pattern ran to its end.
    Completed,
    /// SIGINT or SIGTERM.
    Signal,
    /// No feedback for longer than the deadman timeout.
    LostFeedback,
    /// A transport or output error.
    Error(String),
}

/// What a drive did.
#[derive(Clone, Debug)]
pub struct DriveOutcome {
    /// Why it stopped.
    pub reason: StopReason,
    /// TSV rows written.
    pub rows: u64,
    /// Running estimate at the end, when enough data arrived.
    pub estimate: Option<(f64, f64, f64)>,
}

struct Driver<'a> {
    cfg: &'a DriveConfig,
    node: HostNode,
    transport: &'a mut dyn CanTransport,
}

impl Driver<'_> {
    fn publish(&mut self, now: Instant, readiness: u8, setpoint: f32) {
        let timeout = Duration::from_secs_f64(self.cfg.setpoint_period * 2.0);
        if let Some(id) = self.cfg.readiness_id {
            let _ = self.node.publish_message(
                now,
                id,
                Priority::HIGH,
                &Readiness { value: readiness },
                timeout,
            );
        }
        let _ = self.node.publish_message(
            now,
            self.cfg.setpoint_id,
            Priority::HIGH,
            &Vector31::splat(setpoint),
            timeout,
        );
    }

    fn flush(&mut self, now: Instant) -> Result<(), String> {
        while let Some(f) = self.node.poll_transmit(now) {
            self.transport.send(&f).map_err(|e| e.to_string())?;
        }
        Ok(())
    }

    /// STANDBY and a zero setpoint, several times; errors are ignored (the bus may be broken,
    /// but every attempt counts).
    fn stop(&mut self) {
        for _ in 0..STOP_REPEATS {
            let now = HostClock::now();
            self.publish(now, Readiness::STANDBY, 0.0);
            let _ = self.flush(now);
            std::thread::sleep(Duration::from_secs_f64(self.cfg.setpoint_period));
        }
    }
}

/// Drives the stand until the pattern ends or `stop` is raised; writes the TSV to `out`.
pub fn drive(
    cfg: &DriveConfig,
    transport: &mut dyn CanTransport,
    out: &mut dyn Write,
    stop: &AtomicBool,
) -> DriveOutcome {
    let mtu = if cfg.mtu == 64 { Mtu::Fd } else { Mtu::Classic };
    let mut node_config = NodeConfig::new(cfg.node_id, "org.propid.drive", mtu);
    node_config.software_version.minor = 1;
    let start = HostClock::now();
    let mut d = Driver {
        cfg,
        node: HostNode::new(node_config, start),
        transport,
    };
    let _ = d
        .node
        .subscribe_message(cfg.feedback_id, DoF3rdTs::EXTENT_BYTES);
    let ex = cfg.excitation;
    let period = Duration::from_secs_f64(cfg.setpoint_period);
    let init_end = start + Duration::from_secs_f64(ex.init_duration);
    let mut pattern_start: Option<Instant> = None;
    let mut writer: Option<TsvWriter<&mut dyn Write>> = None;
    let mut out = Some(out);
    let mut next_publish = start;
    let mut last_feedback = start;
    let mut rows = 0u64;
    let mut estimator = LoadEstimator::<f64>::new();
    let mut next_progress = start + Duration::from_secs(1);
    let mut rows_at_progress = 0u64;
    let reason = loop {
        let now = HostClock::now();
        if stop.load(Ordering::Relaxed) {
            break StopReason::Signal;
        }
        // Phase changes.
        if pattern_start.is_none() && now >= init_end {
            pattern_start = Some(now);
            last_feedback = now;
            if let Some(o) = out.take() {
                match TsvWriter::new(o, true) {
                    Ok(w) => writer = Some(w),
                    Err(e) => break StopReason::Error(format!("cannot write the TSV: {e}")),
                }
            }
            if cfg.progress {
                eprintln!(
                    "drive: pattern commenced ({:?}, {} s)",
                    ex.pattern, ex.duration
                );
            }
        }
        let elapsed = pattern_start.map(|p| now.saturating_duration_since(p).as_secs_f64());
        if elapsed.is_some_and(|e| e >= ex.duration) {
            break StopReason::Completed;
        }
        if pattern_start.is_some()
            && now.saturating_duration_since(last_feedback).as_secs_f64() > cfg.deadman
        {
            break StopReason::LostFeedback;
        }
        if now >= next_publish {
            let sp = match elapsed {
                None => ex.hi,
                Some(t) => ex.setpoint(t),
            };
            d.publish(now, Readiness::ENGAGED, sp as f32);
            next_publish = next_publish + period;
            if next_publish < now {
                next_publish = now + period;
            }
        }
        if let Err(e) = d.flush(now) {
            break StopReason::Error(e);
        }
        let wait = next_publish
            .saturating_duration_since(HostClock::now())
            .min(Duration::from_millis(5));
        let frame = match d.transport.receive(wait) {
            Ok(f) => f,
            Err(e) => break StopReason::Error(e.to_string()),
        };
        let Some(frame) = frame else { continue };
        let event_now = HostClock::now();
        let feedback = match d.node.handle_frame(event_now, &frame) {
            Some(Event::Message {
                subject_id,
                timestamp,
                payload,
                ..
            }) if subject_id == cfg.feedback_id => DoF3rdTs::deserialize(payload)
                .ok()
                .map(|fb| (timestamp, fb)),
            _ => None,
        };
        let Some((timestamp, fb)) = feedback else {
            continue;
        };
        // Feedback during the init phase is flushed, as the seed does.
        let Some(w) = writer.as_mut() else { continue };
        last_feedback = event_now;
        let k = &fb.value.kinematics;
        let sample = Sample {
            t: fb.timestamp.microsecond as f64 * 1e-6,
            force: f64::from(fb.value.force),
            velocity: f64::from(k.base.velocity),
            acceleration: f64::from(k.acceleration),
            position: f64::from(k.base.position),
        };
        if let Err(e) = w.write(&Row {
            ts_local: timestamp.as_secs_f64(),
            sample,
        }) {
            break StopReason::Error(format!("cannot write the TSV: {e}"));
        }
        rows += 1;
        if cfg.fit && sample.is_finite() {
            estimator.update(sample.force, sample.velocity, sample.acceleration);
        }
        if cfg.progress && event_now >= next_progress {
            let st = d.node.stats();
            let mut line = format!(
                "drive: pattern {:.1}/{:.0} s, feedback {} /s, dropped transfers {}",
                elapsed.unwrap_or(0.0),
                ex.duration,
                rows - rows_at_progress,
                st.rx.rejected_total()
            );
            if cfg.fit {
                if let Ok(e) = estimator.estimate(&LoadBounds::default()) {
                    line += &format!(", J = {:.4e}, c2 = {:.4e}", e.mass, e.c2);
                }
            }
            eprintln!("{line}");
            rows_at_progress = rows;
            next_progress = next_progress + Duration::from_secs(1);
        }
    };
    d.stop();
    let estimate = estimator
        .estimate(&LoadBounds::default())
        .ok()
        .map(|e| (e.mass, e.c1, e.c2));
    DriveOutcome {
        reason,
        rows,
        estimate,
    }
}

/// Runs `propid drive`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let cfg = args.config()?;
    let mut transport = args.bus.open()?;
    let stop = Arc::new(AtomicBool::new(false));
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register(signal, Arc::clone(&stop))
            .context("installing signal handlers")?;
    }
    let mut out: Box<dyn Write> = match &args.output {
        Some(p) => Box::new(
            std::fs::File::create(p).with_context(|| format!("cannot create {}", p.display()))?,
        ),
        None => Box::new(std::io::stdout()),
    };
    let outcome = drive(&cfg, transport.as_mut(), &mut out, &stop);
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
