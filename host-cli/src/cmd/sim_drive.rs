//! `propid sim-drive`: a simulated Telega on a CAN interface, around
//! [`propid_drive_host::sim_drive::run_sim_drive`]. Its settings are Telega's registers
//! (`mns.pub_interval_min`, `uavcan.pub.dynamics.id`, …), each also a flag and an environment
//! variable.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use propid_core::can::SubjectId;
use propid_core::dsdl::Readiness;
use propid_drive_host::realtime::{Clock, SystemClock};
use propid_drive_host::sim_drive::run_sim_drive_machine;
use propid_drive_host::stand::StandPlant;
use propid_drive_proto::plant::TorqueScaled;
use propid_drive_proto::registers::{
    self, LOCAL_TIMESTAMP, PUB_INTERVAL_MIN, TELEGA_FEEDBACK_ID, TELEGA_READINESS_ID,
    TELEGA_SETPOINT_ID,
};
use propid_drive_proto::settings::{FeedbackInterval, RunLimit, TorqueScale};
use propid_drive_proto::sim_drive::{sim_drive_registers, SimDrive, SimDriveConfig, SimDriveEvent};

use crate::bus::{Bus, BusArgs};
use crate::cmd::drive::NodeIdSetting;
use crate::cmd::sim::StandArgs;
use crate::settings::{
    checked, command_args, environment, fill, setting, ConfigErrors, Names, Problem,
};

setting! {
    /// The readiness subscription.
    ReadinessId: Option<SubjectId> =
        Names::register("readiness-id", TELEGA_READINESS_ID, "UAVCAN__SUB__READINESS__ID"),
        "Readiness subject (no readiness gating when unset)",
        crate::settings::subject_id;
    /// The setpoint subscription.
    SetpointId: Option<SubjectId> =
        Names::register("setpoint-id", TELEGA_SETPOINT_ID, "UAVCAN__SUB__SETPOINT_R_TORQ__ID"),
        "Ratiometric torque setpoint subject [default: 24]",
        crate::settings::subject_id;
    /// The feedback publication.
    FeedbackId: Option<SubjectId> =
        Names::register("feedback-id", TELEGA_FEEDBACK_ID, "UAVCAN__PUB__DYNAMICS__ID"),
        "Dynamics feedback subject [default: 110]",
        crate::settings::subject_id;
    /// The feedback interval.
    Interval: FeedbackInterval =
        Names::register("interval", PUB_INTERVAL_MIN, "MNS__PUB_INTERVAL_MIN"),
        "Feedback interval [s], writable over the bus [default: 0.002]",
        within FeedbackInterval;
    /// Local timestamps.
    LocalTimestamp: bool =
        Names::register("local-timestamp", LOCAL_TIMESTAMP, "MNS__LOCAL_TIMESTAMP"),
        "Stamp the feedback with the drive's clock (false: the timestamp is 0, unknown) [default: true]",
        crate::settings::bit;
    /// How long to run.
    Duration: Option<RunLimit> = Names::flag("duration"),
        "Stop after this many seconds (0: run until interrupted) [default: 0]",
        |text: &str| match crate::settings::numbers::<1>(text)? {
            [0.0] => Ok(None),
            [x] => RunLimit::new(x).map(Some).map_err(Problem::Range),
        };
    /// The simulated motor's torque per commanded torque.
    TorqueScaleSetting: TorqueScale = Names::flag("torque-scale"),
        "The torque the simulated motor makes per torque it is commanded and reports: -1 reverses its sign (a motor wired the other way), 0 makes none; for trying propid drive's limits [default: 1]",
        within TorqueScale;
}

command_args! {
    /// Arguments of `propid sim-drive`: Telega's registers, each also a flag and a variable.
    pub struct Args {
        settings {
            node_id: NodeIdSetting as "ID",
            readiness_id: ReadinessId as "ID",
            setpoint_id: SetpointId as "ID",
            feedback_id: FeedbackId as "ID",
            interval: Interval as "S",
            local_timestamp: LocalTimestamp as "BOOL",
            duration: Duration as "S",
            torque_scale: TorqueScaleSetting as "K",
        }
        registers {}
        nested {
            bus: BusArgs,
        }
        /// The simulated stand.
        #[command(flatten)]
        pub stand: StandArgs,
    }
}

/// `propid sim-drive`'s settings, checked.
pub struct Settings {
    /// The bus.
    pub bus: Bus,
    /// The simulated drive.
    pub sim: SimDriveConfig,
    /// Local timestamps at start.
    pub local_timestamp: bool,
    /// The stand it simulates.
    pub stand: StandArgs,
    /// Its motor's torque per commanded torque.
    pub torque_scale: TorqueScale,
}

impl TryFrom<Args> for Settings {
    type Error = ConfigErrors;

    /// Checks every setting (flags and environment) and reports every error at once.
    fn try_from(mut args: Args) -> Result<Settings, ConfigErrors> {
        let mut errors = ConfigErrors::default();
        fill(&mut args, &environment(), None, &[], &mut errors);
        let Args {
            node_id,
            bus,
            readiness_id,
            setpoint_id,
            feedback_id,
            interval,
            local_timestamp,
            duration,
            torque_scale,
            stand,
        } = args;
        let e = &mut errors;
        let example = SimDriveConfig::example();
        let node_id = e.id_or(node_id, example.node_id);
        let bus = Bus::check(bus, e);
        let readiness_id = e.or(readiness_id, None);
        let setpoint_id = e.id_or(setpoint_id, example.setpoint_id);
        let feedback_id = e.id_or(feedback_id, example.feedback_id);
        let interval = e.or(interval, example.interval);
        let local_timestamp = e.or(local_timestamp, true);
        let duration = e.or(duration, None);
        let torque_scale = e.or(torque_scale, TorqueScale::from_const(1.0));
        checked!(
            errors;
            node_id, bus, readiness_id, setpoint_id, feedback_id, interval, local_timestamp,
            duration, torque_scale,
        );
        let sim = SimDriveConfig {
            node_id,
            mtu: bus.mtu,
            readiness_id,
            setpoint_id,
            feedback_id,
            interval,
            duration,
        };
        Ok(Settings {
            bus,
            sim,
            local_timestamp,
            stand,
            torque_scale,
        })
    }
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
    let Settings {
        bus,
        sim: cfg,
        local_timestamp,
        stand,
        torque_scale,
    } = Settings::try_from(args)?;
    let mut plant = StandPlant::boxed(stand.config()?, stand.seed)?;
    if torque_scale.get() != 1.0 {
        plant = Box::new(TorqueScaled::new(plant, torque_scale.get()));
        eprintln!(
            "sim-drive: the motor makes {} times the torque it is commanded and reports",
            torque_scale
        );
    }
    let mut transport = bus.open()?;
    let stop = Arc::new(AtomicBool::new(false));
    let _handlers = crate::signals::install(&stop)?;
    eprintln!(
        "sim-drive: node {} on {} publishing feedback on subject {}",
        cfg.node_id,
        transport.name(),
        cfg.feedback_id
    );
    let regs = sim_drive_registers(&cfg, local_timestamp);
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
