//! `propid sim | propid diagnose` end to end: the hidden effect comes out of the JSON report, the
//! text report says what the simulation got wrong, plots are written, and bad input exits 2.

mod common;

use common::propid;

#[test]
fn sim_then_diagnose_finds_a_hidden_torque_lag() {
    let dir = tempfile::tempdir().unwrap();
    let tsv = dir.path().join("stand.tsv");
    let out = propid(
        &[
            "sim",
            "--pattern",
            "chirp",
            "--duration",
            "30",
            "--torque-lag",
            "0.012",
            "--seed",
            "3",
            "-o",
            tsv.to_str().unwrap(),
        ],
        None,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let plot = dir.path().join("diag.svg");
    let out = propid(
        &[
            "diagnose",
            tsv.to_str().unwrap(),
            "--format",
            "json",
            "--plot",
            plot.to_str().unwrap(),
        ],
        None,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for key in ["base", "effects", "simulation_rms", "unexplained"] {
        assert!(r.get(key).is_some(), "missing `{key}`");
    }
    let effects = r["effects"].as_array().unwrap();
    assert_eq!(effects.len(), 1, "{effects:?}");
    assert_eq!(effects[0]["name"], "torque_lag");
    assert_eq!(effects[0]["unit"], "s");
    let lag = effects[0]["value"].as_f64().unwrap();
    assert!((lag / 0.012 - 1.0).abs() < 0.05, "lag {lag}");
    assert!(effects[0]["stderr"].as_f64().unwrap() > 0.0);
    assert!(r["simulation_rms"]["gain_percent"].as_f64().unwrap() > 50.0);
    assert!(r["unexplained"].is_null());
    assert!(std::fs::read_to_string(&plot).unwrap().contains("held-out"));

    let out = propid(&["diagnose", tsv.to_str().unwrap()], None);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("What the simulation gets wrong"), "{text}");
    assert!(
        text.contains("torque_lag") && text.contains("← named"),
        "{text}"
    );
}

#[test]
fn clean_data_says_nothing_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let tsv = dir.path().join("clean.tsv");
    let out = propid(
        &[
            "sim",
            "--duration",
            "20",
            "--seed",
            "9",
            "-o",
            tsv.to_str().unwrap(),
        ],
        None,
    );
    assert!(out.status.success());
    let out = propid(&["diagnose", tsv.to_str().unwrap()], None);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8(out.stdout)
        .unwrap()
        .contains("Nothing is wrong"));
}

#[test]
fn bad_input_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let short = dir.path().join("short.tsv");
    std::fs::write(&short, "t\tforce\tvelocity\tacceleration\n0\t1\t2\t3\n").unwrap();
    let out = propid(&["diagnose", short.to_str().unwrap()], None);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("short.tsv") && err.contains("at least 200"),
        "{err}"
    );
    let out = propid(&["sim", "--lo", "0.9", "--hi", "0.1"], None);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("lo < hi"));
}

#[test]
fn import_then_diagnose_a_real_log() {
    let dir = tempfile::tempdir().unwrap();
    let tsv = dir.path().join("f40.tsv");
    let log = common::repo().join("tests/data/esc_test_alspitz/autoquad/f40_steps_5-2.csv");
    let out = propid(
        &[
            "import",
            "autoquad",
            log.to_str().unwrap(),
            "--kv",
            "1600",
            "-o",
            tsv.to_str().unwrap(),
        ],
        None,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("Kt = 60/(2π·kv)"),
        "the importer states its assumption"
    );
    let out = propid(
        &["diagnose", tsv.to_str().unwrap(), "--format", "json"],
        None,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(r["effects"]
        .as_array()
        .unwrap()
        .iter()
        .any(|e| e["name"] == "force_sensor_lag"));
    let out = propid(&["import", "rcbench", "/nonexistent.csv"], None);
    assert_eq!(out.status.code(), Some(2));
}
