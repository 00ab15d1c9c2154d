//! The simulated Telega on a real bus: [`propid_drive_proto::sim_drive::SimDrive`] in the
//! real-time loop, in the caller's thread ([`run_sim_drive`]) or on its own, waited on by what it
//! receives ([`SimDriveThread`]).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

use propid_core::dsdl::Readiness;
use propid_drive_proto::sim_drive::{
    Command, SimDrive, SimDriveConfig, SimDriveEvent, SimDriveSummary,
};
use propid_drive_proto::StopReason;
use propid_transport::CanTransport;

use propid_drive_proto::plant::Plant;

use crate::realtime::{run_realtime, Clock};

/// Runs a [`SimDrive`] of `plant` in real time on `transport` until `stop` is raised or its
/// duration ends. A transport fault is an error (its sentence); otherwise what it saw.
pub fn run_sim_drive(
    cfg: SimDriveConfig,
    plant: Box<dyn Plant>,
    transport: &mut dyn CanTransport,
    clock: &dyn Clock,
    stop: &AtomicBool,
) -> Result<SimDriveSummary, String> {
    let sim = SimDrive::new(cfg, plant, clock.now());
    run_sim_drive_machine(sim, transport, clock, stop, &mut |_| {})
}

/// [`run_sim_drive`] for a [`SimDrive`] built by the caller; every event also goes to
/// `on_event`.
pub fn run_sim_drive_machine(
    mut sim: SimDrive,
    transport: &mut dyn CanTransport,
    clock: &dyn Clock,
    stop: &AtomicBool,
    on_event: &mut dyn FnMut(&SimDriveEvent),
) -> Result<SimDriveSummary, String> {
    let mut end = None;
    run_realtime(&mut sim, transport, clock, stop, &mut |event| {
        on_event(&event);
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

/// The stop commands a simulated drive has received: the STANDBY readiness messages and the zero
/// setpoints since the first STANDBY.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StopCommandsSeen {
    /// STANDBY readiness messages.
    pub standby: u64,
    /// Zero setpoints after the first STANDBY.
    pub zero_setpoints: u64,
}

type Shared = Arc<(Mutex<StopCommandsSeen>, Condvar)>;

/// A simulated drive running in real time on its own thread, whose test or caller can wait for
/// what it has received instead of sleeping: [`SimDriveThread::wait_for_stop_commands`].
pub struct SimDriveThread {
    stop: Arc<AtomicBool>,
    seen: Shared,
    thread: std::thread::JoinHandle<Result<SimDriveSummary, String>>,
}

impl SimDriveThread {
    /// Starts `sim` on `transport` on a thread of its own (on the system clock).
    pub fn spawn(sim: SimDrive, mut transport: Box<dyn CanTransport>) -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let seen: Shared = Arc::default();
        let thread = {
            let (stop, seen) = (Arc::clone(&stop), Arc::clone(&seen));
            std::thread::spawn(move || {
                run_sim_drive_machine(
                    sim,
                    transport.as_mut(),
                    &crate::realtime::SystemClock,
                    &stop,
                    &mut |e| {
                        if let SimDriveEvent::Received(c) = e {
                            let (lock, changed) = &*seen;
                            let mut s = lock.lock().unwrap_or_else(|p| p.into_inner());
                            match *c {
                                Command::Readiness(Readiness::STANDBY) => s.standby += 1,
                                Command::Setpoint(v) if v == 0.0 && s.standby > 0 => {
                                    s.zero_setpoints += 1
                                }
                                _ => return,
                            }
                            changed.notify_all();
                        }
                    },
                )
            })
        };
        SimDriveThread { stop, seen, thread }
    }

    /// Waits until the simulated drive has received at least `standby` STANDBY messages and
    /// `zero_setpoints` zero setpoints after them (what a driver reports it sent), or `timeout`
    /// passed (a bound for a lost frame, not a guess at how long delivery takes); what it has
    /// received then.
    pub fn wait_for_stop_commands(
        &self,
        standby: u32,
        zero_setpoints: u32,
        timeout: Duration,
    ) -> StopCommandsSeen {
        let (lock, changed) = &*self.seen;
        let guard = lock.lock().unwrap_or_else(|p| p.into_inner());
        let (seen, _) = changed
            .wait_timeout_while(guard, timeout, |s| {
                s.standby < u64::from(standby) || s.zero_setpoints < u64::from(zero_setpoints)
            })
            .unwrap_or_else(|p| p.into_inner());
        *seen
    }

    /// Stops it once it has received the stop commands a driver reports it sent (or `timeout`
    /// passed, [`SimDriveThread::wait_for_stop_commands`]): what it received of them, and what it
    /// saw.
    pub fn stop_after_stop_commands(
        self,
        standby: u32,
        zero_setpoints: u32,
        timeout: Duration,
    ) -> (StopCommandsSeen, Result<SimDriveSummary, String>) {
        let seen = self.wait_for_stop_commands(standby, zero_setpoints, timeout);
        (seen, self.stop())
    }

    /// Stops it and returns what it saw (or its loop's error).
    pub fn stop(self) -> Result<SimDriveSummary, String> {
        self.stop.store(true, Ordering::Relaxed);
        self.thread
            .join()
            .unwrap_or_else(|_| Err("the simulated drive's thread panicked".into()))
    }
}
