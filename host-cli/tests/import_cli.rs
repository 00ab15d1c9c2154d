//! `propid import` from the command line: what it measured is printed, bad input exits 2 with
//! the place named, and the stand's columns (command, thrust, voltage, current, power) reach
//! the TSV.

mod common;

use common::{propid, repo};

#[test]
fn bad_kv_and_short_rows_exit_2_with_the_place() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("aq.csv");
    std::fs::write(&p, "Timestamp,Amps,RPM,Duty\n2019-11-05 17:14:08:947,1.0,100,50\n2019-11-05 17:14:08:957,1.0,100\n").unwrap();
    let path = p.to_str().unwrap();
    for kv in ["inf", "0", "-5", "nan"] {
        let out = propid(&["import", "autoquad", path, &format!("--kv={kv}")], None);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{kv}: {err}");
        assert!(err.contains("--kv must be a finite positive"), "{err}");
        assert!(out.stdout.is_empty());
    }
    let out = propid(&["import", "autoquad", path, "--kv", "1600"], None);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("aq.csv: line 3, column `Duty`: missing"),
        "{err}"
    );
}

#[test]
fn rcbench_reports_what_it_measured_and_keeps_the_command() {
    let dir = tempfile::tempdir().unwrap();
    let out_tsv = dir.path().join("rc.tsv");
    let log = repo().join("tests/data/esc_test_alspitz/rcbench/Log_2019-11-09_181347.csv");
    let out = propid(
        &[
            "import",
            "rcbench",
            log.to_str().unwrap(),
            "-o",
            out_tsv.to_str().unwrap(),
        ],
        None,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    for want in [
        "torque sign flipped",
        "zero offset: at zero speed",
        "not subtracted",
        "command = (`ESC signal (µs)` − 1000 µs) / 1000 µs",
        "thrust = `Thrust (gf)` × 0.00980665 N per unit",
    ] {
        assert!(err.contains(want), "`{want}` not in {err}");
    }
    let tsv = std::fs::read_to_string(&out_tsv).unwrap();
    let header: Vec<&str> = tsv.lines().next().unwrap().split('\t').collect();
    let column = |name: &str| -> Vec<f64> {
        let k = header.iter().position(|h| *h == name).unwrap();
        tsv.lines()
            .skip(1)
            .filter_map(|l| l.split('\t').nth(k)?.parse().ok())
            .filter(|c: &f64| c.is_finite())
            .collect()
    };
    let max = |v: Vec<f64>| v.into_iter().fold(f64::MIN, f64::max);
    // The command is the PWM the stand gave: 1050–1950 µs in this run, 0.05–0.95 as a ratio.
    let us = max(column("esc_signal_us"));
    assert!((1900.0..=2000.0).contains(&us), "{us}");
    let ratio = max(column("command"));
    assert!((0.9..=1.0).contains(&ratio), "{ratio}");
    // The thrust in newtons, positive at speed: the 7-inch propeller at full throttle pushes
    // more than 1 kgf.
    let thrust = max(column("thrust"));
    assert!((10.0..30.0).contains(&thrust), "{thrust}");
    for name in ["voltage", "current", "electrical_power", "mechanical_power"] {
        assert!(!column(name).is_empty(), "{name}");
    }
}
