//! `propid sim-drive`: a simulated Telega on a CAN interface, around
//! [`propid_drive::sim_drive::run_sim_drive`].

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use propid_core::dsdl::Readiness;
use propid_drive::sim_drive::{run_sim_drive, SimDriveConfig};

use crate::cmd::sim::StandArgs;
use crate::InputError;

/// Arguments of `propid sim-drive`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// This node's ID.
    #[arg(long, env = "UAVCAN__NODE__ID", default_value_t = 42)]
    pub node_id: u8,
    /// The bus.
    #[command(flatten)]
    pub bus: crate::bus::BusArgs,
    /// Readiness subject (no readiness gating when unset).
    #[arg(long, env = "UAVCAN__SUB__READINESS__ID")]
    pub readiness_id: Option<u16>,
    /// Ratiometric setpoint subject.
    #[arg(long, env = "UAVCAN__SUB__SP_RAT__ID", default_value_t = 24)]
    pub setpoint_id: u16,
    /// Dynamics feedback subject.
    #[arg(long, env = "UAVCAN__PUB__FB_DYN__ID", default_value_t = 110)]
    pub feedback_id: u16,
    /// Feedback interval [s].
    #[arg(long, default_value_t = 0.002)]
    pub interval: f64,
    /// Stop after this many seconds (0: run until interrupted).
    #[arg(long, default_value_t = 0.0)]
    pub duration: f64,
    /// The simulated stand.
    #[command(flatten)]
    pub stand: StandArgs,
}

fn readiness_name(v: u8) -> &'static str {
    match v {
        Readiness::SLEEP => "SLEEP",
        Readiness::STANDBY => "STANDBY",
        Readiness::ENGAGED => "ENGAGED",
        _ => "undefined",
    }
}

/// Runs `propid sim-drive`.
pub fn run(args: Args) -> anyhow::Result<()> {
    if args.interval.is_nan() || args.interval <= 0.0 {
        return Err(InputError(format!(
            "--interval must be positive (got {})",
            args.interval
        ))
        .into());
    }
    let cfg = SimDriveConfig {
        node_id: args.node_id,
        mtu: args.bus.mtu,
        readiness_id: args.readiness_id,
        setpoint_id: args.setpoint_id,
        feedback_id: args.feedback_id,
        interval: args.interval,
        duration: args.duration,
        stand: args.stand.config()?,
        seed: args.stand.seed,
    };
    let mut transport = args.bus.open()?;
    let stop = Arc::new(AtomicBool::new(false));
    crate::signals::install(&stop)?;
    eprintln!(
        "sim-drive: node {} on {} publishing feedback on subject {}",
        cfg.node_id,
        transport.name(),
        cfg.feedback_id
    );
    let summary = run_sim_drive(&cfg, transport.as_mut(), &stop).map_err(anyhow::Error::msg)?;
    eprintln!(
        "sim-drive: {} setpoints received, {} feedback published; last readiness {}, last setpoint {:?}",
        summary.setpoints,
        summary.feedback_published,
        summary.last_readiness.map_or("none", readiness_name),
        summary.last_setpoint
    );
    Ok(())
}
