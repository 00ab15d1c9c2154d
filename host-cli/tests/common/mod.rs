//! Shared helpers for the CLI tests: run the `propid` binary, find the repo, require Python packages or socat.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// The workspace root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

/// Runs `propid` with `args`, feeding `stdin`.
pub fn propid(args: &[&str], stdin: Option<&[u8]>) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_propid"))
        .args(args)
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("propid runs");
    if let Some(input) = stdin {
        use std::io::Write;
        child.stdin.take().unwrap().write_all(input).unwrap();
    }
    child.wait_with_output().unwrap()
}

/// Runs `propid` with `args` (no stdin) and panics, with its arguments and its standard error,
/// unless it succeeds.
#[track_caller]
pub fn propid_ok(args: &[&str]) -> Output {
    let out = propid(args, None);
    assert!(
        out.status.success(),
        "propid {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// `propid diagnose --format json` of `tsv`, which must succeed, as JSON.
#[track_caller]
pub fn diagnose_json(tsv: &Path) -> serde_json::Value {
    let out = propid_ok(&["diagnose", "--format", "json", tsv.to_str().unwrap()]);
    serde_json::from_slice(&out.stdout).expect("diagnose writes JSON")
}

/// Panics unless `python3` can import the given modules. The tests that call this are
/// `#[ignore = "needs …"]`: they run only when asked (`cargo test … -- --ignored`, as
/// ci/steps/30-python-peers.sh does after ci/setup.sh installed the packages), and then a missing
/// package is a failure, never a silent `ok`.
pub fn require_python(modules: &str) {
    let ok = Command::new("python3")
        .args(["-c", &format!("import {modules}")])
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    assert!(
        ok,
        "this test needs python3 with {modules}: run `bash ci/setup.sh` (pip install) first"
    );
}

/// Panics unless the `socat` program runs (see [`require_python`]).
pub fn require_socat() {
    let ok = Command::new("socat")
        .arg("-V")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    assert!(
        ok,
        "this test needs socat: run `bash ci/setup.sh` (apt) first"
    );
}

/// Kept for `pycyphal_interop.rs` until it calls [`require_python`]: never returns `false`
/// (a missing module panics instead of skipping).
pub fn python_has(modules: &str) -> bool {
    require_python(modules);
    true
}

/// A YAML `key: value` line's value.
pub fn yaml_value(text: &str, key: &str) -> f64 {
    text.lines()
        .find_map(|l| {
            let (k, v) = l.split_once(':')?;
            (k.trim() == key).then(|| v.split('#').next().unwrap().trim().parse::<f64>().ok())?
        })
        .unwrap_or_else(|| panic!("no `{key}` in:\n{text}"))
}

/// Compiles the repo's DSDL (uavcan, then zubax) for PyCyphal into `out`; panics if it fails.
pub fn compile_pycyphal_dsdl(out: &Path) {
    let dsdl = repo().join("tests/pycyphal/dsdl");
    let status = Command::new("python3")
        .arg("-c")
        .arg(format!(
            "import pycyphal.dsdl as d; d.compile('{u}', output_directory='{o}'); \
             d.compile('{z}', lookup_directories=['{u}'], output_directory='{o}')",
            u = dsdl.join("uavcan").display(),
            z = dsdl.join("zubax").display(),
            o = out.display()
        ))
        .status()
        .unwrap();
    assert!(status.success(), "DSDL compilation");
}

/// Every setpoint a PyCyphal peer decoded from `propid drive` (a JSON array of 31-element
/// arrays): all 31 elements equal, and either the stop's zero or within the seed's 0.1 … 0.9.
pub fn assert_seed_setpoints(setpoints: &[serde_json::Value]) {
    for sp in setpoints {
        let v: Vec<f64> = sp
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        assert_eq!(v.len(), 31);
        assert!(v.iter().all(|x| *x == v[0]), "all 31 elements equal: {v:?}");
        assert!(v[0] == 0.0 || (0.0999..=0.9001).contains(&v[0]), "{}", v[0]);
    }
}

/// A simulated chirp run of 20 s (`propid sim`, noise seed `seed`) in `dir`: its header and its
/// rows as numbers (ts_local, t, force, velocity, acceleration, position).
pub fn simulated_rows(dir: &Path, seed: u32) -> (String, Vec<Vec<f64>>) {
    let tsv = dir.join("clean.tsv");
    let seed = seed.to_string();
    propid_ok(&[
        "sim",
        "--pattern",
        "chirp",
        "--duration",
        "20",
        "--seed",
        &seed,
        "-o",
        tsv.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&tsv).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_string();
    let rows = lines
        .map(|l| l.split('\t').map(|x| x.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

/// Writes `rows` under `header` as a TSV at `path`.
pub fn write_rows(path: &Path, header: &str, rows: &[Vec<f64>]) {
    let mut text = header.to_string() + "\n";
    for r in rows {
        let cols: Vec<String> = r.iter().map(|x| format!("{x:e}")).collect();
        text += &(cols.join("\t") + "\n");
    }
    std::fs::write(path, text).unwrap();
}
