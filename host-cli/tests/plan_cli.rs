//! `propid plan` writes a pattern file that `propid sim --pattern-file` plays; bad priors and bad
//! files are clear errors.

mod common;

#[test]
fn plan_then_sim_plays_the_planned_pattern() {
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("plan.json");
    let out = common::propid(
        &[
            "plan",
            "--inertia",
            "2e-5",
            "--c2",
            "1.5e-8",
            "--max-torque",
            "0.1",
            "--duration",
            "60",
            "-o",
            plan.to_str().unwrap(),
        ],
        None,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("predicted relative standard error"), "{err}");
    assert!(
        err.contains("coulomb_friction vs torque_lag: separable"),
        "{err}"
    );
    assert!(
        err.contains("seed sine: coulomb_friction vs torque_lag: NOT separable"),
        "{err}"
    );
    let text = std::fs::read_to_string(&plan).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let duration = v["excitation"]["duration"].as_f64().unwrap();
    assert!(duration > 0.0 && duration <= 60.0, "{duration}");
    let tsv = dir.path().join("run.tsv");
    let out = common::propid(
        &[
            "sim",
            "--pattern-file",
            plan.to_str().unwrap(),
            "--rate",
            "100",
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
    let rows = std::fs::read_to_string(&tsv).unwrap().lines().count() - 1;
    assert_eq!(rows as f64, (duration * 100.0).floor());
}

#[test]
fn bad_priors_and_pattern_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, "{\n  \"excitation\": 1\n}\n").unwrap();
    for (args, want) in [
        (
            vec!["plan", "--max-torque", "0.1"],
            "give the prior either as --fit FIT.yaml or as --inertia and --c2",
        ),
        (
            vec![
                "plan",
                "--inertia=-1",
                "--c2",
                "1e-8",
                "--max-torque",
                "0.1",
            ],
            "inertia must be positive",
        ),
        (
            vec!["sim", "--pattern-file", bad.to_str().unwrap()],
            "bad.json: line 2",
        ),
    ] {
        let out = common::propid(&args, None);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {err}");
    }
}
