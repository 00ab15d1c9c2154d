//! `propid propulsion` and `propid size` end to end: simulated stands with thrust and electrical
//! columns (every constant within 2 % of its truth), the measured logs, the sizing round trip and
//! the worked example of docs/PROPULSION.md, and bad input (a clear message, a non-zero exit).

mod common;

use common::{propid, propid_ok, repo};
use serde_json::Value;

const TAU: f64 = std::f64::consts::TAU;

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

fn s(p: &std::path::Path) -> &str {
    p.to_str().unwrap()
}

fn json(out: &std::process::Output) -> Value {
    serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("not JSON ({e}): {}", String::from_utf8_lossy(&out.stdout)))
}

/// An identified quantity's value (panics, naming it, when it is not identified).
#[track_caller]
fn identified(v: &Value, what: &str) -> f64 {
    assert_eq!(v["status"], "identified", "{what}: {v}");
    v["value"].as_f64().unwrap()
}

#[track_caller]
fn within(what: &str, got: f64, truth: f64, tol: f64) {
    assert!(
        ((got - truth) / truth).abs() <= tol,
        "{what}: {got} against the truth {truth}"
    );
}

/// The formula stand in held steps from rest with a thrust cell and the motor's DC side.
fn simulate_steps(dir: &std::path::Path) -> std::path::PathBuf {
    let tsv = dir.join("steps.tsv");
    propid_ok(&[
        "sim",
        "--pattern",
        "steps",
        "--lo",
        "0",
        "--init-duration",
        "0",
        "--period",
        "10",
        "--duration",
        "90",
        "--c2",
        "5.9e-8",
        "--inertia",
        "3e-5",
        "--thrust-k",
        "3.72e-6",
        "--thrust-offset",
        "0.05",
        "--kv",
        "2000",
        "--winding-resistance",
        "0.08",
        "--no-load-current",
        "0.6",
        "--bus-voltage",
        "16",
        "--esc-current-filter",
        "0.02",
        "-o",
        s(&tsv),
    ]);
    tsv
}

#[test]
fn simulated_stand_to_constants_to_a_sizing_round_trip() {
    let dir = tmp();
    let tsv = simulate_steps(dir.path());
    let result = dir.path().join("prop.json");
    let out = propid_ok(&[
        "propulsion",
        s(&tsv),
        "--diameter",
        "7in",
        "--command-is-duty",
        "--motor",
        "--format",
        "json",
        "-o",
        s(&result),
    ]);
    let p = json(&out);
    let rho = 1.225;
    let d: f64 = 0.1778;
    let ct_truth = 3.72e-6 * TAU * TAU / (rho * d.powi(4));
    let cq_truth = 5.9e-8 * TAU * TAU / (rho * d.powi(5));
    within(
        "C_T",
        identified(&p["thrust"]["at_reference"], "C_T"),
        ct_truth,
        0.02,
    );
    within(
        "C_Q",
        identified(&p["torque"]["at_reference"], "C_Q"),
        cq_truth,
        0.02,
    );
    let m = &p["motor"];
    within("Kv", identified(&m["kv"], "Kv"), 2000.0, 0.02);
    within("R", identified(&m["resistance"], "R"), 0.08, 0.02);
    within(
        "K_t",
        identified(&m["kt"], "K_t"),
        60.0 / (TAU * 2000.0),
        0.02,
    );
    within("I_0", identified(&m["no_load_current"], "I_0"), 0.6, 0.02);

    // Round trip: the identified law → a thrust target → speed → the law's thrust there.
    let out = propid_ok(&[
        "size",
        "--propeller",
        s(&result),
        "--thrust",
        "600g",
        "--thrust",
        "5N",
        "--format",
        "json",
    ]);
    let a = json(&out);
    let law = &p["thrust"]["law"];
    let (nr, at, exp) = (
        law["reference_speed"].as_f64().unwrap(),
        law["at_reference"].as_f64().unwrap(),
        law["exponent"].as_f64().unwrap(),
    );
    let quad = p["thrust"]["quadratic"]["value"].as_f64().unwrap();
    let speed_dependent = p["thrust"]["speed_dependent"].as_bool().unwrap();
    for (point, target) in a["points"]
        .as_array()
        .unwrap()
        .iter()
        .zip([0.6 * 9.806_65, 5.0])
    {
        let n = point["speed"]["value"].as_f64().unwrap() / TAU;
        let thrust = if speed_dependent {
            at * (n / nr).powf(exp)
        } else {
            quad * rho * n * n * d.powi(4)
        };
        assert!(
            (thrust / target - 1.0).abs() < 1e-3,
            "{thrust} N for a target of {target} N"
        );
    }
}

/// docs/PROPULSION.md §5's question.
const WORKED_EXAMPLE: &[&str] = &[
    "size",
    "--c-t",
    "0.14",
    "--c-q",
    "0.0107",
    "--diameter",
    "7in",
    "--thrust",
    "6N",
    "--rotors",
    "4",
    "--kv",
    "1750",
    "--resistance",
    "60mohm",
    "--no-load-current",
    "0.8A",
    "--voltage",
    "4S",
    "--battery",
    "3000mAh",
    "--usable",
    "0.8",
    "--density",
    "1.225",
];

#[test]
fn the_worked_example_of_the_docs() {
    // docs/PROPULSION.md §5, computed there by hand.
    let out = propid_ok(&[WORKED_EXAMPLE, &["--format", "json"]].concat());
    let a = json(&out);
    let p = &a["points"][0];
    let e = &p["electrical"];
    let t = &p["totals"];
    let k = &a["kv_advice"][0];
    for (what, got, doc, decimals) in [
        ("rpm", p["rpm"].as_f64().unwrap(), 11226.2, 1),
        ("torque", p["torque"]["value"].as_f64().unwrap(), 0.08153, 5),
        (
            "shaft power",
            p["mechanical_power"]["value"].as_f64().unwrap(),
            95.85,
            2,
        ),
        (
            "figure of merit",
            p["figure_of_merit"].as_f64().unwrap(),
            0.6217,
            4,
        ),
        (
            "motor current",
            e["motor_current"].as_f64().unwrap(),
            15.742,
            3,
        ),
        (
            "motor voltage",
            e["motor_voltage"].as_f64().unwrap(),
            7.359,
            3,
        ),
        ("electrical power", e["power"].as_f64().unwrap(), 115.85, 2),
        ("efficiency", e["efficiency"].as_f64().unwrap(), 0.8274, 4),
        ("duty", e["duty"].as_f64().unwrap(), 0.4973, 4),
        ("DC current", e["dc_current"].as_f64().unwrap(), 7.828, 3),
        ("ripple", e["ripple_current"].as_f64().unwrap(), 7.871, 3),
        (
            "battery current",
            t["battery_current"].as_f64().unwrap(),
            31.31,
            2,
        ),
        ("C-rate", t["c_rate"].as_f64().unwrap(), 10.44, 2),
        (
            "endurance",
            t["endurance_minutes"].as_f64().unwrap(),
            4.60,
            2,
        ),
        ("Kv min", k["kv_min"].as_f64().unwrap(), 782.2, 1),
        (
            "current at Kv min",
            k["motor_current"].as_f64().unwrap(),
            7.479,
            3,
        ),
    ] {
        let half = 0.5 * 10f64.powi(-decimals) * (1.0 + 1e-9);
        assert!(
            (got - doc).abs() <= half,
            "{what}: {got}, the docs print {doc}"
        );
    }
    // The text says the same.
    let out = propid_ok(WORKED_EXAMPLE);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("speed   11226") && text.contains("Kv ≥ 782 rpm/V"),
        "{text}"
    );
}

fn import_rcbench(dir: &std::path::Path, log: &str) -> std::path::PathBuf {
    let tsv = dir.join("rc.tsv");
    let csv = repo().join(format!("tests/data/esc_test_alspitz/rcbench/Log_{log}.csv"));
    propid_ok(&["import", "rcbench", s(&csv), "-o", s(&tsv)]);
    tsv
}

#[test]
fn a_measured_log_from_import_to_coefficients() {
    let dir = tmp();
    let tsv = import_rcbench(dir.path(), "2019-11-07_184325");
    let out = propid_ok(&[
        "propulsion",
        s(&tsv),
        "--diameter",
        "7in",
        "--reference-speed",
        "12000rpm",
        "--format",
        "yaml",
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    // The YAML reads back as the same result (propid size takes either).
    let yaml = dir.path().join("prop.yaml");
    std::fs::write(&yaml, text.as_bytes()).unwrap();
    let out = propid_ok(&[
        "size",
        "--propeller",
        s(&yaml),
        "--speed",
        "12000rpm",
        "--format",
        "json",
    ]);
    let a = json(&out);
    let thrust = a["points"][0]["thrust"]["value"].as_f64().unwrap();
    // C_T = 0.14259 at 12000 rpm (docs/PROPULSION.md §3).
    let expected = 0.14259 * 1.225 * 200.0 * 200.0 * 0.1778f64.powi(4);
    assert!(
        (thrust / expected - 1.0).abs() < 5e-4,
        "{thrust} N against {expected} N"
    );
}

#[test]
fn esc32_kv_from_back_emf_from_the_command_line() {
    let dir = tmp();
    let tsv = dir.path().join("f40.tsv");
    let csv = repo().join("tests/data/esc_test_alspitz/autoquad/f40_steps_5-2.csv");
    propid_ok(&["import", "autoquad", s(&csv), "--kv", "1600", "-o", s(&tsv)]);
    let out = propid_ok(&[
        "propulsion",
        s(&tsv),
        "--diameter",
        "7in",
        "--command-is-duty",
        "--motor",
        "--format",
        "json",
    ]);
    let p = json(&out);
    let kv = identified(&p["motor"]["kv"], "Kv");
    assert!((kv - 2083.0).abs() < 0.5, "{kv}");
    // Without --command-is-duty the duty is not taken from `command`: Kv cannot be judged.
    let out = propid(
        &["propulsion", s(&tsv), "--diameter", "7in", "--motor"],
        None,
    );
    assert_eq!(out.status.code(), Some(3));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--command-is-duty") && err.contains("cannot judge Kv"),
        "{err}"
    );
}

/// Rewrites one column of a TSV through `f`.
fn rewrite(src: &std::path::Path, dst: &std::path::Path, column: &str, f: impl Fn(f64) -> f64) {
    let text = std::fs::read_to_string(src).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let k = header.split('\t').position(|c| c == column).unwrap();
    let mut out = String::from(header);
    out.push('\n');
    for line in lines {
        let fields: Vec<String> = line
            .split('\t')
            .enumerate()
            .map(|(i, v)| match (i == k, v.parse::<f64>()) {
                (true, Ok(x)) if x.is_finite() => format!("{}", f(x)),
                _ => v.to_string(),
            })
            .collect();
        out.push_str(&fields.join("\t"));
        out.push('\n');
    }
    std::fs::write(dst, out).unwrap();
}

#[test]
fn bad_input_gets_a_clear_word_and_a_non_zero_exit() {
    let dir = tmp();
    let tsv = import_rcbench(dir.path(), "2019-11-07_184325");

    // Thrust in gram-force read as newtons.
    let gf = dir.path().join("gf.tsv");
    rewrite(&tsv, &gf, "thrust", |x| x / 9.806_65e-3);
    let out = propid(&["propulsion", s(&gf), "--diameter", "7in"], None);
    assert_eq!(out.status.code(), Some(3));
    let all = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(all.contains("gram-force but read as newtons"), "{all}");

    // A diameter in inches without its unit: refused before anything is read, as by fit and
    // diagnose.
    let out = propid(&["propulsion", s(&tsv), "--diameter", "7"], None);
    assert_eq!(out.status.code(), Some(2));
    let all = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        all.contains("--diameter 7 has no unit") && all.contains("7in, 178mm"),
        "{all}"
    );

    // An electrical speed: C_T comes out 49 times too small; the pole pairs are named, and
    // --pole-pairs puts it right.
    let electrical = dir.path().join("electrical.tsv");
    rewrite(&tsv, &electrical, "velocity", |x| 7.0 * x);
    let out = propid(&["propulsion", s(&electrical), "--diameter", "7in"], None);
    assert_eq!(out.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&out.stdout).contains("--pole-pairs"));
    propid_ok(&[
        "propulsion",
        s(&electrical),
        "--diameter",
        "7in",
        "--pole-pairs",
        "7",
    ]);

    // The motor asked of a log without a voltage column.
    let no_v = dir.path().join("no_voltage.tsv");
    let text = std::fs::read_to_string(&tsv).unwrap();
    let header = text
        .lines()
        .next()
        .unwrap()
        .replace("\tvoltage\t", "\tbus_v\t");
    std::fs::write(
        &no_v,
        text.replacen(text.lines().next().unwrap(), &header, 1),
    )
    .unwrap();
    let out = propid(
        &["propulsion", s(&no_v), "--diameter", "7in", "--motor"],
        None,
    );
    assert_eq!(out.status.code(), Some(3));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no `voltage` column"), "{err}");

    // No steady plateau and a slow thrust cell: nothing to fit.
    let sine = dir.path().join("sine.tsv");
    propid_ok(&[
        "sim",
        "--duration",
        "20",
        "--rate",
        "100",
        "--thrust-k",
        "3.72e-6",
        "--thrust-rate",
        "2",
        "-o",
        s(&sine),
    ]);
    let out = propid(&["propulsion", s(&sine), "--diameter", "7in"], None);
    assert_eq!(out.status.code(), Some(3));
    let all = String::from_utf8_lossy(&out.stdout);
    assert!(
        all.contains("0 steady plateau(s)") && all.contains("too few for a dynamic fit"),
        "{all}"
    );

    // Flags: a unit that is no length, a result file that is no result, no target.
    let out = propid(&["propulsion", s(&tsv), "--diameter", "7 furlongs"], None);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown unit `furlongs`"));
    let out = propid(&["size", "--propeller", s(&tsv), "--thrust", "6N"], None);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a `propid propulsion` result"));
    let out = propid(
        &[
            "size",
            "--c-t",
            "0.14",
            "--c-q",
            "0.0107",
            "--diameter",
            "7in",
        ],
        None,
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("give at least one target"));
    // The output must not be the recording.
    let out = propid(
        &["propulsion", s(&tsv), "--diameter", "7in", "-o", s(&tsv)],
        None,
    );
    assert_eq!(out.status.code(), Some(2));
}
