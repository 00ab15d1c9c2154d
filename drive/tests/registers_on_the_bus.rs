//! propid's nodes serving registers over an in-memory bus, with propid's own client on the other
//! end: the simulated Telega (discover, read, check the seed's prerequisites, fix, store, and a
//! written feedback interval that changes the feedback rate) and the driver (the seed's
//! registers, read and written while it runs).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use propid_core::dsdl::{ExecuteCommandRequest, ExecuteCommandResponse, Value};
use propid_drive::drive::{drive, DriveConfig};
use propid_drive::registers::{check_prerequisites, sim_drive_registers};
use propid_drive::sim_drive::{run_sim_drive_with, SimDriveConfig};
use propid_drive::telega::{read_checked, Client};
use propid_science::excitation::{Excitation, Pattern};
use propid_transport::MemoryBus;

#[test]
fn sim_telega_discovered_checked_fixed_and_obeying() {
    let (mut ours, mut theirs) = MemoryBus::pair(8);
    let mut cfg = SimDriveConfig::example(Default::default(), 7);
    cfg.interval = 0.05; // Telega's factory default: 20 Hz
    let registers = sim_drive_registers(&cfg, false);
    let stop = Arc::new(AtomicBool::new(false));
    let s = stop.clone();
    let sim = std::thread::spawn(move || run_sim_drive_with(&cfg, &registers, &mut theirs, &s));

    let mut client = Client::new(&mut ours, 100, 8);
    assert_eq!(
        client.discover(Duration::from_millis(1200)).unwrap(),
        vec![42]
    );
    let info = client.get_info(42).unwrap().unwrap();
    assert_eq!(&info.name[..], b"org.zubax.telega.sim");
    let all = client.read_all(42).unwrap().unwrap();
    let names: Vec<&str> = all.iter().map(|r| r.name.as_str()).collect();
    assert!(names.contains(&"mns.pub_interval_min") && names.contains(&"uavcan.pub.dynamics.id"));

    // The factory settings spoil the data: 20 Hz, no timestamps.
    let found = read_checked(&mut client, 42).unwrap();
    let problems = check_prerequisites(&found, Some(110));
    let which: Vec<&str> = problems.iter().map(|p| p.register.as_str()).collect();
    assert_eq!(which, ["mns.pub_interval_min", "mns.local_timestamp"]);
    let slow = client.sample_subject(110, Duration::from_secs(1)).unwrap();
    assert!((15..=25).contains(&slow.len()), "{} at 20 Hz", slow.len());
    assert!(slow.iter().all(|t| *t == 0), "no local timestamps yet");

    // Fix them as the drive converts them (a real64 written into a real32 register).
    let r = client
        .access(42, "mns.pub_interval_min", Value::real64(&[0.005]).unwrap())
        .unwrap()
        .unwrap();
    assert_eq!(r.value, Value::real32(&[0.005]).unwrap());
    let r = client
        .access(42, "mns.local_timestamp", Value::bit(&[true]).unwrap())
        .unwrap()
        .unwrap();
    assert_eq!(r.value, Value::bit(&[true]).unwrap());
    // Read-only: refused.
    let r = client
        .access(42, "mns.deadman_timeout", Value::real32(&[9.0]).unwrap())
        .unwrap()
        .unwrap();
    assert_eq!(r.value, Value::real32(&[0.5]).unwrap());
    assert!(!r.mutable);
    let found = read_checked(&mut client, 42).unwrap();
    assert!(check_prerequisites(&found, Some(110)).is_empty());
    assert_eq!(
        client
            .execute(42, ExecuteCommandRequest::COMMAND_STORE_PERSISTENT_STATES)
            .unwrap(),
        Some(ExecuteCommandResponse::STATUS_SUCCESS)
    );
    assert_eq!(
        client
            .execute(42, ExecuteCommandRequest::COMMAND_POWER_OFF)
            .unwrap(),
        Some(ExecuteCommandResponse::STATUS_BAD_COMMAND)
    );

    // The feedback rate follows the register, and the feedback is stamped.
    let fast = client.sample_subject(110, Duration::from_secs(1)).unwrap();
    assert!(
        (170..=210).contains(&fast.len()),
        "{} at 200 Hz",
        fast.len()
    );
    assert!(fast.iter().skip(1).all(|t| *t > 0));
    stop.store(true, Ordering::Relaxed);
    let summary = sim.join().unwrap().unwrap();
    assert_eq!(summary.commands, 1);
    eprintln!(
        "sim telega: feedback {} /s at the factory interval, {} /s after writing 0.005 s",
        slow.len(),
        fast.len()
    );
}

#[test]
fn the_driver_serves_the_seeds_registers() {
    let (mut ours, mut theirs) = MemoryBus::pair(8);
    let cfg = DriveConfig::example(Excitation {
        lo: 0.2,
        hi: 0.7,
        period: 2.0,
        duration: 10.0,
        init_duration: 30.0, // stays in the init phase: no feedback needed
        pattern: Pattern::Sine,
    });
    let stop = Arc::new(AtomicBool::new(false));
    let s = stop.clone();
    let driver = std::thread::spawn(move || {
        let mut out = Vec::new();
        drive(&cfg, &mut theirs, &mut out, &s, &mut |_| {})
    });
    let mut client = Client::new(&mut ours, 100, 8);
    let names = client.list(10).unwrap().unwrap();
    for want in [
        "uavcan.node.id",
        "setpoint_rat_lo_hi",
        "period",
        "pattern_duration",
        "init_duration",
        "setpoint_period",
        "uavcan.pub.readiness.id",
        "uavcan.pub.sp_rat.id",
        "uavcan.sub.fb_dyn.id",
        "uavcan.sub.fb_dyn.type",
    ] {
        assert!(names.iter().any(|n| n == want), "{want} in {names:?}");
    }
    let r = client
        .access(10, "setpoint_rat_lo_hi", Value::Empty)
        .unwrap()
        .unwrap();
    assert_eq!(r.value, Value::real64(&[0.2, 0.7]).unwrap());
    let r = client
        .access(10, "uavcan.sub.fb_dyn.id", Value::Empty)
        .unwrap()
        .unwrap();
    assert_eq!(r.value, Value::natural16(&[110]).unwrap());
    let r = client
        .access(10, "period", Value::natural16(&[3]).unwrap())
        .unwrap()
        .unwrap();
    assert_eq!(r.value, Value::real64(&[3.0]).unwrap());
    let r = client
        .access(10, "uavcan.pub.sp_rat.type", Value::string("x").unwrap())
        .unwrap()
        .unwrap();
    assert_eq!(
        r.value,
        Value::string("zubax.primitive.real16.Vector31.1.0").unwrap()
    );
    stop.store(true, Ordering::Relaxed);
    driver.join().unwrap();
}
