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

/// One bad row costs one row (issue 26, item 5): the real F60 log with its first data row given
/// a stale time (the next rows restart near 0) loses that row only — the old importer dropped
/// every row until the clock passed the stale value (2,974 of 11,717) — and the dropped lines
/// are listed with their reasons.
#[test]
fn a_stale_first_row_costs_one_row() {
    let dir = tempfile::tempdir().unwrap();
    let log = repo().join("tests/data/esc_test_alspitz/rcbench/Log_2019-11-07_184325.csv");
    let text = std::fs::read_to_string(&log).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    // The time of the 2,975th data row, put into the first.
    let stale = lines[2975].split(',').next().unwrap().to_owned();
    let first = format!("{stale}{}", &lines[1][lines[1].find(',').unwrap()..]);
    lines[1] = &first;
    let edited = dir.path().join("edited.csv");
    std::fs::write(&edited, lines.join("\n") + "\n").unwrap();
    let count = |csv: &std::path::Path| {
        let tsv = dir.path().join("out.tsv");
        let out = propid(
            &[
                "import",
                "rcbench",
                csv.to_str().unwrap(),
                "-o",
                tsv.to_str().unwrap(),
            ],
            None,
        );
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "{err}");
        (
            std::fs::read_to_string(&tsv).unwrap().lines().count() - 1,
            err,
        )
    };
    let (original, _) = count(&log);
    let (rows, err) = count(&edited);
    assert!(stale.parse::<f64>().unwrap() > 20.0, "{stale}");
    assert_eq!(rows, original, "{err}");
    assert_eq!(rows, 11717);
    assert!(
        err.contains("8 of 11725 rows dropped, each for itself: line 2 (the time is later than the rows after it (stale))"),
        "{err}"
    );
}

/// A stand's own export given to fit, diagnose or report names the importer to use.
#[test]
fn a_raw_export_names_its_importer() {
    let data = repo().join("tests/data/esc_test_alspitz");
    let rc = data.join("rcbench/Log_2019-11-05_171350.csv");
    let aq = data.join("autoquad/f40_steps_5-2.csv");
    for (file, want) in [
        (&rc, "this is an RCbenchmark/Tyto CSV export, not propid's TSV: convert it first with `propid import rcbench FILE -o run.tsv`"),
        (&aq, "this is an AutoQuad ESC32 telemetry CSV, not propid's TSV: convert it first with `propid import autoquad FILE --kv KV -o run.tsv` (KV: the motor's rpm per volt)"),
    ] {
        let f = file.to_str().unwrap();
        for args in [vec!["fit", f], vec!["diagnose", f], vec!["report", f, "-o", "/dev/null"]] {
            let out = propid(&args, None);
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
            assert!(err.contains(&format!("{f}: line 1: {want}")), "{args:?}: {err}");
        }
    }
}

/// Velocity glitches on a real log are announced with their lines; `--despike` sets exactly those
/// samples' velocity to NaN. Copied lines are dropped and announced.
#[test]
fn glitches_and_copies_are_announced() {
    let dir = tempfile::tempdir().unwrap();
    let log = repo().join("tests/data/esc_test_alspitz/rcbench/Log_2019-11-07_184325.csv");
    let tsv = dir.path().join("rc.tsv");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "import",
            "rcbench",
            log.to_str().unwrap(),
            "-o",
            tsv.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let out = propid(&args, None);
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "{err}");
        let nan = std::fs::read_to_string(&tsv)
            .unwrap()
            .lines()
            .skip(1)
            .filter(|l| l.split('\t').nth(3) == Some("nan"))
            .count();
        (err, nan)
    };
    let (err, nan) = run(&[]);
    let warning = err
        .lines()
        .find(|l| l.contains("straight back"))
        .expect(&err);
    assert!(
        warning.starts_with("warning: `Motor Electrical Speed (RPM)`: 19 samples"),
        "{warning}"
    );
    assert!(warning.contains("--despike sets them to NaN"), "{warning}");
    assert_eq!(nan, 0);
    let (err, nan) = run(&["--despike"]);
    assert!(
        err.contains("their velocity is NaN in the TSV (--despike)"),
        "{err}"
    );
    assert_eq!(nan, 19);
    // Every line written twice.
    let csv = dir.path().join("twice.csv");
    let mut text = String::from("Time (s),Torque (N·m),Motor Optical Speed (RPM)\n");
    for k in 0..300 {
        let line = format!("{},{},{}\n", k as f64 * 0.01, 0.01, 1000 + (k * 37) % 11);
        text += &line;
        text += &line;
    }
    std::fs::write(&csv, text).unwrap();
    let out = propid(&["import", "rcbench", csv.to_str().unwrap()], None);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("warning: 300 of 600 lines repeat the line before them exactly")
            && err.contains("√2"),
        "{err}"
    );
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 301);
}

/// `fit` and `report` accept what `import rcbench` writes (issue 26, item 5): with the load-cell
/// torque in one row of twenty, the seed's window (the last run of complete rows) was one row
/// ("only 1 usable samples"); the complete rows are fitted instead, and said so.
#[test]
fn fit_and_report_accept_an_imported_load_cell_log() {
    let dir = tempfile::tempdir().unwrap();
    let log = repo().join("tests/data/esc_test_alspitz/rcbench/Log_2019-11-07_184325.csv");
    let tsv = dir.path().join("rc.tsv");
    let out = propid(
        &[
            "import",
            "rcbench",
            log.to_str().unwrap(),
            "-o",
            tsv.to_str().unwrap(),
        ],
        None,
    );
    assert!(out.status.success());
    let t = tsv.to_str().unwrap();
    let out = propid(&["fit", t], None);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("rc.tsv: only 620 of 11717 rows have t, force, velocity and acceleration, and they come one or two at a time")
            && err.contains("would hold 1 row(s); fitted instead are the 559 complete rows"),
        "{err}"
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("samples: 559"));
    // The steady plateaus cannot identify J: said, not printed as a precise value.
    assert!(err.contains("the mass sits on its bound"), "{err}");
    let html = dir.path().join("rc.html");
    let out = propid(&["report", t, "-o", html.to_str().unwrap()], None);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.contains("fitted instead are the 559 complete rows"));

    // Where the rows with a torque sample do carry dynamics, the fit of them is the fit of the
    // whole record: a simulated stand whose force is kept in one row of ten only.
    let full = dir.path().join("full.tsv");
    let out = propid(
        &[
            "sim",
            "--duration",
            "60",
            "--rate",
            "500",
            "-o",
            full.to_str().unwrap(),
        ],
        None,
    );
    assert!(out.status.success());
    let text = std::fs::read_to_string(&full).unwrap();
    let mut sparse = String::new();
    for (k, line) in text.lines().enumerate() {
        let mut f: Vec<&str> = line.split('\t').collect();
        if k > 0 && k % 10 != 0 {
            f[2] = "nan";
        }
        sparse += &f.join("\t");
        sparse.push('\n');
    }
    let thin = dir.path().join("thin.tsv");
    std::fs::write(&thin, sparse).unwrap();
    let value = |yaml: &[u8], key: &str| -> f64 {
        let text = String::from_utf8_lossy(yaml);
        let line = text
            .lines()
            .find(|l| l.starts_with(key))
            .unwrap()
            .to_owned();
        line.split_whitespace().nth(1).unwrap().parse().unwrap()
    };
    let a = propid(&["fit", full.to_str().unwrap()], None);
    let b = propid(&["fit", thin.to_str().unwrap()], None);
    assert!(b.status.success(), "{}", String::from_utf8_lossy(&b.stderr));
    for key in ["mass:", "c2:"] {
        let (x, y) = (value(&a.stdout, key), value(&b.stdout, key));
        assert!((x - y).abs() < 0.01 * x, "{key} {x} vs {y}");
    }
    // 3000 complete rows, the seed's cut int(0.1 · 2999) = 299 of them.
    assert_eq!(value(&b.stdout, "samples:"), 2701.0);
}
