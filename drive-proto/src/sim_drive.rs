//! A simulated Telega as a Sans-IO Cyphal node.
//!
//! ```text
//!  handle_frame ─► Node ─► Readiness (torque only when ENGAGED), Vector31 setpoint
//!  every feedback interval: Stand::advance_to(t) ─► Stand::measure ─► DoF3rdTs (device timestamp)
//!                           ─► backlog (FIFO, FEEDBACK_HOLD) ─► Node::publish, one transfer at a
//!                              time ─► poll_transmit
//!  a stalled caller or link: the instants it missed are sampled when it wakes and sent in order;
//!  a sample not sent within FEEDBACK_HOLD is dropped and counted (feedback_dropped)
//!  deadman: no setpoint for SIM_DEADMAN ⇒ zero torque
//!  heartbeat 1 Hz with its uptime (a new SimDrive is a rebooted drive)
//!  registers (Telega's names, see crate::registers): List/Access, port.List every 10 s
//!    mns.pub_interval_min written ─► the feedback interval changes at once
//!    mns.local_timestamp written  ─► feedback stamped with the drive's clock, or 0 (unknown)
//!    uavcan.*.id written          ─► kept; takes effect at the next restart (ExecuteCommand
//!                                    RESTART), as the Cyphal specification and Telega do
//!  ExecuteCommand: RESTART (a reboot: new node, uptime from 0, port-IDs from the registers),
//!                  STORE_PERSISTENT_STATES (acknowledged; values survive a RESTART)
//! ```
//! It runs any [`Plant`]; the host gives it the same stand model as `propid sim`
//! (`propid_science::stand::Stand`).

use std::collections::VecDeque;
use std::time::Duration;

use propid_core::can::{Frame, Mtu, NodeId, Priority, SubjectId};
use propid_core::dsdl::{DataType, DoF3rdTs, ExecuteCommandRequest, Readiness, Value, Vector31};
use propid_core::node::{Event, NodeConfig};
use propid_core::time::Instant;

use crate::machine::{Machine, StopReason};
use crate::node::{HostNode, HostRegistry};
use crate::plant::Plant;
use crate::registers::{
    self, add, n16, port, subject_register, text, FEEDBACK_TYPE, LOCAL_TIMESTAMP, NODE_DESCRIPTION,
    NODE_ID, PUB_INTERVAL_MIN, READINESS_TYPE, SETPOINT_TYPE, TELEGA_FEEDBACK_ID,
    TELEGA_READINESS_ID, TELEGA_SETPOINT_ID,
};
use crate::settings::{FeedbackInterval, RunLimit};

/// The simulated drive zeroes its torque when no setpoint arrived for this long.
pub const SIM_DEADMAN: Duration = Duration::from_millis(500);

/// How long a feedback sample waits to be handed to the node, and then its frames to leave,
/// before the simulated drive drops it: what a drive and its adapter buffer between a busy host's
/// reads. A sample is never superseded by a newer one (a setpoint is; a measurement is not).
pub const FEEDBACK_HOLD: Duration = Duration::from_millis(500);

/// Feedback samples waiting to be sent, at most (0.5 s at 0.1 ms).
const FEEDBACK_BACKLOG: usize = 5000;

/// Telega's deadman timeout register (read-only here: [`SIM_DEADMAN`]).
pub const DEADMAN_TIMEOUT: &str = "mns.deadman_timeout";

/// The simulated drive's settings, each typed: a configuration out of range cannot be built.
#[derive(Clone, Debug, PartialEq)]
pub struct SimDriveConfig {
    /// Node-ID.
    pub node_id: NodeId,
    /// Frame size.
    pub mtu: Mtu,
    /// Readiness subject (no readiness gating when unset).
    pub readiness_id: Option<SubjectId>,
    /// Setpoint subject.
    pub setpoint_id: SubjectId,
    /// Feedback subject.
    pub feedback_id: SubjectId,
    /// Feedback interval.
    pub interval: FeedbackInterval,
    /// Stop by itself after this long (`None`: run until stopped).
    pub duration: Option<RunLimit>,
}

impl SimDriveConfig {
    /// The counterpart of [`crate::drive::DriveConfig::example`]: node 42, readiness on 10,
    /// setpoint on 24, feedback on 110 every 2 ms, Classic CAN, running until stopped.
    pub fn example() -> Self {
        SimDriveConfig {
            node_id: NodeId::from_const(42),
            mtu: Mtu::Classic,
            readiness_id: Some(SubjectId::from_const(10)),
            setpoint_id: SubjectId::from_const(24),
            feedback_id: SubjectId::from_const(110),
            interval: FeedbackInterval::from_const(0.002),
            duration: None,
        }
    }
}

/// The simulated Telega's registers for `cfg`, with local timestamps on or off.
pub fn sim_drive_registers(cfg: &SimDriveConfig, local_timestamp: bool) -> HostRegistry {
    // Every field named: one added to SimDriveConfig does not compile here until it is served or
    // said not to be a register.
    let SimDriveConfig {
        node_id,
        mtu: _,
        readiness_id,
        setpoint_id,
        feedback_id,
        interval,
        duration: _,
    } = cfg;
    let mut r = HostRegistry::new();
    let node_id = n16(Some(u16::from(node_id.get())));
    add(&mut r, NODE_ID, node_id, true, true);
    add(&mut r, NODE_DESCRIPTION, text(""), true, true);
    let interval = Value::real32(&[interval.get() as f32]).unwrap_or_default();
    add(&mut r, PUB_INTERVAL_MIN, interval, true, true);
    let ts = Value::bit(&[local_timestamp]).unwrap_or_default();
    add(&mut r, LOCAL_TIMESTAMP, ts, true, true);
    let deadman = Value::real32(&[SIM_DEADMAN.as_secs_f32()]).unwrap_or_default();
    add(&mut r, DEADMAN_TIMEOUT, deadman, false, true);
    let (feedback, setpoint) = (feedback_id.get(), setpoint_id.get());
    let readiness = readiness_id.map(SubjectId::get);
    port(
        &mut r,
        "pub",
        "dynamics",
        Some(feedback),
        FEEDBACK_TYPE,
        true,
    );
    port(&mut r, "sub", "readiness", readiness, READINESS_TYPE, true);
    port(
        &mut r,
        "sub",
        "setpoint_r_torq",
        Some(setpoint),
        SETPOINT_TYPE,
        true,
    );
    r
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
    /// Feedback messages handed to the link.
    pub feedback_published: u64,
    /// Feedback samples dropped unsent: not handed over within [`FEEDBACK_HOLD`] (the simulated
    /// drive's own loop or its link stalled that long; frames that then expire in the node's
    /// queue are counted in its transmit statistics).
    pub feedback_dropped: u64,
    /// Restarts commanded over the bus.
    pub restarts: u64,
    /// Store commands received.
    pub stores: u64,
}

/// A command the simulated drive received.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Command {
    /// A readiness message.
    Readiness(u8),
    /// A setpoint (its first element).
    Setpoint(f32),
}

/// What the simulated drive reports.
#[derive(Clone, Debug, PartialEq)]
pub enum SimDriveEvent {
    /// A feedback message was queued for sending.
    Feedback(DoF3rdTs),
    /// A readiness or setpoint message arrived (every one, in order).
    Received(Command),
    /// The readiness received changed.
    Readiness(u8),
    /// A register was written over the bus and now holds `value` (a refused value, such as a
    /// non-positive interval, is put back and reported with the value kept).
    RegisterWritten {
        /// The register.
        name: String,
        /// What it holds now.
        value: Value,
    },
    /// It restarted on command: a new node (uptime from 0) with the port-IDs of its registers.
    Restarted,
    /// It was asked to store its registers.
    Stored,
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
    plant: Box<dyn Plant>,
    start: Instant,
    end: Option<Instant>,
    interval: Duration,
    next_feedback: Instant,
    last_setpoint_at: Option<Instant>,
    setpoint: f64,
    summary: SimDriveSummary,
    /// Sampled feedback not yet handed to the node, oldest first, with its sampling instant.
    backlog: VecDeque<(Instant, DoF3rdTs)>,
    held: Option<Frame>,
    stopped: bool,
    last_now: Instant,
    local_timestamp: bool,
    restart_at: Option<Instant>,
    events: VecDeque<SimDriveEvent>,
}

/// The commands the simulated drive carries out.
const SIM_COMMANDS: [u16; 2] = [
    ExecuteCommandRequest::COMMAND_RESTART,
    ExecuteCommandRequest::COMMAND_STORE_PERSISTENT_STATES,
];

/// How long after a RESTART command the simulated drive reboots (its answer leaves first).
const RESTART_DELAY: Duration = Duration::from_millis(100);

fn boot_node(cfg: &SimDriveConfig, registers: &HostRegistry, now: Instant) -> HostNode {
    let mut node = HostNode::new(
        NodeConfig::new(cfg.node_id, "org.propid.sim_drive", cfg.mtu),
        now,
    );
    // Fresh node, validated IDs, 8 ports: cannot fail.
    let _ = node.subscribe_message(cfg.setpoint_id, Vector31::EXTENT_BYTES);
    if let Some(id) = cfg.readiness_id {
        let _ = node.subscribe_message(id, Readiness::EXTENT_BYTES);
    }
    registers::serve(&mut node, registers, &SIM_COMMANDS, now);
    // An interval the simulation cannot use is refused in the answer itself.
    let range = FeedbackInterval::RANGE;
    let _ = node
        .registers_mut()
        .set_limits(PUB_INTERVAL_MIN, range.lo, range.hi);
    node
}

impl SimDrive {
    /// A simulated drive of `plant` that boots now with Telega's registers holding `cfg`'s
    /// values and local timestamps on.
    pub fn new(cfg: SimDriveConfig, plant: Box<dyn Plant>, now: Instant) -> Self {
        let registers = sim_drive_registers(&cfg, true);
        SimDrive::with_registers(cfg, plant, &registers, now)
    }

    /// A simulated drive of `plant` that boots now serving `registers` (as
    /// [`sim_drive_registers`] builds them); the feedback interval and local timestamping are
    /// read from them.
    pub fn with_registers(
        mut cfg: SimDriveConfig,
        plant: Box<dyn Plant>,
        registers: &HostRegistry,
        now: Instant,
    ) -> Self {
        let node = boot_node(&cfg, registers, now);
        if let Some(x) = interval_of(registers) {
            cfg.interval = x;
        }
        let local_timestamp = registers
            .get(LOCAL_TIMESTAMP)
            .and_then(|r| r.value.float_at(0))
            .is_none_or(|x| x != 0.0);
        SimDrive {
            local_timestamp,
            restart_at: None,
            plant,
            end: cfg.duration.map(|d| now + d.duration()),
            interval: cfg.interval.duration(),
            cfg,
            node,
            start: now,
            next_feedback: now,
            last_setpoint_at: None,
            setpoint: 0.0,
            summary: SimDriveSummary::default(),
            backlog: VecDeque::new(),
            held: None,
            stopped: false,
            last_now: now,
            events: VecDeque::new(),
        }
    }

    /// The registers it serves.
    pub fn registers(&self) -> &HostRegistry {
        self.node.registers()
    }

    /// The feedback interval now, in seconds.
    pub fn interval(&self) -> f64 {
        self.interval.as_secs_f64()
    }

    /// The configuration it runs with (port-IDs as of its last boot).
    pub fn config(&self) -> &SimDriveConfig {
        &self.cfg
    }

    /// Applies what was written over the bus and carries out the commands received.
    fn serve(&mut self, now: Instant) {
        while let Some(i) = self.node.take_register_change() {
            let Some(r) = self.node.registers().by_index(i) else {
                continue;
            };
            let name = r.name.as_str().unwrap_or_default().to_string();
            if name == PUB_INTERVAL_MIN {
                match interval_of(self.node.registers()) {
                    Some(x) => {
                        self.interval = x.duration();
                        // The next message follows the new interval at once.
                        self.next_feedback = self.next_feedback.min(now + self.interval);
                    }
                    None => {
                        // Not a usable interval: the register keeps the one in use.
                        let keep =
                            Value::real32(&[self.interval.as_secs_f32()]).unwrap_or_default();
                        let _ = self.node.registers_mut().set(PUB_INTERVAL_MIN, &keep);
                    }
                }
            } else if name == LOCAL_TIMESTAMP {
                self.local_timestamp = r.value.float_at(0).is_none_or(|x| x != 0.0);
            }
            let value = self
                .node
                .registers()
                .get(&name)
                .map(|r| r.value.clone())
                .unwrap_or_default();
            self.events
                .push_back(SimDriveEvent::RegisterWritten { name, value });
        }
        while let Some(c) = self.node.take_command() {
            match c.command {
                ExecuteCommandRequest::COMMAND_RESTART => {
                    // Time for the answer to leave first.
                    self.restart_at.get_or_insert(now + RESTART_DELAY);
                }
                ExecuteCommandRequest::COMMAND_STORE_PERSISTENT_STATES => {
                    self.summary.stores += 1;
                    self.events.push_back(SimDriveEvent::Stored);
                }
                _ => {}
            }
        }
    }

    /// Reboots: a new node with the node- and port-IDs its registers hold (an ID register that
    /// is not a valid ID keeps the old one), the registers' values kept, uptime from 0, torque off
    /// until the next setpoint.
    fn restart(&mut self, now: Instant) {
        self.restart_at = None;
        let registers = self.node.registers().clone();
        let node_id = registers
            .get(NODE_ID)
            .and_then(|r| r.value.float_at(0))
            .and_then(|v| NodeId::try_from(v as u64).ok());
        if let Some(id) = node_id {
            self.cfg.node_id = id;
        }
        if let Ok(Some(id)) = subject_register(&registers, TELEGA_FEEDBACK_ID) {
            self.cfg.feedback_id = id;
        }
        if let Ok(Some(id)) = subject_register(&registers, TELEGA_SETPOINT_ID) {
            self.cfg.setpoint_id = id;
        }
        if let Ok(id) = subject_register(&registers, TELEGA_READINESS_ID) {
            self.cfg.readiness_id = id;
        }
        self.node = boot_node(&self.cfg, &registers, now);
        // A reboot loses what was waiting to be sent.
        self.summary.feedback_dropped += self.backlog.len() as u64;
        self.backlog.clear();
        self.last_setpoint_at = None;
        self.setpoint = 0.0;
        self.summary.last_readiness = None;
        self.summary.restarts += 1;
        self.events.push_back(SimDriveEvent::Restarted);
    }

    /// What it saw so far.
    pub fn summary(&self) -> &SimDriveSummary {
        &self.summary
    }

    /// The plant it drives.
    pub fn plant(&self) -> &dyn Plant {
        self.plant.as_ref()
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
        if self.restart_at.is_some_and(|t| now >= t) {
            self.restart(now);
        }
        // Instants FEEDBACK_HOLD old would be dropped unsent: not sampled at all.
        while self.next_feedback + FEEDBACK_HOLD <= now {
            self.summary.feedback_dropped += 1;
            self.next_feedback = self.next_feedback + self.interval;
        }
        while now >= self.next_feedback {
            let at = self.next_feedback;
            let fb = self.sample_at(at);
            if self.backlog.len() == FEEDBACK_BACKLOG {
                self.backlog.pop_front();
                self.summary.feedback_dropped += 1;
            }
            self.backlog.push_back((at, fb));
            self.next_feedback = self.next_feedback + self.interval;
        }
    }

    /// Runs the plant to `at` and measures it as the drive would report it.
    fn sample_at(&mut self, at: Instant) -> DoF3rdTs {
        let t = at.saturating_duration_since(self.start).as_secs_f64();
        let engaged = match self.cfg.readiness_id {
            Some(_) => self.summary.last_readiness == Some(Readiness::ENGAGED),
            None => true,
        };
        let alive = self
            .last_setpoint_at
            .is_some_and(|s| at.saturating_duration_since(s) < SIM_DEADMAN);
        self.plant
            .set_setpoint(if engaged && alive { self.setpoint } else { 0.0 });
        if t > self.plant.time() {
            self.plant.advance_to(t);
        }
        let s = self.plant.measure();
        let mut fb = DoF3rdTs::default();
        // Without local timestamps the field is 0: "unknown" in Cyphal (this simulation has
        // no network time to stamp with instead).
        fb.timestamp.microsecond = if self.local_timestamp {
            (t * 1e6).round() as u64
        } else {
            0
        };
        fb.value.kinematics.base.position = s.position as f32;
        fb.value.kinematics.base.velocity = s.velocity as f32;
        fb.value.kinematics.acceleration = s.acceleration as f32;
        fb.value.force = s.force as f32;
        fb
    }

    /// Hands the oldest waiting feedback sample to the node once the node has sent everything
    /// before it (one transfer at a time, so none supersedes another); samples older than
    /// [`FEEDBACK_HOLD`] are dropped and counted.
    fn offer_feedback(&mut self, now: Instant) {
        if self.held.is_some() || !self.node.is_transmit_queue_empty() {
            return;
        }
        while let Some((at, fb)) = self.backlog.pop_front() {
            if now >= at + FEEDBACK_HOLD {
                self.summary.feedback_dropped += 1;
                continue;
            }
            // Once handed over, its frames get the whole hold to leave: a sample handed over
            // with only the rest of its hold would expire on a link slower than the stream, and
            // so would every sample after it.
            match self.node.publish_message(
                now,
                self.cfg.feedback_id,
                Priority::HIGH,
                &fb,
                FEEDBACK_HOLD,
            ) {
                Ok(()) => {
                    self.summary.feedback_published += 1;
                    self.events.push_back(SimDriveEvent::Feedback(fb));
                }
                Err(_) => self.summary.feedback_dropped += 1,
            }
            return;
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
                    // A drive applies a setpoint when it arrives: the load runs up to this instant
                    // on the previous one. (Applying it only at the next feedback instant, over
                    // the whole interval before it, made the torque lead the reported force by
                    // about half a feedback interval and every lag read from the data short.)
                    let t = now.saturating_duration_since(self.start).as_secs_f64();
                    if t > self.plant.time() {
                        self.plant.advance_to(t);
                    }
                    self.setpoint = f64::from(v.value[0]);
                    self.events
                        .push_back(SimDriveEvent::Received(Command::Setpoint(v.value[0])));
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
                    self.events
                        .push_back(SimDriveEvent::Received(Command::Readiness(r.value)));
                    if self.summary.last_readiness != Some(r.value) {
                        self.summary.readiness_changes.push(r.value);
                        self.events.push_back(SimDriveEvent::Readiness(r.value));
                    }
                    self.summary.last_readiness = Some(r.value);
                }
            }
            _ => {}
        }
        self.serve(now);
    }

    /// The next frame to send (feedback, heartbeat, answers), if one is due.
    #[must_use]
    pub fn poll_transmit(&mut self, now: Instant) -> Option<Frame> {
        self.advance(now);
        if self.stopped {
            return None;
        }
        self.offer_feedback(now);
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
        } else if !self.backlog.is_empty() {
            t = t.min(self.last_now);
        }
        if let Some(end) = self.end {
            t = t.min(end);
        }
        if let Some(r) = self.restart_at {
            t = t.min(r);
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

/// The feedback interval `mns.pub_interval_min` holds, if usable.
fn interval_of(registers: &HostRegistry) -> Option<FeedbackInterval> {
    registers
        .get(PUB_INTERVAL_MIN)
        .and_then(|r| r.value.float_at(0))
        .and_then(|x| FeedbackInterval::new(x).ok())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::registers::check_prerequisites;
    use propid_core::sample::Sample;

    /// A load that does not move.
    struct Still(f64);

    impl Plant for Still {
        fn set_setpoint(&mut self, _: f64) {}
        fn time(&self) -> f64 {
            self.0
        }
        fn advance_to(&mut self, t: f64) {
            self.0 = self.0.max(t);
        }
        fn measure(&mut self) -> Sample {
            Sample {
                t: self.0,
                force: 0.0,
                velocity: 0.0,
                acceleration: 0.0,
                position: 0.0,
            }
        }
    }

    /// Polls everything out at `now`; the feedback timestamps sent [µs].
    fn drain(sim: &mut SimDrive, now: Instant) -> Vec<u64> {
        while sim.poll_transmit(now).is_some() {}
        std::iter::from_fn(|| sim.poll_event())
            .filter_map(|e| match e {
                SimDriveEvent::Feedback(fb) => Some(fb.timestamp.microsecond),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn a_stalled_loop_sends_every_instant_it_missed_in_order_within_the_hold() {
        let mut sim = SimDrive::new(
            SimDriveConfig::example(),
            Box::new(Still(0.0)),
            Instant::ZERO,
        );
        assert_eq!(drain(&mut sim, Instant::ZERO), [0]);
        // 100 ms without a call: the 50 instants it slept through, in order, none superseded.
        let sent = drain(&mut sim, Instant::from_micros(100_000));
        assert_eq!(sent, (1..=50).map(|k| k * 2_000).collect::<Vec<u64>>());
        assert_eq!(sim.summary().feedback_dropped, 0);
        // 2 s without a call: only the last 0.5 s is sampled; the rest is counted as dropped.
        let sent = drain(&mut sim, Instant::from_micros(2_100_000));
        assert_eq!(sent.len(), 250);
        assert_eq!(sent[0], 1_602_000);
        assert!(sent.windows(2).all(|w| w[1] == w[0] + 2_000));
        assert_eq!(sim.summary().feedback_dropped, 750);
        assert_eq!(sim.summary().feedback_published, 1 + 50 + 250);
    }

    #[test]
    fn prerequisites() {
        let sim = SimDriveConfig::example();
        let as_list = |r: &HostRegistry| -> Vec<(String, Value)> {
            r.iter()
                .map(|x| (x.name.as_str().unwrap().to_string(), x.value.clone()))
                .collect()
        };
        let good = as_list(&sim_drive_registers(&sim, true));
        assert!(check_prerequisites(&good, Some(SubjectId::from_const(110))).is_empty());
        let mut slow = sim;
        slow.interval = FeedbackInterval::new(0.05).unwrap();
        let bad = as_list(&sim_drive_registers(&slow, false));
        let p = check_prerequisites(&bad, Some(SubjectId::from_const(111)));
        let names: Vec<&str> = p.iter().map(|p| p.register.as_str()).collect();
        assert_eq!(
            names,
            [PUB_INTERVAL_MIN, LOCAL_TIMESTAMP, TELEGA_FEEDBACK_ID]
        );
        assert_eq!(p[0].found, "0.05");
        assert_eq!(p[1].found, "false");
    }
}
