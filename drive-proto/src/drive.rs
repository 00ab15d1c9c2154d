//! The seed's driver as a Sans-IO Cyphal node.
//!
//! ```text
//!  DriveConfig: every number and ID typed, so a configuration out of range cannot be built
//!  Drive::new(cfg, now)
//!  phases: SoftStart (a low setpoint; feedback and the direction checked, crate::limits)
//!          → Ramp (optional, to hi) → Init (at hi, no rows) → Pattern (rows recorded)
//!          → Stopping → Stopped
//!  every feedback sample from the soft start on: the limits (maximum speed, speed watchdog)
//!  and, once feedback has come, the dead-man
//!  every setpoint period: Readiness ENGAGED + Vector31 setpoint ─► Node (deadline 2 periods;
//!                         a newer setpoint supersedes a queued one)
//!  handle_frame: DoF3rdTs ─► DriveEvent::Row   Heartbeat of the drive ─► reboot check
//!  stop (end, signal, deadman, a limit, reboot, clock jump, bus-off, BELL, vanished device,
//!        output error):
//!    purge the queue, STANDBY + zero first, re-sent STOP_REPEATS times within STOP_WINDOW
//! ```
//!
//! The link may refuse a frame (congestion): the caller gives it back with
//! [`Drive::handle_blocked`]; it is offered again until its deadline, then dropped and counted.
//! Frames, not the loop, wait: the drive keeps running through congestion and reports the drops.

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Duration;

use propid_core::can::{Frame, Mtu, NodeId, Priority, SubjectId};
use propid_core::dsdl::{DataType, DoF3rdTs, Heartbeat, Readiness, Value, Vector31};
use propid_core::estimate::{LoadBounds, LoadEstimator};
use propid_core::node::{Event, NodeConfig, TxStats};
use propid_core::sample::Sample;
use propid_core::time::Instant;

use crate::excitation::Excitation;
use crate::feedback_loss::{FeedbackLoss, LossCounter};
use crate::limits::{Guard, Limits, SoftStartPassed};
use crate::machine::{Machine, StopReason};
use crate::node::{ends_transfer, subject_of, HostNode, HostRegistry};
use crate::registers::{
    self, n16, real64, DRIVE_FEEDBACK_ID, DRIVE_READINESS_ID, DRIVE_SETPOINT_ID, INIT_DURATION,
    NODE_ID, PATTERN_DURATION, PERIOD, SETPOINT_PERIOD, SETPOINT_RAT_LO_HI,
};
use crate::settings::{Deadman, RelativeError, SetpointPeriod};

/// How many times the stop command (STANDBY + zero setpoint) is queued.
pub const STOP_REPEATS: u32 = 5;
/// The stop sequence ends at the latest this long after it began, sent or not.
pub const STOP_WINDOW: Duration = Duration::from_secs(2);
/// How many recent samples [`Drive::snapshot`] keeps.
pub const SNAPSHOT_SAMPLES: usize = 1000;
/// How soon a frame the link refused is offered again.
const RETRY_STEP: Duration = Duration::from_millis(1);

/// The driver's settings, each typed: a configuration out of range cannot be built.
#[derive(Clone, Debug)]
pub struct DriveConfig {
    /// Node-ID.
    pub node_id: NodeId,
    /// Frame size.
    pub mtu: Mtu,
    /// Readiness subject, if any.
    pub readiness_id: Option<SubjectId>,
    /// Setpoint subject.
    pub setpoint_id: SubjectId,
    /// Feedback subject.
    pub feedback_id: SubjectId,
    /// The drive's node-ID, whose heartbeat is watched for a reboot; `None`: the publisher of
    /// the first feedback message.
    pub drive_node_id: Option<NodeId>,
    /// What to play.
    pub excitation: Arc<dyn Excitation>,
    /// Setpoint publication period.
    pub setpoint_period: SetpointPeriod,
    /// Deadman timeout: no feedback this long during the pattern stops the run.
    pub deadman: Deadman,
    /// Keep a running estimate of J, c1, c2 (reported in [`Progress`]).
    pub fit: bool,
    /// Stop (with STANDBY, as always) once the relative standard errors of J and c2 are both at
    /// most this (checked once a second); `None`: run the whole pattern.
    pub until_rel_stderr: Option<RelativeError>,
    /// The limits that stop a runaway rotor (soft start, maximum speed, watchdog, ramp).
    pub limits: Limits,
}

impl DriveConfig {
    /// The seed document's example set-up playing `excitation`: node 10, readiness on subject
    /// 10, setpoint on 24, feedback on 110, Classic CAN, a setpoint every 5 ms, a 0.5 s deadman,
    /// no running fit, the default limits ([`Limits::DEFAULT`]: a 1 s soft start at 0.1 before
    /// the init phase, the speed watchdog).
    pub fn example(excitation: impl Excitation + 'static) -> Self {
        DriveConfig {
            node_id: NodeId::from_const(10),
            mtu: Mtu::Classic,
            readiness_id: Some(SubjectId::from_const(10)),
            setpoint_id: SubjectId::from_const(24),
            feedback_id: SubjectId::from_const(110),
            drive_node_id: None,
            excitation: Arc::new(excitation),
            setpoint_period: SetpointPeriod::SEED,
            deadman: Deadman::DEFAULT,
            fit: false,
            until_rel_stderr: None,
            limits: Limits::DEFAULT,
        }
    }
}

/// The drive's registers holding `cfg`'s values (what the node serves while it drives). Every
/// field is named: one added to [`DriveConfig`] does not compile here until it is served or said
/// not to be a register.
pub fn drive_registers(cfg: &DriveConfig, persistent: bool) -> HostRegistry {
    let DriveConfig {
        node_id,
        mtu: _,
        readiness_id,
        setpoint_id,
        feedback_id,
        drive_node_id: _,
        excitation,
        setpoint_period,
        deadman: _,
        fit: _,
        until_rel_stderr: _,
        limits,
    } = cfg;
    let mut r = registers::drive_defaults(persistent);
    let s = excitation.schedule();
    let set = |r: &mut HostRegistry, name: &str, v: Value| {
        // The names are the defaults' and the types match them: cannot fail.
        let _ = r.set(name, &v);
    };
    set(&mut r, NODE_ID, n16(Some(u16::from(node_id.get()))));
    let range = [s.range.lo(), s.range.hi()];
    set(&mut r, SETPOINT_RAT_LO_HI, real64(&range));
    set(&mut r, PERIOD, real64(&[s.period.get()]));
    set(&mut r, PATTERN_DURATION, real64(&[s.duration.get()]));
    set(&mut r, INIT_DURATION, real64(&[s.init_duration.get()]));
    set(&mut r, SETPOINT_PERIOD, real64(&[setpoint_period.get()]));
    let readiness = n16(readiness_id.map(SubjectId::get));
    set(&mut r, DRIVE_READINESS_ID, readiness);
    set(&mut r, DRIVE_SETPOINT_ID, n16(Some(setpoint_id.get())));
    set(&mut r, DRIVE_FEEDBACK_ID, n16(Some(feedback_id.get())));
    for (name, value) in registers::limit_values(limits) {
        set(&mut r, name, real64(&[value]));
    }
    r
}

/// Where the run is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// The soft start: a low setpoint that must produce feedback and speed the rotor up the
    /// commanded way.
    SoftStart,
    /// From the soft start's setpoint to the high one.
    Ramp,
    /// At the high setpoint, no rows recorded (the seed's init phase).
    Init,
    /// Playing the pattern and recording.
    Pattern,
    /// Sending STANDBY and a zero setpoint.
    Stopping,
    /// Done.
    Stopped,
}

/// The running estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Inertia J [kg·m²].
    pub j: f64,
    /// Viscous coefficient c1.
    pub c1: f64,
    /// Quadratic drag c2.
    pub c2: f64,
    /// Standard error of J.
    pub j_stderr: f64,
    /// Standard error of c2.
    pub c2_stderr: f64,
}

/// Transmit-side counters of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TxCounters {
    /// Frames the link refused for now (WouldBlock, write timeout); each was offered again.
    pub would_block: u64,
    /// Frames dropped: past their deadline in the queue, or refused by the link until then.
    pub dropped: u64,
    /// Queued setpoints replaced by a newer one before any of their frames left.
    pub superseded: u64,
    /// Transfers the full queue refused.
    pub refused: u64,
    /// Frames purged by the stop sequence.
    pub purged: u64,
}

/// Once a second during the pattern.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// Seconds into the pattern.
    pub elapsed: f64,
    /// Feedback rows in the last second.
    pub feedback_per_s: u64,
    /// Received transfers the reassembler rejected so far.
    pub dropped_transfers: u64,
    /// Feedback transfers lost on their way so far (gaps during the pattern).
    pub feedback_lost: FeedbackLoss,
    /// Transmit counters so far.
    pub tx: TxCounters,
    /// The running estimate, when `fit` is on and the data identify it.
    pub estimate: Option<Estimate>,
}

/// What the stop sequence did, and the run's totals.
#[derive(Clone, Debug, PartialEq)]
pub struct StopReport {
    /// Why it stopped.
    pub reason: StopReason,
    /// Rows recorded.
    pub rows: u64,
    /// Feedback transfers lost on their way during the pattern (gaps in transfer-IDs and in
    /// the drive's timestamps).
    pub feedback_lost: FeedbackLoss,
    /// Received frames the reassembler discarded as parts of damaged transfers (a lost start, a
    /// bad toggle, transfer-ID or CRC, no free session); frames of ports nobody subscribed to are
    /// not counted.
    pub damaged_frames: u64,
    /// STANDBY readiness messages handed to the link (0 when no readiness subject is set).
    pub standby_sent: u32,
    /// Whole zero-setpoint transfers handed to the link.
    pub zero_setpoints_sent: u32,
    /// Transmit counters of the whole run.
    pub tx: TxCounters,
    /// The running estimate at the end (computed whether or not `fit` was on).
    pub estimate: Option<Estimate>,
}

impl StopReport {
    /// True when at least one STANDBY (if readiness is published) and one whole zero setpoint
    /// were handed to the link.
    pub fn stop_commands_sent(&self, readiness: bool) -> bool {
        self.zero_setpoints_sent > 0 && (!readiness || self.standby_sent > 0)
    }
}

/// One feedback message as the drive received it: a row of the recording.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeedbackRow {
    /// When it arrived, on the caller's clock [s] (the TSV's `ts_local`).
    pub ts_local: f64,
    /// What it says (time from the drive's own timestamp).
    pub sample: Sample,
}

/// Frames the reassembler discarded as parts of damaged transfers.
fn damaged_frames(rx: &propid_core::can::RxStats) -> u64 {
    use propid_core::can::RxError;
    [
        RxError::MissingStart,
        RxError::BadToggle,
        RxError::WrongTransferId,
        RxError::BadCrc,
        RxError::OutOfSessions,
    ]
    .into_iter()
    .map(|e| rx.rejected(e))
    .sum()
}

/// What the drive reports while it runs.
#[derive(Clone, Debug, PartialEq)]
pub enum DriveEvent {
    /// The soft start passed: feedback came and the rotor sped up the commanded way.
    SoftStartPassed(SoftStartPassed),
    /// The init phase is over and recording begins.
    PatternStarted,
    /// One feedback row: write it (and flush it) before the next.
    Row(FeedbackRow),
    /// Once a second during the pattern.
    Progress(Progress),
    /// The stop sequence began (STANDBY is first in line).
    Stopping(StopReason),
    /// The stop sequence ended; the machine does nothing more.
    Stopped(StopReport),
    /// A register was written over the bus (`uavcan.register.Access`). The run goes on with the
    /// values it started with, as the seed's PyCyphal node does: the new value takes effect on
    /// the next run (the caller may store it in its register file).
    RegisterWritten {
        /// The register.
        name: String,
        /// Its new value.
        value: Value,
    },
}

/// A cheap copy of the drive's state for a live view.
#[derive(Clone, Debug, PartialEq)]
pub struct DriveSnapshot {
    /// Where the run is.
    pub phase: Phase,
    /// Seconds into the pattern (0 before it).
    pub elapsed: f64,
    /// The last setpoint commanded.
    pub setpoint: f32,
    /// The last readiness commanded.
    pub readiness: u8,
    /// The last [`SNAPSHOT_SAMPLES`] samples, oldest first.
    pub recent: Vec<Sample>,
    /// Rows recorded.
    pub rows: u64,
    /// The running estimate with standard errors (when the data identify it).
    pub estimate: Option<Estimate>,
    /// Transmit counters.
    pub tx: TxCounters,
    /// Received transfers rejected.
    pub dropped_transfers: u64,
    /// Feedback transfers lost on their way during the pattern.
    pub feedback_lost: FeedbackLoss,
}

struct Stopping {
    reason: StopReason,
    until: Instant,
    repeats_left: u32,
    next: Instant,
}

/// The driver. See the module documentation.
pub struct Drive {
    cfg: DriveConfig,
    node: HostNode,
    phase: Phase,
    soft_start_end: Instant,
    ramp_end: Instant,
    init_end: Instant,
    pattern_start: Option<Instant>,
    /// Feedback arrived at least once (the dead-man watches from then on).
    fed: bool,
    guard: Guard,
    next_publish: Instant,
    last_feedback: Instant,
    last_now: Instant,
    drive_id: Option<NodeId>,
    drive_uptime: Option<u32>,
    held: Option<Frame>,
    held_deadline: Instant,
    would_block: u64,
    held_dropped: u64,
    rows: u64,
    loss: LossCounter,
    estimator: LoadEstimator<f64>,
    next_progress: Instant,
    rows_at_progress: u64,
    recent: VecDeque<Sample>,
    setpoint: f32,
    readiness: u8,
    stopping: Option<Stopping>,
    standby_sent: u32,
    zero_setpoints_sent: u32,
    events: VecDeque<DriveEvent>,
}

impl Drive {
    /// A drive that starts now, in the init phase, serving the seed's registers with `cfg`'s
    /// values.
    pub fn new(cfg: DriveConfig, now: Instant) -> Self {
        let registers = drive_registers(&cfg, false);
        Drive::with_registers(cfg, &registers, now)
    }

    /// A drive that starts now and serves `registers` (List, Access, port.List every 10 s), as
    /// [`drive_registers`] builds them.
    pub fn with_registers(cfg: DriveConfig, registers: &HostRegistry, now: Instant) -> Self {
        let mut node_config = NodeConfig::new(cfg.node_id, "org.propid.drive", cfg.mtu);
        node_config.software_version.minor = 1;
        let mut node = HostNode::new(node_config, now);
        // Two subscriptions on a fresh node with 8 ports and validated IDs cannot fail.
        let _ = node.subscribe_message(cfg.feedback_id, DoF3rdTs::EXTENT_BYTES);
        let _ = node.subscribe_message(
            SubjectId::from_const(Heartbeat::FIXED_SUBJECT_ID),
            Heartbeat::EXTENT_BYTES,
        );
        registers::serve(&mut node, registers, &[], now);
        let limits = cfg.limits;
        let soft_start_end = now
            + limits
                .soft_start
                .map_or(Duration::ZERO, |s| s.duration.duration());
        let ramp_end = soft_start_end + limits.ramp.map_or(Duration::ZERO, |r| r.duration());
        let init_end = ramp_end + cfg.excitation.schedule().init_duration.duration();
        let phase = if limits.soft_start.is_some() {
            Phase::SoftStart
        } else if limits.ramp.is_some() {
            Phase::Ramp
        } else {
            Phase::Init
        };
        Drive {
            drive_id: cfg.drive_node_id,
            cfg,
            node,
            phase,
            soft_start_end,
            ramp_end,
            init_end,
            pattern_start: None,
            fed: false,
            guard: Guard::new(limits),
            next_publish: now,
            last_feedback: now,
            last_now: now,
            drive_uptime: None,
            held: None,
            held_deadline: now,
            would_block: 0,
            held_dropped: 0,
            rows: 0,
            loss: LossCounter::new(),
            estimator: LoadEstimator::new(),
            next_progress: now,
            rows_at_progress: 0,
            recent: VecDeque::with_capacity(SNAPSHOT_SAMPLES),
            setpoint: 0.0,
            readiness: Readiness::SLEEP,
            stopping: None,
            standby_sent: 0,
            zero_setpoints_sent: 0,
            events: VecDeque::new(),
        }
    }

    /// The configuration.
    pub fn config(&self) -> &DriveConfig {
        &self.cfg
    }

    /// The registers it serves (with the values written over the bus).
    pub fn registers(&self) -> &HostRegistry {
        self.node.registers()
    }

    /// Where the run is.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Rows recorded so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    fn setpoint_deadline(&self) -> Duration {
        Duration::from_secs_f64(self.cfg.setpoint_period.get() * 2.0)
    }

    fn tx_counters(&self) -> TxCounters {
        let tx: TxStats = self.node.stats().tx;
        TxCounters {
            would_block: self.would_block,
            dropped: tx.expired + self.held_dropped,
            superseded: tx.superseded,
            refused: tx.refused,
            purged: tx.purged,
        }
    }

    fn estimate(&self) -> Option<Estimate> {
        self.estimator
            .estimate(&LoadBounds::default())
            .ok()
            .map(|e| Estimate {
                j: e.mass,
                c1: e.c1,
                c2: e.c2,
                j_stderr: e.mass_stderr,
                c2_stderr: e.c2_stderr,
            })
    }

    /// A copy of the state for a live view (the recent samples, the estimate, the counters).
    pub fn snapshot(&self) -> DriveSnapshot {
        DriveSnapshot {
            phase: self.phase,
            elapsed: self.elapsed(self.last_now),
            setpoint: self.setpoint,
            readiness: self.readiness,
            recent: self.recent.iter().copied().collect(),
            rows: self.rows,
            estimate: self.estimate(),
            tx: self.tx_counters(),
            dropped_transfers: self.node.stats().rx.rejected_total(),
            feedback_lost: self.loss.loss(),
        }
    }

    fn elapsed(&self, now: Instant) -> f64 {
        self.pattern_start
            .map_or(0.0, |p| now.saturating_duration_since(p).as_secs_f64())
    }

    /// Notes the time of a call; a step backwards, or forwards by more than the loop may sleep,
    /// is a clock jump and stops the run.
    fn observe(&mut self, now: Instant) {
        let (last, max_gap) = (
            self.last_now,
            Duration::from_secs_f64((2.0 * self.cfg.setpoint_period.get()).max(1.0)),
        );
        self.last_now = self.last_now.max(now);
        if matches!(self.phase, Phase::Stopping | Phase::Stopped) {
            return;
        }
        let step = if now + Duration::from_millis(1) < last {
            Some(-(last.saturating_duration_since(now).as_secs_f64()))
        } else if now.saturating_duration_since(last) > max_gap {
            Some(now.saturating_duration_since(last).as_secs_f64())
        } else {
            None
        };
        if let Some(step) = step {
            // From here on the new clock is the truth: the stop sequence runs on it.
            self.last_now = now;
            self.stop(now, StopReason::ClockJump { step });
        }
    }

    /// The dead-man's stop, when no feedback came for longer than it allows.
    fn lost_feedback(&self, now: Instant) -> Option<StopReason> {
        let deadman = self.cfg.deadman.get();
        let silent = now.saturating_duration_since(self.last_feedback);
        (silent.as_secs_f64() > deadman).then_some(StopReason::LostFeedback { deadman })
    }

    /// Torque is commanded (the soft start to the end of the pattern).
    fn is_driving(&self) -> bool {
        matches!(
            self.phase,
            Phase::SoftStart | Phase::Ramp | Phase::Init | Phase::Pattern
        )
    }

    /// The soft start's setpoint: its magnitude in the direction of `hi`, at most |hi|.
    fn soft_start_setpoint(&self) -> f64 {
        let hi = self.cfg.excitation.schedule().range.hi();
        let magnitude = self.cfg.limits.soft_start.map_or(0.0, |s| s.setpoint.get());
        magnitude
            .min(hi.abs())
            .copysign(if hi < 0.0 { -1.0 } else { 1.0 })
    }

    /// The setpoint the phase commands at `now`.
    fn setpoint_at(&self, now: Instant) -> f64 {
        let hi = self.cfg.excitation.schedule().range.hi();
        match self.phase {
            Phase::SoftStart => self.soft_start_setpoint(),
            Phase::Ramp => {
                let from = self.soft_start_setpoint();
                let total = self.ramp_end.saturating_duration_since(self.soft_start_end);
                let done = now.saturating_duration_since(self.soft_start_end);
                let x = if total.is_zero() {
                    1.0
                } else {
                    (done.as_secs_f64() / total.as_secs_f64()).min(1.0)
                };
                from + (hi - from) * x
            }
            Phase::Pattern => self.cfg.excitation.setpoint(self.elapsed(now)),
            _ => hi,
        }
    }

    fn publish(&mut self, now: Instant, readiness: u8, setpoint: f32, deadline: Duration) {
        // A full queue refuses (counted in the node's stats); nothing else can fail here.
        if let Some(id) = self.cfg.readiness_id {
            let _ = self.node.publish_message(
                now,
                id,
                Priority::HIGH,
                &Readiness { value: readiness },
                deadline,
            );
        }
        let _ = self.node.publish_message(
            now,
            self.cfg.setpoint_id,
            Priority::HIGH,
            &Vector31::splat(setpoint),
            deadline,
        );
        self.readiness = readiness;
        self.setpoint = setpoint;
    }

    /// Moves the phases along: pattern start, end, deadman, setpoints, stop repeats, progress.
    fn advance(&mut self, now: Instant) {
        if self.phase == Phase::SoftStart && now >= self.soft_start_end {
            match self
                .guard
                .end_soft_start(self.soft_start_setpoint(), self.cfg.feedback_id.get())
            {
                Ok(passed) => {
                    self.events.push_back(DriveEvent::SoftStartPassed(passed));
                    self.phase = if now < self.ramp_end {
                        Phase::Ramp
                    } else {
                        Phase::Init
                    };
                }
                Err(limit) => {
                    self.stop(now, StopReason::Limit(limit));
                    return;
                }
            }
        }
        if self.phase == Phase::Ramp && now >= self.ramp_end {
            self.phase = Phase::Init;
        }
        // Before the pattern, the dead-man watches once feedback has come.
        if matches!(self.phase, Phase::SoftStart | Phase::Ramp | Phase::Init) && self.fed {
            if let Some(lost) = self.lost_feedback(now) {
                self.stop(now, lost);
                return;
            }
        }
        if self.phase == Phase::Init && now >= self.init_end {
            self.phase = Phase::Pattern;
            self.pattern_start = Some(self.init_end);
            self.last_feedback = now;
            self.next_progress = self.init_end + Duration::from_secs(1);
            self.events.push_back(DriveEvent::PatternStarted);
        }
        if self.phase == Phase::Pattern {
            let elapsed = self.elapsed(now);
            if elapsed >= self.cfg.excitation.schedule().duration.get() {
                self.stop(now, StopReason::Completed);
            } else if let Some(lost) = self.lost_feedback(now) {
                self.stop(now, lost);
            } else if now >= self.next_progress {
                let precise = self.cfg.until_rel_stderr.and_then(|target| {
                    let target = target.get();
                    let e = self.estimate()?;
                    let (rj, rc) = (e.j_stderr / e.j.abs(), e.c2_stderr / e.c2.abs());
                    (rj <= target && rc <= target).then_some((rj, rc))
                });
                if let Some((rel_j, rel_c2)) = precise {
                    self.stop(
                        now,
                        StopReason::Precise {
                            elapsed,
                            rel_j,
                            rel_c2,
                        },
                    );
                    return;
                }
                // The running fit's inertia bounds the watchdog once it is identified (inside
                // its bounds: a J pinned at the largest one says nothing).
                if let Ok(e) = self.estimator.estimate(&LoadBounds::default()) {
                    if !e.at_bound[0] {
                        self.guard.model_inertia(e.mass, e.mass_stderr);
                    }
                }
                let estimate = if self.cfg.fit { self.estimate() } else { None };
                self.events.push_back(DriveEvent::Progress(Progress {
                    elapsed,
                    feedback_per_s: self.rows - self.rows_at_progress,
                    dropped_transfers: self.node.stats().rx.rejected_total(),
                    feedback_lost: self.loss.loss(),
                    tx: self.tx_counters(),
                    estimate,
                }));
                self.rows_at_progress = self.rows;
                self.next_progress = self.next_progress + Duration::from_secs(1);
                if self.next_progress <= now {
                    self.next_progress = now + Duration::from_secs(1);
                }
            }
        }
        if self.is_driving() && now >= self.next_publish {
            let sp = self.setpoint_at(now);
            self.publish(now, Readiness::ENGAGED, sp as f32, self.setpoint_deadline());
            let period = self.cfg.setpoint_period.duration();
            self.next_publish = self.next_publish + period;
            if self.next_publish <= now {
                self.next_publish = now + period;
            }
        }
        if let Some(s) = &self.stopping {
            if self.phase == Phase::Stopping {
                let (until, repeats_left, next) = (s.until, s.repeats_left, s.next);
                // A repeat waits until the one before it has left: repeats queued behind a
                // congested link would supersede each other and leave as one transfer, which a
                // receiver discards when its transfer-ID equals the last one it took (PyCyphal
                // and libcanard deduplicate so; 1 in 32 after a gap). Repeats that leave one by
                // one have consecutive transfer-IDs, so at most the first can be discarded.
                if repeats_left > 0 && now >= next && self.nothing_waiting() {
                    let deadline = until.saturating_duration_since(now);
                    self.publish(now, Readiness::STANDBY, 0.0, deadline);
                    let period = self.cfg.setpoint_period.duration();
                    if let Some(s) = self.stopping.as_mut() {
                        s.repeats_left -= 1;
                        s.next = now + period;
                    }
                }
                let left = self.stopping.as_ref().map_or(0, |s| s.repeats_left);
                let drained = left == 0 && self.nothing_waiting();
                if drained || now >= until {
                    self.finish(now);
                }
            }
        }
    }

    /// Drops the frame held for the link, if any (counted): it never reached the bus, so its
    /// transfer-ID goes back to its subject ([`propid_core::node::Node::unsent`]).
    fn drop_held(&mut self) {
        if let Some(f) = self.held.take() {
            self.held_dropped += 1;
            self.node.unsent(&f);
        }
    }

    /// Nothing is queued or held for the link.
    fn nothing_waiting(&self) -> bool {
        self.held.is_none() && self.node.is_transmit_queue_empty()
    }

    fn finish(&mut self, now: Instant) {
        let Some(s) = self.stopping.as_ref() else {
            return;
        };
        let reason = s.reason.clone();
        // Whatever is still queued will never be sent.
        self.drop_held();
        self.held_dropped += self.node.transmit_queue_len() as u64;
        self.last_now = self.last_now.max(now);
        self.phase = Phase::Stopped;
        self.events.push_back(DriveEvent::Stopped(StopReport {
            reason,
            rows: self.rows,
            feedback_lost: self.loss.loss(),
            damaged_frames: damaged_frames(&self.node.stats().rx),
            standby_sent: self.standby_sent,
            zero_setpoints_sent: self.zero_setpoints_sent,
            tx: self.tx_counters(),
            estimate: self.estimate(),
        }));
    }

    /// Begins the stop sequence (once; later calls are ignored): purges what is queued, puts
    /// STANDBY and a zero setpoint first in line, and re-sends them [`STOP_REPEATS`] times within
    /// [`STOP_WINDOW`].
    pub fn stop(&mut self, now: Instant, reason: StopReason) {
        if self.stopping.is_some() {
            return;
        }
        // STANDBY and the zero setpoint follow on from the last transfers a receiver took.
        self.drop_held();
        self.node.purge_transmit();
        self.phase = Phase::Stopping;
        self.events.push_back(DriveEvent::Stopping(reason.clone()));
        self.stopping = Some(Stopping {
            reason,
            until: now + STOP_WINDOW,
            repeats_left: STOP_REPEATS,
            next: now,
        });
        self.advance(now);
    }

    /// Takes one received frame.
    pub fn handle_frame(&mut self, now: Instant, frame: &Frame) {
        self.observe(now);
        self.advance(now);
        let feedback_id = self.cfg.feedback_id;
        let mut heartbeat = None;
        let mut feedback = None;
        if let Some(Event::Message {
            subject_id,
            source,
            timestamp,
            transfer_id,
            payload,
            ..
        }) = self.node.handle_frame(now, frame)
        {
            if subject_id == feedback_id {
                if let Ok(fb) = DoF3rdTs::deserialize(payload) {
                    feedback = Some((timestamp, source, transfer_id, fb));
                }
            } else if subject_id.get() == Heartbeat::FIXED_SUBJECT_ID {
                if let (Some(src), Ok(hb)) = (source, Heartbeat::deserialize(payload)) {
                    heartbeat = Some((src, hb.uptime));
                }
            }
        }
        while let Some(i) = self.node.take_register_change() {
            if let Some(r) = self.node.registers().by_index(i) {
                self.events.push_back(DriveEvent::RegisterWritten {
                    name: r.name.as_str().unwrap_or_default().to_string(),
                    value: r.value.clone(),
                });
            }
        }
        if let Some((src, uptime)) = heartbeat {
            if self.drive_id == Some(src) {
                if let Some(before) = self.drive_uptime.filter(|b| uptime < *b) {
                    self.stop(
                        now,
                        StopReason::DriveRebooted {
                            node_id: src.get(),
                            before,
                            after: uptime,
                        },
                    );
                }
                self.drive_uptime = Some(uptime);
            }
        }
        let Some((timestamp, source, transfer_id, fb)) = feedback else {
            return;
        };
        if self.drive_id.is_none() {
            self.drive_id = source;
        }
        if !self.is_driving() {
            return;
        }
        self.last_feedback = now;
        self.fed = true;
        let sample = Sample::from(&fb);
        let soft_start = (self.phase == Phase::SoftStart).then(|| self.soft_start_setpoint());
        let stamped = fb.timestamp.microsecond != 0;
        if let Some(limit) = self
            .guard
            .feedback(&sample, stamped, now.as_secs_f64(), soft_start)
        {
            self.stop(now, StopReason::Limit(limit));
            return;
        }
        // Feedback before the pattern is not recorded, as the seed does.
        if self.phase == Phase::Pattern {
            if source == self.drive_id {
                self.loss.observe(transfer_id, fb.timestamp.microsecond);
            }
            self.rows += 1;
            if sample.is_finite() {
                self.estimator
                    .update(sample.force, sample.velocity, sample.acceleration);
            }
            if self.recent.len() == SNAPSHOT_SAMPLES {
                self.recent.pop_front();
            }
            self.recent.push_back(sample);
            self.events.push_back(DriveEvent::Row(FeedbackRow {
                ts_local: timestamp.as_secs_f64(),
                sample,
            }));
        }
    }

    /// The next frame to send, if one is due. STANDBY is first after a stop.
    #[must_use]
    pub fn poll_transmit(&mut self, now: Instant) -> Option<Frame> {
        self.observe(now);
        self.advance(now);
        if self.phase == Phase::Stopped {
            return None;
        }
        // A frame the link refused until its deadline is stale: dropped, the queue goes on.
        if now > self.held_deadline {
            self.drop_held();
        }
        let frame = match self.held.take() {
            Some(f) => Some(f),
            None => self.node.poll_transmit(now),
        }?;
        if self.phase == Phase::Stopping {
            self.count_stop_frame(&frame, 1);
        }
        Some(frame)
    }

    fn count_stop_frame(&mut self, frame: &Frame, sign: i32) {
        let subject = subject_of(frame);
        let add = |n: &mut u32| {
            *n = if sign > 0 {
                n.saturating_add(1)
            } else {
                n.saturating_sub(1)
            }
        };
        if ends_transfer(frame) {
            if subject == Some(self.cfg.setpoint_id.get()) {
                add(&mut self.zero_setpoints_sent);
            } else if subject.is_some() && subject == self.cfg.readiness_id.map(SubjectId::get) {
                add(&mut self.standby_sent);
            }
        }
    }

    /// The link could not take `frame`, the last one polled: it is offered again until its
    /// deadline (one setpoint deadline after it was first polled), then dropped and counted.
    pub fn handle_blocked(&mut self, now: Instant, frame: Frame) {
        self.would_block += 1;
        if self.phase == Phase::Stopping {
            self.count_stop_frame(&frame, -1);
        }
        if self.held.is_none() {
            self.held_deadline = if self.phase == Phase::Stopping {
                self.stopping.as_ref().map_or(now, |s| s.until)
            } else {
                frame.timestamp + self.setpoint_deadline()
            };
        }
        self.held = Some(frame);
    }

    /// When to call [`Drive::poll_transmit`] next.
    #[must_use]
    pub fn poll_timeout(&self) -> Option<Instant> {
        match self.phase {
            Phase::Stopped => None,
            _ => {
                // While the link refuses a frame, the queue waits behind it: come back to offer
                // it again (the node would say "now" for its non-empty queue).
                let t = if self.held.is_some() {
                    self.last_now + RETRY_STEP
                } else {
                    self.node.poll_timeout().unwrap_or(self.next_publish)
                };
                match (&self.stopping, self.phase) {
                    (Some(s), Phase::Stopping) => {
                        let mut t = t.min(s.until);
                        // (A repeat due but waiting for the one before it wakes nobody: the
                        // link's retry does.)
                        if s.repeats_left > 0 && self.nothing_waiting() {
                            t = t.min(s.next);
                        }
                        Some(t)
                    }
                    _ => {
                        let mut t = t.min(self.next_publish);
                        if self.fed && self.phase != Phase::Pattern {
                            t = t.min(
                                self.last_feedback
                                    + self.cfg.deadman.duration()
                                    + Duration::from_micros(1),
                            );
                        }
                        match self.phase {
                            Phase::SoftStart => t = t.min(self.soft_start_end),
                            Phase::Ramp => t = t.min(self.ramp_end),
                            Phase::Init => t = t.min(self.init_end),
                            _ => {
                                let deadman = self.last_feedback
                                    + self.cfg.deadman.duration()
                                    + Duration::from_micros(1);
                                t = t.min(deadman).min(self.next_progress);
                            }
                        }
                        Some(t)
                    }
                }
            }
        }
    }

    /// The next event.
    #[must_use]
    pub fn poll_event(&mut self) -> Option<DriveEvent> {
        self.events.pop_front()
    }
}

impl Machine for Drive {
    type Event = DriveEvent;
    fn handle_frame(&mut self, now: Instant, frame: &Frame) {
        Drive::handle_frame(self, now, frame)
    }
    fn poll_transmit(&mut self, now: Instant) -> Option<Frame> {
        Drive::poll_transmit(self, now)
    }
    fn handle_blocked(&mut self, now: Instant, frame: Frame) {
        Drive::handle_blocked(self, now, frame)
    }
    fn poll_timeout(&self) -> Option<Instant> {
        Drive::poll_timeout(self)
    }
    fn poll_event(&mut self) -> Option<DriveEvent> {
        Drive::poll_event(self)
    }
    fn handle_fault(&mut self, now: Instant, reason: StopReason) {
        self.last_now = self.last_now.max(now);
        self.stop(now, reason)
    }
    fn is_stopped(&self) -> bool {
        self.phase == Phase::Stopped
    }
}
