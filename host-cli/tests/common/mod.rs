//! Shared helpers for the CLI tests: run the `propid` binary, find the repo, check for Python.
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

/// True if `python3` can import the given modules. In CI a missing module is a failure; on a
/// developer machine the caller skips loudly.
pub fn python_has(modules: &str) -> bool {
    let ok = Command::new("python3")
        .args(["-c", &format!("import {modules}")])
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !ok {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must provide python3 with {modules} (pip install)"
        );
        eprintln!("SKIPPED: python3 with {modules} is not available");
    }
    ok
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
