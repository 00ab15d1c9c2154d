//! `propid demo --live`: the live page while the drive runs. Without a browser: a request
//! without the token is refused, the event stream carries samples, and STOP (as the page's button
//! sends it) makes the driver command STANDBY, which reaches the simulated drive. With headless
//! Chromium (the `#[ignore]`d test, run by ci/steps/25-browser.sh): the page draws its charts
//! from live data and a screenshot is taken.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Starts `propid demo --live 127.0.0.1:0`-style on a free port; returns the child, the page
/// URL and a reader of the rest of its stderr.
fn start_demo(dir: &std::path::Path) -> (Child, String, BufReader<std::process::ChildStderr>) {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let mut child = Command::new(env!("CARGO_BIN_EXE_propid"))
        .args([
            "demo",
            "--duration",
            "60",
            "--init-duration",
            "1",
            "--out",
            dir.to_str().unwrap(),
            "--live",
            &format!("127.0.0.1:{port}"),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    let url = loop {
        line.clear();
        assert!(err.read_line(&mut line).unwrap() > 0, "demo ended early");
        if let Some(rest) = line.trim().strip_prefix("live: open ") {
            break rest.split_whitespace().next().unwrap().to_string();
        }
    };
    (child, url, err)
}

fn http(addr: &str, request: &str) -> (u16, String) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.write_all(request.as_bytes()).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    let mut text = String::new();
    let _ = s.read_to_string(&mut text);
    let code = text
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    (code, text)
}

fn addr_and_token(url: &str) -> (String, String) {
    let rest = url.strip_prefix("http://").unwrap();
    let (addr, query) = rest.split_once("/?token=").unwrap();
    (addr.to_string(), query.to_string())
}

/// The first event of the stream with at least one sample.
fn first_samples(addr: &str, token: &str) -> serde_json::Value {
    let mut s = TcpStream::connect(addr).unwrap();
    write!(
        s,
        "GET /events?token={token} HTTP/1.1\r\nHost: localhost\r\n\r\n"
    )
    .unwrap();
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    let mut r = BufReader::new(s);
    let deadline = Instant::now() + Duration::from_secs(30);
    let mut line = String::new();
    while Instant::now() < deadline {
        line.clear();
        if r.read_line(&mut line).unwrap_or(0) == 0 {
            break;
        }
        if let Some(d) = line.trim_end().strip_prefix("data: ") {
            let v: serde_json::Value = serde_json::from_str(d).unwrap();
            if v["seq"].as_u64().unwrap_or(0) > 100 {
                return v;
            }
        }
    }
    panic!("no samples on the event stream");
}

/// Presses STOP as the page's button does, then waits for the demo to end; returns its stderr.
fn stop_and_finish(
    addr: &str,
    token: &str,
    mut child: Child,
    mut err: BufReader<std::process::ChildStderr>,
) -> (String, Option<i32>) {
    let (code, body) = http(
        addr,
        &format!("POST /stop HTTP/1.1\r\nHost: localhost\r\nX-Propid-Token: {token}\r\nContent-Length: 0\r\nConnection: close\r\n\r\n"),
    );
    assert_eq!(code, 200, "{body}");
    let mut rest = String::new();
    err.read_to_string(&mut rest).unwrap();
    let status = child.wait().unwrap();
    (rest, status.code())
}

#[test]
fn live_page_needs_the_token_streams_data_and_stop_reaches_the_drive() {
    let dir = tempfile::tempdir().unwrap();
    let (child, url, err) = start_demo(dir.path());
    let (addr, token) = addr_and_token(&url);
    assert_eq!(token.len(), 32);
    // No token, a wrong token, STOP without the header: refused, and the run goes on.
    let close = "Connection: close\r\n\r\n";
    assert_eq!(
        http(&addr, &format!("GET / HTTP/1.1\r\nHost: x\r\n{close}")).0,
        403
    );
    assert_eq!(
        http(
            &addr,
            &format!("GET /?token=0123 HTTP/1.1\r\nHost: x\r\n{close}")
        )
        .0,
        403
    );
    assert_eq!(
        http(
            &addr,
            &format!(
                "POST /stop?token={token} HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\n{close}"
            )
        )
        .0,
        403
    );
    let (code, page) = http(
        &addr,
        &format!("GET /?token={token} HTTP/1.1\r\nHost: x\r\n{close}"),
    );
    assert_eq!(code, 200);
    assert!(page.contains("STOP") && page.contains("uPlot"));
    let update = first_samples(&addr, &token);
    assert!(!update["points"].as_array().unwrap().is_empty());
    let (rest, code) = stop_and_finish(&addr, &token, child, err);
    assert!(
        rest.contains("stopping (interrupted by a signal)"),
        "{rest}"
    );
    assert!(
        rest.contains("the simulated Telega saw STANDBY and a zero setpoint last"),
        "{rest}"
    );
    assert_ne!(
        code,
        Some(0),
        "a stopped demo is not a completed one: {rest}"
    );
}

#[test]
#[ignore = "needs Debian's chromium and node with playwright-core (ci/steps/25-browser.sh installs them and runs this)"]
fn live_page_in_chromium_shows_live_data_and_its_stop_button_works() {
    let dir = tempfile::tempdir().unwrap();
    let (child, url, mut err) = start_demo(dir.path());
    let script =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/browser/live_page.mjs");
    let mut cmd = Command::new("node");
    cmd.arg(&script).arg(&url);
    if let Some(shots) = std::env::var_os("PROPID_SCREENSHOT_DIR") {
        cmd.arg(std::path::Path::new(&shots).join("live.png"));
    }
    let out = cmd.output().expect("node runs");
    let said =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "the browser check failed: {said}");
    // The page's STOP button stopped the drive, and STANDBY reached the simulated drive.
    let mut rest = String::new();
    err.read_to_string(&mut rest).unwrap();
    let mut child = child;
    let _ = child.wait();
    assert!(
        rest.contains("stopping (interrupted by a signal)"),
        "{rest}"
    );
    assert!(
        rest.contains("the simulated Telega saw STANDBY and a zero setpoint last"),
        "{rest}"
    );
}
