//! The contract every machine of this crate keeps, so one real-time loop
//! (`propid_drive_host::realtime::run_realtime`) and one virtual link
//! ([`crate::virtual_link::VirtualLink`]) can run any of them; and why a machine stops.

use propid_core::can::Frame;
use propid_core::time::Instant;

use crate::limits::LimitStop;

/// A Sans-IO machine that a real-time loop and [`crate::virtual_link`] can drive.
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
    /// A limit stopped the rotor (soft start, maximum speed, speed watchdog).
    Limit(LimitStop),
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
            StopReason::Limit(l) => write!(f, "{l}"),
        }
    }
}
