//! `propid sim --stand mechanism` end to end: it writes propid's TSV (with an optional setpoint
//! column that `fit` ignores), `fit` recovers the stand's J and c2 from a clean run, and bad flags
//! exit 2 naming the flag.

mod common;

use common::{diagnose_json, propid, propid_ok, yaml_value};

#[test]
fn mechanism_stand_writes_a_tsv_that_fit_reads() {
    let dir = tempfile::tempdir().unwrap();
    let tsv = dir.path().join("mech.tsv");
    propid_ok(&[
        "sim",
        "--stand",
        "mechanism",
        "--pattern",
        "chirp",
        "--duration",
        "20",
        "--rate",
        "1000",
        "--noise-force",
        "0",
        "--noise-velocity",
        "0",
        "--noise-acceleration",
        "0",
        "--jitter",
        "0",
        "--write-setpoint",
        "-o",
        tsv.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&tsv).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "ts_local\tt\tforce\tvelocity\tacceleration\tposition\tsetpoint"
    );
    assert_eq!(lines.count(), 20_001);

    let out = propid_ok(&["fit", tsv.to_str().unwrap()]);
    let yaml = String::from_utf8(out.stdout).unwrap();
    // The clean mechanism stand obeys the seed's equation exactly: J = 2e-5, c2 = 1.5e-8.
    assert!(
        (yaml_value(&yaml, "mass") / 2e-5 - 1.0).abs() < 1e-6,
        "{yaml}"
    );
    assert!(
        (yaml_value(&yaml, "c2") / 1.5e-8 - 1.0).abs() < 1e-6,
        "{yaml}"
    );
}

#[test]
fn mechanism_flags_reach_the_stand() {
    // A 100 rad/s current loop reported as demand: the felt torque lags, so the seed's fit no
    // longer finds the true inertia exactly; a current sense that reports the measured current
    // keeps it exact.
    let dir = tempfile::tempdir().unwrap();
    let fit_mass = |report: &str| {
        let tsv = dir.path().join(format!("{report}.tsv"));
        propid_ok(&[
            "sim",
            "--stand",
            "mechanism",
            "--duration",
            "20",
            "--pattern",
            "chirp",
            "--noise-force",
            "0",
            "--noise-velocity",
            "0",
            "--noise-acceleration",
            "0",
            "--current-loop-bandwidth",
            "100",
            "--report",
            report,
            "-o",
            tsv.to_str().unwrap(),
        ]);
        let out = propid(&["fit", tsv.to_str().unwrap()], None);
        yaml_value(&String::from_utf8(out.stdout).unwrap(), "mass")
    };
    let measured = fit_mass("current");
    let demand = fit_mass("demand");
    assert!((measured / 2e-5 - 1.0).abs() < 1e-3, "{measured}");
    assert!((demand / 2e-5 - 1.0).abs() > 0.01, "{demand}");
}

#[test]
fn bad_mechanism_flags_exit_2_naming_the_flag() {
    for (args, needle) in [
        (
            vec!["sim", "--stand", "mechanism", "--torque-lag", "0.01"],
            "--torque-lag is a formula-stand effect",
        ),
        (
            vec!["sim", "--current-loop-bandwidth", "100"],
            "--current-loop-bandwidth applies only to --stand mechanism",
        ),
        (
            vec!["sim", "--stand", "mechanism", "--rate", "0"],
            "--rate must be",
        ),
        (
            vec!["sim", "--stand", "mechanism", "--observer-hz=-5"],
            "--observer-hz must be",
        ),
    ] {
        let out = propid(&args, None);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("OutOfRange"), "{err}");
    }
}

/// The loop a user follows: a viscous bearing friction on propid's chirp (lo 0.1, speeds
/// 800–2450 rad/s) is ambiguous among the drag shapes; `diagnose` says so, exits 0, and names in
/// its JSON the `propid drive` run that would separate them; that run (steps down to lo 0.02),
/// simulated on the same stand, gets the friction named alone with its value.
#[test]
fn an_ambiguous_report_names_the_run_that_resolves_it() {
    let dir = tempfile::tempdir().unwrap();
    let sim = |name: &str, extra: &[&str]| {
        let tsv = dir.path().join(name);
        let mut args = vec![
            "sim",
            "--stand",
            "mechanism",
            "--c1",
            "2e-6",
            "--duration",
            "60",
            "--rate",
            "250",
            "--seed",
            "3",
        ];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["-o", tsv.to_str().unwrap()]);
        let out = propid(&args, None);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        tsv
    };
    let first = diagnose_json(&sim("chirp.tsv", &["--pattern", "chirp"]));
    assert_eq!(first["verdict"]["kind"], "ambiguous", "{first:#}");
    let a = &first["ambiguities"][0];
    assert!(
        a["between"]
            .as_array()
            .unwrap()
            .iter()
            .any(|n| n == "viscous_friction"),
        "{a:#}"
    );
    let run = &a["separating_run"];
    assert_eq!(run["pattern"], "steps", "{a:#}");
    let (lo, hi) = (run["lo"].as_f64().unwrap(), run["hi"].as_f64().unwrap());
    let (lo, hi) = (lo.to_string(), hi.to_string());
    let second = diagnose_json(&sim(
        "advised.tsv",
        &["--pattern", "steps", "--lo", &lo, "--hi", &hi],
    ));
    assert_eq!(second["verdict"]["kind"], "explained", "{second:#}");
    let effects = second["effects"].as_array().unwrap();
    assert_eq!(effects.len(), 1, "{second:#}");
    assert_eq!(effects[0]["name"], "viscous_friction");
    let value = effects[0]["value"].as_f64().unwrap();
    assert!((value / 2e-6 - 1.0).abs() < 0.05, "{value}");
}

#[test]
fn a_held_load_cell_is_read_as_a_delay_from_its_updates() {
    // A load cell (100 Hz natural frequency, damping 0.2) read at 80 Hz, its readings repeated in
    // 500 Hz rows. Each reading first shows in the row after it, 1 ms late on average, and the
    // cell itself delays by 2ζ/ω_n: force_sensor_lag = 0.4/(2π·100) + 1/(2·500) = 1.64 ms, and J
    // as the stand has it (read row by row, the staircase was a lag of 6–12 ms and J 2.5 % high).
    let dir = tempfile::tempdir().unwrap();
    let tsv = dir.path().join("cell.tsv");
    propid_ok(&[
        "sim",
        "--stand",
        "mechanism",
        "--report",
        "load-cell",
        "--pattern",
        "chirp",
        "--duration",
        "60",
        "--rate",
        "500",
        "--seed",
        "3",
        "-o",
        tsv.to_str().unwrap(),
    ]);
    let report = diagnose_json(&tsv);
    let effects = report["effects"].as_array().unwrap();
    assert_eq!(effects.len(), 1, "{report:#}");
    assert_eq!(effects[0]["name"], "force_sensor_lag", "{report:#}");
    let form = effects[0]["lag_form"].as_str().unwrap();
    assert!(form == "delay" || form == "first_order", "{form}");
    let expected = 0.4 / (std::f64::consts::TAU * 100.0) + 0.5 / 500.0;
    let lag = effects[0]["value"].as_f64().unwrap();
    assert!((lag / expected - 1.0).abs() < 0.1, "{lag} for {expected}");
    let notes = report["notes"].as_array().unwrap();
    assert!(
        notes
            .iter()
            .any(|n| n.as_str().unwrap().starts_with("the force updates every")),
        "{report:#}"
    );
    let mass = report["extended"]["inertia"].as_f64().unwrap();
    assert!((mass / 2e-5 - 1.0).abs() < 0.02, "{mass}");
}

/// A lag the acceleration equation barely shows, end to end: a 70 Hz velocity observer (a PLL on
/// a 4096-count angle) delays the velocity and acceleration by 2ζ/ω_n = 3.2 ms, which the seed's
/// 0.5 Hz sine hardly shows in the acceleration equation (held-out gain under the 3 % an effect
/// needs from it alone), and the simulated velocity shows clearly: `diagnose` names the lag, at
/// its value, and the chirp names it too.
#[test]
fn a_lag_the_equation_barely_shows_is_named_by_the_simulation() {
    let dir = tempfile::tempdir().unwrap();
    let sim = |pattern: &str| {
        let tsv = dir.path().join(format!("{pattern}.tsv"));
        propid_ok(&[
            "sim",
            "--stand",
            "mechanism",
            "--observer-hz",
            "70",
            "--counts-per-rev",
            "4096",
            "--pattern",
            pattern,
            "--rate",
            "500",
            "--duration",
            "120",
            "--seed",
            "1",
            "-o",
            tsv.to_str().unwrap(),
        ]);
        tsv
    };
    let lag = 2.0 * std::f64::consts::FRAC_1_SQRT_2 / (std::f64::consts::TAU * 70.0);
    let delay_of = |e: &serde_json::Value| {
        e["lag_delay_s"]
            .as_f64()
            .unwrap_or_else(|| panic!("not a lag: {e:#}"))
    };
    let first = diagnose_json(&sim("sine"));
    let effects = first["effects"].as_array().unwrap();
    assert_eq!(effects.len(), 1, "{first:#}");
    let value = delay_of(&effects[0]);
    assert!((value / lag - 1.0).abs() < 0.1, "{value} for {lag}");
    let gain = effects[0]["cv_gain_percent"].as_f64().unwrap();
    assert!(gain < 3.0, "{gain}");
    let second = diagnose_json(&sim("chirp"));
    assert_eq!(second["verdict"]["kind"], "explained", "{second:#}");
    let effects = second["effects"].as_array().unwrap();
    assert_eq!(effects.len(), 1, "{second:#}");
    let value = delay_of(&effects[0]);
    assert!((value / lag - 1.0).abs() < 0.1, "{value} for {lag}");
    assert!(
        second["near_misses"].as_array().unwrap().is_empty(),
        "{second:#}"
    );
}

#[test]
fn speed_flags_take_rpm() {
    // 10 rad/s is 95.4930 rpm: the two runs are the same simulation, byte for byte.
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, flags: &[&str]| {
        let tsv = dir.path().join(name);
        let base = [
            "sim",
            "--stand",
            "mechanism",
            "--duration",
            "1",
            "--breakaway",
            "0.01",
        ];
        let out = propid(
            &[&base[..], flags, &["-o", tsv.to_str().unwrap()]].concat(),
            None,
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        std::fs::read(tsv).unwrap()
    };
    let rpm = 10.0 * 60.0 / std::f64::consts::TAU;
    assert_eq!(
        run(
            "rad.tsv",
            &[
                "--stribeck-speed",
                "10",
                "--cq-reference-speed",
                "1500rad/s"
            ]
        ),
        run(
            "rpm.tsv",
            &[
                "--stribeck-speed",
                &format!("{rpm}rpm"),
                "--cq-reference-speed",
                &format!("{}rpm", 150.0 * rpm)
            ]
        )
    );
    let out = propid(&["sim", "--noise-velocity", "fast"], None);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("`fast` is not a speed"));
}
