//! Every numeric flag of `drive`, `sim-drive` and `demo` is checked before anything is opened or
//! sent: a clear error naming the flag, exit 2, no panic, no Rust debug text.

use std::process::Command;

fn check(args: &[&str], flag: &str) {
    let dir = tempfile::tempdir().unwrap();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_propid"));
    cmd.args(args)
        .env_remove("UAVCAN__NODE__ID")
        .env("UAVCAN__PUB__READINESS__ID", "10")
        .env("UAVCAN__PUB__SP_RAT__ID", "24")
        .env("UAVCAN__SUB__FB_DYN__ID", "110")
        .current_dir(dir.path());
    if args[0] == "drive" {
        cmd.env("UAVCAN__NODE__ID", "10");
    }
    if args[0] != "demo" {
        cmd.args(["--iface", "slcan:/dev/null-not-opened"]);
    } else {
        cmd.arg("-o").arg(dir.path().join("out"));
    }
    let out = cmd.output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert!(err.contains(flag), "{args:?} should name {flag}: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    for debug in ["Some(", "None", "{ ", "Error(", "..="] {
        assert!(!err.contains(debug), "{args:?}: debug text in {err}");
    }
    // Refused before the interface (or the demo's pty) was touched.
    assert!(!err.contains("null-not-opened"), "{err}");
    assert!(!err.contains("simulated Telega"), "{err}");
    assert!(out.stdout.is_empty(), "{args:?}: nothing written");
}

#[test]
fn drive_numbers_are_checked() {
    for (args, flag) in [
        (&["--init-duration", "inf"][..], "--init-duration"),
        (&["--init-duration", "1e20"], "--init-duration"),
        (&["--init-duration=-1"], "--init-duration"),
        (&["--pattern-duration", "nan"], "--pattern-duration"),
        (&["--pattern-duration", "0"], "--pattern-duration"),
        (&["--period", "inf"], "--period"),
        (&["--setpoint-period", "0"], "--setpoint-period"),
        (&["--setpoint-period", "nan"], "--setpoint-period"),
        (&["--setpoint-period", "inf"], "--setpoint-period"),
        (&["--deadman", "inf"], "--deadman"),
        (&["--deadman=-0.1"], "--deadman"),
        (&["--node-id", "200"], "--node-id"),
        (&["--drive-node-id", "128"], "--drive-node-id"),
        (&["--feedback-id", "9000"], "--feedback-id"),
        (&["--readiness-id", "8192"], "--readiness-id"),
        (&["--setpoint-rat-lo-hi", "0.1 inf"], "setpoint"),
        (&["--setpoint-rat-lo-hi", "nan 0.5"], "setpoint"),
        (&["--max-speed", "fast"], "--max-speed"),
        (&["--max-speed", "nan"], "--max-speed"),
        (&["--max-speed=-5"], "--max-speed"),
        (&["--max-speed", "2e6rpm"], "--max-speed"),
        (&["--soft-start-setpoint", "1.5"], "--soft-start-setpoint"),
        (&["--soft-start-setpoint", "0"], "--soft-start-setpoint"),
        (&["--soft-start-duration", "100"], "--soft-start-duration"),
        (&["--soft-start-duration=-1"], "--soft-start-duration"),
        (&["--ramp-duration", "inf"], "--ramp-duration"),
        (&["--speed-watchdog", "nan"], "--speed-watchdog"),
        (&["--speed-watchdog=-1"], "--speed-watchdog"),
    ] {
        let mut a = vec!["drive"];
        a.extend_from_slice(args);
        check(&a, flag);
    }
}

#[test]
fn sim_drive_numbers_are_checked() {
    for (args, flag) in [
        (&["--interval", "inf"][..], "--interval"),
        (&["--interval", "0"], "--interval"),
        (&["--interval", "nan"], "--interval"),
        (&["--duration", "nan"], "--duration"),
        (&["--duration", "inf"], "--duration"),
        (&["--duration=-1"], "--duration"),
        (&["--node-id", "200"], "--node-id"),
        (&["--feedback-id", "9000"], "--feedback-id"),
        (&["--setpoint-id", "8192"], "--setpoint-id"),
        (&["--readiness-id", "9000"], "--readiness-id"),
        (&["--torque-scale", "20"], "--torque-scale"),
        (&["--torque-scale", "nan"], "--torque-scale"),
    ] {
        let mut a = vec!["sim-drive"];
        a.extend_from_slice(args);
        check(&a, flag);
    }
}

#[test]
fn demo_numbers_are_checked() {
    for (args, flag) in [
        (&["--init-duration", "inf"][..], "--init-duration"),
        (&["--init-duration", "1e20"], "--init-duration"),
        (&["--duration", "1e20"], "--duration"),
        (&["--duration", "nan"], "--duration"),
    ] {
        let mut a = vec!["demo"];
        a.extend_from_slice(args);
        check(&a, flag);
    }
}
