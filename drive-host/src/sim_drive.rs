//! The simulated Telega on a real bus: [`propid_drive_proto::sim_drive::SimDrive`] in the
//! real-time loop.

use std::sync::atomic::AtomicBool;

use propid_drive_proto::sim_drive::{SimDrive, SimDriveConfig, SimDriveEvent, SimDriveSummary};
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
