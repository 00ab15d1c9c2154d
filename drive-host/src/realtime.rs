//! The one real-time loop: a [`Machine`] on a [`CanTransport`], against a [`Clock`].
//!
//! ```text
//!  loop:
//!    stop flag raised? ─► machine.handle_fault(Signal)
//!    transport.health(): bus-off / adapter refusal (BELL) ─► machine.handle_fault(..)
//!    machine.poll_transmit ─► transport.send ── WouldBlock ─► machine.handle_blocked (counted)
//!                                           └── fault ─────► machine.handle_fault (the link is dead:
//!                                                            nothing more is written to it)
//!    machine.poll_event ─► sink (a sink error ─► machine.handle_fault(Output))
//!    machine stopped? ─► transport.flush(bounded) ─► RunOutcome { flushed }
//!    transport.receive(until poll_timeout) ─► machine.handle_frame
//! ```
//! The loop never waits on a write: a congested link is the machine's business (it keeps the
//! frame and offers it again until its deadline). For the run's length its thread runs at a
//! real-time priority where the OS permits it ([`propid_transport::priority`]): on a busy machine a
//! normal thread waited in the run queue for over a second and the run stopped.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use propid_core::time::Instant;
use propid_transport::priority::{raise_thread_priority, ThreadPriority};
use propid_transport::{BusState, CanTransport, Health, HostClock, TransportError};

use propid_drive_proto::{Machine, StopReason};

/// Where the loop reads the time.
pub trait Clock {
    /// Now, on the clock the transport timestamps frames with.
    fn now(&self) -> Instant;
}

/// The process's monotonic clock ([`HostClock`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct SystemClock;

impl Clock for SystemClock {
    fn now(&self) -> Instant {
        HostClock::now()
    }
}

/// How long the loop sleeps at most in one wait (so the stop flag is seen promptly).
const MAX_WAIT: Duration = Duration::from_millis(20);
/// How long, at most, the final flush waits for the stop commands to leave the transport.
pub const FLUSH_BOUND: Duration = Duration::from_millis(200);

/// What the loop saw of the link.
#[derive(Clone, Debug, PartialEq)]
pub struct RunOutcome {
    /// Everything the machine handed over left the transport (false when the link failed or
    /// the final flush ran out of time).
    pub flushed: bool,
    /// Frames the machine produced after the link failed (never written).
    pub lost_to_fault: u64,
    /// The transport's error that ended the link, if any.
    pub link_fault: Option<String>,
    /// What the loop's thread ran at (real-time where the OS permits it).
    pub priority: ThreadPriority,
}

/// What a transport error means for the run.
enum Outcome {
    /// Congestion: try again later.
    Blocked,
    /// The link is unusable.
    Fault(StopReason),
}

fn classify(e: &TransportError) -> Outcome {
    match e {
        TransportError::WouldBlock => Outcome::Blocked,
        TransportError::Closed(what) => Outcome::Fault(StopReason::DeviceVanished(what.clone())),
        TransportError::Refused { command, .. } => {
            Outcome::Fault(StopReason::AdapterRefused(command.clone()))
        }
        other => Outcome::Fault(StopReason::Transport(other.to_string())),
    }
}

/// A fault the transport's counters show since `seen`: the controller went bus-off, or the
/// adapter refused a line (SLCAN BELL).
fn health_fault(now: &Health, seen: &Health) -> Option<StopReason> {
    if now.bus_state == BusState::BusOff && seen.bus_state != BusState::BusOff {
        return Some(StopReason::BusOff);
    }
    if now.refused > seen.refused {
        let line = now
            .last_refused
            .clone()
            .unwrap_or_else(|| "a line it was sent".into());
        return Some(StopReason::AdapterRefused(line));
    }
    None
}

/// Runs `machine` on `transport` in real time until it stops; its events go to `sink`.
/// `stop` (set by a signal handler) starts the machine's stop sequence.
pub fn run_realtime<M: Machine>(
    machine: &mut M,
    transport: &mut dyn CanTransport,
    clock: &dyn Clock,
    stop: &AtomicBool,
    sink: &mut dyn FnMut(M::Event) -> Result<(), String>,
) -> RunOutcome {
    // A loop that waits in the run queue of a busy machine stops reading the link and sending
    // setpoints; for the run's length the thread runs at a real-time priority where permitted.
    let priority = raise_thread_priority();
    let mut signalled = false;
    let mut dead: Option<String> = None;
    let mut lost = 0u64;
    let mut seen = transport.health();
    loop {
        let now = clock.now();
        if !signalled && stop.load(Ordering::Relaxed) {
            signalled = true;
            machine.handle_fault(now, StopReason::Signal);
        }
        if dead.is_none() {
            let health = transport.health();
            if let Some(reason) = health_fault(&health, &seen) {
                machine.handle_fault(now, reason);
            }
            seen = health;
        }
        while let Some(frame) = machine.poll_transmit(now) {
            if dead.is_some() {
                lost += 1;
                continue;
            }
            match transport.send(&frame) {
                Ok(()) => {}
                Err(e) => match classify(&e) {
                    Outcome::Blocked => {
                        machine.handle_blocked(now, frame);
                        break;
                    }
                    Outcome::Fault(reason) => {
                        lost += 1;
                        dead = Some(e.to_string());
                        machine.handle_fault(now, reason);
                    }
                },
            }
        }
        while let Some(event) = machine.poll_event() {
            if let Err(e) = sink(event) {
                machine.handle_fault(clock.now(), StopReason::Output(e));
            }
        }
        if machine.is_stopped() {
            break;
        }
        let wake = machine.poll_timeout();
        let now = clock.now();
        let wait = wake
            .map_or(MAX_WAIT, |w| w.saturating_duration_since(now))
            .min(MAX_WAIT);
        if dead.is_some() {
            std::thread::sleep(wait);
            continue;
        }
        match transport.receive(wait) {
            Ok(Some(frame)) => machine.handle_frame(clock.now(), &frame),
            Ok(None) => {}
            Err(e) => match classify(&e) {
                Outcome::Blocked => {}
                Outcome::Fault(reason) => {
                    dead = Some(e.to_string());
                    machine.handle_fault(clock.now(), reason);
                }
            },
        }
    }
    // The stop commands were accepted whole; make sure their bytes leave too.
    let flushed = dead.is_none()
        && lost == 0
        && transport
            .flush(std::time::Instant::now() + FLUSH_BOUND)
            .unwrap_or(false);
    RunOutcome {
        flushed,
        lost_to_fault: lost,
        link_fault: dead,
        priority: priority.obtained().clone(),
    }
}
