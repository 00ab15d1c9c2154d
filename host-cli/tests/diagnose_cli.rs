//! `propid sim | propid diagnose` end to end: the hidden effect comes out of the JSON report, the
//! text report says what the simulation got wrong, plots are written, and bad input exits 2.

mod common;

use common::{propid, propid_ok, write_rows};

/// `propid sim`'s 30 s chirp with a hidden 12 ms torque lag, written into `dir`.
fn hidden_lag(dir: &std::path::Path) -> std::path::PathBuf {
    let tsv = dir.join("stand.tsv");
    propid_ok(&[
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
    ]);
    tsv
}

#[test]
fn sim_then_diagnose_finds_a_hidden_torque_lag() {
    let dir = tempfile::tempdir().unwrap();
    let tsv = hidden_lag(dir.path());
    let plot = dir.path().join("diag.svg");
    let out = propid_ok(&[
        "diagnose",
        tsv.to_str().unwrap(),
        "--format",
        "json",
        "--plot",
        plot.to_str().unwrap(),
    ]);
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
    let out = propid_ok(&["diagnose", tsv.to_str().unwrap()]);
    assert!(String::from_utf8(out.stdout)
        .unwrap()
        .contains("Nothing is wrong"));
}

#[test]
fn bad_input_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let back = dir.path().join("back.tsv");
    let mut text = String::from("t\tforce\tvelocity\tacceleration\n");
    for k in 0..600 {
        let t = if k == 300 { 0.0 } else { k as f64 * 0.002 };
        text += &format!("{t}\t0.01\t100\t0\n");
    }
    std::fs::write(&back, text).unwrap();
    let out = propid(&["diagnose", back.to_str().unwrap()], None);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("back.tsv") && err.contains("time goes backwards"),
        "{err}"
    );
    let out = propid(&["sim", "--lo", "0.9", "--hi", "0.1"], None);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("lo < hi"));
}

/// A clean simulated recording, each row's columns as numbers (ts_local, t, force, velocity,
/// acceleration, position).
fn clean_rows(dir: &std::path::Path) -> (String, Vec<Vec<f64>>) {
    common::simulated_rows(dir, 4)
}

/// Garbage in: each case gets "cannot judge: <why>", exit status 3, never a verdict.
#[test]
fn garbage_cannot_be_judged_exit_3() {
    let dir = tempfile::tempdir().unwrap();
    let (header, rows) = clean_rows(dir.path());
    assert_eq!(
        header,
        "ts_local\tt\tforce\tvelocity\tacceleration\tposition"
    );
    type Spoil = fn(&mut Vec<Vec<f64>>);
    let cases: [(&str, Spoil, &str); 4] = [
        (
            "zero_force",
            |r| r.iter_mut().for_each(|x| x[2] = 0.0),
            "force is zero",
        ),
        ("absurd", |r| r[1000][3] = 1e300, "velocity = 1e300"),
        (
            "milliseconds",
            |r| r.iter_mut().for_each(|x| x[1] *= 1000.0),
            "the time column looks like it is in ms, not seconds",
        ),
        (
            "short",
            |r| r.truncate(150),
            "the effects tested need at least",
        ),
    ];
    for (name, spoil, why) in cases {
        let mut r = rows.clone();
        spoil(&mut r);
        let path = dir.path().join(format!("{name}.tsv"));
        write_rows(&path, &header, &r);
        let out = propid(&["diagnose", path.to_str().unwrap()], None);
        let text = String::from_utf8_lossy(&out.stdout);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(3), "{name}: {text}{err}");
        assert!(
            text.contains("cannot judge: ") && text.contains(why),
            "{name}: {text}"
        );
        assert!(!text.contains("Nothing is wrong"), "{name}: {text}");
        assert!(
            err.contains(&format!("{name}.tsv: cannot judge")),
            "{name}: {err}"
        );
        let out = propid(
            &["diagnose", path.to_str().unwrap(), "--format", "json"],
            None,
        );
        assert_eq!(out.status.code(), Some(3));
        let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(j["verdict"]["kind"], "cannot_judge", "{name}");
    }
    let out = propid(&["diagnose", "--help"], None);
    assert!(String::from_utf8_lossy(&out.stdout).contains("3 cannot judge"));
}

#[test]
fn import_then_diagnose_a_real_log() {
    let dir = tempfile::tempdir().unwrap();
    let tsv = dir.path().join("f40.tsv");
    let log = common::repo().join("tests/data/esc_test_alspitz/autoquad/f40_steps_5-2.csv");
    let out = propid_ok(&[
        "import",
        "autoquad",
        log.to_str().unwrap(),
        "--kv",
        "1600",
        "-o",
        tsv.to_str().unwrap(),
    ]);
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("Kt = 60/(2π·kv)"),
        "the importer states its assumption"
    );
    let out = propid_ok(&["diagnose", tsv.to_str().unwrap(), "--format", "json"]);
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    // The F40 log as tests/tests/real_data.rs reads it: the span where the speed freezes at full
    // duty left out, a constant torque (Coulomb or its offset twin) and a telemetry lag named
    // (docs/REAL_DATA.md).
    assert_eq!(r["verdict"]["kind"], "ambiguous", "{r:#}");
    let named: Vec<&str> = r["effects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["name"].as_str().unwrap())
        .collect();
    assert_eq!(named, ["coulomb_friction", "force_sensor_lag"], "{r:#}");
    assert!(r["left_out"]["samples"].as_u64().is_some(), "{r:#}");
    let out = propid(&["import", "rcbench", "/nonexistent.csv"], None);
    assert_eq!(out.status.code(), Some(2));
}

/// `--compare`: a model the engineer asks about is fitted and scored beside the one named. On a
/// hidden 12 ms torque lag, a Coulomb friction in its place is what the data reject (the model
/// named preferred, by a gain the folds agree on), a force sensor's lag there fits with a sign no
/// sensor has (said, typed), the lag itself is the model named, and a name propid does not know
/// is refused before anything is read, naming the flag and the effects.
#[test]
fn compare_scores_a_model_asked_about_beside_the_one_named() {
    let dir = tempfile::tempdir().unwrap();
    let tsv = hidden_lag(dir.path());
    let tsv = tsv.to_str().unwrap();
    let json = |compare: &str| -> serde_json::Value {
        let out = propid_ok(&["diagnose", tsv, "--format", "json", "--compare", compare]);
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let r = json("coulomb_friction");
    let c = &r["compared"];
    assert_eq!(c["preferred"], "named", "{c}");
    assert_eq!(c["asked"][0], "coulomb_friction");
    assert_eq!(c["effects"][0]["name"], "coulomb_friction");
    let gain = &c["gain"];
    assert!(gain["mean"].as_f64().unwrap() < 0.0, "{gain}");
    assert_eq!(gain["folds_better"], 0, "{gain}");
    assert!(c["model"]["inertia"].as_f64().unwrap() > 0.0);
    // The run that tells a lag from a constant torque: a sweep of frequencies.
    assert_eq!(c["separating_run"]["pattern"], "chirp", "{c}");

    // A force sensor's lag in the torque lag's place fits with the sign no sensor can have: said
    // so, typed.
    let r = json("force_sensor_lag");
    let c = &r["compared"];
    assert_eq!(c["preferred"], "named", "{c}");
    assert_eq!(c["inadmissible"][0]["effect"], "force_sensor_lag", "{c}");
    assert_eq!(c["inadmissible"][0]["why"], "wrong_sign", "{c}");

    let r = json("torque_lag");
    assert_eq!(r["compared"]["preferred"], "same", "{}", r["compared"]);
    assert!(r["compared"]["separating_run"].is_null());
    let lag = r["compared"]["effects"][0]["value"].as_f64().unwrap();
    assert!((lag / 0.012 - 1.0).abs() < 0.05, "lag {lag}");

    let out = propid_ok(&["diagnose", tsv, "--compare", "coulomb_friction"]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("5. The model asked about (--compare coulomb_friction)")
            && text.contains("the data prefer the model named"),
        "{text}"
    );
    // Without the flag the report has no such section and the JSON's key is null.
    let out = propid_ok(&["diagnose", tsv, "--format", "json"]);
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(r["compared"].is_null(), "{}", r["compared"]);

    let out = propid(&["diagnose", tsv, "--compare", "torque_lag,viscous"], None);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--compare")
            && err.contains("unknown effect `viscous`")
            && err.contains("viscous_friction"),
        "{err}"
    );
    assert!(out.stdout.is_empty());
}
