//! `propid sim-drive`: a simulated Telega on a CAN interface, around
//! [`propid_drive_host::sim_drive::run_sim_drive`].

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use propid_core::can::{Mtu, NodeId, SubjectId};
use propid_core::dsdl::Readiness;
use propid_drive_host::realtime::{Clock, SystemClock};
use propid_drive_host::sim_drive::run_sim_drive_machine;
use propid_drive_host::stand::StandPlant;
use propid_drive_proto::registers;
use propid_drive_proto::settings::{FeedbackInterval, RunLimit};
use propid_drive_proto::sim_drive::{sim_drive_registers, SimDrive, SimDriveConfig, SimDriveEvent};

use crate::cmd::sim::StandArgs;

/// Arguments of `propid sim-drive`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// This node's ID.
    #[arg(long, env = "UAVCAN__NODE__ID", default_value = "42")]
    pub node_id: NodeId,
    /// The bus.
    #[command(flatten)]
    pub bus: crate::bus::BusArgs,
    /// Readiness subject (no readiness gating when unset).
    #[arg(long, env = "UAVCAN__SUB__READINESS__ID")]
    pub readiness_id: Option<SubjectId>,
    /// Ratiometric setpoint subject.
    #[arg(long, env = "UAVCAN__SUB__SP_RAT__ID", default_value = "24")]
    pub setpoint_id: SubjectId,
    /// Dynamics feedback subject.
    #[arg(long, env = "UAVCAN__PUB__FB_DYN__ID", default_value = "110")]
    pub feedback_id: SubjectId,
    /// Feedback interval [s] (register mns.pub_interval_min; writable over the bus).
    #[arg(long, default_value_t = 0.002)]
    pub interval: f64,
    /// Stamp the feedback with the drive's clock (register mns.local_timestamp; when false the
    /// timestamp is 0, unknown).
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    pub local_timestamp: bool,
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
    let flag = crate::cmd::drive::flag_error;
    let cfg = SimDriveConfig {
        node_id: args.node_id,
        mtu: Mtu::from_bytes(args.bus.mtu)
            .ok_or_else(|| flag("mtu", format!("must be 8 or 64 (got {})", args.bus.mtu)))?,
        readiness_id: args.readiness_id,
        setpoint_id: args.setpoint_id,
        feedback_id: args.feedback_id,
        interval: FeedbackInterval::new(args.interval)
            .map_err(|e| flag("interval", e.to_string()))?,
        duration: match args.duration {
            0.0 => None,
            d => Some(RunLimit::new(d).map_err(|e| flag("duration", e.to_string()))?),
        },
    };
    let plant = StandPlant::boxed(args.stand.config()?, args.stand.seed)?;
    let mut transport = args.bus.open()?;
    let stop = Arc::new(AtomicBool::new(false));
    crate::signals::install(&stop)?;
    eprintln!(
        "sim-drive: node {} on {} publishing feedback on subject {}",
        cfg.node_id,
        transport.name(),
        cfg.feedback_id
    );
    let regs = sim_drive_registers(&cfg, args.local_timestamp);
    let sim = SimDrive::with_registers(cfg, plant, &regs, SystemClock.now());
    let summary =
        run_sim_drive_machine(
            sim,
            transport.as_mut(),
            &SystemClock,
            &stop,
            &mut |e| match e {
                SimDriveEvent::RegisterWritten { name, value } => eprintln!(
                    "sim-drive: register {name} written: {}",
                    registers::show(value)
                ),
                SimDriveEvent::Restarted => {
                    eprintln!("sim-drive: restarted (port-IDs from the registers)")
                }
                SimDriveEvent::Stored => eprintln!("sim-drive: asked to store its registers"),
                _ => {}
            },
        )
        .map_err(anyhow::Error::msg)?;
    eprintln!(
        "sim-drive: {} setpoints received, {} feedback published, {} feedback samples dropped unsent (not sent within {} s); last readiness {}, last setpoint {}",
        summary.setpoints,
        summary.feedback_published,
        summary.feedback_dropped,
        propid_drive_proto::sim_drive::FEEDBACK_HOLD.as_secs_f64(),
        summary.last_readiness.map_or("none", readiness_name),
        summary
            .last_setpoint
            .map_or("none".to_string(), |v| v.to_string())
    );
    Ok(())
}
