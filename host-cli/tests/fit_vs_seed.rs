//! `propid fit` against the seed regressor (tests/seed/dynamics_id_regressor.py) on the same
//! generated files: the same numbers where the seed's optimiser converges, and a lower (better)
//! value of the seed's own objective where it does not.

mod common;

use common::{propid, repo, require_python, yaml_value};
use std::process::Command;

fn make_case(dir: &std::path::Path, name: &str, args: &str) -> std::path::PathBuf {
    let out = dir.join(name);
    let status = Command::new("python3")
        .arg(repo().join("tests/seed/make_case.py"))
        .arg(&out)
        .args(args.split_whitespace())
        .status()
        .unwrap();
    assert!(status.success(), "make_case {args}");
    out
}

fn seed(file: &std::path::Path, opts: &[&str]) -> (f64, f64, f64) {
    let out = Command::new("python3")
        .arg(repo().join("tests/seed/dynamics_id_regressor.py"))
        .arg("--no-plot")
        .args(opts)
        .stdin(std::fs::File::open(file).unwrap())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "seed failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    (
        yaml_value(&text, "mass"),
        yaml_value(&text, "c1"),
        yaml_value(&text, "c2"),
    )
}

fn ours(file: &std::path::Path, opts: &[&str]) -> (f64, f64, f64) {
    let mut args = vec!["fit", file.to_str().unwrap()];
    args.extend_from_slice(opts);
    let out = propid(&args, None);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    (
        yaml_value(&text, "mass"),
        yaml_value(&text, "c1"),
        yaml_value(&text, "c2"),
    )
}

/// One unit of the sixth significant digit of a printed value (0 for an exact 0).
fn sixth_digit(printed: f64) -> f64 {
    if printed == 0.0 {
        0.0
    } else {
        10f64.powf(printed.abs().log10().floor() - 5.0) * (1.0 + 1e-9)
    }
}

fn rel(a: f64, b: f64) -> f64 {
    if a == b {
        0.0
    } else {
        (a - b).abs() / a.abs().max(b.abs())
    }
}

#[test]
#[ignore = "needs python3 with numpy, scipy, pandas (ci/setup.sh; ci/steps/30-python-peers.sh runs it)"]
fn agrees_with_the_seed_where_it_converges() {
    require_python("numpy, scipy, pandas");
    let dir = tempfile::tempdir().unwrap();
    // (generator arguments, fit options, what it exercises, what must then hold of propid's
    // (J, c1, c2) so that the case really exercises it).
    type Holds = fn(f64, f64, f64) -> bool;
    let cases: [(&str, &[&str], &str, Holds); 5] = [
        (
            "0.5 0 0.02 --torque 1,9 --w0 10 --noise 0.5 --nan-head 5",
            &[],
            "free fit, incomplete head rows",
            |m, _, c2| rel(m, 0.5) < 0.02 && rel(c2, 0.02) < 0.02,
        ),
        (
            "0.5 0.3 0.02 --torque 1,9 --w0 10 --noise 0.5",
            &[],
            "c1 bound active (c1_max = 0)",
            |_, c1, _| c1 == 0.0,
        ),
        (
            "2.0 0 0.05 --torque 2,20 --w0 10 --noise 0.1 --rows 5000 --seed 4",
            &[],
            "another load",
            |m, _, c2| rel(m, 2.0) < 0.02 && rel(c2, 0.05) < 0.02,
        ),
        (
            "0.5 0 0.02 --torque 1,9 --w0 10 --noise 0.5 --seed 2",
            &["--mass-max", "0.4"],
            "mass bound active",
            |m, _, _| m == 0.4,
        ),
        (
            "1.0 0.2 0.03 --torque 1,9 --w0 10 --noise 0.2 --seed 3",
            &["--c1-max", "1"],
            "viscous term free",
            |_, c1, _| c1 > 0.0 && c1 < 1.0 && rel(c1, 0.2) < 0.2,
        ),
    ];
    for (k, (gen, opts, what, holds)) in cases.iter().enumerate() {
        let file = make_case(dir.path(), &format!("case{k}.tsv"), gen);
        let (sm, sc1, sc2) = seed(&file, opts);
        let (m, c1, c2) = ours(&file, opts);
        eprintln!("{what}: seed ({sm}, {sc1}, {sc2}) propid ({m}, {c1}, {c2})");
        // The seed prints 6 significant digits; README: propid agrees with them, within one unit
        // of the sixth (the seed's L-BFGS-B stops short of the exact minimum by less than that).
        for (name, printed, exact) in [("mass", sm, m), ("c1", sc1, c1), ("c2", sc2, c2)] {
            assert!(
                (printed - exact).abs() <= sixth_digit(printed),
                "{what}: {name} seed {printed} propid {exact}"
            );
        }
        assert!(
            holds(m, c1, c2),
            "{what}: ({m}, {c1}, {c2}) does not exercise what the case claims"
        );
    }
}

#[test]
#[ignore = "needs python3 with numpy, scipy, pandas (ci/setup.sh; ci/steps/30-python-peers.sh runs it)"]
fn beats_the_seed_objective_where_the_seed_stalls() {
    require_python("numpy, scipy, pandas");
    // A real 7-inch propeller's magnitudes: the seed's L-BFGS-B (x0 = (1, 0, 0), finite-difference
    // gradients) stops short; the exact solution must have a lower value of the seed's own loss.
    let dir = tempfile::tempdir().unwrap();
    let file = make_case(
        dir.path(),
        "prop.tsv",
        "2e-5 0 1.5e-8 --noise 50 --nan-head 3",
    );
    let (sm, sc1, sc2) = seed(&file, &[]);
    let (m, c1, c2) = ours(&file, &[]);
    let out = Command::new("python3")
        .arg(repo().join("tests/seed/loss.py"))
        .arg(&file)
        .args([sm, sc1, sc2, m, c1, c2].map(|v| v.to_string()))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let losses: Vec<f64> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| l.parse().unwrap())
        .collect();
    eprintln!(
        "seed loss {} at ({sm}, {sc2}); propid loss {} at ({m}, {c2})",
        losses[0], losses[1]
    );
    assert!(
        losses[1] <= losses[0],
        "propid's optimum must be at least as good"
    );
    // And it is near the truth used to generate the data.
    assert!(rel(m, 2e-5) < 5e-3 && rel(c2, 1.5e-8) < 5e-3, "({m}, {c2})");
    // README: the seed (SciPy 1.17.1, pinned in ci/setup.sh) stops 0.2 % off in J and 1.1 % off
    // in c2 from the exact answer.
    let off = |seed: f64, exact: f64| (100.0 * rel(seed, exact) * 10.0).round() / 10.0;
    assert_eq!((off(sm, m), off(sc2, c2)), (0.2, 1.1), "({sm}, {sc2})");
}
