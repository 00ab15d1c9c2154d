//! `propid fit` end to end from the command line: formats, stdin, plots, and bad input.

mod common;

use common::{propid, propid_ok, yaml_value};

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
    let out = propid_ok(&["fit", path.to_str().unwrap(), "--diameter", "0.2"]);
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
    // Exact samples: the standard error is round-off, not zero by construction.
    let se = v["mass_stderr"].as_f64().unwrap();
    assert!(se.is_finite() && se < 1e-6 * 0.5, "mass_stderr {se}");
    assert_eq!(v["at_bound"][0], "c1");
}

/// A reproducible standard normal deviate (xorshift64* and Box–Muller).
fn gauss(state: &mut u64) -> f64 {
    let mut uniform = || {
        *state ^= *state >> 12;
        *state ^= *state << 25;
        *state ^= *state >> 27;
        (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    };
    let (u1, u2) = (uniform().max(1e-300), uniform());
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

#[test]
fn reported_standard_errors_match_the_scatter_of_repeated_fits() {
    // J = 0.5, c1 = 0.2 (free: --c1-max 1), c2 = 0.02; white noise of 0.5 rad/s² on the logged
    // acceleration. 40 independent noise draws: the standard deviation of the fitted J and c2
    // must match the standard error propid reports (the scatter of a standard deviation over
    // 40 draws is ±11 %, so [0.7, 1.4] is a 3-sigma band).
    let (j, c1, c2, sigma) = (0.5, 0.2, 0.02, 0.5);
    let dir = tempfile::tempdir().unwrap();
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let (mut js, mut c2s, mut j_se, mut c2_se) = (vec![], vec![], 0.0, 0.0);
    let draws = 40;
    for k in 0..draws {
        let mut s = String::from("t\tforce\tvelocity\tacceleration\n");
        let (mut w, dt) = (10.0f64, 0.005);
        for i in 0..3000 {
            let t = i as f64 * dt;
            let q = 5.0 + 4.0 * (std::f64::consts::TAU * t / 2.0).sin();
            let a = (q - c1 * w - c2 * w * w.abs()) / j;
            s += &format!("{t}\t{q}\t{w}\t{}\n", a + sigma * gauss(&mut state));
            w += a * dt;
        }
        let path = dir.path().join(format!("n{k}.tsv"));
        std::fs::write(&path, s).unwrap();
        let out = propid_ok(&[
            "fit",
            path.to_str().unwrap(),
            "--c1-max",
            "1",
            "--format",
            "json",
        ]);
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        js.push(v["mass"].as_f64().unwrap());
        c2s.push(v["c2"].as_f64().unwrap());
        j_se += v["mass_stderr"].as_f64().unwrap() / draws as f64;
        c2_se += v["c2_stderr"].as_f64().unwrap() / draws as f64;
    }
    let spread = |x: &[f64]| {
        let m = x.iter().sum::<f64>() / x.len() as f64;
        (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (x.len() - 1) as f64).sqrt()
    };
    for (name, x, se, truth) in [("J", &js, j_se, j), ("c2", &c2s, c2_se, c2)] {
        let sd = spread(x);
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        eprintln!("{name}: mean {mean}, scatter {sd}, reported stderr {se}");
        assert!(
            (0.7..1.4).contains(&(sd / se)),
            "{name}: scatter {sd} vs reported standard error {se}"
        );
        // Unbiased: the mean of 40 fits is within 3 standard errors of the mean of the truth.
        assert!(
            (mean - truth).abs() < 3.0 * se / (draws as f64).sqrt(),
            "{name}: mean {mean} vs {truth}"
        );
    }
}

#[test]
fn writes_a_plot() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.tsv");
    std::fs::write(&path, synthetic(2000, false)).unwrap();
    let svg = dir.path().join("fit.svg");
    propid_ok(&[
        "fit",
        path.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("measured") && text.contains("force"));
}

#[test]
fn bad_input_names_the_place_and_exits_2() {
    let cases: [(&str, &str); 5] = [
        ("", "empty input"),
        ("t\tforce\tvelocity\n1\t2\t3\n", "no column `acceleration`"),
        (
            "t\tforce\tvelocity\tacceleration\n0\t1\t2\t3\n0.1\t1\tfast\t3\n",
            "line 3, column `velocity`: `fast`",
        ),
        ("t\tforce\tvelocity\tacceleration\n", "no data rows"),
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

/// `synthetic` with one row changed by `edit(row index, [t, force, velocity, acceleration])`.
fn edited(rows: usize, edit: impl Fn(usize, &mut [f64; 4])) -> String {
    let mut out = String::from("t\tforce\tvelocity\tacceleration\n");
    for (i, line) in synthetic(rows, false).lines().skip(1).enumerate() {
        let mut v = [0.0; 4];
        for (slot, field) in v.iter_mut().zip(line.split('\t')) {
            *slot = field.parse().unwrap();
        }
        edit(i, &mut v);
        out += &format!("{}\t{}\t{}\t{}\n", v[0], v[1], v[2], v[3]);
    }
    out
}

fn fit_text(dir: &std::path::Path, name: &str, text: &str, flags: &[&str]) -> std::process::Output {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    let mut args = vec!["fit", path.to_str().unwrap()];
    args.extend_from_slice(flags);
    propid(&args, None)
}

#[test]
fn one_huge_value_names_its_line() {
    let dir = tempfile::tempdir().unwrap();
    // Row 500 (line 502) has a force of 1e200: its square overflows.
    let text = edited(2000, |i, v| {
        if i == 500 {
            v[1] = 1e200;
        }
    });
    let out = fit_text(dir.path(), "huge.tsv", &text, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("huge.tsv: line 502") && err.contains("overflow"),
        "{err}"
    );
    assert!(!err.contains("zero in every sample"), "{err}");
    assert!(out.stdout.is_empty());
}

#[test]
fn constant_velocity_cannot_be_judged() {
    let dir = tempfile::tempdir().unwrap();
    let text = edited(2000, |_, v| {
        v[1] = 2.0;
        v[2] = 100.0;
        v[3] = 0.0;
    });
    let out = fit_text(dir.path(), "flat.tsv", &text, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    // Exit status 3, as for `diagnose`: the data cannot support a verdict.
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(
        err.contains("flat.tsv: cannot judge: the data cannot identify"),
        "{err}"
    );
    assert!(out.stdout.is_empty(), "no numbers printed");
    // Too few samples likewise.
    let out = fit_text(
        dir.path(),
        "two.tsv",
        "t\tforce\tvelocity\tacceleration\n0\t1\t2\t3\n1\t1\t2\t3\n",
        &[],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(
        err.contains("two.tsv: cannot judge: only 2 usable samples"),
        "{err}"
    );
}

#[test]
fn nan_mid_file_keeps_the_seeds_window_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    // Row 1000 (line 1002) has a NaN velocity: the seed fits rows 1001.. only.
    let text = edited(2000, |i, v| {
        if i == 1000 {
            v[2] = f64::NAN;
        }
    });
    let out = fit_text(dir.path(), "hole.tsv", &text, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let yaml = String::from_utf8(out.stdout).unwrap();
    // The last run is rows 1001..=1999 (999 rows); the seed then drops int(0.1 · 998) = 99.
    assert_eq!(yaml_value(&yaml, "samples"), 900.0, "{yaml}");
    assert!(
        err.contains("1000 complete rows dropped by the seed's trimming")
            && err.contains("line 1002")
            && err.contains("`velocity`"),
        "{err}"
    );
    // A file whose head lacks values drops no complete row: no warning.
    let text = edited(2000, |i, v| {
        if i < 3 {
            v[3] = f64::NAN;
        }
    });
    let out = fit_text(dir.path(), "head.tsv", &text, &[]);
    assert!(out.status.success());
    assert!(!String::from_utf8_lossy(&out.stderr).contains("dropped"));
}

#[test]
fn infinite_bounds_are_accepted_alike_and_bad_geometry_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let text = synthetic(2000, false);
    let finite = fit_text(
        dir.path(),
        "a.tsv",
        &text,
        &["--c2-max", "1e30", "--c1-max", "1e30"],
    );
    assert!(finite.status.success());
    for flags in [
        &["--c2-max", "inf"][..],
        &["--mass-max", "inf"],
        &["--c1-max", "inf", "--c2-max", "inf"],
    ] {
        let out = fit_text(dir.path(), "a.tsv", &text, flags);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{flags:?}: {err}");
        let yaml = String::from_utf8(out.stdout).unwrap();
        assert!(
            (yaml_value(&yaml, "mass") / 0.5 - 1.0).abs() < 1e-9,
            "{flags:?}: {yaml}"
        );
        assert!(
            (yaml_value(&yaml, "c2") / 0.02 - 1.0).abs() < 1e-9,
            "{flags:?}: {yaml}"
        );
    }
    // Refused before the data is read: the file does not exist, the message is about the flag.
    for (flags, want) in [
        (&["--diameter", "0"][..], "diameter"),
        (&["--diameter", "-0.1"], "diameter"),
        (&["--diameter", "nan"], "diameter"),
        (&["--diameter", "inf"], "diameter"),
        (&["--density", "-1"], "density"),
        (&["--density", "0"], "density"),
        (&["--c2-max", "-1"], "c2_max"),
        (&["--mass-min", "nan"], "mass"),
    ] {
        let mut args = vec!["fit", "/nonexistent/never-read.tsv"];
        args.extend_from_slice(flags);
        let out = propid(&args, None);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{flags:?}: {err}");
        assert!(
            err.contains(want) && !err.contains("never-read"),
            "{flags:?}: {err}"
        );
    }
}

/// Every number propid prints in YAML must be a float to YAML 1.1 (PyYAML), as the seed's were.
#[test]
#[ignore = "needs python3 with PyYAML (ci/steps/35-fit-pyyaml.sh runs it)"]
fn yaml_numbers_are_floats_to_pyyaml() {
    let dir = tempfile::tempdir().unwrap();
    let out = fit_text(
        dir.path(),
        "a.tsv",
        &synthetic(2000, false),
        &["--diameter", "0.2"],
    );
    assert!(out.status.success());
    let check = std::process::Command::new("python3")
        .args([
            "-c",
            "import sys, yaml\n\
             d = yaml.safe_load(sys.stdin)\n\
             bad = [k for k, v in d.items() if k not in ('samples', 'at_bound') and type(v) is not float]\n\
             assert not bad, (bad, d)\n\
             assert d['c1'] == 0.0 and abs(d['mass'] / 0.5 - 1) < 1e-9, d\n\
             print(len(d))",
        ])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    use std::io::Write;
    check
        .stdin
        .as_ref()
        .unwrap()
        .write_all(&out.stdout)
        .unwrap();
    let result = check.wait_with_output().unwrap();
    assert!(
        result.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&result.stderr)
    );
}
