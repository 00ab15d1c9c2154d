//! `propid report`: one self-contained HTML page per recording, checked as text here and as a
//! rendered page in headless Chromium (the `#[ignore]`d test, run by ci/steps/25-browser.sh).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

/// Simulates a recording with a hidden torque lag and writes its report; returns the page path.
fn make_report(dir: &Path) -> PathBuf {
    let tsv = dir.join("run.tsv");
    let out = common::propid(
        &[
            "sim",
            "--duration",
            "20",
            "--pattern",
            "chirp",
            "--torque-lag",
            "0.012",
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
    let html = dir.join("report.html");
    let out = common::propid(
        &[
            "report",
            tsv.to_str().unwrap(),
            "-o",
            html.to_str().unwrap(),
            "--diameter",
            "0.1778",
        ],
        None,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    html
}

#[test]
fn report_is_one_self_contained_page_with_fit_diagnosis_and_plots() {
    let dir = tempfile::tempdir().unwrap();
    let page = std::fs::read_to_string(make_report(dir.path())).unwrap();
    for want in [
        "J (inertia)",
        "c2 (quadratic drag)",
        "C_Q (torque coefficient)",
        "Diagnosis",
        "torque_lag",
        "propidChart(",
        "Reproduce",
        "propid diagnose",
    ] {
        assert!(page.contains(want), "the report lacks `{want}`");
    }
    // Its commands reproduce it: each with the diameter in metres and its unit (a bare number
    // is refused), the diagnosis too.
    let reproduce = &page[page.find("<h2>Reproduce</h2>").unwrap()..];
    for command in ["propid fit", "propid diagnose", "propid report"] {
        let line = reproduce
            .lines()
            .find(|l| l.contains(&format!("{command} ")) && l.contains(".tsv"))
            .unwrap_or_else(|| panic!("no `{command}` line"));
        assert!(line.ends_with(" --diameter 0.1778m"), "{line}");
    }
    // Works offline: uPlot is inside, nothing is loaded from elsewhere.
    assert!(page.contains("uPlot"));
    assert!(!page.contains("<script src") && !page.contains("<link"));
}

#[test]
fn report_of_a_missing_file_is_a_clear_error() {
    let out = common::propid(&["report", "/nonexistent/run.tsv"], None);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("/nonexistent/run.tsv: cannot open: No such file or directory"),
        "{err}"
    );
}

/// Headless Chromium, as Debian ships it (`apt-get install chromium`).
pub fn chromium() -> Command {
    let mut c = Command::new("chromium");
    c.args([
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
    ]);
    c
}

#[test]
#[ignore = "needs Debian's chromium (ci/steps/25-browser.sh installs it and runs this)"]
fn report_renders_its_charts_in_chromium() {
    let dir = tempfile::tempdir().unwrap();
    let html = make_report(dir.path());
    let url = format!("file://{}", html.display());
    let profile = tempfile::tempdir().unwrap();
    let out = chromium()
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .args(["--virtual-time-budget=5000", "--dump-dom", &url])
        .output()
        .expect("chromium runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let dom = String::from_utf8_lossy(&out.stdout);
    // Every chart placeholder was filled by uPlot with a canvas: the script ran, the data parsed.
    let charts = dom.matches("class=\"chart\"").count();
    let drawn = dom.matches("<canvas").count();
    assert!(charts >= 4, "{charts} charts in the page");
    assert_eq!(drawn, charts, "{drawn} canvases for {charts} charts");
    assert!(
        dom.contains("class=\"uplot"),
        "uPlot did not build its charts"
    );
    // A screenshot for the README (docs/img/report.png), when asked to refresh it.
    if let Some(shot) = std::env::var_os("PROPID_SCREENSHOT_DIR") {
        let png = Path::new(&shot).join("report.png");
        let out = chromium()
            .arg(format!("--user-data-dir={}", profile.path().display()))
            .args([
                "--virtual-time-budget=5000",
                "--window-size=1280,1800",
                &format!("--screenshot={}", png.display()),
                &url,
            ])
            .output()
            .expect("chromium runs");
        assert!(out.status.success() && png.exists());
    }
}
