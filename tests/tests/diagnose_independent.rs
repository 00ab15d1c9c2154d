//! `propid diagnose` against the independent reference stand (tests/independent_stand: Python,
//! written from first principles without reading propid's simulators or its diagnosis). Every
//! diagnosis case of the stand, one effect or two at once, is generated with six noise seeds (two read while tuning, four held out) and
//! judged against the truth the stand's JSON states: the effects an ideal report names (or an
//! ambiguity the stand itself lists as equivalent), each value within 10 %, the extended model's J
//! and drag within 2 %, a load transient localised in time, and nothing named on clean data.
//!
//! The table it prints is docs/SCIENCE.md's "The independent stand". Cases the diagnosis does not
//! get right are listed in [`KNOWN_LIMITS`] with the reason, and asserted to stay honest (never a
//! verdict that the model explains the data while J or the drag is off): a case leaves that list when it is fixed, and the
//! test fails if a listed case starts passing, so the list and the docs cannot drift.
//!
//! `#[ignore]`d: it needs python3 with numpy and scipy (ci/setup.sh installs them);
//! ci/steps/38-diagnose-independent.sh runs it with `-- --ignored`.

mod expect;

use std::path::{Path, PathBuf};
use std::process::Command;

use expect::{
    against_ledger, describe, fit_errors, judge, model_errors, say, silently_wrong, Expected, Ties,
    Truth,
};
use propid_science::diagnose::{
    diagnose, read_samples, EffectKind, EffectSet, Options, Preference, Report, Verdict,
    NEAR_MISS_GAIN,
};
use propid_science::result::Outcome;
use serde_json::Value;

/// The stand's diagnosis cases (its thrust cases are propulsion's: propulsion_independent.rs).
const CASES: &[&str] = &[
    "clean",
    "clean_chirp",
    "torque_lag_8ms",
    "torque_lag_15ms",
    "force_offset",
    "viscous",
    "coulomb_reversing",
    "drag_exponent_1p8",
    "drag_exponent_2p2",
    "force_sensor_lag",
    "force_sensor_2nd_order",
    "acceleration_lag",
    "braking",
    "lag_offset",
    "lag_viscous",
    "lag_coulomb_reversing",
    "drag_exponent_offset",
    "braking_lag",
    "sensor_filter_drag_exponent",
    "large_clean",
    "large_torque_lag_25ms",
    "transient_late",
    "transient_early",
];

/// The noise seeds every case is drawn with: [`TUNING_SEEDS`], then [`HELD_OUT_SEEDS`].
const SEEDS: [u64; 6] = [1, 2, 3, 4, 5, 6];

/// The seeds the selection was developed against: its rules and the lags' tuning were changed
/// while reading these runs (docs/SCIENCE.md "Lags tuned by the simulated velocity").
const TUNING_SEEDS: [u64; 2] = [1, 2];

/// Seeds drawn only after those changes, to validate them on runs that played no part in them:
/// first run on 2026-11-26 against main 6b363b0: 15, 15, 16 and 16 of 23 right as judged here,
/// the second-order sensor stage "explained" with J 3.6 % low on seeds 3, 4 and 6, and the clean
/// runs of seeds 3 and 4 "unexplained" (a residual peak at the sine's own frequency). Seeds 3 and
/// 4 were then read to find why (what the simulated velocity alone shows is now reported:
/// `SimulationOnly`; a peak where the force is driven is not a disturbance); seeds 5 and 6 were
/// not, and validate the first change (seed 6's stage is no longer "explained").
const HELD_OUT_SEEDS: [u64; 4] = [3, 4, 5, 6];

/// Cases (case, seed) the diagnosis does not get right today, and why. Each must still end
/// honestly: no verdict that the model explains the data while its J or drag is more than 2 %
/// off.
const KNOWN_LIMITS: &[(&str, u64, &str, Against)] = &[
    ("lag_viscous", 2, LAG_UNDER_A_TERM, Against::Same),
    (
        "drag_exponent_offset",
        1,
        SPEED_SHAPES,
        Against::TruthPreferredBySimulation,
    ),
    ("drag_exponent_offset", 2, SPEED_SHAPES, Against::CannotTell),
    (
        "sensor_filter_drag_exponent",
        1,
        SPEED_SHAPES,
        Against::CannotTell,
    ),
    (
        "sensor_filter_drag_exponent",
        2,
        SPEED_SHAPES,
        Against::TruthPreferredBySimulation,
    ),
    ("force_sensor_lag", 1, SENSOR_LAG, Against::Same),
    ("force_sensor_2nd_order", 2, SENSOR_LAG, Against::Same),
    // The held-out seeds: the same families, and the second-order stage on both.
    ("lag_viscous", 3, LAG_UNDER_A_TERM, Against::CannotTell),
    (
        "lag_viscous",
        4,
        LAG_UNDER_A_TERM,
        Against::TruthPreferredBySimulation,
    ),
    (
        "drag_exponent_offset",
        3,
        SPEED_SHAPES,
        Against::TruthPreferredBySimulation,
    ),
    (
        "drag_exponent_offset",
        4,
        SPEED_SHAPES,
        Against::TruthPreferredBySimulation,
    ),
    (
        "sensor_filter_drag_exponent",
        3,
        SPEED_SHAPES,
        Against::NamedPreferred,
    ),
    (
        "sensor_filter_drag_exponent",
        4,
        SPEED_SHAPES,
        Against::CannotTell,
    ),
    (
        "force_sensor_2nd_order",
        4,
        SENSOR_LAG,
        Against::NamedPreferred,
    ),
    ("lag_viscous", 5, LAG_UNDER_A_TERM, Against::CannotTell),
    ("lag_viscous", 6, LAG_UNDER_A_TERM, Against::CannotTell),
    (
        "drag_exponent_offset",
        5,
        SPEED_SHAPES,
        Against::TruthPreferredBySimulation,
    ),
    (
        "drag_exponent_offset",
        6,
        SPEED_SHAPES,
        Against::TruthPreferredBySimulation,
    ),
    (
        "sensor_filter_drag_exponent",
        5,
        SPEED_SHAPES,
        Against::CannotTell,
    ),
    (
        "sensor_filter_drag_exponent",
        6,
        SPEED_SHAPES,
        Against::NamedPreferred,
    ),
    ("force_sensor_lag", 5, SENSOR_LAG, Against::Same),
    ("force_sensor_lag", 6, SENSOR_LAG, Against::Same),
    ("force_sensor_2nd_order", 5, SENSOR_LAG, Against::CannotTell),
    (
        "force_sensor_2nd_order",
        6,
        SENSOR_LAG,
        Against::NamedPreferred,
    ),
    ("lag_offset", 5, LAG_PRECISION, Against::CannotTell),
    ("lag_offset", 6, LAG_PRECISION, Against::CannotTell),
];

/// What the truth's own effects show against the model named, fitted as the search fits a model
/// and scored on the same folds (`diagnose --compare`, the effects the stand hides): whether a
/// limit is the data's (they cannot tell the two apart, or prefer the model named) or the
/// selection's (they prefer the truth's).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Against {
    /// The model named holds the truth's effects (a value off, or a tie listed beside it).
    Same,
    /// The data cannot tell the two apart.
    CannotTell,
    /// The data prefer the model named.
    NamedPreferred,
    /// The data prefer the truth's effects, and the acceleration equation confirms them: the
    /// search did not reach that model.
    TruthPreferred,
    /// The data prefer the truth's effects by the simulated velocity while the acceleration
    /// equation alone gains under 0.5 % (rule 4's floor) or loses: where rule 4 rejected them
    /// (the drag exponent beside an offset in the report's round 2, a sensor filter as what the
    /// simulated velocity alone shows) or the report gives them as rule 10's tie.
    TruthPreferredBySimulation,
}

impl Against {
    fn of(r: &Report) -> Option<Against> {
        let c = r.compared.as_ref()?;
        Some(match c.preferred {
            Preference::Same => Against::Same,
            Preference::Neither => Against::CannotTell,
            Preference::Named => Against::NamedPreferred,
            Preference::Asked if c.equation.mean < NEAR_MISS_GAIN => {
                Against::TruthPreferredBySimulation
            }
            Preference::Asked => Against::TruthPreferred,
        })
    }
}

/// A 15 ms lag beside a 0.02 N·m offset named at 17.2 and 13.4 ms (+15 % and −11 %; 13.5–16.3 ms
/// on seeds 1–4): the lag's spread on this stand's noise is wider than the 10 % judged.
const LAG_PRECISION: &str = "a lag's value beside an offset, 11–15 % off on two draws";

/// Known limits where the verdict is worse than a miss: it says the model explains the data
/// while J or the drag is more than 2 % off (docs/SCIENCE.md would say so). None today. The
/// second-order sensor stage was on held-out seeds 3, 4 and 6: a −2.7 mN·m offset named, J
/// 3.6 % low, the drag 5.3 % high, "explained", while a drag exponent or a viscous term gained
/// 22 % in the simulated velocity and 0.1 % in the equation (rule 4 names nothing the equation
/// does not confirm); the report now says the velocity is unexplained and what J would read.
/// (Braking
/// beside a torque lag, seed 2, was until the braking spells were located where the velocity
/// kinks: the ±20 ms slope turned 12 ms before each step the braking makes, a timing error a
/// viscous friction absorbed better than the lag, and J read 3.5 % high, c2 6.3 % low.)
const SILENTLY_WRONG: &[(&str, u64)] = &[];

/// A torque lag beside a term that takes most of it first: a 10 ms lag beside a viscous friction
/// on the sine (a Coulomb friction is named in the first round, beside which the lag, re-tuned,
/// no longer passes). Rule 10 exchanges the Coulomb friction for the lag and the viscous term on
/// seed 1 (right) and seed 2 (both named, the lag 11.2 ms, 12 % long; J and c2 within 1 %); on
/// seeds 3–6 no exchange is made (on seed 4 the pair is not separated from the Coulomb friction
/// beside another effect; on 3, 5 and 6 no pair passes rule 9), and the lag and the viscous term
/// are given as the alternative the data cannot rule out (rule 10's tie): on seeds 5 and 6 with
/// every value within 10 % and J and the drag within 2 %, but as an ambiguity the stand's ideal
/// report does not list. Each lag's time constant is
/// tuned by both held-out errors (the simulated
/// velocity's too) since the equation's alone, dominated by this stand's acceleration noise,
/// tuned a 15 ms lag to 0.4 ms.
const LAG_UNDER_A_TERM: &str = "a lag beside a torque term that absorbs it in the first round";

/// A drag exponent of 1.8 beside an offset: found at its value in round 2 and rejected by rule 4
/// (the acceleration equation gains 0.44–0.49 %, under its 0.5 %, while the simulated velocity
/// gains most of the 0.8–0.9: `Against::TruthPreferredBySimulation` on five seeds); a constant
/// torque 23 % above the offset is named. A sensor filter beside an exponent of 2.2: an offset
/// named first takes part of the filter's phase, and the search's tuning does not reach the
/// truth's values from these data (the truth's effects tuned as the search tunes them do no
/// better than the model named, except on seed 2).
const SPEED_SHAPES: &str =
    "torque shapes of speed the sine's band does not separate for the selection";

/// A 10 ms first-order force-sensor lag is tied with an offset on seeds 1, 5 and 6 (named at
/// 9.4–10.7 ms; 11.0–12.3 ms, 10–23 % long, on every seed until the reported parameters were
/// taken without the force noise's errors-in-variables bias, which read the lag long and J high);
/// the second-order sensor stage is named as a 14.0 ms delay tied with an offset on seed 2, read
/// as an offset on seeds 4–6 (seed 3 right since re-tuning the model after a step is kept only
/// where the selection's criterion does not lose: its named delay had moved from 14.2 to 17.9 ms
/// by the equation alone, and an offset later took its place). (The 10 ms acceleration lag, not found on any seed while ȧ's
/// instrument shared the differenced acceleration's correlated noise, is right on all six.)
const SENSOR_LAG: &str = "sensor-side lags on this stand's noise";

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

fn kind(name: &str) -> EffectKind {
    *EffectKind::ALL
        .iter()
        .find(|k| k.name() == name)
        .unwrap_or_else(|| panic!("the stand names an effect propid does not know: {name}"))
}

/// Every case of the stand drawn with `seed` and every noise scaled by `noise_scale`, into `out`;
/// whether stand.py ran.
fn draw(out: &Path, seed: u64, noise_scale: &str) -> bool {
    Command::new("python3")
        .arg(repo().join("tests/independent_stand/stand.py"))
        .args(["--all", "--noise-scale", noise_scale])
        .args(["--seed", &seed.to_string(), "--out"])
        .arg(out)
        .stdout(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// `case` drawn with `seed` in `out`, diagnosed, with the truth the stand states.
fn diagnosed(out: &Path, case: &str, seed: u64) -> (Report, Value) {
    let tsv = out.join(format!("{case}-seed{seed}.tsv"));
    let json = std::fs::read_to_string(out.join(format!("{case}-seed{seed}.json"))).unwrap();
    let truth: Value = serde_json::from_str(&json).unwrap();
    let (samples, _) = read_samples(&tsv).expect("the stand's TSV reads");
    // The truth's own effects scored beside the model named (`Against`).
    let compare = truth["effects"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|e| e["name"].as_str())
        .try_fold(EffectSet::EMPTY, |set, name| set.with(kind(name)))
        .expect("the stand's effects make one model");
    let options = Options {
        compare,
        ..Options::default()
    };
    let r = diagnose(&samples, options).expect("diagnosis runs");
    (r, truth)
}

/// The stand's J and drag law, compared at the steady speed at half of full scale (the middle
/// of the seed's 0.1..0.9).
fn truth_of(truth: &Value) -> Truth {
    let ideal = &truth["ideal_report"];
    let p = ideal["effects"]["drag_exponent"]["value"]
        .as_f64()
        .unwrap_or(2.0);
    let k = ideal["c2"].as_f64().unwrap();
    let full_scale = truth["rotor"]["full_scale_torque_Nm"].as_f64().unwrap();
    Truth {
        inertia: ideal["J"].as_f64().unwrap(),
        c1: ideal["effects"]["viscous_friction"]["value"]
            .as_f64()
            .unwrap_or(0.0),
        k,
        p,
        speed: (0.5 * full_scale / k).powf(1.0 / p),
    }
}

/// What is wrong with `r` against the stand's truth (empty: right).
fn problems(r: &Report, truth: &Value) -> Vec<String> {
    let ideal = &truth["ideal_report"];
    let expected: Vec<Expected> = ideal["effects"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(name, e)| Expected {
            kind: kind(name),
            value: e["value"].as_f64().unwrap(),
            tolerance: 0.10,
        })
        .collect();
    let pairs: Vec<(EffectKind, EffectKind)> = ideal["equivalent_alternatives"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| {
            (
                kind(a["instead_of"].as_str().unwrap()),
                kind(a["name"].as_str().unwrap()),
            )
        })
        .collect();
    let mut bad = judge(r, &expected, Ties::Only(&pairs), Some(truth_of(truth)));
    // Nothing hidden: the ideal report says the seed's model explains the data, and so must the
    // verdict (nothing named is not enough: an "unexplained" there is a false alarm).
    if expected.is_empty()
        && ideal["unexplained"].as_array().unwrap().is_empty()
        && r.verdict != Verdict::NothingWrong
    {
        bad.push(format!(
            "nothing is hidden, but the verdict is {:?}",
            r.verdict
        ));
    }
    for window in ideal["unexplained"].as_array().unwrap() {
        let (from, to) = (
            window["t_start_s"].as_f64().unwrap(),
            window["t_end_s"].as_f64().unwrap(),
        );
        let found = r.concentration.as_ref().is_some_and(|c| {
            c.from_s < to && c.to_s > from && c.to_s - c.from_s < 4.0 * (to - from)
        });
        // Its span left out of the fit: within half a second of the transient's ends.
        let left_out = r
            .left_out
            .as_ref()
            .is_some_and(|l| (l.from_s - from).abs() <= 0.5 && (l.to_s - to).abs() <= 0.5);
        if !found || !left_out || r.verdict != Verdict::Unexplained {
            bad.push(format!(
                "the load transient at {from}–{to} s not reported as unexplained, localised and left out"
            ));
        }
    }
    bad
}

#[test]
#[ignore = "needs python3 with numpy and scipy (ci/steps/38-diagnose-independent.sh)"]
fn the_independent_stand_is_diagnosed_right() {
    let out = std::env::temp_dir().join(format!("propid-independent-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let mut wrong = Vec::new();
    let mut right = 0;
    let mut right_held_out = 0;
    let mut transient_bias = Vec::new();
    say(format!(
        "{:<30} {:>4}  {:<7} report",
        "case", "seed", "outcome"
    ));
    let seeds: Vec<u64> = match std::env::var("PROPID_SEED") {
        Ok(s) => s
            .split(',')
            .map(|x| {
                x.parse()
                    .expect("PROPID_SEED is a comma-separated list of numbers")
            })
            .collect(),
        Err(_) => SEEDS.to_vec(),
    };
    // Another noise level (tests/independent_stand/noise_sweep.sh): every noise scaled by it;
    // the ledger, written for the stand's own noise, is then not asserted, only the tally printed.
    let noise_scale: Option<String> = std::env::var("PROPID_NOISE_SCALE").ok();
    let scale_arg = noise_scale.clone().unwrap_or_else(|| "1".into());
    let mut silent = 0;
    // Of the runs not right, what the truth's effects show against the model named.
    let mut tally = std::collections::BTreeMap::<String, usize>::new();
    // The stand draws the next seed while this one is diagnosed (two cores: the step's time is
    // the larger of the two, not their sum).
    let (drawn, draws) = std::sync::mpsc::channel();
    let generator = {
        let (seeds, out) = (seeds.clone(), out.clone());
        std::thread::spawn(move || {
            for seed in seeds {
                let ok = draw(&out, seed, &scale_arg);
                if drawn.send((seed, ok)).is_err() || !ok {
                    return;
                }
            }
        })
    };
    for (seed, ok) in draws {
        assert!(
            ok,
            "stand.py --all --seed {seed} failed (python3 with numpy and scipy?)"
        );
        let only = std::env::var("PROPID_CASE").ok();
        for &case in CASES
            .iter()
            .filter(|c| only.as_deref().is_none_or(|o| o == **c))
        {
            let (r, truth) = diagnosed(&out, case, seed);
            expect::verbose(&r);
            let bad = problems(&r, &truth);
            if let Some(l) = r
                .left_out
                .as_ref()
                .filter(|_| case.starts_with("transient") && TUNING_SEEDS.contains(&seed))
            {
                transient_bias.push(100.0 * (l.inertia_with / r.extended.inertia - 1.0));
            }
            let limit = KNOWN_LIMITS
                .iter()
                .find(|&&(c, s, _, _)| c == case && s == seed);
            let outcome = match (bad.is_empty(), limit) {
                (true, None) => "right",
                (true, Some(_)) => "FIXED",
                (false, Some(_)) => "limit",
                (false, None) => "WRONG",
            };
            let against = Against::of(&r);
            say(format!(
                "{case:<30} {seed:>4}  {outcome:<7} {}{}{}",
                describe(&r),
                if bad.is_empty() {
                    String::new()
                } else {
                    format!(
                        "\n{:>44}{}\n{:>44}J, drag of each model (named, then each tie's): {}",
                        "",
                        bad.join("; "),
                        "",
                        model_errors(&r, truth_of(&truth))
                            .iter()
                            .map(|(j, d)| format!("{:+.2} %, {:+.2} %", 100.0 * j, 100.0 * d))
                            .collect::<Vec<_>>()
                            .join("; ")
                    )
                },
                match (&r.compared, against) {
                    (Some(c), Some(a)) if !bad.is_empty() => format!(
                        "\n{:>44}the truth's effects: {a:?} (gain {:+.3} ± {:.3}, equation {:+.4}) [{}] J {:.4e}",
                        "",
                        c.gain.mean,
                        c.gain.stderr,
                        c.equation.mean,
                        c.effects
                            .iter()
                            .map(|e| format!("{}={:.4e}", e.effect, e.value))
                            .collect::<Vec<_>>()
                            .join(", "),
                        c.model.inertia
                    ),
                    _ => String::new(),
                }
            ));
            if let Some(a) = against.filter(|_| !bad.is_empty()) {
                *tally.entry(format!("{a:?}")).or_insert(0) += 1;
            }
            // Where the truth's effects do better than the model named, the report never says
            // it explains the data, and the Result says its values are not established.
            if r.asked_does_better() {
                let text = Outcome::from_diagnosis(&r, 0, None)
                    .map(|o| o.to_text())
                    .unwrap_or_default();
                if matches!(r.verdict, Verdict::NothingWrong | Verdict::Explained)
                    || !text.contains("not established")
                {
                    wrong.push(format!(
                        "{case} seed {seed}: the truth's effects do better, yet {:?}:\n{text}",
                        r.verdict
                    ));
                }
            }
            if let (Some(&(_, _, _, ledger)), Some(a), None) = (limit, against, &noise_scale) {
                if ledger != a {
                    wrong.push(format!(
                        "{case} seed {seed}: the truth's effects against the model named: {a:?}, the ledger says {ledger:?}"
                    ));
                }
            }
            if silently_wrong(&r, truth_of(&truth)) {
                silent += 1;
                let (j, drag) = fit_errors(&r, truth_of(&truth));
                say(format!(
                    "{case} seed {seed}: SILENTLY WRONG (J {:+.1} %, drag {:+.1} %)",
                    100.0 * j,
                    100.0 * drag
                ));
            }
            if noise_scale.is_some() {
                if bad.is_empty() {
                    right += 1;
                }
                continue;
            }
            if bad.is_empty() && limit.is_none() {
                right += 1;
                if HELD_OUT_SEEDS.contains(&seed) {
                    right_held_out += 1;
                }
            }
            wrong.extend(against_ledger(
                &format!("{case} seed {seed}"),
                bad,
                limit.is_some(),
                silently_wrong(&r, truth_of(&truth)),
                SILENTLY_WRONG.iter().any(|&(c, s)| c == case && s == seed),
            ));
        }
    }
    generator.join().expect("the stand's thread ends");
    say(format!(
        "the truth's effects against the model named, on the runs not right: {tally:?}"
    ));
    let total = CASES.len() * seeds.len();
    if let Some(scale) = noise_scale {
        say(format!(
            "noise scale {scale}: right {right} of {total} on seeds {seeds:?}; silently wrong {silent}"
        ));
        let _ = std::fs::remove_dir_all(&out);
        return;
    }
    let held_out = seeds.iter().filter(|s| HELD_OUT_SEEDS.contains(s)).count();
    say(format!(
        "right {right} of {total}: {} of {} on the tuning seeds {TUNING_SEEDS:?}, {right_held_out} of {} on the held-out seeds {HELD_OUT_SEEDS:?}; known limits {}",
        right - right_held_out,
        CASES.len() * (seeds.len() - held_out),
        CASES.len() * held_out,
        KNOWN_LIMITS.len()
    ));
    // docs/SCIENCE.md, "An event in time": the transients' samples moved J by 3.2–5.2 %.
    if transient_bias.len() == 4 {
        let (lo, hi) = transient_bias
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), &b| (l.min(b), h.max(b)));
        say(format!(
            "J with the transients' samples: {lo:+.1} .. {hi:+.1} %"
        ));
        if (lo * 10.0).round() != 32.0 || (hi * 10.0).round() != 52.0 {
            wrong.push(format!(
                "J with the transients' samples {lo:+.1} .. {hi:+.1} %; the docs print 3.2–5.2 %"
            ));
        }
    }
    let _ = std::fs::remove_dir_all(&out);
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// Noise-free draws the search does not bring to the truth, with the reason. None today. The
/// sensor filter beside a drag exponent was, until a force sensor's lag re-tuned beside the rest
/// of the model had its form decided again: named as a 3.3 ms delay beside an offset, it could
/// only be re-tuned as a delay once the offset was taken out, that model lost, and the offset
/// the truth does not have stayed.
const NOISE_FREE_LIMITS: &[(&str, &str)] = &[];

/// The same cases drawn without noise (`--noise-scale 0`, seed 1): where the data separate every
/// model, the search must reach the truth — each effect the stand hides named within 2 % (in the
/// model, or in a model an ambiguity gives: a Coulomb friction and an offset on a rotor that never
/// reverses are one column), and J
/// within 0.2 % and the drag within 0.5 % of the truth, so that anything named beside them is
/// negligible (a 2·10⁻⁹ viscous term beside a drag exponent is resolved on noise-free data and
/// moves nothing). A wrong model here is the search's fault, not the noise's: this is how the
/// backward step's re-tuning was found (a 10 ms lag beside viscous friction ended on a 6.3 ms
/// lag, a viscous term 35 % low and an offset).
#[test]
#[ignore = "needs python3 with numpy and scipy (ci/steps/38-diagnose-independent.sh)"]
fn noise_free_draws_reach_the_truth() {
    let out = std::env::temp_dir().join(format!("propid-noise-free-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    assert!(
        draw(&out, 1, "0"),
        "stand.py --all --noise-scale 0 failed (python3 with numpy and scipy?)"
    );
    let mut wrong = Vec::new();
    let mut right = 0;
    for &case in CASES {
        let (r, truth) = diagnosed(&out, case, 1);
        let (inertia, drag) = fit_errors(&r, truth_of(&truth));
        // The values only: a verdict on a record whose residual is the stand's float32 rounding
        // is not what this judges (the clean draw's rounding is larger at high speed, and is
        // reported so).
        let mut bad = Vec::new();
        let hidden = truth["ideal_report"]["effects"].as_object().unwrap();
        for (name, e) in hidden {
            let value = e["value"].as_f64().unwrap();
            let mut named = r.effects.iter().map(|x| (x.effect, x.value)).chain(
                r.ambiguities
                    .iter()
                    .flat_map(|a| a.alternative_effects.iter().map(|x| (x.effect, x.value))),
            );
            if !named.any(|(k, v)| k == kind(name) && (v / value - 1.0).abs() <= 0.02) {
                bad.push(format!("{name} not within 2 % of {value:.4e}"));
            }
        }
        if inertia.abs() > 0.002 || drag.abs() > 0.005 {
            bad.push(format!(
                "J {:+.3} %, drag {:+.3} % (within 0.2 % and 0.5 %)",
                100.0 * inertia,
                100.0 * drag
            ));
        }
        let limit = NOISE_FREE_LIMITS.iter().find(|(c, _)| *c == case);
        say(format!(
            "{case:<30} {:<7} J {:+.3} % drag {:+.3} % {}{}",
            match (bad.is_empty(), limit) {
                (true, None) => "right",
                (true, Some(_)) => "FIXED",
                (false, Some(_)) => "limit",
                (false, None) => "WRONG",
            },
            100.0 * inertia,
            100.0 * drag,
            describe(&r),
            if bad.is_empty() {
                String::new()
            } else {
                format!(" — {}", bad.join("; "))
            }
        ));
        match (bad.is_empty(), limit) {
            (true, None) => right += 1,
            (true, Some(_)) => wrong.push(format!(
                "{case}: right now without noise; take it off NOISE_FREE_LIMITS"
            )),
            (false, Some(_)) => {}
            (false, None) => wrong.push(format!("{case}: {}", bad.join("; "))),
        }
    }
    say(format!(
        "noise-free: right {right} of {}; known limits {}",
        CASES.len(),
        NOISE_FREE_LIMITS.len()
    ));
    let _ = std::fs::remove_dir_all(&out);
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// At a quarter of the stand's noise (held-out seeds 3 and 4), no run is silently wrong: more
/// runs are right there (tests/independent_stand/noise_sweep.sh: 83 of 92 on seeds 3–6), and a
/// quieter record must not turn a miss into a model said to explain the data while J or the drag
/// is off. Before the verdict counted a consistent gain for an unresolved value as something the
/// model lacks, the sensor filter beside a drag exponent on seed 3 was "explained" with J 3 % low.
#[test]
#[ignore = "needs python3 with numpy and scipy (ci/steps/38-diagnose-independent.sh)"]
fn quieter_draws_are_never_silently_wrong() {
    let out = std::env::temp_dir().join(format!("propid-quieter-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let mut silent = Vec::new();
    for seed in [3, 4] {
        assert!(
            draw(&out, seed, "0.25"),
            "stand.py --all --noise-scale 0.25 failed (python3 with numpy and scipy?)"
        );
        for &case in CASES {
            let (r, truth) = diagnosed(&out, case, seed);
            if silently_wrong(&r, truth_of(&truth)) {
                silent.push(format!("{case} seed {seed}: {}", describe(&r)));
            }
            // Where the diagnosis finds something the model lacks, the Result at the top says
            // its values are not established.
            if r.simulation_only.is_some() {
                let text = Outcome::from_diagnosis(&r, 0, None)
                    .map(|o| o.to_text())
                    .unwrap_or_default();
                if !text.contains("not established") {
                    silent.push(format!(
                        "{case} seed {seed}: the Result does not say its values are not established:\n{text}"
                    ));
                }
            }
        }
    }
    say(format!(
        "a quarter of the noise, seeds 3 and 4: {} of {} runs silently wrong",
        silent.len(),
        2 * CASES.len()
    ));
    let _ = std::fs::remove_dir_all(&out);
    assert!(silent.is_empty(), "silently wrong:\n{}", silent.join("\n"));
}
