//! The drive against the simulated Telega in virtual time: the seed's whole sequence (5 s init
//! at hi with feedback ignored, the 200 s sine at a 5 ms setpoint period, STANDBY + zero), with
//! exact phases and row counts; congestion; and the faults of the live path.

use std::time::Duration;

use propid_core::can::Frame;
use propid_core::dsdl::{DataType, DoF3rdTs, Readiness, Vector31};
use propid_core::sample::Sample;
use propid_core::time::Instant;
use propid_drive_host::stand::{Played, StandPlant};
use propid_drive_proto::drive::{
    Drive, DriveConfig, DriveEvent, FeedbackRow, Phase, StopReport, SNAPSHOT_SAMPLES, STOP_WINDOW,
};
use propid_drive_proto::plant::Plant;
use propid_drive_proto::settings::{Deadman, RelativeError};
use propid_drive_proto::sim_drive::{SimDrive, SimDriveConfig, SimDriveEvent};
use propid_drive_proto::virtual_link::{LinkModel, VirtualLink};
use propid_drive_proto::{Machine, StopReason};
use propid_science::excitation::{Excitation, Pattern};
use propid_science::stand::StandConfig;

const T0: Instant = Instant::ZERO;

fn seed_excitation(init: f64, duration: f64) -> Excitation {
    Excitation {
        lo: 0.1,
        hi: 0.9,
        period: 2.0,
        duration,
        init_duration: init,
        pattern: Pattern::Sine,
    }
}

fn sim_cfg() -> SimDriveConfig {
    SimDriveConfig::example()
}

fn stand() -> Box<dyn Plant> {
    StandPlant::boxed(StandConfig::default(), 5).unwrap()
}

/// Everything a run produced.
#[derive(Default)]
struct Run {
    rows: Vec<FeedbackRow>,
    /// (time [µs], event) of phase events.
    phases: Vec<(u64, &'static str)>,
    report: Option<StopReport>,
    published: Vec<DoF3rdTs>,
    /// What the sim drive received, in order: (readiness or setpoint).
    sim_inputs: Vec<(f64, SimInput)>,
    progress: u64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum SimInput {
    Readiness(u8),
    Setpoint(f32),
}

/// A simulated drive that also logs every readiness/setpoint it receives (decoded by a second
/// node-less path: the frames themselves, reassembled by a separate core reassembler).
struct Observed {
    sim: SimDrive,
    rx: propid_core::can::Reassembler<4, 8, 128>,
    log: Vec<(f64, SimInput)>,
}

impl Observed {
    fn new(sim: SimDrive) -> Self {
        let mut rx = propid_core::can::Reassembler::new(None);
        for (subject, extent) in [
            (10u16, Readiness::EXTENT_BYTES),
            (24, Vector31::EXTENT_BYTES),
        ] {
            rx.subscribe(propid_core::can::Subscription {
                port: propid_core::can::Port::Subject(propid_core::can::SubjectId::from_const(
                    subject,
                )),
                extent,
                transfer_id_timeout: propid_core::can::DEFAULT_TRANSFER_ID_TIMEOUT,
            })
            .unwrap();
        }
        Observed {
            sim,
            rx,
            log: Vec::new(),
        }
    }
}

impl Machine for Observed {
    type Event = SimDriveEvent;
    fn handle_frame(&mut self, now: Instant, frame: &Frame) {
        if let Ok(Some(t)) = self.rx.accept(frame) {
            if let propid_core::can::TransferKind::Message { subject_id } = t.header.kind {
                let input = if subject_id.get() == 10 {
                    SimInput::Readiness(Readiness::deserialize(t.payload).unwrap().value)
                } else {
                    SimInput::Setpoint(Vector31::deserialize(t.payload).unwrap().value[0])
                };
                self.log.push((now.as_secs_f64(), input));
            }
        }
        self.sim.handle_frame(now, frame)
    }
    fn poll_transmit(&mut self, now: Instant) -> Option<Frame> {
        self.sim.poll_transmit(now)
    }
    fn handle_blocked(&mut self, now: Instant, frame: Frame) {
        self.sim.handle_blocked(now, frame)
    }
    fn poll_timeout(&self) -> Option<Instant> {
        self.sim.poll_timeout()
    }
    fn poll_event(&mut self) -> Option<SimDriveEvent> {
        self.sim.poll_event()
    }
    fn handle_fault(&mut self, now: Instant, reason: StopReason) {
        self.sim.handle_fault(now, reason)
    }
    fn is_stopped(&self) -> bool {
        self.sim.is_stopped()
    }
}

fn drain(link: &VirtualLink, drive: &mut Tap, sim: &mut Observed, run: &mut Run) {
    let t = link.now().as_micros();
    let drive = &mut drive.drive;
    while let Some(e) = drive.poll_event() {
        match e {
            DriveEvent::PatternStarted => run.phases.push((t, "pattern")),
            DriveEvent::Row(r) => run.rows.push(r),
            DriveEvent::Progress(_) => run.progress += 1,
            DriveEvent::Stopping(_) => run.phases.push((t, "stopping")),
            DriveEvent::Stopped(r) => {
                run.phases.push((t, "stopped"));
                run.report = Some(r);
            }
            DriveEvent::RegisterWritten { .. } => {}
        }
    }
    while let Some(e) = sim.poll_event() {
        if let SimDriveEvent::Feedback(fb) = e {
            run.published.push(fb);
        }
    }
}

/// Runs until the drive stops, then 50 ms more so the last frames arrive; `fault` may act on
/// the machines at each step (returning true once it acted).
fn run_pair(
    cfg: DriveConfig,
    model: LinkModel,
    fault: &mut dyn FnMut(&mut VirtualLink, &mut Drive, &mut Observed) -> bool,
) -> (Run, Observed, VirtualLink) {
    let mut drive = Tap {
        drive: Drive::new(cfg, T0),
        first_stop_frames: Vec::new(),
        last_recorded: false,
    };
    let mut sim = Observed::new(SimDrive::new(sim_cfg(), stand(), T0));
    let mut link = VirtualLink::new(model, T0);
    let mut run = Run::default();
    let mut acted = false;
    while !drive.is_stopped() {
        assert!(link.step(&mut drive, &mut sim), "the drive planned nothing");
        drain(&link, &mut drive, &mut sim, &mut run);
        if !acted {
            acted = fault(&mut link, &mut drive.drive, &mut sim);
            drain(&link, &mut drive, &mut sim, &mut run);
        }
    }
    let end = link.now() + Duration::from_millis(50);
    while link.now() < end && link.step(&mut drive, &mut sim) {
        drain(&link, &mut drive, &mut sim, &mut run);
    }
    run.sim_inputs = sim.log.clone();
    assert_first_frames_are_stop_commands(&drive.first_stop_frames);
    (run, sim, link)
}

/// The rows are exactly a contiguous run of what the simulated stand published.
fn assert_rows_are_published(run: &Run) {
    let first = run.rows.first().expect("rows").sample;
    let k = run
        .published
        .iter()
        .position(|fb| Sample::from(fb).t == first.t)
        .expect("the first row was published");
    for (i, row) in run.rows.iter().enumerate() {
        let fb = &run.published[k + i];
        // Through the wire: what DoF3rdTs carries (float16 fields are rounded by it).
        let mut buf = [0u8; DoF3rdTs::MAX_SIZE_BYTES];
        fb.serialize(&mut buf);
        let wire = Sample::from(&DoF3rdTs::deserialize(&buf).unwrap());
        assert_eq!(row.sample, wire, "row {i}");
    }
}

/// After the stop began, once frames already on the wire have arrived, the simulated drive
/// receives STANDBY, then a zero setpoint, and nothing but STANDBY / zero after.
fn assert_standby_first(run: &Run, stop_at: f64) {
    let after: Vec<SimInput> = run
        .sim_inputs
        .iter()
        .filter(|(t, _)| *t > stop_at)
        .map(|(_, i)| *i)
        .skip_while(|i| *i != SimInput::Readiness(Readiness::STANDBY))
        .collect();
    assert!(after.len() >= 2, "stop commands arrived: {after:?}");
    assert_eq!(
        after[0],
        SimInput::Readiness(Readiness::STANDBY),
        "{after:?}"
    );
    assert_eq!(after[1], SimInput::Setpoint(0.0), "{after:?}");
    assert!(
        after.iter().all(|i| matches!(
            i,
            SimInput::Readiness(Readiness::STANDBY) | SimInput::Setpoint(0.0)
        )),
        "{after:?}"
    );
}

fn stopping_at(run: &Run) -> f64 {
    run.phases
        .iter()
        .find(|(_, p)| *p == "stopping")
        .expect("stopping")
        .0 as f64
        * 1e-6
}

/// The drive, and the first frames it emitted once stopping.
struct Tap {
    drive: Drive,
    first_stop_frames: Vec<Frame>,
    last_recorded: bool,
}

impl Machine for Tap {
    type Event = DriveEvent;
    fn handle_frame(&mut self, now: Instant, frame: &Frame) {
        self.drive.handle_frame(now, frame)
    }
    fn poll_transmit(&mut self, now: Instant) -> Option<Frame> {
        let f = self.drive.poll_transmit(now)?;
        self.last_recorded =
            self.drive.phase() == Phase::Stopping && self.first_stop_frames.len() < 11;
        if self.last_recorded {
            self.first_stop_frames.push(f.clone());
        }
        Some(f)
    }
    fn handle_blocked(&mut self, now: Instant, frame: Frame) {
        // Refused: it will be offered again, and recorded then.
        if std::mem::take(&mut self.last_recorded) {
            self.first_stop_frames.pop();
        }
        self.drive.handle_blocked(now, frame)
    }
    fn poll_timeout(&self) -> Option<Instant> {
        self.drive.poll_timeout()
    }
    fn poll_event(&mut self) -> Option<DriveEvent> {
        self.drive.poll_event()
    }
    fn handle_fault(&mut self, now: Instant, reason: StopReason) {
        self.drive.handle_fault(now, reason)
    }
    fn is_stopped(&self) -> bool {
        self.drive.is_stopped()
    }
}

/// The first frame the drive emitted once stopping is STANDBY, then comes the zero setpoint.
fn assert_first_frames_are_stop_commands(frames: &[Frame]) {
    let ids: Vec<u32> = frames.iter().map(|f| f.id() >> 8 & 0x1FFF).collect();
    assert_eq!(frames.len(), 11, "{ids:?}");
    assert_eq!(frames[0].id() >> 8 & 0x1FFF, 10, "readiness first");
    assert_eq!(frames[0].data()[0], Readiness::STANDBY);
    let mut payload = Vec::new();
    for f in &frames[1..] {
        assert_eq!(f.id() >> 8 & 0x1FFF, 24, "then the setpoint {ids:?}");
        payload.extend_from_slice(&f.data()[..f.data().len() - 1]);
    }
    assert_eq!(
        Vector31::deserialize(&payload[..62]).unwrap(),
        Vector31::splat(0.0)
    );
}

#[test]
fn the_seed_sequence_in_virtual_time() {
    let t = std::time::Instant::now();
    let cfg = DriveConfig::example(Played::try_from(seed_excitation(5.0, 200.0)).unwrap());
    let (run, sim, link) = run_pair(cfg, LinkModel::ideal(), &mut |_, _, _| true);
    let wall = t.elapsed();
    let report = run.report.clone().unwrap();
    assert_eq!(report.reason, StopReason::Completed);
    // Phases exactly on time.
    assert_eq!(
        run.phases,
        vec![
            (5_000_000, "pattern"),
            (205_000_000, "stopping"),
            (205_020_000, "stopped")
        ],
        "wall time {wall:?}"
    );
    // One row per feedback published in [5 s, 205 s): every 2 ms, arriving 100 µs later.
    assert_eq!(run.rows.len(), 100_000);
    assert_eq!(report.rows, 100_000);
    assert_eq!(run.rows[0].sample.t, 5.0);
    assert_rows_are_published(&run);
    // Init at hi (float16 of 0.9), then the sine, then STANDBY + zero first and last.
    let sp: Vec<f32> = run
        .sim_inputs
        .iter()
        .filter_map(|(_, i)| match i {
            SimInput::Setpoint(v) => Some(*v),
            _ => None,
        })
        .collect();
    assert_eq!(
        sp.len(),
        41_000 + 5,
        "one setpoint per 5 ms, 5 stop repeats"
    );
    assert!((sp[0] - 0.9).abs() < 1e-3);
    assert_standby_first(&run, 205.0);
    assert_eq!(sim.sim.summary().last_readiness, Some(Readiness::STANDBY));
    assert_eq!(sim.sim.summary().last_setpoint, Some(0.0));
    assert_eq!(
        sim.sim.summary().readiness_changes,
        vec![Readiness::ENGAGED, Readiness::STANDBY]
    );
    assert_eq!(report.standby_sent, 5);
    assert_eq!(report.zero_setpoints_sent, 5);
    assert_eq!(report.tx.dropped, 0);
    assert_eq!(run.progress, 199);
    assert_eq!(link.refused(), (0, 0));
    // The fit on the rows recovers the simulated load.
    let truth = StandConfig::default();
    let est = report.estimate.unwrap();
    assert!((est.j / truth.inertia - 1.0).abs() < 0.02, "J {}", est.j);
    eprintln!("the seed sequence took {wall:?} of wall time");
}

#[test]
fn the_same_run_twice_is_the_same() {
    let cfg = DriveConfig::example(Played::try_from(seed_excitation(1.0, 5.0)).unwrap());
    let (a, _, _) = run_pair(cfg.clone(), LinkModel::ideal(), &mut |_, _, _| true);
    let (b, _, _) = run_pair(cfg, LinkModel::ideal(), &mut |_, _, _| true);
    assert_eq!(a.rows, b.rows);
    assert_eq!(a.sim_inputs, b.sim_inputs);
    assert_eq!(a.report, b.report);
}

#[test]
fn congestion_drops_frames_but_the_run_completes_and_standby_arrives() {
    // 1 frame per ms and at most 4 frames in flight: the setpoints (11 frames per 5 ms) and the
    // feedback (4 frames per 2 ms) cannot all pass.
    let model = LinkModel {
        frame_time: Duration::from_millis(1),
        latency: Duration::from_micros(100),
        capacity: 4,
    };
    let cfg = DriveConfig {
        deadman: Deadman::new(2.0).unwrap(),
        ..DriveConfig::example(Played::try_from(seed_excitation(1.0, 10.0)).unwrap())
    };
    let (run, sim, link) = run_pair(cfg, model, &mut |_, _, _| true);
    let report = run.report.clone().unwrap();
    assert_eq!(report.reason, StopReason::Completed);
    assert!(link.refused().0 > 0, "the link was congested");
    assert!(report.tx.would_block > 0, "{:?}", report.tx);
    assert!(
        report.tx.dropped + report.tx.superseded > 0,
        "{:?}",
        report.tx
    );
    assert!(run.rows.len() > 1000, "{}", run.rows.len());
    // Every row is something the stand published, in order; some feedback was lost.
    let mut published = run.published.iter().map(|fb| {
        let mut buf = [0u8; DoF3rdTs::MAX_SIZE_BYTES];
        fb.serialize(&mut buf);
        Sample::from(&DoF3rdTs::deserialize(&buf).unwrap())
    });
    for row in &run.rows {
        assert!(published.any(|p| p == row.sample), "{row:?} was published");
    }
    assert_standby_first(&run, stopping_at(&run));
    assert_eq!(sim.sim.summary().last_readiness, Some(Readiness::STANDBY));
    assert_eq!(sim.sim.summary().last_setpoint, Some(0.0));
    assert!(report.stop_commands_sent(true));
}

fn at(t: f64) -> impl FnMut(&mut VirtualLink) -> bool {
    move |link: &mut VirtualLink| link.now().as_secs_f64() >= t
}

#[test]
fn lost_feedback_stops_at_the_deadman() {
    let mut when = at(3.0);
    let (run, sim, _) = run_pair(
        DriveConfig::example(Played::try_from(seed_excitation(1.0, 10.0)).unwrap()),
        LinkModel::ideal(),
        &mut |link, _, _| {
            let go = when(link);
            link.mute_b |= go;
            go
        },
    );
    let report = run.report.clone().unwrap();
    assert_eq!(report.reason, StopReason::LostFeedback { deadman: 0.5 });
    let stop = stopping_at(&run);
    assert!((3.5..3.52).contains(&stop), "{stop}");
    assert_eq!(sim.sim.summary().last_readiness, Some(Readiness::STANDBY));
    assert_eq!(sim.sim.summary().last_setpoint, Some(0.0));
}

#[test]
fn a_drive_reboot_stops_the_run() {
    let mut when = at(3.5);
    let (run, _, _) = run_pair(
        DriveConfig::example(Played::try_from(seed_excitation(1.0, 10.0)).unwrap()),
        LinkModel::ideal(),
        &mut |link, _, sim| {
            let go = when(link);
            if go {
                // The drive comes back: a new node, uptime 0.
                *sim = Observed {
                    sim: SimDrive::new(sim_cfg(), stand(), link.now()),
                    rx: std::mem::replace(&mut sim.rx, propid_core::can::Reassembler::new(None)),
                    log: std::mem::take(&mut sim.log),
                };
            }
            go
        },
    );
    let report = run.report.clone().unwrap();
    assert_eq!(
        report.reason,
        StopReason::DriveRebooted {
            node_id: 42,
            before: 3,
            after: 0
        }
    );
    assert_standby_first(&run, stopping_at(&run));
    assert_eq!(report.rows as usize, run.rows.len());
}

#[test]
fn a_clock_jump_stops_the_run_with_standby_first() {
    for step in [-2.0f64, 5.0] {
        let cfg = DriveConfig::example(Played::try_from(seed_excitation(1.0, 10.0)).unwrap());
        let mut drive = Drive::new(cfg, T0);
        let mut sim = SimDrive::new(sim_cfg(), stand(), T0);
        let mut link = VirtualLink::new(LinkModel::ideal(), T0);
        while link.now() < Instant::from_micros(3_000_000) {
            link.step(&mut drive, &mut sim);
        }
        while drive.poll_event().is_some() {}
        // The live view's snapshot: the last samples, the estimate, the commands, the counters.
        let snap = drive.snapshot();
        assert_eq!(snap.phase, Phase::Pattern);
        assert_eq!(snap.readiness, Readiness::ENGAGED);
        assert_eq!(snap.recent.len(), SNAPSHOT_SAMPLES);
        assert_eq!(snap.rows, drive.rows());
        assert!(snap.rows >= SNAPSHOT_SAMPLES as u64, "{}", snap.rows);
        assert!((snap.recent.last().unwrap().t - 2.998).abs() < 1e-9);
        let est = snap
            .estimate
            .expect("two seconds of the sine identify the load");
        assert!(est.j_stderr > 0.0 && est.j_stderr < 0.1 * est.j, "{est:?}");
        assert_eq!(snap.tx.dropped, 0);
        let jumped = Instant::from_micros((3_000_000.0 + step * 1e6) as u64);
        let first = drive.poll_transmit(jumped).expect("a frame after the jump");
        assert_eq!(drive.phase(), Phase::Stopping);
        // STANDBY is the first frame after the fault.
        assert_eq!(first.id() >> 8 & 0x1FFF, 10);
        let mut buf = [0u8; 1];
        buf.copy_from_slice(&first.data()[..1]);
        assert_eq!(buf[0], Readiness::STANDBY);
        let events: Vec<DriveEvent> = std::iter::from_fn(|| drive.poll_event()).collect();
        match &events[0] {
            DriveEvent::Stopping(StopReason::ClockJump { step: s }) => {
                assert!((s - step).abs() < 0.01, "{s} vs {step}")
            }
            e => panic!("{e:?}"),
        }
        // The machine ends its stop sequence within its window, whatever the clock does.
        let mut now = jumped;
        loop {
            while drive.poll_transmit(now).is_some() {}
            match drive.poll_timeout() {
                Some(t) => now = t.max(now),
                None => break,
            }
        }
        assert!(drive.is_stopped());
        assert!(now.saturating_duration_since(jumped) <= STOP_WINDOW);
    }
}

#[test]
fn a_fault_from_the_loop_puts_standby_first_and_keeps_rows() {
    for reason in [
        StopReason::BusOff,
        StopReason::AdapterRefused("T1060180A8...".into()),
        StopReason::DeviceVanished("slcan:/dev/pts/9".into()),
        StopReason::Signal,
    ] {
        let mut when = at(2.5);
        let r = reason.clone();
        let (run, _, _) = run_pair(
            DriveConfig::example(Played::try_from(seed_excitation(1.0, 10.0)).unwrap()),
            LinkModel::ideal(),
            &mut |link, drive, _| {
                let go = when(link);
                if go {
                    drive.handle_fault(link.now(), r.clone());
                }
                go
            },
        );
        let report = run.report.clone().unwrap();
        assert_eq!(report.reason, reason);
        assert!(report.reason.is_fault());
        assert_eq!(report.rows as usize, run.rows.len());
        assert!(run.rows.len() > 700, "{}", run.rows.len());
        assert_standby_first(&run, stopping_at(&run));
    }
}

/// `--until-stderr`: the drive stops, with STANDBY first as always, once the running estimate is
/// as precise as asked — within 20 % of the time `propid plan` predicts for that precision.
#[test]
fn until_stderr_stops_when_precise_near_the_planned_time() {
    use propid_science::plan::{design, Constraints, Prior};
    let stand = StandConfig::default();
    let target = 1.5e-4;
    let plan = design(
        &Prior::new(stand.inertia, stand.c2, stand.max_torque),
        &Constraints {
            lo: 0.1,
            hi: 0.9,
            max_speed: None,
            max_duration: 200.0,
        },
        Some(target),
    )
    .unwrap();
    let predicted = plan.predicted.seconds;
    let cfg = DriveConfig {
        until_rel_stderr: Some(RelativeError::new(target).unwrap()),
        ..DriveConfig::example(
            Played::try_from(Excitation {
                duration: 200.0,
                init_duration: 1.0,
                ..plan.excitation
            })
            .unwrap(),
        )
    };
    let (run, _, _) = run_pair(cfg, LinkModel::ideal(), &mut |_, _, _| true);
    let report = run.report.clone().unwrap();
    let StopReason::Precise {
        elapsed,
        rel_j,
        rel_c2,
    } = report.reason
    else {
        panic!("{:?}", report.reason)
    };
    assert!(rel_j <= target && rel_c2 <= target);
    assert!(
        (elapsed / predicted - 1.0).abs() <= 0.2,
        "stopped after {elapsed:.1} s, predicted {predicted:.1} s"
    );
    assert_standby_first(&run, stopping_at(&run) - 1e-3);
}
