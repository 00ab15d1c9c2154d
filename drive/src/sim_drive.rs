//! A simulated Telega as a Cyphal node.
//!
//! ```text
//!  transport ─► Node::handle_frame ─► Readiness (torque only when ENGAGED), Vector31 setpoint
//!  every feedback interval: Stand::advance_to(t) ─► Stand::measure ─► DoF3rdTs (device timestamp)
//!                           ─► Node::publish ─► transport
//!  deadman: no setpoint for 0.5 s ⇒ zero torque
//! ```
//! It runs the same stand model as `propid sim` (`propid_science::stand::Stand`), in real time.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use propid_core::can::{Mtu, Priority};
use propid_core::dsdl::{DataType, DoF3rdTs, Readiness, Vector31};
use propid_core::node::{Event, NodeConfig};
use propid_core::time::Instant;
use propid_transport::{CanTransport, HostClock};

use propid_science::stand::{Stand, StandConfig};

use crate::HostNode;

/// The simulated drive's settings.
#[derive(Clone, Debug)]
pub struct SimDriveConfig {
    /// Node-ID.
    pub node_id: u8,
    /// 8 or 64.
    pub mtu: usize,
    /// Readiness subject.
    pub readiness_id: Option<u16>,
    /// Setpoint subject.
    pub setpoint_id: u16,
    /// Feedback subject.
    pub feedback_id: u16,
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
            node_id: 42,
            mtu: 8,
            readiness_id: Some(10),
            setpoint_id: 24,
            feedback_id: 110,
            interval: 0.002,
            duration: 0.0,
            stand,
            seed,
        }
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
    /// ExecuteCommand requests accepted (restart, store: the simulation has nothing to do).
    pub commands: u64,
}

/// Runs the simulated drive until `stop` is raised or its duration ends.
pub fn run_sim_drive(
    cfg: &SimDriveConfig,
    transport: &mut dyn CanTransport,
    stop: &AtomicBool,
) -> Result<SimDriveSummary, String> {
    let registers = crate::registers::sim_drive_registers(cfg, true);
    run_sim_drive_with(cfg, &registers, transport, stop)
}

/// [`run_sim_drive`] serving Telega-like `registers` (see
/// [`crate::registers::sim_drive_registers`]) and obeying them: `mns.pub_interval_min` sets the
/// feedback interval and `mns.local_timestamp` whether feedback carries the drive's timestamp
/// (0 otherwise), both at once when written over the bus.
pub fn run_sim_drive_with(
    cfg: &SimDriveConfig,
    registers: &crate::registers::HostRegistry,
    transport: &mut dyn CanTransport,
    stop: &AtomicBool,
) -> Result<SimDriveSummary, String> {
    let mtu = if cfg.mtu == 64 { Mtu::Fd } else { Mtu::Classic };
    let start = HostClock::now();
    let mut node = HostNode::new(
        NodeConfig::new(cfg.node_id, "org.zubax.telega.sim", mtu),
        start,
    );
    let commands = [
        propid_core::dsdl::ExecuteCommandRequest::COMMAND_RESTART,
        propid_core::dsdl::ExecuteCommandRequest::COMMAND_STORE_PERSISTENT_STATES,
    ];
    crate::registers::serve(&mut node, registers, &commands, start);
    let mut obeyed = crate::registers::SimSettings::read(node.registers(), cfg.interval);
    let _ = node.subscribe_message(cfg.setpoint_id, Vector31::EXTENT_BYTES);
    if let Some(id) = cfg.readiness_id {
        let _ = node.subscribe_message(id, Readiness::EXTENT_BYTES);
    }
    let mut stand = Stand::new(cfg.stand, cfg.seed);
    let mut summary = SimDriveSummary::default();
    let mut interval = Duration::from_secs_f64(obeyed.interval);
    let mut next_feedback = start;
    let mut last_setpoint_at: Option<Instant> = None;
    let mut setpoint = 0.0f64;
    loop {
        let now = HostClock::now();
        let t = now.saturating_duration_since(start).as_secs_f64();
        if stop.load(Ordering::Relaxed) || (cfg.duration > 0.0 && t >= cfg.duration) {
            return Ok(summary);
        }
        if now >= next_feedback {
            let engaged = match cfg.readiness_id {
                Some(_) => summary.last_readiness == Some(Readiness::ENGAGED),
                None => true,
            };
            let alive = last_setpoint_at
                .is_some_and(|at| now.saturating_duration_since(at) < Duration::from_millis(500));
            stand.set_setpoint(if engaged && alive { setpoint } else { 0.0 });
            stand.advance_to(t);
            let s = stand.measure();
            let mut fb = DoF3rdTs::default();
            if obeyed.local_timestamp {
                fb.timestamp.microsecond = (t * 1e6) as u64;
            }
            fb.value.kinematics.base.position = s.position as f32;
            fb.value.kinematics.base.velocity = s.velocity as f32;
            fb.value.kinematics.acceleration = s.acceleration as f32;
            fb.value.force = s.force as f32;
            if node
                .publish_message(now, cfg.feedback_id, Priority::HIGH, &fb, interval * 5)
                .is_ok()
            {
                summary.feedback_published += 1;
            }
            next_feedback = next_feedback + interval;
            if next_feedback < now {
                next_feedback = now + interval;
            }
        }
        if node.take_register_change().is_some() {
            obeyed = crate::registers::SimSettings::read(node.registers(), obeyed.interval);
            interval = Duration::from_secs_f64(obeyed.interval);
            next_feedback = next_feedback.min(now + interval);
        }
        while node.take_command().is_some() {
            summary.commands += 1;
        }
        while let Some(f) = node.poll_transmit(now) {
            match transport.send(&f) {
                // Nobody reading, or reading slowly: drop the frame (the transport counts it).
                Err(e) if e.is_would_block() => {}
                r => r.map_err(|e| e.to_string())?,
            }
        }
        let wait = next_feedback
            .saturating_duration_since(HostClock::now())
            .min(Duration::from_millis(5));
        let Some(frame) = transport.receive(wait).map_err(|e| e.to_string())? else {
            continue;
        };
        match node.handle_frame(HostClock::now(), &frame) {
            Some(Event::Message {
                subject_id,
                payload,
                ..
            }) if subject_id == cfg.setpoint_id => {
                if let Ok(v) = Vector31::deserialize(payload) {
                    setpoint = f64::from(v.value[0]);
                    summary.last_setpoint = Some(v.value[0]);
                    summary.setpoints += 1;
                    last_setpoint_at = Some(HostClock::now());
                }
            }
            Some(Event::Message {
                subject_id,
                payload,
                ..
            }) if Some(subject_id) == cfg.readiness_id => {
                if let Ok(r) = Readiness::deserialize(payload) {
                    if summary.last_readiness != Some(r.value) {
                        summary.readiness_changes.push(r.value);
                    }
                    summary.last_readiness = Some(r.value);
                }
            }
            _ => {}
        }
    }
}
