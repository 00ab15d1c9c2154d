//! `propid import` from the command line: what it measured is printed, bad input exits 2 with
//! the place named, and the command column reaches the TSV.

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
        "command = `ESC signal (µs)`",
    ] {
        assert!(err.contains(want), "`{want}` not in {err}");
    }
    let tsv = std::fs::read_to_string(&out_tsv).unwrap();
    assert!(tsv.lines().next().unwrap().ends_with("\tcommand"));
    // The command is the PWM the stand gave: 1050–1950 µs in this run.
    let cmds: Vec<f64> = tsv
        .lines()
        .skip(1)
        .filter_map(|l| l.rsplit('\t').next()?.parse().ok())
        .filter(|c: &f64| c.is_finite())
        .collect();
    let max = cmds.iter().copied().fold(f64::MIN, f64::max);
    assert!((1900.0..=2000.0).contains(&max), "{max}");
}
