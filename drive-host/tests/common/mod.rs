//! What the drive-host tests in virtual time share: the drive against the simulated Telega on a
//! `VirtualLink`, every readiness and setpoint the simulated drive received decoded on the side,
//! and the frames the drive sent once stopping (STANDBY must be first).
#![allow(dead_code)] // each test binary uses a part

use std::time::Duration;

use propid_core::can::Frame;
use propid_core::dsdl::{DataType, DoF3rdTs, Readiness, Vector31};
use propid_core::sample::Sample;
use propid_core::time::Instant;
use propid_drive_host::stand::StandPlant;
use propid_drive_proto::drive::{Drive, DriveConfig, DriveEvent, FeedbackRow, Phase, StopReport};
use propid_drive_proto::plant::Plant;
use propid_drive_proto::sim_drive::{SimDrive, SimDriveConfig, SimDriveEvent};
use propid_drive_proto::virtual_link::{LinkModel, VirtualLink};
use propid_drive_proto::{Machine, StopReason};
use propid_science::excitation::{Excitation, Pattern};
use propid_science::stand::StandConfig;

pub const T0: Instant = Instant::ZERO;

/// The default soft start's length [s]: every run below that does not turn the limits off
/// begins with it, before the init phase.
pub const SOFT: f64 = 1.0;

pub fn seed_excitation(init: f64, duration: f64) -> Excitation {
    Excitation {
        lo: 0.1,
        hi: 0.9,
        period: 2.0,
        duration,
        init_duration: init,
        pattern: Pattern::Sine,
    }
}

pub fn sim_cfg() -> SimDriveConfig {
    SimDriveConfig::example()
}

pub fn stand() -> Box<dyn Plant> {
    StandPlant::boxed(StandConfig::default(), 5).unwrap()
}

/// Everything a run produced.
#[derive(Default)]
pub struct Run {
    pub rows: Vec<FeedbackRow>,
    /// (time [µs], event) of phase events.
    pub phases: Vec<(u64, &'static str)>,
    pub report: Option<StopReport>,
    pub published: Vec<DoF3rdTs>,
    /// What the sim drive received, in order: (readiness or setpoint).
    pub sim_inputs: Vec<(f64, SimInput)>,
    pub progress: u64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SimInput {
    Readiness(u8),
    Setpoint(f32),
}

/// A simulated drive that also logs every readiness/setpoint it receives (decoded by a second
/// node-less path: the frames themselves, reassembled by a separate core reassembler).
pub struct Observed {
    pub sim: SimDrive,
    pub rx: propid_core::can::Reassembler<4, 8, 128>,
    pub log: Vec<(f64, SimInput)>,
}

impl Observed {
    pub fn new(sim: SimDrive) -> Self {
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

pub fn drain(link: &VirtualLink, drive: &mut Tap, sim: &mut Observed, run: &mut Run) {
    let t = link.now().as_micros();
    let drive = &mut drive.drive;
    while let Some(e) = drive.poll_event() {
        match e {
            DriveEvent::SoftStartPassed(_) => run.phases.push((t, "soft start passed")),
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

/// Runs the drive against the simulated drive of the default stand until the drive stops, then
/// 50 ms more so the last frames arrive; `fault` may act on the machines at each step (returning
/// true once it acted).
pub fn run_pair(
    cfg: DriveConfig,
    model: LinkModel,
    fault: &mut dyn FnMut(&mut VirtualLink, &mut Drive, &mut Observed) -> bool,
) -> (Run, Observed, VirtualLink) {
    run_pair_with(stand(), cfg, model, fault)
}

/// [`run_pair`] with the simulated drive running `plant`; the first frames the drive sent once
/// stopping must be STANDBY, then a zero setpoint.
pub fn run_pair_with(
    plant: Box<dyn Plant>,
    cfg: DriveConfig,
    model: LinkModel,
    fault: &mut dyn FnMut(&mut VirtualLink, &mut Drive, &mut Observed) -> bool,
) -> (Run, Observed, VirtualLink) {
    run_against(SimDrive::new(sim_cfg(), plant, T0), cfg, model, fault)
}

/// [`run_pair`] against `sim`, a simulated drive booted at [`T0`].
pub fn run_against(
    sim: SimDrive,
    cfg: DriveConfig,
    model: LinkModel,
    fault: &mut dyn FnMut(&mut VirtualLink, &mut Drive, &mut Observed) -> bool,
) -> (Run, Observed, VirtualLink) {
    let mut drive = Tap {
        drive: Drive::new(cfg, T0),
        first_stop_frames: Vec::new(),
        last_recorded: false,
    };
    let mut sim = Observed::new(sim);
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
pub fn assert_rows_are_published(run: &Run) {
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
pub fn assert_standby_first(run: &Run, stop_at: f64) {
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

pub fn stopping_at(run: &Run) -> f64 {
    run.phases
        .iter()
        .find(|(_, p)| *p == "stopping")
        .expect("stopping")
        .0 as f64
        * 1e-6
}

/// The drive, and the first frames it emitted once stopping.
pub struct Tap {
    pub drive: Drive,
    pub first_stop_frames: Vec<Frame>,
    pub last_recorded: bool,
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
pub fn assert_first_frames_are_stop_commands(frames: &[Frame]) {
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

pub fn at(t: f64) -> impl FnMut(&mut VirtualLink) -> bool {
    move |link: &mut VirtualLink| link.now().as_secs_f64() >= t
}
