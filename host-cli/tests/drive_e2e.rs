//! `propid drive` against the simulated Telega over a real SLCAN pseudo-terminal pair: the TSV
//! has the expected rows, the fit recovers the simulated inertia and drag within 2 %, and the
//! drive saw STANDBY and a zero setpoint last — also when the driver is killed by SIGINT midway.
//! Each limit stops a runaway over the same link: the maximum speed, a reversed torque (the
//! simulated motor wired the other way), no feedback during the soft start.
//!
//! The tests wait for events, never for the clock: the simulated drive is stopped once it has
//! received every stop command the driver says it sent; a bound on that wait is only there so
//! that a lost frame fails the test instead of hanging it.

mod common;

use std::os::fd::AsRawFd;
use std::process::{Command, Stdio};
use std::sync::atomic::AtomicBool;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use propid_core::can::SubjectId;
use propid_core::dsdl::{DataType, Readiness, Vector31};
use propid_drive_host::drive::{run_drive, DriveOutcome};
use propid_drive_host::realtime::{Clock, SystemClock};
use propid_drive_host::sim_drive::SimDriveThread;
use propid_drive_host::stand::{Played, StandPlant};
use propid_drive_proto::drive::DriveConfig;
use propid_drive_proto::limits::{LimitStop, Limits};
use propid_drive_proto::plant::{Plant, TorqueScaled};
use propid_drive_proto::settings::MaxSpeed;
use propid_drive_proto::sim_drive::{SimDrive, SimDriveConfig, SimDriveSummary};
use propid_drive_proto::StopReason;
use propid_science::excitation::{Excitation, Pattern};
use propid_science::stand::StandConfig;
use propid_slcan::SlcanTransport;
use propid_transport::{CanTransport, Frame, Health, TransportError};
use serialport::{SerialPort, TTYPort};

/// The real-time tests take turns: each runs a 500 Hz drive and a simulated Telega on real
/// pseudo-terminals, and several at once on a 2-core machine compete for the same CPUs (their
/// loops run at a real-time priority where permitted, and so would preempt each other).
static REAL_TIME: Mutex<()> = Mutex::new(());

fn real_time_turn() -> std::sync::MutexGuard<'static, ()> {
    REAL_TIME
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

fn stand() -> Box<dyn Plant> {
    StandPlant::boxed(StandConfig::default(), 5).unwrap()
}

/// The simulated Telega of `plant` on `port`, on its own thread.
fn start_telega_with(port: TTYPort, cfg: SimDriveConfig, plant: Box<dyn Plant>) -> SimDriveThread {
    let t = SlcanTransport::from_tty(port, "telega").unwrap();
    SimDriveThread::spawn(SimDrive::new(cfg, plant, SystemClock.now()), Box::new(t))
}

fn start_telega(port: TTYPort) -> SimDriveThread {
    start_telega_with(port, SimDriveConfig::example(), stand())
}

/// Stops the simulated Telega once it has received the stop commands the driver says it sent
/// (`standby`, `zero`); what it saw.
fn stop_after_stop_commands(telega: SimDriveThread, standby: u32, zero: u32) -> SimDriveSummary {
    let (seen, summary) = telega.stop_after_stop_commands(standby, zero, Duration::from_secs(10));
    assert_eq!(
        (seen.standby, seen.zero_setpoints),
        (u64::from(standby), u64::from(zero)),
        "every stop command the driver sent arrived"
    );
    summary.unwrap()
}

/// The driver's transport, recording every frame it accepted.
struct Recording {
    inner: SlcanTransport,
    sent: Vec<Frame>,
}

impl CanTransport for Recording {
    fn send(&mut self, frame: &Frame) -> Result<(), TransportError> {
        self.inner.send(frame)?;
        self.sent.push(frame.clone());
        Ok(())
    }
    fn flush(&mut self, deadline: std::time::Instant) -> Result<bool, TransportError> {
        self.inner.flush(deadline)
    }
    fn receive(&mut self, timeout: Duration) -> Result<Option<Frame>, TransportError> {
        self.inner.receive(timeout)
    }
    fn mtu(&self) -> usize {
        self.inner.mtu()
    }
    fn name(&self) -> String {
        self.inner.name()
    }
    fn health(&self) -> Health {
        self.inner.health()
    }
}

/// Drives the simulated Telega of `plant` (configured by `sim`) with `cfg` over a pty: what the
/// driver did, the frames it sent, and what the simulated Telega saw once every stop command
/// arrived.
fn drive_over_pty(
    cfg: DriveConfig,
    sim: SimDriveConfig,
    plant: Box<dyn Plant>,
) -> (DriveOutcome, Vec<Frame>, SimDriveSummary, Vec<u8>) {
    let (drive_end, telega_end) = TTYPort::pair().unwrap();
    let telega = start_telega_with(telega_end, sim, plant);
    let mut out = Vec::new();
    let mut t = Recording {
        inner: SlcanTransport::from_tty(drive_end, "driver").unwrap(),
        sent: Vec::new(),
    };
    let outcome = run_drive(
        cfg,
        &mut t,
        &SystemClock,
        &AtomicBool::new(false),
        &mut out,
        &mut |_| {},
    );
    let r = &outcome.report;
    let summary = stop_after_stop_commands(telega, r.standby_sent, r.zero_setpoints_sent);
    (outcome, t.sent, summary, out)
}

fn seed_pattern(init_duration: f64, duration: f64) -> Played {
    Played::try_from(Excitation {
        lo: 0.1,
        hi: 0.9,
        period: 2.0,
        duration,
        init_duration,
        pattern: Pattern::Sine,
    })
    .unwrap()
}

/// Over the wire, from the first STANDBY on: no readiness but STANDBY and no setpoint but zero
/// (the node's heartbeat goes on), and the frame before it (if any) ended its transfer (the stop
/// purged the rest of the queue).
fn assert_standby_first_on_the_wire(sent: &[Frame]) {
    let subject = |f: &Frame| f.id() >> 8 & 0x1FFF;
    let first = sent
        .iter()
        .position(|f| subject(f) == 10 && f.data()[0] == Readiness::STANDBY)
        .expect("a STANDBY was sent");
    let mut payload = Vec::new();
    for f in &sent[first + 1..] {
        match subject(f) {
            10 => assert_eq!(f.data()[0], Readiness::STANDBY),
            24 => {
                payload.extend_from_slice(&f.data()[..f.data().len() - 1]);
                if f.data().last().is_some_and(|t| t & 0x40 != 0) {
                    // End of a transfer: a zero setpoint (payload and its CRC).
                    assert_eq!(
                        Vector31::deserialize(&payload[..62]).unwrap(),
                        Vector31::splat(0.0)
                    );
                    payload.clear();
                }
            }
            // The node's own heartbeat and port list go on.
            7509 | 7510 => {}
            other => panic!("frame on subject {other} after STANDBY"),
        }
    }
    if first > 0 {
        let before = &sent[first - 1];
        assert!(
            before.data().last().is_some_and(|t| t & 0x40 != 0),
            "the frame before STANDBY ended its transfer"
        );
    }
}

fn check_tsv(text: &str) -> usize {
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("ts_local\tt\tforce\tvelocity\tacceleration\tposition")
    );
    let mut rows = 0;
    for line in lines {
        let fields: Vec<f64> = line
            .split('\t')
            .map(|f| f.parse().expect("numeric field"))
            .collect();
        assert_eq!(fields.len(), 6, "whole row: {line}");
        rows += 1;
    }
    assert!(text.ends_with('\n'), "the last row is complete");
    rows
}

#[test]
fn drives_the_simulated_telega_and_fits_it() {
    let _turn = real_time_turn();
    let cfg = DriveConfig {
        fit: true,
        ..DriveConfig::example(seed_pattern(1.0, 10.0))
    };
    let (outcome, sent, summary, out) = drive_over_pty(cfg, SimDriveConfig::example(), stand());
    assert_eq!(outcome.report.reason, StopReason::Completed);
    assert_standby_first_on_the_wire(&sent);
    assert!(outcome.standby_delivered(true), "{outcome:?}");
    let text = String::from_utf8(out).unwrap();
    let rows = check_tsv(&text);
    // 10 s of feedback at 500 Hz; scheduling on a loaded CI machine may lose a few percent.
    assert!(
        (4500..=5010).contains(&rows),
        "{rows} rows; {} feedback published, {} dropped unsent by the simulated drive; {:?}; {:?}",
        summary.feedback_published,
        summary.feedback_dropped,
        outcome.report.feedback_lost,
        outcome.link.priority
    );
    assert_eq!(rows as u64, outcome.report.rows);
    // The loss the summary reports is the gaps in the recording's own drive timestamps.
    let t: Vec<f64> = text
        .lines()
        .skip(1)
        .map(|l| l.split('\t').nth(1).unwrap().parse().unwrap())
        .collect();
    let gaps: u64 = t
        .windows(2)
        .map(|w| (((w[1] - w[0]) / 0.002).round() as u64).saturating_sub(1))
        .sum();
    assert_eq!(outcome.report.feedback_lost.by_timestamp, gaps);
    assert_eq!(outcome.report.damaged_frames, 0);
    assert_eq!(
        summary.last_readiness,
        Some(Readiness::STANDBY),
        "{summary:?}"
    );
    assert_eq!(summary.last_setpoint, Some(0.0));
    assert_eq!(
        summary.readiness_changes,
        vec![Readiness::ENGAGED, Readiness::STANDBY]
    );
    // The fit, as `propid fit` does it, recovers the simulated load.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.tsv");
    std::fs::write(&path, &text).unwrap();
    let out = common::propid(&["fit", path.to_str().unwrap()], None);
    let yaml = String::from_utf8(out.stdout).unwrap();
    let truth = StandConfig::default();
    let (j, c2) = (
        common::yaml_value(&yaml, "mass"),
        common::yaml_value(&yaml, "c2"),
    );
    assert!((j / truth.inertia - 1.0).abs() < 0.02, "J {j}");
    assert!((c2 / truth.c2 - 1.0).abs() < 0.02, "c2 {c2}");
}

#[test]
fn sigint_midway_commands_standby_and_keeps_every_row() {
    let _turn = real_time_turn();
    let (telega_end, driver_end) = TTYPort::pair().unwrap();
    let path = driver_end.name().expect("the pty has a path");
    let telega = start_telega(telega_end);
    let dir = tempfile::tempdir().unwrap();
    let tsv = dir.path().join("run.tsv");
    let child = Command::new(env!("CARGO_BIN_EXE_propid"))
        .args([
            "drive",
            "--iface",
            &format!("slcan:{path}"),
            "--pattern-duration",
            "60",
            "--init-duration",
            "1",
            "-o",
        ])
        .arg(&tsv)
        .env("UAVCAN__NODE__ID", "10")
        .env("UAVCAN__PUB__READINESS__ID", "10")
        .env("UAVCAN__PUB__SP_RAT__ID", "24")
        .env("UAVCAN__SUB__FB_DYN__ID", "110")
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Wait for a few hundred rows, then interrupt.
    let t0 = Instant::now();
    loop {
        let n = std::fs::read_to_string(&tsv)
            .map(|s| s.lines().count())
            .unwrap_or(0);
        if n > 301 {
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(20),
            "no feedback recorded"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert!(
        err.contains("interrupted by a signal") && err.contains("STANDBY"),
        "{err}"
    );
    let (standby, zero) = stop_commands_said(&err);
    let summary = stop_after_stop_commands(telega, standby, zero);
    assert_eq!(
        summary.last_readiness,
        Some(Readiness::STANDBY),
        "{summary:?}"
    );
    assert_eq!(summary.last_setpoint, Some(0.0));
    let rows = check_tsv(&std::fs::read_to_string(&tsv).unwrap());
    assert!(rows >= 300, "{rows}");
    drop(driver_end);
}

#[test]
fn invalid_settings_are_refused_before_anything_is_sent() {
    let cases: [(&[(&str, &str)], &str); 4] = [
        (&[("SETPOINT_RAT_LO_HI", "0.9 0.1")], "lo < hi"),
        (&[("SETPOINT_RAT_LO_HI", "0.1 1.5")], "lo < hi ≤ 1"),
        (
            &[("UAVCAN__SUB__FB_DYN__ID", "")],
            "--feedback-id is not set (nor its register uavcan.sub.fb_dyn.id in a --registers file, nor its environment variable UAVCAN__SUB__FB_DYN__ID)",
        ),
        (&[("UAVCAN__PUB__SP_RAT__ID", "9000")], "from 0 to 8191"),
    ];
    for (env, want) in cases {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_propid"));
        cmd.args(["drive", "--iface", "slcan:/dev/null-not-opened"])
            .env("UAVCAN__NODE__ID", "10")
            .env("UAVCAN__PUB__SP_RAT__ID", "24")
            .env("UAVCAN__SUB__FB_DYN__ID", "110");
        for (k, v) in env {
            if v.is_empty() {
                cmd.env_remove(k);
            } else {
                cmd.env(k, v);
            }
        }
        let out = cmd.output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{env:?}: {err}");
        assert!(err.contains(want), "{env:?}: {err}");
        // Refused before the interface was touched.
        assert!(!err.contains("null-not-opened"), "{err}");
    }
}

#[test]
fn the_serial_device_vanishing_midway_stops_with_a_clear_reason_and_every_row() {
    let _turn = real_time_turn();
    let (telega_end, driver_end) = TTYPort::pair().unwrap();
    // The child must not inherit the simulated drive's end, or it never closes.
    for raw in [telega_end.as_raw_fd(), driver_end.as_raw_fd()] {
        // SAFETY: `raw` is an open descriptor owned by a TTYPort that outlives this borrow.
        let fd = unsafe { std::os::fd::BorrowedFd::borrow_raw(raw) };
        rustix::io::fcntl_setfd(fd, rustix::io::FdFlags::CLOEXEC).unwrap();
    }
    let path = driver_end.name().expect("the pty has a path");
    let telega = start_telega(telega_end);
    let dir = tempfile::tempdir().unwrap();
    let tsv = dir.path().join("run.tsv");
    let child = Command::new(env!("CARGO_BIN_EXE_propid"))
        .args([
            "drive",
            "--iface",
            &format!("slcan:{path}"),
            "--pattern-duration",
            "60",
            "--init-duration",
            "0.5",
            "--deadman",
            "5",
            "-o",
        ])
        .arg(&tsv)
        .env("UAVCAN__NODE__ID", "10")
        .env("UAVCAN__PUB__READINESS__ID", "10")
        .env("UAVCAN__PUB__SP_RAT__ID", "24")
        .env("UAVCAN__SUB__FB_DYN__ID", "110")
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while std::fs::read_to_string(&tsv)
        .map(|s| s.lines().count())
        .unwrap_or(0)
        <= 201
    {
        assert!(
            t0.elapsed() < Duration::from_secs(20),
            "no feedback recorded"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    // Unplug: the other end of the pseudo-terminal closes (the simulated drive's thread ends and
    // drops it; the test's own handle on the device side goes too).
    telega.stop().unwrap();
    drop(driver_end);
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_ne!(out.status.code(), Some(0), "{err}");
    assert!(err.contains("device vanished"), "{err}");
    assert!(err.contains("NOT confirmed sent"), "{err}");
    let rows = check_tsv(&std::fs::read_to_string(&tsv).unwrap());
    let reported: usize = err
        .split(" rows written")
        .next()
        .and_then(|s| s.rsplit(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{err}"));
    assert_eq!(rows, reported, "every row counted reached the file");
}

/// The counts in `propid drive`'s "STANDBY and a zero setpoint sent (N and M times)".
fn stop_commands_said(err: &str) -> (u32, u32) {
    let counts = err
        .split("STANDBY and a zero setpoint sent (")
        .nth(1)
        .and_then(|s| s.split(" times)").next())
        .unwrap_or_else(|| panic!("no stop commands said: {err}"));
    let (a, b) = counts.split_once(" and ").unwrap();
    (a.parse().unwrap(), b.parse().unwrap())
}

/// The limits over the pty, each with the simulated Telega at the other end.
fn limit_over_pty(
    cfg: DriveConfig,
    sim: SimDriveConfig,
    plant: Box<dyn Plant>,
) -> (LimitStop, SimDriveSummary) {
    let _turn = real_time_turn();
    let (outcome, sent, summary, _) = drive_over_pty(cfg, sim, plant);
    let StopReason::Limit(limit) = outcome.report.reason.clone() else {
        panic!("not stopped by a limit: {outcome:?}")
    };
    assert!(outcome.standby_delivered(true), "{outcome:?}");
    assert_standby_first_on_the_wire(&sent);
    assert_eq!(summary.last_readiness, Some(Readiness::STANDBY));
    assert_eq!(summary.last_setpoint, Some(0.0));
    (limit, summary)
}

#[test]
fn over_the_pty_the_maximum_speed_stops_the_rotor() {
    let cfg = DriveConfig {
        limits: Limits {
            max_speed: Some(MaxSpeed::new(1500.0).unwrap()),
            ..Limits::DEFAULT
        },
        ..DriveConfig::example(seed_pattern(2.0, 10.0))
    };
    let (limit, _) = limit_over_pty(cfg, SimDriveConfig::example(), stand());
    assert!(
        matches!(limit, LimitStop::MaxSpeed { speed, max } if max == 1500.0 && (1500.0..1550.0).contains(&speed)),
        "{limit:?}"
    );
}

#[test]
fn over_the_pty_a_motor_wired_the_other_way_stops_in_the_soft_start() {
    let plant = Box::new(TorqueScaled::new(stand(), -1.0));
    let cfg = DriveConfig::example(seed_pattern(2.0, 10.0));
    let (limit, summary) = limit_over_pty(cfg, SimDriveConfig::example(), plant);
    assert!(
        matches!(limit, LimitStop::SoftStartWrongWay { setpoint, to, .. } if setpoint == 0.1 && to < -50.0),
        "{limit:?}"
    );
    // Only the soft start's setpoint (0.1, as float16) was ever commanded.
    assert_eq!(
        summary.readiness_changes,
        [Readiness::ENGAGED, Readiness::STANDBY]
    );
}

#[test]
fn over_the_pty_no_feedback_during_the_soft_start_stops_the_drive() {
    let sim = SimDriveConfig {
        feedback_id: SubjectId::from_const(111),
        ..SimDriveConfig::example()
    };
    let cfg = DriveConfig::example(seed_pattern(2.0, 10.0));
    let (limit, _) = limit_over_pty(cfg, sim, stand());
    assert_eq!(
        limit,
        LimitStop::SoftStartNoFeedback {
            messages: 0,
            seconds: 1.0,
            subject: 110
        }
    );
}

/// The command line: a limit is exit status 4 with its sentence (a reversed motor, whose stop
/// the simulated Telega sees last).
#[test]
fn a_limit_is_exit_status_4_with_its_reason() {
    let _turn = real_time_turn();
    let (telega_end, driver_end) = TTYPort::pair().unwrap();
    let path = driver_end.name().expect("the pty has a path");
    let telega = start_telega_with(
        telega_end,
        SimDriveConfig::example(),
        Box::new(TorqueScaled::new(stand(), -1.0)),
    );
    let out = Command::new(env!("CARGO_BIN_EXE_propid"))
        .args([
            "drive",
            "--iface",
            &format!("slcan:{path}"),
            "-o",
            "/dev/null",
        ])
        .env("UAVCAN__NODE__ID", "10")
        .env("UAVCAN__PUB__READINESS__ID", "10")
        .env("UAVCAN__PUB__SP_RAT__ID", "24")
        .env("UAVCAN__SUB__FB_DYN__ID", "110")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(4), "{err}");
    assert!(
        err.contains("error: stopped by a limit: the rotor accelerated the wrong way: the torque sign is reversed"),
        "{err}"
    );
    assert!(
        err.contains("drive: limits: soft start at +0.1 for 1 s"),
        "{err}"
    );
    let (standby, zero) = stop_commands_said(&err);
    let summary = stop_after_stop_commands(telega, standby, zero);
    assert_eq!(summary.last_readiness, Some(Readiness::STANDBY));
    assert_eq!(summary.last_setpoint, Some(0.0));
    drop(driver_end);
}
