//! Faults the real-time loop sees on the transport, with the simulated drive on a thread at the
//! other end of an in-memory bus: the adapter refuses a line (BELL), the controller goes bus-off,
//! the device vanishes. In each: a clear stop reason, every row kept, and (where the link still
//! works) STANDBY is the first frame after the fault.
//!
//! The tests wait for events, not for the clock: the fault comes once the drive has recorded 500
//! rows, and the simulated drive is stopped once it has received the stop commands the drive
//! says it sent. They take turns (each is a real-time pair of loops).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use propid_drive_host::sim_drive::SimDriveThread;
use propid_drive_proto::drive::DriveEvent;
use propid_drive_proto::sim_drive::SimDrive;

use propid_core::dsdl::Readiness;
use propid_drive_host::drive::run_drive;
use propid_drive_host::realtime::{Clock, SystemClock};
use propid_drive_host::stand::{Played, StandPlant};
use propid_drive_proto::drive::DriveConfig;
use propid_drive_proto::sim_drive::SimDriveConfig;
use propid_drive_proto::StopReason;
use propid_science::excitation::{Excitation, Pattern};
use propid_science::stand::StandConfig;
use propid_transport::{BusState, CanTransport, Frame, Health, MemoryBus, TransportError};

#[derive(Clone, Copy, PartialEq)]
enum Fault {
    Bell,
    BusOff,
    Vanished,
}

/// The real-time tests take turns.
static REAL_TIME: Mutex<()> = Mutex::new(());

/// A memory bus end that turns faulty once `armed` is raised; records what it sent (and whether
/// the fault had been reported by then).
struct Faulty {
    inner: MemoryBus,
    fault: Fault,
    armed: Arc<AtomicBool>,
    sent: Arc<Mutex<Vec<(bool, Frame)>>>,
    /// The fault was reported through health() (the loop knows of it from then on).
    reported: AtomicBool,
}

impl Faulty {
    fn faulted(&self) -> bool {
        self.armed.load(Ordering::Relaxed)
    }
}

impl CanTransport for Faulty {
    fn send(&mut self, frame: &Frame) -> Result<(), TransportError> {
        if self.faulted() && self.fault == Fault::Vanished {
            return Err(TransportError::Closed("mem".into()));
        }
        let reported = self.reported.load(Ordering::Relaxed);
        self.sent.lock().unwrap().push((reported, frame.clone()));
        self.inner.send(frame)
    }
    fn flush(&mut self, deadline: std::time::Instant) -> Result<bool, TransportError> {
        self.inner.flush(deadline)
    }
    fn receive(&mut self, timeout: Duration) -> Result<Option<Frame>, TransportError> {
        if self.faulted() && self.fault == Fault::Vanished {
            return Err(TransportError::Closed("mem".into()));
        }
        self.inner.receive(timeout)
    }
    fn mtu(&self) -> usize {
        8
    }
    fn name(&self) -> String {
        "faulty".into()
    }
    fn health(&self) -> Health {
        let mut h = self.inner.health();
        if self.faulted() {
            self.reported.store(true, Ordering::Relaxed);
            match self.fault {
                Fault::Bell => {
                    h.refused = 1;
                    h.last_refused = Some("T1060180A8…".into());
                }
                Fault::BusOff => h.bus_state = BusState::BusOff,
                Fault::Vanished => {}
            }
        }
        h
    }
}

fn run(fault: Fault) {
    let _turn = REAL_TIME.lock().unwrap_or_else(|p| p.into_inner());
    let (a, b) = MemoryBus::pair(8);
    let sim = SimDriveThread::spawn(
        SimDrive::new(
            SimDriveConfig::example(),
            StandPlant::boxed(StandConfig::default(), 3).unwrap(),
            SystemClock.now(),
        ),
        Box::new(b),
    );
    let sent = Arc::new(Mutex::new(Vec::new()));
    let armed = Arc::new(AtomicBool::new(false));
    let mut t = Faulty {
        inner: a,
        fault,
        armed: Arc::clone(&armed),
        sent: Arc::clone(&sent),
        reported: AtomicBool::new(false),
    };
    let cfg = DriveConfig::example(
        Played::try_from(Excitation {
            lo: 0.1,
            hi: 0.9,
            period: 2.0,
            duration: 30.0,
            init_duration: 0.5,
            pattern: Pattern::Sine,
        })
        .unwrap(),
    );
    let mut out = Vec::new();
    // The fault comes 1 s into the pattern (500 rows at 500 Hz).
    let mut rows = 0;
    let outcome = run_drive(
        cfg,
        &mut t,
        &SystemClock,
        &AtomicBool::new(false),
        &mut out,
        &mut |e| {
            if let DriveEvent::Row(_) = e {
                rows += 1;
                armed.store(rows >= 500, Ordering::Relaxed);
            }
        },
    );
    let r = &outcome.report;
    let (seen, summary) = sim.stop_after_stop_commands(
        r.standby_sent,
        r.zero_setpoints_sent,
        Duration::from_secs(10),
    );
    let summary = summary.unwrap();
    if fault != Fault::Vanished {
        // Everything the drive says it sent reaches the simulated drive.
        assert_eq!(
            (seen.standby, seen.zero_setpoints),
            (u64::from(r.standby_sent), u64::from(r.zero_setpoints_sent)),
            "{r:?}"
        );
    }
    let rows = String::from_utf8(out).unwrap().lines().count() - 1;
    assert_eq!(rows as u64, r.rows, "every row reached the output");
    assert!(rows >= 500, "{rows}");
    match fault {
        Fault::Bell => assert!(
            matches!(&r.reason, StopReason::AdapterRefused(l) if l.starts_with("T106")),
            "{:?}",
            r.reason
        ),
        Fault::BusOff => assert_eq!(r.reason, StopReason::BusOff),
        Fault::Vanished => {
            assert!(
                matches!(r.reason, StopReason::DeviceVanished(_)),
                "{:?}",
                r.reason
            );
            assert!(!outcome.link.flushed);
            assert!(!outcome.standby_delivered(true));
            assert!(outcome.link.link_fault.is_some());
            return;
        }
    }
    // The first frame sent once the loop knew of the fault is STANDBY; the drive saw it last.
    let sent = sent.lock().unwrap();
    let first = sent
        .iter()
        .filter(|(faulted, _)| *faulted)
        .map(|(_, f)| f)
        .next()
        .expect("frames after the fault");
    assert_eq!(first.id() >> 8 & 0x1FFF, 10, "readiness first");
    assert_eq!(first.data()[0], Readiness::STANDBY);
    assert!(outcome.standby_delivered(true), "{outcome:?}");
    assert_eq!(summary.last_readiness, Some(Readiness::STANDBY));
    assert_eq!(summary.last_setpoint, Some(0.0));
}

#[test]
fn adapter_bell_stops_with_standby_first() {
    run(Fault::Bell);
}

#[test]
fn bus_off_stops_with_standby_first() {
    run(Fault::BusOff);
}

#[test]
fn a_vanished_device_stops_and_says_standby_did_not_leave() {
    run(Fault::Vanished);
}
