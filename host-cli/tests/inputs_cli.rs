//! Inputs that cannot hurt (issue 26, item 4), from the command line: lines without an end,
//! `/dev/zero`, compressed input, directories and OS errors, a cut last line, an output path that
//! is an input, and one exit status per kind of failure across the commands.

mod common;

use std::io::Write;
use std::path::Path;
use std::process::{Command, Stdio};

use common::propid;

/// Runs `propid args` with `stdin`, and returns its exit code, standard error and peak RSS [KiB]
/// (from `wait4`: the child's own, not the test's).
// The child is reaped by `libc::wait4` below, which clippy does not see.
#[allow(clippy::zombie_processes)]
fn run_measured(args: &[&str], stdin: Stdio) -> (Option<i32>, String, i64) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_propid"))
        .args(args)
        .stdin(stdin)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut err).unwrap();
    let mut status = 0;
    // SAFETY: an all-zero rusage is a valid value of this plain C struct.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: wait4 on our own child's pid with valid pointers to locals; the child is not
    // waited for anywhere else (std's Child is dropped without waiting).
    let pid = unsafe { libc::wait4(child.id() as libc::pid_t, &mut status, 0, &mut usage) };
    assert_eq!(pid, child.id() as libc::pid_t);
    let code = libc::WIFEXITED(status).then(|| libc::WEXITSTATUS(status));
    (code, err, usage.ru_maxrss)
}

fn sim(dir: &Path, name: &str, seconds: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    let out = propid(
        &[
            "sim",
            "--duration",
            seconds,
            "--rate",
            "200",
            "-o",
            p.to_str().unwrap(),
        ],
        None,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    p
}

/// A line far longer than the bound (1 MiB without a line end) is an error naming its line, for
/// each reading command; the line is never echoed.
#[test]
fn a_line_without_an_end_is_named_never_echoed() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("long.tsv");
    let mut text = b"t\tforce\tvelocity\tacceleration\n0\t1\t2\t3\n".to_vec();
    text.extend(std::iter::repeat_n(b'7', 1 << 20));
    std::fs::write(&p, &text).unwrap();
    let path = p.to_str().unwrap();
    for args in [
        vec!["fit", path],
        vec!["diagnose", path],
        vec!["report", path, "-o", "/dev/null"],
    ] {
        let (code, err, _) = run_measured(&args, Stdio::null());
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(
            err.contains(&format!("{path}: line 3: the line is longer than 64 KiB")),
            "{args:?}: {err}"
        );
        assert!(
            err.len() < 1000,
            "{args:?} echoed the line: {} bytes",
            err.len()
        );
    }
    // The same as a header, through the importers' CSV reader and through standard input.
    let csv = dir.path().join("long.csv");
    std::fs::write(&csv, &text[40..]).unwrap();
    let (code, err, _) = run_measured(&["import", "rcbench", csv.to_str().unwrap()], Stdio::null());
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("longer than 64 KiB"), "{err}");
    assert!(err.len() < 1000);
}

/// Endless input on standard input stops at once in bounded memory: `/dev/zero` (not text) and
/// an endless line of digits (longer than the bound), for `fit` (which spools standard input to
/// a file) and `diagnose` (which streams it).
#[test]
fn endless_standard_input_stops_in_bounded_memory() {
    for command in ["fit", "diagnose"] {
        let zero = std::fs::File::open("/dev/zero").unwrap();
        let (code, err, rss) = run_measured(&[command, "-"], Stdio::from(zero));
        assert_eq!(code, Some(2), "{command}: {err}");
        assert!(err.contains("<stdin>: not text"), "{command}: {err}");
        assert!(rss < 64 << 10, "{command}: peak RSS {rss} KiB");

        let mut child = Command::new(env!("CARGO_BIN_EXE_propid"))
            .args([command, "-"])
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut stdin = child.stdin.take().unwrap();
        let writer = std::thread::spawn(move || {
            let chunk = [b'7'; 1 << 16];
            let _ = stdin.write_all(b"t\tforce\tvelocity\tacceleration\n");
            // Until propid stops reading (a broken pipe), at most 256 MiB.
            for _ in 0..4096 {
                if stdin.write_all(&chunk).is_err() {
                    return true;
                }
            }
            false
        });
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{command}: {err}");
        assert!(
            err.contains("<stdin>: line 2: the line is longer than 64 KiB"),
            "{command}: {err}"
        );
        assert!(writer.join().unwrap(), "{command} read the whole stream");
    }
}

/// gzip is read transparently (the same answer as the plain file); zstd and other compressions
/// are refused in plain words, with the command that decompresses them.
#[test]
fn gzip_is_read_other_compressions_refused() {
    let dir = tempfile::tempdir().unwrap();
    let plain = sim(dir.path(), "run.tsv", "20");
    let gz = dir.path().join("run.tsv.gz");
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(&std::fs::read(&plain).unwrap()).unwrap();
    std::fs::write(&gz, enc.finish().unwrap()).unwrap();
    let a = propid(&["fit", plain.to_str().unwrap()], None);
    let b = propid(&["fit", gz.to_str().unwrap()], None);
    assert!(b.status.success(), "{}", String::from_utf8_lossy(&b.stderr));
    assert_eq!(a.stdout, b.stdout);
    // Through standard input too.
    let c = propid(&["fit"], Some(&std::fs::read(&gz).unwrap()));
    assert_eq!(a.stdout, c.stdout);
    let d = propid(
        &["diagnose", "--format", "json", gz.to_str().unwrap()],
        None,
    );
    assert!(d.status.success(), "{}", String::from_utf8_lossy(&d.stderr));
    let zst = dir.path().join("run.tsv.zst");
    std::fs::write(&zst, [0x28, 0xb5, 0x2f, 0xfd, 0x24, 0x00, 0x01, 0x00]).unwrap();
    for command in ["fit", "diagnose", "report"] {
        let out = propid(&[command, zst.to_str().unwrap()], None);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{command}: {err}");
        assert!(
            err.contains("run.tsv.zst: zstd compressed")
                && err.contains("`zstd -dc FILE > run.tsv`"),
            "{command}: {err}"
        );
    }
}

/// A directory, a missing file, a path through a file: exit 2, the path named, the system's
/// words once.
#[test]
fn os_errors_name_the_path_once() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap().to_string();
    let file = sim(dir.path(), "run.tsv", "2");
    let through = format!("{}/x.tsv", file.display());
    for (path, words) in [
        (d.as_str(), "is a directory, not a file"),
        (
            "/nonexistent/run.tsv",
            "cannot open: No such file or directory",
        ),
        (through.as_str(), "cannot open: Not a directory"),
    ] {
        for args in [
            vec!["fit", path],
            vec!["diagnose", path],
            vec!["report", path, "-o", "/dev/null"],
            vec!["import", "rcbench", path],
            vec!["import", "autoquad", path, "--kv", "1000"],
            vec!["replay", path, "--feedback-id", "100"],
        ] {
            let out = propid(&args, None);
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
            assert!(err.contains(&format!("{path}: {words}")), "{args:?}: {err}");
            assert_eq!(err.matches(words).count(), 1, "{args:?}: {err}");
            assert!(!err.contains("os error"), "{args:?}: {err}");
        }
    }
}

/// A last line cut without a line end (mid-number): not used, and said — by `fit` as a
/// warning, by `diagnose` in its notes (text and JSON); the answer is that of the file without it.
#[test]
fn a_cut_last_line_is_dropped_and_announced() {
    let dir = tempfile::tempdir().unwrap();
    let whole = sim(dir.path(), "whole.tsv", "20");
    let text = std::fs::read_to_string(&whole).unwrap();
    let lines = text.lines().count();
    // Cut inside the last row's acceleration: "…\t-12.345678" becomes "…\t-12.3".
    let cut_at = text.trim_end().rfind('\t').unwrap() + 5;
    let cut = dir.path().join("cut.tsv");
    std::fs::write(&cut, &text[..cut_at]).unwrap();
    // The file without the last row, for comparison.
    let shorter = dir.path().join("shorter.tsv");
    let last_row = text.trim_end().rfind('\n').unwrap() + 1;
    std::fs::write(&shorter, &text[..last_row]).unwrap();
    let a = propid(&["fit", cut.to_str().unwrap()], None);
    let b = propid(&["fit", shorter.to_str().unwrap()], None);
    let err = String::from_utf8_lossy(&a.stderr);
    assert!(a.status.success(), "{err}");
    assert_eq!(a.stdout, b.stdout, "the cut row is not fitted");
    let said = format!("cut.tsv: line {lines} has no line end");
    assert!(err.contains(&said), "{err}");
    let out = propid(
        &["diagnose", "--format", "json", cut.to_str().unwrap()],
        None,
    );
    assert!(out.status.success());
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let notes = json["notes"].to_string();
    assert!(notes.contains(&said), "{notes}");
}

/// An output that is an input is refused before anything is written (the input untouched, no
/// stray file): `report run.tsv -o run.tsv`, the same through another spelling and a link,
/// `import rcbench x.csv -o x.csv`, `replay log -o log`, `plan --fit f -o f`.
#[test]
fn an_output_that_is_an_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let run = sim(dir.path(), "run.tsv", "20");
    let before = std::fs::read(&run).unwrap();
    let r = run.to_str().unwrap();
    let dotted = format!("{}/./run.tsv", dir.path().display());
    let link = dir.path().join("link.tsv");
    std::os::unix::fs::symlink(&run, &link).unwrap();
    let csv = dir.path().join("x.csv");
    std::fs::write(
        &csv,
        "Time (s),Torque (N·m),Motor Electrical Speed (RPM)\n0,0.1,100\n0.01,0.1,200\n0.02,0.1,300\n",
    )
    .unwrap();
    let csv_before = std::fs::read(&csv).unwrap();
    let x = csv.to_str().unwrap();
    let fit_yaml = dir.path().join("fit.yaml");
    std::fs::write(&fit_yaml, propid(&["fit", r], None).stdout).unwrap();
    let f = fit_yaml.to_str().unwrap();
    let fit_before = std::fs::read(&fit_yaml).unwrap();
    for args in [
        vec!["report", r, "-o", r],
        vec!["report", r, "-o", dotted.as_str()],
        vec!["report", r, "-o", link.to_str().unwrap()],
        vec!["import", "rcbench", x, "-o", x],
        vec!["replay", r, "--feedback-id", "100", "-o", r],
        vec!["plan", "--fit", f, "--max-torque", "0.1", "-o", f],
    ] {
        let out = propid(&args, None);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("is this input file") && err.contains("choose another output path"),
            "{args:?}: {err}"
        );
    }
    assert_eq!(std::fs::read(&run).unwrap(), before);
    assert_eq!(std::fs::read(&csv).unwrap(), csv_before);
    assert_eq!(std::fs::read(&fit_yaml).unwrap(), fit_before);
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["fit.yaml", "link.tsv", "run.tsv", "x.csv"]);
}

/// One exit status per kind of failure, whatever the command: 2 for bad input, 3 when the data
/// cannot support a verdict.
#[test]
fn exit_statuses_are_the_same_across_commands() {
    let dir = tempfile::tempdir().unwrap();
    // Bad input: a field that is not a number.
    let bad = dir.path().join("bad.tsv");
    std::fs::write(&bad, "t\tforce\tvelocity\tacceleration\n0\t1\tfast\t3\n").unwrap();
    let b = bad.to_str().unwrap();
    for args in [
        vec!["fit", b],
        vec!["diagnose", b],
        vec!["report", b, "-o", "/dev/null"],
    ] {
        let out = propid(&args, None);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("bad.tsv: line 2, column `velocity`: `fast` is not a number"));
    }
    // Cannot judge: all-zero force.
    let zero = dir.path().join("zero.tsv");
    let mut text = String::from("t\tforce\tvelocity\tacceleration\n");
    for k in 0..500 {
        text += &format!("{}\t0\t{}\t{}\n", k as f64 * 0.01, 100.0 + k as f64, 1.0);
    }
    std::fs::write(&zero, text).unwrap();
    let z = zero.to_str().unwrap();
    for args in [
        vec!["fit", z],
        vec!["diagnose", z],
        vec!["report", z, "-o", "/dev/null"],
    ] {
        let out = propid(&args, None);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(3), "{args:?}: {err}");
        assert!(err.contains("zero.tsv: cannot judge"), "{args:?}: {err}");
    }
}

/// Every row written twice (issue 26: standard errors √2 too small, no warning): `fit` warns
/// with the first copy's line, `diagnose` says it in its notes.
#[test]
fn every_row_doubled_is_announced() {
    let dir = tempfile::tempdir().unwrap();
    let run = sim(dir.path(), "run.tsv", "20");
    let text = std::fs::read_to_string(&run).unwrap();
    let mut lines = text.lines();
    let mut doubled = format!("{}\n", lines.next().unwrap());
    for l in lines {
        doubled += &format!("{l}\n{l}\n");
    }
    let twice = dir.path().join("twice.tsv");
    std::fs::write(&twice, doubled).unwrap();
    let out = propid(&["fit", twice.to_str().unwrap()], None);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("warning: ")
            && err.contains(
                "twice.tsv: 4000 rows are copies of the row before them (the first at line 3)"
            )
            && err.contains("√2"),
        "{err}"
    );
    let clean = propid(&["fit", run.to_str().unwrap()], None);
    assert!(!String::from_utf8_lossy(&clean.stderr).contains("copies"));
    let out = propid(
        &["diagnose", "--format", "json", twice.to_str().unwrap()],
        None,
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(
        json["notes"]
            .to_string()
            .contains("4000 rows repeat the previous row's time (the first at line 3)"),
        "{}",
        json["notes"]
    );
}
