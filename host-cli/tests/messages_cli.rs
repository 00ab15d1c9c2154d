//! What reaches a user when writing fails: the path named, the operating system's message once,
//! never Rust's debug form.

mod common;

use common::propid;

/// A clean synthetic file the fit and diagnose accept.
fn synthetic() -> String {
    let (j, c2) = (0.5, 0.02);
    let mut s = String::from("t\tforce\tvelocity\tacceleration\n");
    let (mut w, dt) = (10.0f64, 0.005);
    for i in 0..3000 {
        let t = i as f64 * dt;
        let q = 5.0 + 4.0 * (std::f64::consts::TAU * t / 2.0).sin();
        let a = (q - c2 * w * w.abs()) / j;
        s += &format!("{t}\t{q}\t{w}\t{a}\n");
        w += a * dt;
    }
    s
}

#[track_caller]
fn clean(err: &str, path: &str, os: &str) {
    assert!(err.contains(path), "the path is named: {err}");
    assert_eq!(err.matches(os).count(), 1, "the OS error once: {err}");
    for debug in [
        "Os {",
        "BackendError",
        "DrawingError",
        "ImageError",
        "Some(",
        "kind:",
    ] {
        assert!(!err.contains(debug), "debug text `{debug}` in: {err}");
    }
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn unwritable_plots_name_the_path_in_words() {
    let dir = tempfile::tempdir().unwrap();
    let tsv = dir.path().join("a.tsv");
    std::fs::write(&tsv, synthetic()).unwrap();
    let tsv = tsv.to_str().unwrap();
    for cmd in ["fit", "diagnose"] {
        for ext in ["svg", "png", "html"] {
            let plot = format!("/nonexistent/dir/plot.{ext}");
            let out = propid(&[cmd, tsv, "--plot", &plot], None);
            let err = String::from_utf8_lossy(&out.stderr);
            assert_ne!(out.status.code(), Some(0), "{cmd} {ext}: {err}");
            clean(&err, &plot, "No such file or directory");
            assert!(err.contains("cannot write the plot"), "{err}");
        }
        let out = propid(&[cmd, tsv, "--plot", "/tmp/x.pdf"], None);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("/tmp/x.pdf") && err.contains("unknown plot format `pdf`"),
            "{err}"
        );
    }
}

#[test]
fn a_full_disk_names_the_output_once() {
    if !std::path::Path::new("/dev/full").exists() {
        panic!("this test needs Linux's /dev/full");
    }
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("rc.csv");
    let mut text = String::from("Time (s),Torque (N·m),Motor Electrical Speed (RPM)\n");
    for k in 0..20000 {
        text += &format!("{},{},{}\n", k as f64 * 0.01, 0.01, 1000 + k % 7);
    }
    std::fs::write(&csv, text).unwrap();
    let log = dir.path().join("in.log");
    std::fs::write(&log, "(1.0) can0 107D552A#0000000000000000E0\n").unwrap();
    for args in [
        vec![
            "import",
            "rcbench",
            csv.to_str().unwrap(),
            "-o",
            "/dev/full",
        ],
        vec!["sim", "-o", "/dev/full"],
        vec![
            "replay",
            log.to_str().unwrap(),
            "--feedback-id",
            "100",
            "-o",
            "/dev/full",
        ],
    ] {
        let out = propid(&args, None);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_ne!(out.status.code(), Some(0), "{args:?}: {err}");
        clean(&err, "writing /dev/full", "No space left on device");
    }
}
