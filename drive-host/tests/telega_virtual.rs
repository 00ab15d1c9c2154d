//! propid's telega client configures the simulated Telega over a modelled CAN link in virtual
//! time, and the drive then runs on the port-IDs it read: discover, check, configure (the
//! feedback rate follows the written interval), drive, STANDBY. Port-ID writes take effect at
//! the drive's RESTART, as the specification has it.

use std::time::Duration;

use propid_core::can::{Mtu, NodeId, SubjectId};
use propid_core::dsdl::{ExecuteCommandRequest, ExecuteCommandResponse, Readiness, Value};
use propid_core::time::Instant;
use propid_drive_host::register_file::parse_text;
use propid_drive_host::stand::{Played, StandPlant};
use propid_drive_proto::drive::{Drive, DriveConfig, DriveEvent};
use propid_drive_proto::registers::{
    self, check_prerequisites, LOCAL_TIMESTAMP, PUB_INTERVAL_MIN, TELEGA_FEEDBACK_ID,
    TELEGA_SETPOINT_ID,
};
use propid_drive_proto::settings::FeedbackInterval;
use propid_drive_proto::sim_drive::{sim_drive_registers, SimDrive, SimDriveConfig, SimDriveEvent};
use propid_drive_proto::telega::{Client, ClientEvent, Op, CHECKED_REGISTERS};
use propid_drive_proto::virtual_link::{LinkModel, VirtualLink};
use propid_science::excitation::{Excitation, Pattern};
use propid_science::stand::StandConfig;

const T0: Instant = Instant::ZERO;
const DRIVE: NodeId = NodeId::from_const(42);

/// The simulated Telega as found on a fresh bench: feedback at 20 Hz, no local timestamps.
fn misconfigured() -> SimDrive {
    let mut cfg = SimDriveConfig::example();
    cfg.interval = FeedbackInterval::new(0.05).unwrap();
    let regs = sim_drive_registers(&cfg, false);
    let plant = StandPlant::boxed(StandConfig::default(), 3).unwrap();
    SimDrive::with_registers(cfg, plant, &regs, T0)
}

/// Runs the client's ops to their end; its events, and the feedback messages the simulated
/// drive published meanwhile with their (virtual) times and timestamps.
struct Bench {
    link: VirtualLink,
    client: Client,
    sim: SimDrive,
    /// (time [s], drive timestamp [µs]) of each feedback message.
    feedback: Vec<(f64, u64)>,
}

impl Bench {
    fn new(sim: SimDrive) -> Bench {
        Bench {
            link: VirtualLink::new(LinkModel::ideal(), T0),
            client: Client::new(NodeId::from_const(126), Mtu::Classic, T0),
            sim,
            feedback: Vec::new(),
        }
    }

    fn run(&mut self, ops: Vec<Op>) -> Vec<ClientEvent> {
        for op in ops {
            self.client.push(op);
        }
        let mut events = Vec::new();
        let until = self.link.now() + Duration::from_secs(600);
        while !self.client.is_idle() && self.link.now() < until {
            assert!(self.link.step(&mut self.client, &mut self.sim));
            while let Some(e) = self.client.poll_event() {
                events.push(e);
            }
            let t = self.link.now().as_secs_f64();
            while let Some(e) = self.sim.poll_event() {
                if let SimDriveEvent::Feedback(fb) = e {
                    self.feedback.push((t, fb.timestamp.microsecond));
                }
            }
        }
        assert!(self.client.is_idle(), "the client did not finish");
        events
    }

    fn read(&mut self, names: &[&str]) -> Vec<(String, Value)> {
        let ops = names
            .iter()
            .map(|n| Op::Access(DRIVE, n.to_string(), Value::Empty))
            .collect();
        self.run(ops)
            .into_iter()
            .filter_map(|e| match e {
                ClientEvent::Register(_, Some(r)) if !r.value.is_empty() => Some((r.name, r.value)),
                _ => None,
            })
            .collect()
    }

    fn write(&mut self, name: &str, text: &str) -> Value {
        let current = self.read(&[name]).remove(0).1;
        let value = parse_text(&current, text).unwrap();
        match self
            .run(vec![Op::Access(DRIVE, name.into(), value)])
            .remove(0)
        {
            ClientEvent::Register(_, Some(r)) => r.value,
            e => panic!("no answer to the write of {name}: {e:?}"),
        }
    }

    /// Feedback messages per second over the next `secs` seconds (the client listening).
    fn rate(&mut self, secs: u64) -> f64 {
        let from = self.link.now().as_secs_f64();
        let before = self.feedback.len();
        self.run(vec![Op::Listen(Duration::from_secs(secs))]);
        let n = self.feedback[before..]
            .iter()
            .filter(|(t, _)| *t > from)
            .count();
        n as f64 / secs as f64
    }
}

#[test]
fn telega_client_configures_the_simulated_drive_and_the_feedback_rate_follows() {
    let mut b = Bench::new(misconfigured());
    // Discover: heartbeats, then GetInfo.
    let events = b.run(vec![
        Op::Listen(Duration::from_millis(1500)),
        Op::GetInfo(DRIVE),
    ]);
    assert_eq!(events[0], ClientEvent::Heard(vec![DRIVE]));
    match &events[1] {
        ClientEvent::Info(_, Some(info)) => assert_eq!(&info.name[..], b"org.propid.sim_drive"),
        e => panic!("no GetInfo answer: {e:?}"),
    }
    // List: every Telega register is there.
    let names = match b.run(vec![Op::List(DRIVE)]).remove(0) {
        ClientEvent::Names(_, Some(n)) => n,
        e => panic!("no List answer: {e:?}"),
    };
    for want in CHECKED_REGISTERS
        .iter()
        .chain(&[TELEGA_SETPOINT_ID, "mns.deadman_timeout"])
    {
        assert!(names.iter().any(|n| n == want), "{want} not in {names:?}");
    }
    // Check: both prerequisites fail.
    let found = b.read(&CHECKED_REGISTERS);
    let problems = check_prerequisites(&found, Some(SubjectId::from_const(110)));
    let bad: Vec<&str> = problems.iter().map(|p| p.register.as_str()).collect();
    assert_eq!(bad, [PUB_INTERVAL_MIN, LOCAL_TIMESTAMP]);
    let slow = b.rate(2);
    assert!((19.0..=21.0).contains(&slow), "{slow} Hz at 0.05 s");
    assert!(
        b.feedback.iter().all(|(_, ts)| *ts == 0),
        "no local timestamps yet"
    );

    // Configure: the seed's values, then store.
    assert_eq!(
        b.write(PUB_INTERVAL_MIN, "0.005"),
        Value::real32(&[0.005]).unwrap()
    );
    assert_eq!(
        b.write(LOCAL_TIMESTAMP, "true"),
        Value::bit(&[true]).unwrap()
    );
    let stored = b.run(vec![Op::Execute(
        DRIVE,
        ExecuteCommandRequest::COMMAND_STORE_PERSISTENT_STATES,
    )]);
    assert_eq!(
        stored,
        [ClientEvent::Executed(
            DRIVE,
            ExecuteCommandRequest::COMMAND_STORE_PERSISTENT_STATES,
            Some(ExecuteCommandResponse::STATUS_SUCCESS)
        )]
    );
    assert!(check_prerequisites(
        &b.read(&CHECKED_REGISTERS),
        Some(SubjectId::from_const(110))
    )
    .is_empty());
    let fast = b.rate(2);
    assert!((199.0..=201.0).contains(&fast), "{fast} Hz at 0.005 s");
    let last = b.feedback.last().unwrap();
    assert!(last.1 > 0, "timestamps on");
    // A value the drive cannot use is refused: the answer carries the interval in use.
    assert_eq!(
        b.write(PUB_INTERVAL_MIN, "0"),
        Value::real32(&[0.005]).unwrap()
    );
    assert!(
        (b.sim.interval() - 0.005).abs() < 1e-9,
        "{}",
        b.sim.interval()
    );
}

#[test]
fn port_ids_take_effect_at_restart_and_the_drive_runs_on_them() {
    let mut b = Bench::new(misconfigured());
    b.write(PUB_INTERVAL_MIN, "0.005");
    b.write(LOCAL_TIMESTAMP, "1");
    assert_eq!(
        b.write(TELEGA_FEEDBACK_ID, "111"),
        Value::natural16(&[111]).unwrap()
    );
    // Written, not yet in effect: the spec reads port-IDs at start-up.
    assert_eq!(b.sim.config().feedback_id.get(), 110);
    let restarted = b.run(vec![
        Op::Execute(DRIVE, ExecuteCommandRequest::COMMAND_RESTART),
        Op::Listen(Duration::from_millis(500)),
    ]);
    assert_eq!(
        restarted[0],
        ClientEvent::Executed(
            DRIVE,
            ExecuteCommandRequest::COMMAND_RESTART,
            Some(ExecuteCommandResponse::STATUS_SUCCESS)
        )
    );
    assert_eq!(b.sim.config().feedback_id.get(), 111);
    assert_eq!(b.sim.summary().restarts, 1);
    // The values survive the restart.
    let found = b.read(&CHECKED_REGISTERS);
    assert!(check_prerequisites(&found, Some(SubjectId::from_const(111))).is_empty());

    // Drive on the IDs the drive's registers hold: 3 s of pattern, then STANDBY.
    let ids = b.read(&[TELEGA_FEEDBACK_ID, TELEGA_SETPOINT_ID]);
    let id = |i: usize| SubjectId::try_from(ids[i].1.float_at(0).unwrap() as u16).unwrap();
    let mut cfg = DriveConfig::example(
        Played::try_from(Excitation {
            lo: 0.1,
            hi: 0.9,
            period: 2.0,
            duration: 3.0,
            init_duration: 0.5,
            pattern: Pattern::Sine,
        })
        .unwrap(),
    );
    cfg.feedback_id = id(0);
    cfg.setpoint_id = id(1);
    cfg.drive_node_id = Some(DRIVE);
    let mut drive = Drive::new(cfg, b.link.now());
    let mut sim = b.sim;
    let mut link = b.link;
    let mut rows = 0;
    let mut report = None;
    while report.is_none() {
        assert!(link.step(&mut drive, &mut sim));
        while let Some(e) = drive.poll_event() {
            match e {
                DriveEvent::Row(_) => rows += 1,
                DriveEvent::Stopped(r) => report = Some(r),
                _ => {}
            }
        }
        while sim.poll_event().is_some() {}
    }
    let report = report.unwrap();
    assert!(!report.reason.is_fault(), "{}", report.reason);
    // 3 s of feedback at 200 Hz.
    assert!((595..=601).contains(&rows), "{rows} rows");
    for _ in 0..100 {
        link.step(&mut drive, &mut sim);
    }
    assert_eq!(sim.summary().last_readiness, Some(Readiness::STANDBY));
    assert_eq!(sim.summary().last_setpoint, Some(0.0));
}

#[test]
fn the_drive_serves_the_seeds_registers_and_reports_writes() {
    let mut cfg = DriveConfig::example(
        Played::try_from(Excitation {
            lo: 0.2,
            hi: 0.8,
            period: 2.0,
            duration: 30.0,
            init_duration: 20.0,
            pattern: Pattern::Sine,
        })
        .unwrap(),
    );
    cfg.node_id = NodeId::from_const(10);
    let mut drive = Drive::new(cfg, T0);
    let mut link = VirtualLink::new(LinkModel::ideal(), T0);
    let mut client = Client::new(NodeId::from_const(126), Mtu::Classic, T0);
    let seed_names = [
        "uavcan.node.id",
        "uavcan.node.description",
        "setpoint_rat_lo_hi",
        "period",
        "pattern_duration",
        "init_duration",
        "setpoint_period",
        "max_speed",
        "soft_start_setpoint",
        "soft_start_duration",
        "ramp_duration",
        "speed_watchdog",
        "uavcan.pub.readiness.id",
        "uavcan.pub.readiness.type",
        "uavcan.pub.sp_rat.id",
        "uavcan.pub.sp_rat.type",
        "uavcan.sub.fb_dyn.id",
        "uavcan.sub.fb_dyn.type",
    ];
    let node = NodeId::from_const(10);
    client.push(Op::List(node));
    client.push(Op::Access(node, "setpoint_rat_lo_hi".into(), Value::Empty));
    client.push(Op::Access(
        node,
        "period".into(),
        Value::real64(&[3.0]).unwrap(),
    ));
    client.push(Op::Access(
        node,
        "uavcan.sub.fb_dyn.type".into(),
        Value::string("x").unwrap(),
    ));
    let mut events = Vec::new();
    let mut written = Vec::new();
    while !client.is_idle() {
        // The drive sends setpoints meanwhile: nothing listens, and that is fine.
        assert!(link.step(&mut client, &mut drive));
        while let Some(e) = client.poll_event() {
            events.push(e);
        }
        while let Some(e) = drive.poll_event() {
            if let DriveEvent::RegisterWritten { name, value } = e {
                written.push((name, value));
            }
        }
    }
    match &events[0] {
        ClientEvent::Names(_, Some(n)) => assert_eq!(n, &seed_names),
        e => panic!("{e:?}"),
    }
    let reg = |i: usize| match &events[i] {
        ClientEvent::Register(_, Some(r)) => r.clone(),
        e => panic!("{e:?}"),
    };
    assert_eq!(reg(1).value, Value::real64(&[0.2, 0.8]).unwrap());
    assert!(reg(1).mutable);
    assert_eq!(reg(2).value, Value::real64(&[3.0]).unwrap());
    // The .type registers are read-only.
    assert_eq!(
        reg(3).value,
        Value::string(registers::FEEDBACK_TYPE).unwrap()
    );
    assert!(!reg(3).mutable);
    assert_eq!(
        written,
        [("period".to_string(), Value::real64(&[3.0]).unwrap())]
    );
    // The run keeps the value it started with (the seed reads its registers at start-up).
    assert_eq!(drive.config().excitation.schedule().period.get(), 2.0);
    assert!(drive.registers().get(TELEGA_FEEDBACK_ID).is_none());
}
