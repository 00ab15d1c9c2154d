//! `propid sim-drive`: a simulated Telega on a CAN interface, around
//! [`propid_drive::sim_drive::run_sim_drive`].

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use propid_core::dsdl::Readiness;
use propid_drive::registers;
use propid_drive::sim_drive::{run_sim_drive_with, SimDriveConfig};

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
    /// Set one of its Telega-like registers at start, NAME=VALUE (repeatable), e.g.
    /// `mns.pub_interval_min=0.05` or `mns.local_timestamp=false` (Telega's factory settings).
    /// Environment variables named after the registers (MNS__PUB_INTERVAL_MIN, …) apply too.
    #[arg(long = "register", value_name = "NAME=VALUE")]
    pub registers: Vec<String>,
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
    let mut cfg = cfg;
    let mut r = registers::sim_drive_registers(&cfg, true);
    // Its own node-ID and ports come from the flags (and their variables): only the others here.
    let env = std::env::vars().filter(|(k, _)| k.starts_with("MNS__"));
    registers::apply_environment(&mut r, env)?;
    for a in &args.registers {
        let (name, value) = a
            .split_once('=')
            .ok_or_else(|| InputError(format!("--register `{a}`: expected NAME=VALUE")))?;
        let origin = format!("--register {name}");
        registers::set_text(
            &mut r,
            name.trim(),
            registers::normalize_bool(value),
            &origin,
        )?;
    }
    let first = |n: &str| r.get(n).and_then(|x| x.value.float_at(0));
    let port = |n: &str| first(n).filter(|v| *v <= 8191.0).map(|v| v as u16);
    cfg.feedback_id = port("uavcan.pub.dynamics.id").unwrap_or(cfg.feedback_id);
    cfg.setpoint_id = port("uavcan.sub.setpoint_r_torq.id").unwrap_or(cfg.setpoint_id);
    cfg.readiness_id = port("uavcan.sub.readiness.id");
    cfg.interval = registers::SimSettings::read(&r, cfg.interval).interval;
    let mut transport = args.bus.open()?;
    let stop = Arc::new(AtomicBool::new(false));
    crate::signals::install(&stop)?;
    eprintln!(
        "sim-drive: node {} on {} publishing feedback on subject {}",
        cfg.node_id,
        transport.name(),
        cfg.feedback_id
    );
    let summary =
        run_sim_drive_with(&cfg, &r, transport.as_mut(), &stop).map_err(anyhow::Error::msg)?;
    eprintln!(
        "sim-drive: {} setpoints received, {} feedback published; last readiness {}, last setpoint {:?}",
        summary.setpoints,
        summary.feedback_published,
        summary.last_readiness.map_or("none", readiness_name),
        summary.last_setpoint
    );
    Ok(())
}
