//! The Result from the command line (issue 26, item 1): the same keys in JSON and YAML, every
//! value a number where a number is meant (PyYAML and json in Python too), units, diameter,
//! density, rows used and dropped, warnings; C_Q outside a propeller's range warns of inches.

mod common;

use common::{propid, propid_ok};
use std::path::{Path, PathBuf};

/// A simulated chirp run with a hidden torque lag of 12 ms.
fn lagged(dir: &Path) -> PathBuf {
    let tsv = dir.join("lag.tsv");
    propid_ok(&[
        "sim",
        "--pattern",
        "chirp",
        "--duration",
        "20",
        "--torque-lag",
        "0.012",
        "-o",
        tsv.to_str().unwrap(),
    ]);
    tsv
}

/// Every key path of a JSON value, with the kind of its leaf.
fn leaves(v: &serde_json::Value, at: String, out: &mut Vec<(String, &'static str)>) {
    match v {
        serde_json::Value::Object(m) => m
            .iter()
            .for_each(|(k, x)| leaves(x, format!("{at}.{k}"), out)),
        serde_json::Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, x)| leaves(x, format!("{at}[{i}]"), out)),
        serde_json::Value::Number(_) => out.push((at, "number")),
        serde_json::Value::String(_) => out.push((at, "string")),
        serde_json::Value::Bool(_) => out.push((at, "bool")),
        serde_json::Value::Null => out.push((at, "null")),
    }
}

fn result_of(tsv: &Path, flags: &[&str]) -> (serde_json::Value, serde_json::Value, String) {
    let t = tsv.to_str().unwrap();
    let json = propid_ok(&[&["diagnose", t, "--format", "json"], flags].concat());
    let json: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    let yaml = propid_ok(&[&["diagnose", t, "--format", "yaml"], flags].concat());
    let yaml = String::from_utf8(yaml.stdout).unwrap();
    let parsed: serde_json::Value = serde_norway::from_str(&yaml).unwrap();
    (json["result"].clone(), parsed, yaml)
}

#[test]
fn json_and_yaml_carry_the_same_result_with_its_units_and_air() {
    let dir = tempfile::tempdir().unwrap();
    let tsv = lagged(dir.path());
    let (json, yaml, text) = result_of(&tsv, &["--diameter", "7in"]);
    let (mut a, mut b) = (vec![], vec![]);
    leaves(&json, String::new(), &mut a);
    leaves(&yaml, String::new(), &mut b);
    assert_eq!(a, b, "{text}");
    assert!(a.iter().all(|(_, kind)| *kind != "null"), "{a:?}");
    assert_eq!(json["model"], "extended");
    assert_eq!(json["effects"][0]["name"], "torque_lag");
    assert_eq!(json["effects"][0]["unit"], "s");
    assert_eq!(json["inertia"]["unit"], "kg·m²");
    assert_eq!(json["air"]["diameter_m"].as_f64(), Some(0.1778));
    assert_eq!(json["air"]["density_kg_m3"].as_f64(), Some(1.225));
    assert!(json["rows_used"].as_u64().unwrap() > 9000);
    assert!(json["rows_dropped"].is_u64());
    assert!(json["caveat"].as_str().unwrap().contains("torque-constant"));
    assert_eq!(json["seed_model_holds"], false);
    // The extended J, not the seed fit's biased one, within 2 % of the truth.
    let j = json["inertia"]["value"].as_f64().unwrap();
    assert!((j / 2e-5 - 1.0).abs() < 0.02, "J {j}");
    for v in [
        &json["inertia"],
        &json["c2"],
        &json["c_q"],
        &json["effects"][0],
    ] {
        let se = v["stderr"].as_f64().unwrap();
        assert!(se > 0.0 && se.is_finite(), "{v}");
        assert!(v["model_spread"].as_f64().unwrap() >= 0.0, "{v}");
    }
    // The text leads with the Result.
    let out = propid_ok(&["diagnose", tsv.to_str().unwrap(), "--diameter", "0.1778m"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.starts_with("Result (the seed's model with torque_lag)"),
        "{text}"
    );
    assert!(
        text.contains("with D = 0.1778 m (7.00 in), ρ = 1.2250 kg/m³"),
        "{text}"
    );
}

#[test]
fn a_diameter_in_inches_read_as_metres_is_refused_or_warned() {
    let dir = tempfile::tempdir().unwrap();
    let tsv = lagged(dir.path());
    let t = tsv.to_str().unwrap();
    for command in ["fit", "diagnose"] {
        let out = propid(&[command, t, "--diameter", "7"], None);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{command}: {err}");
        assert!(
            err.contains("--diameter 7 has no unit") && err.contains("7in"),
            "{command}: {err}"
        );
    }
    // 2.5 m is a length a bare number may mean: C_Q then falls outside a propeller's range.
    let (json, _, _) = result_of(&tsv, &["--diameter", "2.5"]);
    let warnings = json["warnings"].to_string();
    assert!(
        warnings.contains("outside") && warnings.contains("--diameter 2.5in"),
        "{warnings}"
    );
    // fit says the same on stderr, beside the seed's YAML.
    let out = propid_ok(&["fit", t, "--diameter", "2.5m"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("Result (the seed's model)") && err.contains("C_Q"),
        "{err}"
    );
    assert!(err.contains("is outside"), "{err}");
    // diagnose's text says it under C_Q, both ways: too small (inches read as metres) and too
    // large (a diameter given too small, 7mm for 7in).
    for (diameter, says) in [
        ("2.5m", "--diameter 2.5in if inches were meant"),
        ("7mm", "7mm for 7in is f = 25.4"),
    ] {
        let out = propid_ok(&["diagnose", t, "--diameter", diameter]);
        let text = String::from_utf8_lossy(&out.stdout);
        let warning = text
            .lines()
            .skip_while(|l| !l.starts_with("   C_Q"))
            .nth(2)
            .unwrap_or_default();
        assert!(
            warning.starts_with("        Warning: C_Q = ") && warning.contains(says),
            "{diameter}: {text}"
        );
    }
}

/// PyYAML (YAML 1.1) and Python's json read every number of the Result as a number, and the
/// same keys from both.
#[test]
#[ignore = "needs python3 with PyYAML (ci/steps/35-fit-pyyaml.sh runs it)"]
fn python_reads_the_result_as_numbers() {
    common::require_python("yaml");
    let dir = tempfile::tempdir().unwrap();
    let tsv = lagged(dir.path());
    let t = tsv.to_str().unwrap();
    let yaml = dir.path().join("r.yaml");
    let json = dir.path().join("r.json");
    let out = propid_ok(&["diagnose", t, "--diameter", "7in", "--format", "yaml"]);
    std::fs::write(&yaml, &out.stdout).unwrap();
    let out = propid_ok(&["diagnose", t, "--diameter", "7in", "--format", "json"]);
    std::fs::write(&json, &out.stdout).unwrap();
    let script = "import sys, json, yaml\n\
        y = yaml.safe_load(open(sys.argv[1]))\n\
        j = json.load(open(sys.argv[2]))['result']\n\
        assert y == j, (y, j)\n\
        numeric = ('value', 'stderr', 'model_spread', 'diameter_m', 'density_kg_m3', 'rows_used', 'rows_dropped')\n\
        seen = []\n\
        def walk(v, key):\n\
        \x20   if isinstance(v, dict):\n\
        \x20       [walk(x, k) for k, x in v.items()]\n\
        \x20   elif isinstance(v, list):\n\
        \x20       [walk(x, key) for x in v]\n\
        \x20   elif key in numeric:\n\
        \x20       assert type(v) in (int, float) and v == v, (key, v)\n\
        \x20       seen.append(key)\n\
        walk(y, None)\n\
        assert len(seen) >= 15, seen\n\
        print(len(seen))";
    let out = std::process::Command::new("python3")
        .args(["-c", script, yaml.to_str().unwrap(), json.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// README.md's example of the Result is what `propid diagnose lag.tsv --diameter 7in` prints on
/// the command's own simulated run (the stand is deterministic): every line of the example's
/// block, a line ending in `…` as a prefix.
#[test]
fn the_readmes_result_example_is_what_diagnose_prints() {
    let dir = tempfile::tempdir().unwrap();
    let tsv = lagged(dir.path());
    let out = propid_ok(&["diagnose", tsv.to_str().unwrap(), "--diameter", "7in"]);
    let text = String::from_utf8(out.stdout).unwrap();
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../README.md"))
            .unwrap();
    let from = readme
        .find("**One answer: the Result.**")
        .expect("README has the Result paragraph");
    let block = &readme[from..];
    let start = block.find("```text\n").expect("its example") + "```text\n".len();
    let example = &block[start..start + block[start..].find("```").unwrap()];
    let lines: Vec<&str> = example.lines().filter(|l| !l.trim().is_empty()).collect();
    assert!(lines.len() >= 5, "{example}");
    for line in lines {
        let found = match line.strip_suffix(" …") {
            Some(prefix) => text.lines().any(|l| l.starts_with(prefix)),
            None => text.lines().any(|l| l == line),
        };
        assert!(
            found,
            "README's line not printed: {line:?}\n--- diagnose printed:\n{text}"
        );
    }
}

/// C_T of a 7-inch propeller, 0.14: T = k·ω² with k = C_T·ρ·D⁴/(2π)².
const C_T: f64 = 0.14;

fn with_thrust(dir: &Path, scale: f64) -> PathBuf {
    let tsv = dir.join(format!("thrust-{scale}.tsv"));
    let k = C_T * 1.225 * 0.1778f64.powi(4) / (4.0 * std::f64::consts::PI.powi(2));
    propid_ok(&[
        "sim",
        "--duration",
        "30",
        "--thrust-k",
        &format!("{:e}", k * scale),
        "-o",
        tsv.to_str().unwrap(),
    ]);
    tsv
}

#[test]
fn the_result_carries_c_t_where_the_file_has_thrust() {
    let dir = tempfile::tempdir().unwrap();
    let tsv = with_thrust(dir.path(), 1.0);
    let t = tsv.to_str().unwrap();
    let (json, yaml, text) = result_of(&tsv, &["--diameter", "7in"]);
    let (mut a, mut b) = (vec![], vec![]);
    leaves(&json, String::new(), &mut a);
    leaves(&yaml, String::new(), &mut b);
    assert_eq!(a, b, "{text}");
    let c_t = &json["thrust"]["c_t"];
    let (v, se) = (
        c_t["value"].as_f64().unwrap(),
        c_t["stderr"].as_f64().unwrap(),
    );
    assert!((v / C_T - 1.0).abs() < 0.01, "C_T {v}");
    assert!(se > 0.0 && se < 0.01 * v, "{c_t}");
    assert!((json["thrust"]["exponent"]["value"].as_f64().unwrap() - 2.0).abs() < 0.01);
    assert!(json["thrust"]["speed_rpm"].as_f64().unwrap() > 1000.0);
    // fit's Result (on stderr) has it too, from the same identification.
    let out = propid_ok(&["fit", t, "--diameter", "7in"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("C_T  = {v:.4e} ±")), "{err}");
    assert!(err.contains("(T = C_T·ρ·n²·D⁴) at"), "{err}");
    // Without a diameter there is no coefficient, and the Result says what to give.
    for command in ["fit", "diagnose"] {
        let out = propid_ok(&[command, t]);
        let all = String::from_utf8_lossy(&out.stderr).to_string()
            + &String::from_utf8_lossy(&out.stdout);
        assert!(
            all.contains("the file has a `thrust` column: give --diameter"),
            "{command}: {all}"
        );
    }
}

#[test]
fn thrust_in_gram_force_read_as_newtons_is_named() {
    let dir = tempfile::tempdir().unwrap();
    // The thrust column 101.97 times too large: grams-force written where newtons belong.
    let tsv = with_thrust(dir.path(), 1000.0 / 9.80665);
    let (json, _, _) = result_of(&tsv, &["--diameter", "7in"]);
    let warnings = json["warnings"].to_string();
    assert!(warnings.contains("gram-force"), "{warnings}");
}

/// An RCbenchmark log of tests/data imported as `rc.tsv` in `dir`.
fn rcbench(dir: &Path, log: &str) -> PathBuf {
    let tsv = dir.join("rc.tsv");
    let csv = common::repo().join(format!("tests/data/esc_test_alspitz/rcbench/{log}.csv"));
    propid_ok(&[
        "import",
        "rcbench",
        csv.to_str().unwrap(),
        "-o",
        tsv.to_str().unwrap(),
    ]);
    tsv
}

#[test]
fn c_t_of_a_real_log_is_propid_propulsion_s() {
    // An RCbenchmark export: the thrust cell updates on rows the torque does not, so the
    // Result's C_T must rest on every row, as `propid propulsion` reads them.
    let dir = tempfile::tempdir().unwrap();
    let tsv = rcbench(dir.path(), "Log_2019-11-07_184325");
    let t = tsv.to_str().unwrap();
    let p = propid_ok(&["propulsion", t, "--diameter", "7in", "--format", "json"]);
    let p: serde_json::Value = serde_json::from_slice(&p.stdout).unwrap();
    let (json, _, _) = result_of(&tsv, &["--diameter", "7in"]);
    let at = &p["thrust"]["at_reference"];
    assert_eq!(json["thrust"]["c_t"]["value"], at["value"], "{at}");
    assert_eq!(json["thrust"]["c_t"]["stderr"], at["stderr"], "{at}");
    assert_eq!(json["thrust"]["method"], "plateaus");
    // report.html's Result, the same.
    let html = dir.path().join("rc.html");
    propid_ok(&[
        "report",
        t,
        "--diameter",
        "7in",
        "-o",
        html.to_str().unwrap(),
    ]);
    let html = std::fs::read_to_string(&html).unwrap();
    let c_t = json["thrust"]["c_t"]["value"].as_f64().unwrap();
    assert!(html.contains(&format!("C_T  = {c_t:.4e} ±")), "{c_t}");
    // And its propulsion section: `propid propulsion`'s text (the plateaus with the efficiency
    // η of each) and plot; a value the fit does not identify is not in a title.
    let text =
        String::from_utf8(propid_ok(&["propulsion", t, "--diameter", "7in"]).stdout).unwrap();
    let escaped = |s: &str| {
        s.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
    };
    let c_t_line = text
        .lines()
        .find(|l| l.trim_start().starts_with("C_T ="))
        .unwrap();
    assert!(html.contains("<h2>Propulsion: thrust, torque, power and the motor</h2>"));
    assert!(html.contains(&escaped(c_t_line)), "{c_t_line}");
    assert!(html.contains("η gf/W_e"));
    assert!(!html.contains("J = 1.0000e3"));
    let bare = dir.path().join("bare.html");
    propid_ok(&["report", t, "-o", bare.to_str().unwrap()]);
    let bare = std::fs::read_to_string(&bare).unwrap();
    assert!(bare.contains("give <code>--diameter</code>"));
}

/// A steady-state log (an RCbenchmark load cell at ~7 Hz on held plateaus): the Result is the
/// seed's drag law from the plateaus with its standard error (the c2 docs/REAL_DATA.md's table
/// gives), J is said not identified, and no line of the text shows a NaN.
#[test]
fn a_steady_state_log_gives_the_seeds_drag_law_and_no_nan() {
    let dir = tempfile::tempdir().unwrap();
    let tsv = rcbench(dir.path(), "Log_2019-11-05_171350");
    let t = tsv.to_str().unwrap();
    let out = propid_ok(&["diagnose", t, "--format", "json"]);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let law = &json["steady_state"];
    let c2 = &json["result"]["c2"];
    assert_eq!(c2["value"], law["c2"], "{c2}");
    assert_eq!(c2["stderr"], law["c2_stderr"], "{c2}");
    // REAL_DATA.md's table: 5.97e-8 for this run.
    assert!(
        (c2["value"].as_f64().unwrap() * 1e8 - 5.97).abs() <= 0.005,
        "{c2}"
    );
    let not_identified = json["result"]["not_identified"].to_string();
    assert!(
        not_identified.contains("J") && !not_identified.contains("c2"),
        "{not_identified}"
    );
    let text = String::from_utf8(propid_ok(&["diagnose", t]).stdout).unwrap();
    assert!(!text.contains("NaN"), "{text}");
    assert!(
        text.contains("Torque residual RMS on the steady-state data")
            && !text.contains("rad/s (gain"),
        "{text}"
    );
}
