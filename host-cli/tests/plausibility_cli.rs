//! The plausibility gate from the command line (issue 26, item 3): each plausible mistake on a
//! simulated run — a flipped torque sign, a velocity in rpm, rev/s or deg/s, a parameter on its
//! bound, `--max-effects 0` — gets a message naming what to do and a non-zero exit, or the right
//! answer once the flag it names is given; nothing is written over the input.

mod common;

use common::{propid, yaml_value};
use std::path::{Path, PathBuf};

/// A simulated chirp run (J = 2e-5, c2 = 1.5e-8), its header and rows as numbers.
fn simulated(dir: &Path) -> (String, Vec<Vec<f64>>) {
    let (header, rows) = common::simulated_rows(dir, 7);
    assert_eq!(
        header,
        "ts_local\tt\tforce\tvelocity\tacceleration\tposition"
    );
    (header, rows)
}

fn write(dir: &Path, name: &str, header: &str, rows: &[Vec<f64>]) -> PathBuf {
    let path = dir.join(name);
    common::write_rows(&path, header, rows);
    path
}

fn text(out: &std::process::Output) -> (String, String) {
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_flipped_torque_sign_is_named_and_flip_torque_answers_it() {
    let dir = tempfile::tempdir().unwrap();
    let (header, mut rows) = simulated(dir.path());
    rows.iter_mut().for_each(|r| r[2] = -r[2]);
    let path = write(dir.path(), "flipped.tsv", &header, &rows);
    let before = std::fs::read(&path).unwrap();
    let p = path.to_str().unwrap();
    for command in ["fit", "diagnose"] {
        let out = propid(&[command, p], None);
        let (stdout, err) = text(&out);
        assert_eq!(out.status.code(), Some(3), "{command}: {stdout}{err}");
        assert!(
            err.contains("flipped.tsv")
                && err.contains("the torque sign looks flipped")
                && err.contains("--flip-torque"),
            "{command}: {err}"
        );
        assert!(
            !stdout.contains("Nothing is wrong") && !stdout.contains("mass:"),
            "{command}: {stdout}"
        );
    }
    // Answered: the truth back, from both commands.
    let out = propid(&["fit", "--flip-torque", p], None);
    let (yaml, err) = text(&out);
    assert!(out.status.success(), "{err}");
    let j = yaml_value(&yaml, "mass");
    assert!((j / 2e-5 - 1.0).abs() < 0.05, "J {j}");
    let out = propid(&["diagnose", "--flip-torque", "--format", "json", p], None);
    assert!(out.status.success(), "{}", text(&out).1);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let j = v["base"]["inertia"].as_f64().unwrap();
    assert!((j / 2e-5 - 1.0).abs() < 0.05, "J {j}");
    assert_eq!(
        std::fs::read(&path).unwrap(),
        before,
        "the input is untouched"
    );
}

#[test]
fn a_velocity_in_another_unit_is_named_with_its_unit() {
    let dir = tempfile::tempdir().unwrap();
    let (header, rows) = simulated(dir.path());
    let truth = {
        let path = write(dir.path(), "clean.tsv", &header, &rows);
        let out = propid(&["fit", path.to_str().unwrap()], None);
        assert!(out.status.success());
        yaml_value(&text(&out).0, "c2")
    };
    for (unit, per_rad_s) in [
        ("rpm", 60.0 / std::f64::consts::TAU),
        ("rev/s", 1.0 / std::f64::consts::TAU),
        ("deg/s", 180.0 / std::f64::consts::PI),
    ] {
        let mut r = rows.clone();
        r.iter_mut().for_each(|x| x[3] *= per_rad_s);
        let path = write(dir.path(), "speed.tsv", &header, &r);
        let p = path.to_str().unwrap();
        for command in ["fit", "diagnose"] {
            let out = propid(&[command, p], None);
            let (_, err) = text(&out);
            assert_eq!(out.status.code(), Some(3), "{unit} {command}: {err}");
            assert!(
                err.contains("speed.tsv")
                    && err.contains(&format!("the velocity looks like it is in {unit}"))
                    && err.contains(&format!("--velocity-unit {unit}")),
                "{unit} {command}: {err}"
            );
        }
        let out = propid(&["fit", "--velocity-unit", unit, p], None);
        let (yaml, err) = text(&out);
        assert!(out.status.success(), "{unit}: {err}");
        let c2 = yaml_value(&yaml, "c2");
        assert!(
            (c2 / truth - 1.0).abs() < 1e-6,
            "{unit}: c2 {c2} vs {truth}"
        );
    }
    let out = propid(&["fit", "--velocity-unit", "furlongs", "x.tsv"], None);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out).1.contains("--velocity-unit"));
}

#[test]
fn a_parameter_on_its_bound_is_not_identified_and_has_no_zero_error() {
    let dir = tempfile::tempdir().unwrap();
    let (header, rows) = simulated(dir.path());
    let path = write(dir.path(), "run.tsv", &header, &rows);
    let p = path.to_str().unwrap();
    // J is 2e-5: a bound of 1e-5 holds it there.
    let out = propid(&["fit", "--mass-max", "1e-5", "--format", "json", p], None);
    let (json, err) = text(&out);
    assert!(out.status.success(), "{err}");
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["at_bound"][0], "mass", "{json}");
    assert_eq!(v["not_identified"][0], "mass", "{json}");
    let se = v["mass_stderr"].as_f64().unwrap();
    assert!(se > 0.0 && se.is_finite(), "{json}");
    assert!(err.contains("the mass sits on its bound"), "{err}");
    // The Result (stderr) calls it J and gives no statistical error for a value on its bound.
    let j_line = err
        .lines()
        .find(|l| l.starts_with("   J    ="))
        .unwrap_or_default();
    assert!(
        j_line.ends_with("(not identified by these data)") && !j_line.contains("statistical"),
        "{err}"
    );
    assert!(
        err.contains("Not identified (values are not measurements): J"),
        "{err}"
    );
    // c2 held at a bound far below its value: named, with a finite non-zero error.
    let out = propid(&["fit", "--c2-max", "1e-9", p], None);
    let (yaml, err) = text(&out);
    assert!(out.status.success(), "{err}");
    assert!(yaml.contains("not_identified: [c2]"), "{yaml}");
    assert!(yaml_value(&yaml, "c2_stderr") > 0.0, "{yaml}");
    assert!(
        err.contains("c2 is not identified: it sits on its bound"),
        "{err}"
    );
}

#[test]
fn max_effects_zero_is_refused_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let (header, rows) = simulated(dir.path());
    let path = write(dir.path(), "run.tsv", &header, &rows);
    let out = propid(
        &["diagnose", "--max-effects", "0", path.to_str().unwrap()],
        None,
    );
    let (stdout, err) = text(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(!stdout.contains("Nothing is wrong"));
    assert!(
        err.contains("--max-effects") && err.contains("propid fit"),
        "{err}"
    );
}

/// Speed glitches (an optical probe's missed mark: one sample 30 % off, then back) in a TSV are
/// announced by diagnose with the rows' times, kept unless `--despike` leaves them out, and by
/// fit with their lines.
#[test]
fn velocity_glitches_are_announced_and_left_out_only_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let (header, rows) = simulated(dir.path());
    let clean = write(dir.path(), "clean.tsv", &header, &rows);
    let json = |path: &Path, extra: &[&str]| {
        let out = propid(
            &[
                &["diagnose", path.to_str().unwrap(), "--format", "json"][..],
                extra,
            ]
            .concat(),
            None,
        );
        assert!(out.status.success(), "{}", text(&out).1);
        serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap()
    };
    let notes = |v: &serde_json::Value| v["notes"].to_string();
    // None on the clean run.
    assert!(!notes(&json(&clean, &[])).contains("glitch"));
    let mut glitched = rows.clone();
    let at = [1000, 2500, 4000];
    for &k in &at {
        glitched[k][3] *= 1.3;
    }
    let path = write(dir.path(), "glitched.tsv", &header, &glitched);
    let kept = json(&path, &[]);
    let n = notes(&kept);
    assert!(n.contains("3 samples jump away"), "{n}");
    for &k in &at {
        assert!(n.contains(&format!("{:.4}", glitched[k][1])), "{n}");
    }
    assert!(n.contains("--despike leaves those rows out"), "{n}");
    let dropped = json(&path, &["--despike"]);
    assert!(notes(&dropped).contains("those rows are left out (--despike)"));
    assert_eq!(
        dropped["result"]["rows_used"].as_u64().unwrap() + 3,
        kept["result"]["rows_used"].as_u64().unwrap()
    );
    assert_eq!(
        dropped["result"]["rows_dropped"].as_u64().unwrap(),
        kept["result"]["rows_dropped"].as_u64().unwrap() + 3
    );
    // fit, which keeps no rows, finds the same three and names their lines (header = line 1).
    let out = propid(&["fit", path.to_str().unwrap()], None);
    let (_, err) = text(&out);
    assert!(out.status.success(), "{err}");
    let lines: Vec<String> = at.iter().map(|k| (k + 2).to_string()).collect();
    assert!(
        err.contains("3 samples jump away")
            && err.contains(&format!("(lines {})", lines.join(", "))),
        "{err}"
    );
    assert!(
        err.contains("`propid diagnose --despike` leaves those rows out"),
        "{err}"
    );
    let (_, clean_err) = text(&propid(&["fit", clean.to_str().unwrap()], None));
    assert!(!clean_err.contains("jump away"), "{clean_err}");
}
