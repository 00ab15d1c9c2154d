//! `propid fit` end to end from the command line: formats, stdin, plots, and bad input.

mod common;

use common::{propid, yaml_value};

/// A clean synthetic file: J = 0.5, c2 = 0.02 driven by a sinusoidal torque (exact samples).
fn synthetic(rows: usize, with_position: bool) -> String {
    let (j, c2) = (0.5, 0.02);
    let mut s = String::from(if with_position {
        "ts_local\tt\tforce\tvelocity\tacceleration\tposition\textra\n"
    } else {
        "t\tforce\tvelocity\tacceleration\n"
    });
    let (mut w, dt) = (10.0f64, 0.005);
    for i in 0..rows {
        let t = i as f64 * dt;
        let q = 5.0 + 4.0 * (std::f64::consts::TAU * t / 2.0).sin();
        let a = (q - c2 * w * w.abs()) / j;
        if with_position {
            s += &format!("{}\t{t}\t{q}\t{w}\t{a}\t0.0\tfoo\n", 100.0 + t);
        } else {
            s += &format!("{t}\t{q}\t{w}\t{a}\n");
        }
        w += a * dt;
    }
    s
}

#[test]
fn fits_from_file_and_stdin_in_yaml_and_json() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.tsv");
    std::fs::write(&path, synthetic(3000, true)).unwrap();
    let out = propid(&["fit", path.to_str().unwrap(), "--diameter", "0.2"], None);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let yaml = String::from_utf8(out.stdout).unwrap();
    assert!(
        (yaml_value(&yaml, "mass") / 0.5 - 1.0).abs() < 1e-9,
        "{yaml}"
    );
    assert!(
        (yaml_value(&yaml, "c2") / 0.02 - 1.0).abs() < 1e-9,
        "{yaml}"
    );
    let cq = yaml_value(&yaml, "c_q");
    let want = 4.0 * std::f64::consts::PI.powi(2) * 0.02 / (1.225 * 0.2f64.powi(5));
    assert!((cq / want - 1.0).abs() < 1e-6, "{cq} vs {want}");
    // The seed keeps rows int(0.1 · 2999) = 299 ..= 2999.
    assert_eq!(yaml_value(&yaml, "samples"), 2701.0, "the seed's 10 % trim");

    let out = propid(
        &["fit", "--format", "json"],
        Some(synthetic(3000, false).as_bytes()),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!((v["mass"].as_f64().unwrap() / 0.5 - 1.0).abs() < 1e-9);
    assert!(v["mass_stderr"].as_f64().unwrap() >= 0.0);
    assert_eq!(v["at_bound"][0], "c1");
}

#[test]
fn writes_a_plot() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.tsv");
    std::fs::write(&path, synthetic(2000, false)).unwrap();
    let svg = dir.path().join("fit.svg");
    let out = propid(
        &[
            "fit",
            path.to_str().unwrap(),
            "--plot",
            svg.to_str().unwrap(),
        ],
        None,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("measured") && text.contains("force"));
}

#[test]
fn bad_input_names_the_place_and_exits_2() {
    let cases: [(&str, &str); 6] = [
        ("", "empty input"),
        (
            "t\tforce\tvelocity\n1\t2\t3\n",
            "missing column `acceleration`",
        ),
        (
            "t\tforce\tvelocity\tacceleration\n0\t1\t2\t3\n0.1\t1\tfast\t3\n",
            "line 3, column `velocity`: `fast`",
        ),
        ("t\tforce\tvelocity\tacceleration\n", "no data rows"),
        (
            "t\tforce\tvelocity\tacceleration\n0\t1\t2\t3\n1\t1\t2\t3\n",
            "only",
        ),
        (
            "t\tforce\tvelocity\tacceleration\nnan\tnan\tnan\tnan\ninf\t1\t1\t1\n",
            "no row has finite",
        ),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (k, (text, want)) in cases.iter().enumerate() {
        let path = dir.path().join(format!("bad{k}.tsv"));
        std::fs::write(&path, text).unwrap();
        let out = propid(&["fit", path.to_str().unwrap()], None);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "case {k}: {err}");
        assert!(err.contains(want), "case {k}: `{err}` lacks `{want}`");
        assert!(
            err.contains(&format!("bad{k}.tsv")),
            "case {k} names the file: {err}"
        );
        assert!(!err.contains("panicked"), "{err}");
        assert!(out.stdout.is_empty());
    }
    // Standard input is named as such.
    let out = propid(&["fit"], Some(b"t\tforce\n"));
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("<stdin>"));
    // A missing file.
    let out = propid(&["fit", "/nonexistent/x.tsv"], None);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/x.tsv"));
    // Invalid bounds.
    let path = dir.path().join("ok.tsv");
    std::fs::write(&path, synthetic(500, false)).unwrap();
    let out = propid(
        &[
            "fit",
            path.to_str().unwrap(),
            "--mass-min",
            "2",
            "--mass-max",
            "1",
        ],
        None,
    );
    assert_eq!(out.status.code(), Some(2));
}
