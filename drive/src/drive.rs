//! The seed's driver as a Cyphal node.
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
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use propid_core::can::{Mtu, Priority};
use propid_core::dsdl::{DataType, DoF3rdTs, Readiness, Vector31};
use propid_core::estimate::{LoadBounds, LoadEstimator};
use propid_core::node::{Event, NodeConfig};
use propid_core::time::Instant;
use propid_transport::{CanTransport, HostClock};

use propid_io::tsv::{Row, Sample, TsvWriter};
use propid_io::InputError;
use propid_science::excitation::Excitation;

use crate::HostNode;

/// How many times the stop command (STANDBY + zero setpoint) is sent.
pub const STOP_REPEATS: usize = 5;

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
    /// Keep a running estimate of J, c1, c2 (reported in [`DriveEvent::Progress`]).
    pub fit: bool,
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
        }
    }
}

impl DriveConfig {
    /// Checks every value before anything is sent.
    pub fn validate(&self) -> Result<(), InputError> {
        if self.node_id > 127 {
            return Err(InputError(format!(
                "node id must be 0..=127 (got {})",
                self.node_id
            )));
        }
        for (name, id) in [
            ("setpoint", Some(self.setpoint_id)),
            ("feedback", Some(self.feedback_id)),
            ("readiness", self.readiness_id),
        ] {
            if let Some(id) = id.filter(|id| *id > 8191) {
                return Err(InputError(format!(
                    "{name} subject-ID must be 0..=8191 (got {id})"
                )));
            }
        }
        self.excitation.validate()?;
        if !(self.setpoint_period > 0.0 && self.setpoint_period < 1.0) {
            return Err(InputError(format!(
                "setpoint_period must be in (0, 1) s (got {})",
                self.setpoint_period
            )));
        }
        if !(self.deadman > 0.0 && self.deadman <= 60.0) {
            return Err(InputError(format!(
                "the deadman timeout must be in (0, 60] s (got {})",
                self.deadman
            )));
        }
        if self.mtu != 8 && self.mtu != 64 {
            return Err(InputError(format!(
                "MTU must be 8 or 64 (got {})",
                self.mtu
            )));
        }
        Ok(())
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

/// What the drive reports while it runs (the caller decides what to show).
#[derive(Clone, Debug, PartialEq)]
pub enum DriveEvent {
    /// The init phase is over and recording begins.
    PatternStarted,
    /// Once a second during the pattern.
    Progress {
        /// Seconds into the pattern.
        elapsed: f64,
        /// Feedback rows in the last second.
        feedback_per_s: u64,
        /// Transfers the reassembler rejected so far.
        dropped_transfers: u64,
        /// The running estimate (J, c1, c2), when `fit` is on and the data identify it.
        estimate: Option<(f64, f64, f64)>,
    },
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
            match self.transport.send(&f) {
                // A congested link (a slow reader at the other end): the frame is dropped and
                // counted by the transport; the next setpoint follows within a period.
                Err(e) if e.is_would_block() => {}
                r => r.map_err(|e| e.to_string())?,
            }
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
    events: &mut dyn FnMut(DriveEvent),
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
    // The seed's registers, holding the values in use, for Yakut and friends to read.
    let registers = crate::registers::drive_registers(Some(cfg), false);
    crate::registers::serve(&mut d.node, &registers, &[], start);
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
            events(DriveEvent::PatternStarted);
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
        if event_now >= next_progress {
            let estimate = cfg
                .fit
                .then(|| estimator.estimate(&LoadBounds::default()).ok())
                .flatten()
                .map(|e| (e.mass, e.c1, e.c2));
            events(DriveEvent::Progress {
                elapsed: elapsed.unwrap_or(0.0),
                feedback_per_s: rows - rows_at_progress,
                dropped_transfers: d.node.stats().rx.rejected_total(),
                estimate,
            });
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
