//! A simulated Telega as a Sans-IO Cyphal node.
//!
//! ```text
//!  handle_frame ─► Node ─► Readiness (torque only when ENGAGED), Vector31 setpoint
//!  every feedback interval: Stand::advance_to(t) ─► Stand::measure ─► DoF3rdTs (device timestamp)
//!                           ─► Node::publish ─► poll_transmit
//!  deadman: no setpoint for SIM_DEADMAN ⇒ zero torque
//!  heartbeat 1 Hz with its uptime (a new SimDrive is a rebooted drive)
//! ```
//! It runs the same stand model as `propid sim` (`propid_science::stand::Stand`).

use std::collections::VecDeque;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use propid_core::can::{Frame, Mtu, NodeId, Priority, SubjectId};
use propid_core::dsdl::{DataType, DoF3rdTs, Readiness, Vector31};
use propid_core::node::{Event, NodeConfig};
use propid_core::time::Instant;
use propid_science::stand::{Stand, StandConfig};

use propid_transport::CanTransport;

use crate::drive::{check_mtu, check_range, ConfigError, DAY};
use crate::realtime::{run_realtime, Clock};
use crate::{HostNode, Machine, StopReason};

/// The simulated drive zeroes its torque when no setpoint arrived for this long.
pub const SIM_DEADMAN: Duration = Duration::from_millis(500);

/// The simulated drive's settings.
#[derive(Clone, Debug)]
pub struct SimDriveConfig {
    /// Node-ID.
    pub node_id: NodeId,
    /// 8 or 64.
    pub mtu: usize,
    /// Readiness subject (no readiness gating when unset).
    pub readiness_id: Option<SubjectId>,
    /// Setpoint subject.
    pub setpoint_id: SubjectId,
    /// Feedback subject.
    pub feedback_id: SubjectId,
    /// Feedback interval [s].
    pub interval: f64,
    /// Run time limit [s] (0: none).
    pub duration: f64,
    /// The stand.
    pub stand: StandConfig,
    /// Noise seed.
    pub seed: u64,
}

impl SimDriveConfig {
    /// The counterpart of `DriveConfig::example`: node 42, readiness on 10, setpoint on 24,
    /// feedback on 110 every 2 ms, Classic CAN, running until stopped.
    pub fn example(stand: StandConfig, seed: u64) -> Self {
        SimDriveConfig {
            node_id: NodeId::from_const(42),
            mtu: 8,
            readiness_id: Some(SubjectId::from_const(10)),
            setpoint_id: SubjectId::from_const(24),
            feedback_id: SubjectId::from_const(110),
            interval: 0.002,
            duration: 0.0,
            stand,
            seed,
        }
    }

    /// Checks every value before anything is sent.
    pub fn validate(&self) -> Result<(), ConfigError> {
        check_mtu(self.mtu)?;
        check_range("interval", self.interval, 0.0, true, 1.0, "s")?;
        check_range("duration", self.duration, 0.0, false, DAY, "s")?;
        self.stand
            .validate()
            .map_err(|e| ConfigError::new("stand", e.0))
    }
}

/// What the simulated drive saw.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SimDriveSummary {
    /// Readiness values received, in order, with consecutive repeats collapsed.
    pub readiness_changes: Vec<u8>,
    /// The last readiness received.
    pub last_readiness: Option<u8>,
    /// The last setpoint received.
    pub last_setpoint: Option<f32>,
    /// Setpoints received.
    pub setpoints: u64,
    /// Feedback messages published.
    pub feedback_published: u64,
}

/// What the simulated drive reports.
#[derive(Clone, Debug, PartialEq)]
pub enum SimDriveEvent {
    /// A feedback message was queued for sending.
    Feedback(DoF3rdTs),
    /// The readiness received changed.
    Readiness(u8),
    /// It stopped.
    Stopped {
        /// Why.
        reason: StopReason,
        /// What it saw.
        summary: SimDriveSummary,
    },
}

/// The simulated drive. See the module documentation.
pub struct SimDrive {
    cfg: SimDriveConfig,
    node: HostNode,
    stand: Stand,
    start: Instant,
    end: Option<Instant>,
    interval: Duration,
    next_feedback: Instant,
    last_setpoint_at: Option<Instant>,
    setpoint: f64,
    summary: SimDriveSummary,
    held: Option<Frame>,
    stopped: bool,
    last_now: Instant,
    events: VecDeque<SimDriveEvent>,
}

impl SimDrive {
    /// A simulated drive that boots now. `cfg` must have passed [`SimDriveConfig::validate`].
    pub fn new(cfg: SimDriveConfig, now: Instant) -> Self {
        let mtu = if cfg.mtu == 64 { Mtu::Fd } else { Mtu::Classic };
        let mut node = HostNode::new(
            NodeConfig::new(cfg.node_id, "org.propid.sim_drive", mtu),
            now,
        );
        // Fresh node, validated IDs, 8 ports: cannot fail.
        let _ = node.subscribe_message(cfg.setpoint_id, Vector31::EXTENT_BYTES);
        if let Some(id) = cfg.readiness_id {
            let _ = node.subscribe_message(id, Readiness::EXTENT_BYTES);
        }
        SimDrive {
            stand: Stand::new(cfg.stand, cfg.seed),
            end: (cfg.duration > 0.0).then(|| now + Duration::from_secs_f64(cfg.duration)),
            interval: Duration::from_secs_f64(cfg.interval),
            cfg,
            node,
            start: now,
            next_feedback: now,
            last_setpoint_at: None,
            setpoint: 0.0,
            summary: SimDriveSummary::default(),
            held: None,
            stopped: false,
            last_now: now,
            events: VecDeque::new(),
        }
    }

    /// What it saw so far.
    pub fn summary(&self) -> &SimDriveSummary {
        &self.summary
    }

    /// The stand (for tests that compare with its state).
    pub fn stand(&self) -> &Stand {
        &self.stand
    }

    /// Stops (once): nothing more is sent.
    pub fn stop(&mut self, _now: Instant, reason: StopReason) {
        if self.stopped {
            return;
        }
        self.stopped = true;
        self.events.push_back(SimDriveEvent::Stopped {
            reason,
            summary: self.summary.clone(),
        });
    }

    fn advance(&mut self, now: Instant) {
        self.last_now = self.last_now.max(now);
        if self.stopped {
            return;
        }
        if self.end.is_some_and(|end| now >= end) {
            self.stop(now, StopReason::Completed);
            return;
        }
        while now >= self.next_feedback {
            let at = self.next_feedback;
            let t = at.saturating_duration_since(self.start).as_secs_f64();
            let engaged = match self.cfg.readiness_id {
                Some(_) => self.summary.last_readiness == Some(Readiness::ENGAGED),
                None => true,
            };
            let alive = self
                .last_setpoint_at
                .is_some_and(|s| at.saturating_duration_since(s) < SIM_DEADMAN);
            self.stand
                .set_setpoint(if engaged && alive { self.setpoint } else { 0.0 });
            self.stand.advance_to(t);
            let s = self.stand.measure();
            let mut fb = DoF3rdTs::default();
            fb.timestamp.microsecond = (t * 1e6).round() as u64;
            fb.value.kinematics.base.position = s.position as f32;
            fb.value.kinematics.base.velocity = s.velocity as f32;
            fb.value.kinematics.acceleration = s.acceleration as f32;
            fb.value.force = s.force as f32;
            if self
                .node
                .publish_message(
                    now,
                    self.cfg.feedback_id,
                    Priority::HIGH,
                    &fb,
                    self.interval * 5,
                )
                .is_ok()
            {
                self.summary.feedback_published += 1;
                self.events.push_back(SimDriveEvent::Feedback(fb));
            }
            self.next_feedback = self.next_feedback + self.interval;
            if self.next_feedback + self.interval <= now {
                // Far behind (a stalled caller): resume from now instead of bursting.
                self.next_feedback = now + self.interval;
            }
        }
    }

    /// Takes one received frame.
    pub fn handle_frame(&mut self, now: Instant, frame: &Frame) {
        self.advance(now);
        if self.stopped {
            return;
        }
        let (setpoint_id, readiness_id) = (self.cfg.setpoint_id, self.cfg.readiness_id);
        match self.node.handle_frame(now, frame) {
            Some(Event::Message {
                subject_id,
                payload,
                ..
            }) if subject_id == setpoint_id => {
                if let Ok(v) = Vector31::deserialize(payload) {
                    self.setpoint = f64::from(v.value[0]);
                    self.summary.last_setpoint = Some(v.value[0]);
                    self.summary.setpoints += 1;
                    self.last_setpoint_at = Some(now);
                }
            }
            Some(Event::Message {
                subject_id,
                payload,
                ..
            }) if Some(subject_id) == readiness_id => {
                if let Ok(r) = Readiness::deserialize(payload) {
                    if self.summary.last_readiness != Some(r.value) {
                        self.summary.readiness_changes.push(r.value);
                        self.events.push_back(SimDriveEvent::Readiness(r.value));
                    }
                    self.summary.last_readiness = Some(r.value);
                }
            }
            _ => {}
        }
    }

    /// The next frame to send (feedback, heartbeat), if one is due.
    #[must_use]
    pub fn poll_transmit(&mut self, now: Instant) -> Option<Frame> {
        self.advance(now);
        if self.stopped {
            return None;
        }
        self.held.take().or_else(|| self.node.poll_transmit(now))
    }

    /// The link refused `frame`: offered again on the next poll (feedback that waited too long
    /// expires in the node's queue instead).
    pub fn handle_blocked(&mut self, _now: Instant, frame: Frame) {
        self.held = Some(frame);
    }

    /// When to call again.
    #[must_use]
    pub fn poll_timeout(&self) -> Option<Instant> {
        if self.stopped {
            return None;
        }
        let mut t = self.next_feedback;
        if self.held.is_some() {
            // The queue waits behind the refused frame: come back to offer it again.
            t = t.min(self.last_now + Duration::from_millis(1));
        } else if let Some(n) = self.node.poll_timeout() {
            t = t.min(n);
        }
        if let Some(end) = self.end {
            t = t.min(end);
        }
        Some(t)
    }

    /// The next event.
    #[must_use]
    pub fn poll_event(&mut self) -> Option<SimDriveEvent> {
        self.events.pop_front()
    }
}

impl Machine for SimDrive {
    type Event = SimDriveEvent;
    fn handle_frame(&mut self, now: Instant, frame: &Frame) {
        SimDrive::handle_frame(self, now, frame)
    }
    fn poll_transmit(&mut self, now: Instant) -> Option<Frame> {
        SimDrive::poll_transmit(self, now)
    }
    fn handle_blocked(&mut self, now: Instant, frame: Frame) {
        SimDrive::handle_blocked(self, now, frame)
    }
    fn poll_timeout(&self) -> Option<Instant> {
        SimDrive::poll_timeout(self)
    }
    fn poll_event(&mut self) -> Option<SimDriveEvent> {
        SimDrive::poll_event(self)
    }
    fn handle_fault(&mut self, now: Instant, reason: StopReason) {
        self.stop(now, reason)
    }
    fn is_stopped(&self) -> bool {
        self.stopped
    }
}

/// Runs a [`SimDrive`] in real time on `transport` until `stop` is raised or its duration ends.
/// A transport fault is an error (its sentence); otherwise what it saw.
pub fn run_sim_drive(
    cfg: SimDriveConfig,
    transport: &mut dyn CanTransport,
    clock: &dyn Clock,
    stop: &AtomicBool,
) -> Result<SimDriveSummary, String> {
    let mut sim = SimDrive::new(cfg, clock.now());
    let mut end = None;
    run_realtime(&mut sim, transport, clock, stop, &mut |event| {
        if let SimDriveEvent::Stopped { reason, summary } = event {
            end = Some((reason, summary));
        }
        Ok(())
    });
    match end {
        Some((StopReason::Completed | StopReason::Signal, summary)) => Ok(summary),
        Some((reason, _)) => Err(reason.to_string()),
        None => Err("the simulated drive's loop ended before it stopped".into()),
    }
}
