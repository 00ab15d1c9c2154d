//! # propid-drive: the identification run on a bus, as state machines
//!
//! The seed's driver is a PyCyphal node that engages a Telega, plays a ratiometric torque pattern
//! and records the drive's dynamics feedback. [`drive::Drive`] is that node; [`sim_drive::SimDrive`]
//! is its counterpart, a simulated Telega that runs `propid_science::stand::Stand` behind the same
//! Cyphal ports, so the whole run can be tested without hardware.
//!
//! Both are Sans-IO state machines in the style of the core's `Node` and quinn-proto: they read
//! no clock and touch no device. Time and frames go in, frames and events come out:
//!
//! ```text
//!  handle_frame(now, &Frame) ─► Node ─► DoF3rdTs ─► DriveEvent::Row (the caller writes + flushes it)
//!                                   └─► Heartbeat of the drive (uptime went down ⇒ it rebooted: stop)
//!  poll_transmit(now) ◄─ Node's TxQueue ◄─ Readiness ENGAGED + Vector31 setpoint every period
//!  handle_blocked(now, frame)   the link refused a frame (WouldBlock): kept, re-offered until its
//!                               deadline, then dropped and counted
//!  poll_timeout()               when to call again (the next setpoint, heartbeat or retry)
//!  poll_event()                 phases, rows, progress, the stop and its report
//!  handle_fault(now, reason)    signal, transport fault, bus-off, output error ⇒ the stop sequence
//!  stop sequence: purge the queue ─► STANDBY + zero setpoint first, re-sent STOP_REPEATS times
//!                 within STOP_WINDOW ─► Stopped(StopReport)
//! ```
//!
//! The only real-time code is [`realtime::run_realtime`]: one thin loop that sleeps until
//! `poll_timeout` or until a frame arrives, feeds the machine, sends what it polls, hands its
//! events to the caller and, after the stop, flushes the transport and says whether the stop
//! commands left. [`virtual_link`] runs two machines against each other on a modelled CAN link in
//! virtual time, so the seed's 200 s run is a deterministic test of well under a second.
//!
//! Both serve registers ([`registers`]): the drive the seed's PyCyphal names (built from defaults,
//! a register file, the environment and flags), the simulated Telega Telega's (`mns.*`,
//! `uavcan.pub.dynamics.id`, …), which it obeys. [`telega::Client`] is a third machine, a Cyphal
//! client on the core `Node` that discovers drives and reads, writes and stores their registers
//! (what `propid telega` runs on the bus, and the tests run against `SimDrive` in virtual time).
//!
//! The library never prints: progress reaches the caller as events.
#![deny(missing_docs)]

pub mod drive;
pub mod realtime;
pub mod registers;
pub mod sim_drive;
pub mod telega;
pub mod virtual_link;

use propid_core::can::Frame;
use propid_core::dsdl::DoF3rdTs;
use propid_core::node::Node;
use propid_core::time::Instant;
use propid_io::tsv::Sample;

/// The node type of the host tools: 8 ports, 16 sessions, 515-byte transfers (a whole
/// `uavcan.register.Access` request), 256 queued frames, [`registers::HOST_REGISTERS`] registers.
pub type HostNode = Node<8, 16, 515, 256, { registers::HOST_REGISTERS }>;

/// A Sans-IO machine that [`realtime::run_realtime`] and [`virtual_link`] can drive.
pub trait Machine {
    /// What it reports to its caller.
    type Event;
    /// Takes one received frame.
    fn handle_frame(&mut self, now: Instant, frame: &Frame);
    /// The next frame to send, if one is due.
    #[must_use]
    fn poll_transmit(&mut self, now: Instant) -> Option<Frame>;
    /// The link could not take `frame` (the last one polled) now: the machine keeps it and
    /// offers it again until its deadline.
    fn handle_blocked(&mut self, now: Instant, frame: Frame);
    /// When to call again at the latest (`None`: nothing planned).
    #[must_use]
    fn poll_timeout(&self) -> Option<Instant>;
    /// The next event for the caller.
    #[must_use]
    fn poll_event(&mut self) -> Option<Self::Event>;
    /// Something outside the machine went wrong or asked it to stop.
    fn handle_fault(&mut self, now: Instant, reason: StopReason);
    /// True once the machine has nothing more to do.
    fn is_stopped(&self) -> bool;
}

/// Why a machine stopped. Displays as a sentence for people, no debug text.
#[derive(Clone, Debug, PartialEq)]
pub enum StopReason {
    /// The pattern (or the simulated drive's duration) ran to its end.
    Completed,
    /// The running estimate reached the precision asked for (`--until-stderr`).
    Precise {
        /// Seconds into the pattern.
        elapsed: f64,
        /// Relative standard error of J then.
        rel_j: f64,
        /// Relative standard error of c2 then.
        rel_c2: f64,
    },
    /// SIGINT or SIGTERM (or the caller's stop flag).
    Signal,
    /// No feedback for longer than the deadman timeout [s].
    LostFeedback {
        /// The deadman timeout [s].
        deadman: f64,
    },
    /// The drive's heartbeat uptime went down: it rebooted mid-run.
    DriveRebooted {
        /// The drive's node-ID.
        node_id: u8,
        /// Uptime in its previous heartbeat [s].
        before: u32,
        /// Uptime in the heartbeat that showed the reboot [s].
        after: u32,
    },
    /// The monotonic clock stepped by more than the machine allows between two calls.
    ClockJump {
        /// The step [s]; negative when the clock went backwards.
        step: f64,
    },
    /// The CAN controller went bus-off (reported by the adapter).
    BusOff,
    /// The adapter refused a command (SLCAN BELL).
    AdapterRefused(String),
    /// The device went away (adapter unplugged, port closed).
    DeviceVanished(String),
    /// Another transport error.
    Transport(String),
    /// The recording could not be written.
    Output(String),
}

impl StopReason {
    /// True for every reason except a completed run.
    pub fn is_fault(&self) -> bool {
        !matches!(self, StopReason::Completed | StopReason::Precise { .. })
    }
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StopReason::Completed => write!(f, "the pattern is complete"),
            StopReason::Precise {
                elapsed,
                rel_j,
                rel_c2,
            } => write!(
                f,
                "precise enough after {elapsed:.1} s of the pattern (relative standard error J {:.3} %, c2 {:.3} %)",
                100.0 * rel_j,
                100.0 * rel_c2
            ),
            StopReason::Signal => write!(f, "interrupted by a signal"),
            StopReason::LostFeedback { deadman } => {
                write!(f, "no feedback for {deadman} s (deadman)")
            }
            StopReason::DriveRebooted {
                node_id,
                before,
                after,
            } => write!(
                f,
                "the drive (node {node_id}) rebooted: its uptime went from {before} s to {after} s"
            ),
            StopReason::ClockJump { step } => write!(
                f,
                "the host clock jumped by {step:+.3} s between two steps of the loop"
            ),
            StopReason::BusOff => write!(f, "the CAN controller went bus-off"),
            StopReason::AdapterRefused(cmd) => {
                write!(f, "the adapter refused a command ({cmd})")
            }
            StopReason::DeviceVanished(what) => write!(f, "the device vanished: {what}"),
            StopReason::Transport(e) => write!(f, "transport error: {e}"),
            StopReason::Output(e) => write!(f, "cannot write the recording: {e}"),
        }
    }
}

/// The TSV sample a `DoF3rdTs` message carries (time from the drive's timestamp).
pub fn sample_of(fb: &DoF3rdTs) -> Sample {
    let k = &fb.value.kinematics;
    Sample {
        t: fb.timestamp.microsecond as f64 * 1e-6,
        force: f64::from(fb.value.force),
        velocity: f64::from(k.base.velocity),
        acceleration: f64::from(k.acceleration),
        position: f64::from(k.base.position),
    }
}

/// Whether `frame` ends a transfer (its tail byte's end-of-transfer bit).
pub(crate) fn ends_transfer(frame: &Frame) -> bool {
    frame.data().last().is_some_and(|t| t & 0x40 != 0)
}

/// The subject-ID of a message frame (`None` for a service frame).
pub(crate) fn subject_of(frame: &Frame) -> Option<u16> {
    let id = frame.id();
    // Bit 25: service; bits 8..=20: subject-ID.
    (id & (1 << 25) == 0).then_some(((id >> 8) & 0x1FFF) as u16)
}
