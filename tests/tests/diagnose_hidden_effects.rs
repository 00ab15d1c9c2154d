//! Hide effects in simulated data (the formula-level stand, `propid_science::stand`) and require
//! `propid diagnose` to find them: the right names and only them (or, where the pattern cannot
//! separate two, an ambiguity with the right one among the two), each value within a stated
//! tolerance, and the extended model's J and c2 within 2 % of the truth — ambiguous or not.
//! Clean data must name nothing; a periodic disturbance must be reported as unexplained.
//! Magnitudes, noise seeds, sample rates and durations are drawn at random from a fixed seed
//! (printed), so a failure is reproducible.
//!
//! One effect at a time, the excitation is a chirp. Tolerances: 5 % on friction, ripple and the
//! torque lag, 1 % on the drag exponent, 10 % on the force-sensor and acceleration lags (read
//! from a derivative of a noisy signal, with instrumental variables: docs/SCIENCE.md, "Lags").
//! Two effects at once, on the seed's sine and on a chirp: each value within 10 %.

mod expect;

use expect::{
    against_ledger, describe, judge, judge_fit, say, silently_wrong, verbose, Expected, Ties,
    Truth, CONSTANT_TWINS,
};
use propid_science::diagnose::{diagnose, EffectKind, LagShape, Options, Report, Verdict};
use propid_science::excitation::{Excitation, Pattern};
use propid_science::stand::{simulate, StandConfig};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

use EffectKind::*;

/// The torque shapes beside c2·ω² that a narrow band of speeds may not tell apart: a constant
/// (friction or offset), ω and ω^p.
const TORQUE_SHAPES: [(EffectKind, EffectKind); 6] = [
    CONSTANT_TWINS,
    (CoulombFriction, ViscousFriction),
    (ForceOffset, ViscousFriction),
    (ViscousFriction, DragExponent),
    (CoulombFriction, DragExponent),
    (ForceOffset, DragExponent),
];

fn excitation(rng: &mut StdRng) -> Excitation {
    Excitation {
        lo: 0.1,
        hi: 0.9,
        period: 2.0,
        duration: rng.random_range(30.0..50.0),
        init_duration: 2.0,
        pattern: Pattern::Chirp,
    }
}

fn base(rng: &mut StdRng) -> StandConfig {
    StandConfig {
        inertia: rng.random_range(1.5e-5..3.0e-5),
        c2: rng.random_range(1.0e-8..2.0e-8),
        rate: [250.0, 500.0, 1000.0][rng.random_range(0..3)],
        ..StandConfig::default()
    }
}

fn run(config: &StandConfig, rng: &mut StdRng) -> Report {
    let samples = simulate(*config, &excitation(rng), rng.random());
    diagnose(&samples, Options::default()).expect("diagnosis runs")
}

/// The stand's J and drag law, compared at its steady speed at setpoint `s`.
fn truth(c: &StandConfig, s: f64) -> Truth {
    Truth {
        inertia: c.inertia,
        c1: c.c1,
        k: c.c2,
        p: c.drag_exponent,
        speed: (s * c.max_torque / c.c2).powf(1.0 / c.drag_exponent),
    }
}

#[test]
fn every_hidden_effect_is_found_named_and_measured() {
    let seed = 20261122;
    let mut rng = StdRng::seed_from_u64(seed);
    say(format!("hidden effects (rng seed {seed}):"));
    let mut cases = Vec::new();
    for kind in [
        CoulombFriction,
        ViscousFriction,
        DragExponent,
        TorqueLag,
        ForceSensorLag,
        AccelerationLag,
        TorqueRipple,
    ] {
        for _ in 0..2 {
            let mut c = base(&mut rng);
            let (truth, tolerance) = match kind {
                CoulombFriction => {
                    c.coulomb = rng.random_range(0.002..0.005);
                    (c.coulomb, 0.05)
                }
                ViscousFriction => {
                    c.c1 = rng.random_range(1.0e-6..3.0e-6);
                    (c.c1, 0.05)
                }
                DragExponent => {
                    c.drag_exponent = if rng.random_bool(0.5) {
                        rng.random_range(1.7..1.9)
                    } else {
                        rng.random_range(2.15..2.4)
                    };
                    // c2 keeps the torque at 1500 rad/s as it was at p = 2.
                    c.c2 *= 1500f64.powf(2.0 - c.drag_exponent);
                    (c.drag_exponent, 0.01)
                }
                TorqueLag => {
                    c.torque_lag = rng.random_range(0.005..0.025);
                    (c.torque_lag, 0.05)
                }
                ForceSensorLag => {
                    c.force_sensor_lag = rng.random_range(0.005..0.020);
                    (c.force_sensor_lag, 0.10)
                }
                AccelerationLag => {
                    c.acceleration_lag = rng.random_range(0.005..0.020);
                    (c.acceleration_lag, 0.10)
                }
                _ => {
                    c.ripple = rng.random_range(0.002..0.006);
                    (c.ripple, 0.05)
                }
            };
            cases.push((kind, c, truth, tolerance));
        }
    }
    let mut failures = Vec::new();
    for (kind, c, truth, tolerance) in &cases {
        let r = run(c, &mut rng);
        say(format!(
            "  {kind:<17} truth {truth:.4e} at {} Hz: {}",
            c.rate,
            describe(&r)
        ));
        verbose(&r);
        // A rotor that never reverses (lo > 0) cannot tell a Coulomb friction from a force-sensor
        // offset: both are a constant torque; and over the chirp's band of speeds (800–2450
        // rad/s) a constant, ω and ω^p beside c2·ω² are nearly one curve.
        let mut bad = judge(
            &r,
            &[Expected {
                kind: *kind,
                value: *truth,
                tolerance: *tolerance,
            }],
            Ties::Only(&TORQUE_SHAPES),
            None,
        );
        if *kind == CoulombFriction
            && !r
                .ambiguities
                .iter()
                .any(|a| a.between.contains(&ForceOffset))
        {
            bad.push("not ambiguous with force_offset on a rotor that never reverses".into());
        }
        // The stand's drag is c2·|ω|^p: with a drag exponent named, its coefficient is the law's
        // own k (extended.c2 is then the quadratic equivalent at the RMS speed).
        let c2_found = r.extended.k.unwrap_or(r.extended.c2);
        if (r.extended.inertia / c.inertia - 1.0).abs() > 0.02
            || (c2_found / c.c2 - 1.0).abs() > 0.02
        {
            bad.push(format!(
                "extended J {:.4e} (truth {:.4e}), c2 {c2_found:.4e} (truth {:.4e})",
                r.extended.inertia, c.inertia, c.c2
            ));
        }
        if r.simulation_rms.gain_percent <= 0.0 && *kind != TorqueRipple {
            bad.push("no simulation gain".into());
        }
        failures.extend(bad.into_iter().map(|b| format!("{kind}: {b}")));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn clean_data_names_nothing() {
    let mut rng = StdRng::seed_from_u64(7);
    for pattern in [Pattern::Sine, Pattern::Chirp, Pattern::Steps] {
        for _ in 0..2 {
            let c = base(&mut rng);
            let e = Excitation {
                pattern,
                ..excitation(&mut rng)
            };
            let r = diagnose(&simulate(c, &e, rng.random()), Options::default()).unwrap();
            say(format!(
                "  clean {pattern:?} at {} Hz: {}",
                c.rate,
                describe(&r)
            ));
            assert!(r.effects.is_empty(), "false alarm: {}", describe(&r));
            assert!(r.unexplained.is_none(), "false alarm: {}", describe(&r));
            assert_eq!(r.verdict, Verdict::NothingWrong, "{}", describe(&r));
            assert!((r.base.inertia / c.inertia - 1.0).abs() < 0.02);
        }
    }
}

#[test]
fn a_periodic_disturbance_is_unexplained_not_misnamed() {
    let mut rng = StdRng::seed_from_u64(11);
    let mut c = base(&mut rng);
    c.disturbance = 0.004;
    c.disturbance_hz = rng.random_range(3.0..12.0);
    let r = run(&c, &mut rng);
    say(format!(
        "  disturbance at {:.3} Hz: {}",
        c.disturbance_hz,
        describe(&r)
    ));
    assert!(r.effects.is_empty(), "misnamed: {}", describe(&r));
    let u = r.unexplained.expect("reported as unexplained");
    assert!(
        (u.frequency_hz - c.disturbance_hz).abs() < 0.02,
        "{} Hz",
        u.frequency_hz
    );
    assert!(u.description.contains("periodic"));
}

/// The seed's sinusoid.
fn sine(duration: f64) -> Excitation {
    Excitation {
        lo: 0.1,
        hi: 0.9,
        period: 2.0,
        duration,
        init_duration: 5.0,
        pattern: Pattern::Sine,
    }
}

/// On the seed's sinusoid a Coulomb friction and a torque lag fit the acceleration alike, but
/// the simulated velocity tells them apart: the friction is found (as the constant torque it
/// is, ambiguous only with its twin the offset), at its value, never read as a lag.
#[test]
fn coulomb_friction_on_the_seeds_sine_is_not_a_lag() {
    for seed in [1, 2] {
        let stand = StandConfig {
            coulomb: 3e-3,
            rate: 250.0,
            ..StandConfig::default()
        };
        let r = diagnose(&simulate(stand, &sine(60.0), seed), Options::default()).unwrap();
        say(format!(
            "  coulomb 3e-3 on the sine, seed {seed}: {}",
            describe(&r)
        ));
        let bad = judge(
            &r,
            &[Expected {
                kind: CoulombFriction,
                value: 3e-3,
                tolerance: 0.05,
            }],
            Ties::Only(&[CONSTANT_TWINS]),
            Some(truth(&stand, 0.5)),
        );
        assert!(bad.is_empty(), "seed {seed}: {bad:?} {}", describe(&r));
        assert!(r.unexplained.is_none(), "seed {seed}: {:?}", r.unexplained);
        let fit = judge_fit(&r, truth(&stand, 0.5));
        assert!(fit.is_empty(), "seed {seed}: {fit:?}");
    }
}

/// A single torque lag on the seed's sine at 500 Hz, and a 25 ms lag on a large propeller (J =
/// 10⁻² kg·m², c2 = 10⁻⁵, 4 N·m at full setpoint, 100 Hz): named alone, where the simulated
/// velocity separates it from a constant torque that fits the acceleration about as well.
#[test]
fn a_lag_on_the_seeds_sine_is_named_alone() {
    let small = StandConfig {
        torque_lag: 0.008,
        rate: 500.0,
        ..StandConfig::default()
    };
    let large = StandConfig {
        inertia: 1e-2,
        c2: 1e-5,
        max_torque: 4.0,
        torque_lag: 0.025,
        rate: 100.0,
        noise_force: 8e-3,
        noise_velocity: 0.5,
        noise_acceleration: 5.0,
        ..StandConfig::default()
    };
    let mut failures = Vec::new();
    for (name, stand) in [("7-inch, 8 ms", small), ("large propeller, 25 ms", large)] {
        for seed in [1, 2] {
            let r = diagnose(&simulate(stand, &sine(90.0), seed), Options::default()).unwrap();
            say(format!("  {name}, seed {seed}: {}", describe(&r)));
            verbose(&r);
            let mut bad = judge(
                &r,
                &[Expected {
                    kind: TorqueLag,
                    value: stand.torque_lag,
                    tolerance: 0.05,
                }],
                Ties::Only(&[]),
                Some(truth(&stand, 0.5)),
            );
            bad.extend(judge_fit(&r, truth(&stand, 0.5)));
            failures.extend(bad.into_iter().map(|b| format!("{name} seed {seed}: {b}")));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A hidden pair of effects on `pattern`.
struct Pair {
    name: &'static str,
    config: StandConfig,
    excitation: Excitation,
    expected: Vec<Expected>,
    ties: Vec<(EffectKind, EffectKind)>,
}

/// The two-effect cases, drawn from `rng` on `pattern`.
fn pairs(rng: &mut StdRng, pattern: Pattern) -> Vec<Pair> {
    let mut out = Vec::new();
    let expected = |kind, value| Expected {
        kind,
        value,
        tolerance: 0.10,
    };
    let stand = |rng: &mut StdRng| StandConfig {
        inertia: rng.random_range(1.5e-5..3.0e-5),
        c2: rng.random_range(1.0e-8..2.0e-8),
        rate: [100.0, 250.0, 500.0, 1000.0][rng.random_range(0..4)],
        ..StandConfig::default()
    };
    let run = |rng: &mut StdRng, lo: f64| Excitation {
        lo,
        hi: 0.9,
        period: 2.0,
        duration: rng.random_range(40.0..60.0),
        init_duration: 2.0,
        pattern,
    };
    // A torque lag and a force offset (the 15 ms and 0.02 N·m among them).
    let mut c = stand(rng);
    c.torque_lag = rng.random_range(0.008..0.02);
    c.force_offset = rng.random_range(0.005..0.02);
    out.push(Pair {
        name: "lag + offset",
        config: c,
        excitation: run(rng, 0.1),
        expected: vec![
            expected(TorqueLag, c.torque_lag),
            expected(ForceOffset, c.force_offset),
        ],
        ties: TORQUE_SHAPES.to_vec(),
    });
    let mut c = stand(rng);
    c.torque_lag = rng.random_range(0.008..0.02);
    c.c1 = rng.random_range(2.0e-6..4.0e-6);
    out.push(Pair {
        name: "lag + viscous",
        config: c,
        excitation: run(rng, 0.1),
        expected: vec![
            expected(TorqueLag, c.torque_lag),
            expected(ViscousFriction, c.c1),
        ],
        ties: TORQUE_SHAPES.to_vec(),
    });
    // A pattern that reverses the rotor (the run diagnose advises to tell a Coulomb friction from
    // an offset): Coulomb friction changes sign, an offset does not.
    let mut c = stand(rng);
    c.torque_lag = rng.random_range(0.008..0.02);
    c.coulomb = rng.random_range(0.003..0.006);
    out.push(Pair {
        name: "lag + coulomb, reversing",
        config: c,
        excitation: run(rng, -0.5),
        expected: vec![
            expected(TorqueLag, c.torque_lag),
            expected(CoulombFriction, c.coulomb),
        ],
        ties: TORQUE_SHAPES.to_vec(),
    });
    let mut c = stand(rng);
    c.drag_exponent = if rng.random_bool(0.5) {
        rng.random_range(1.7..1.9)
    } else {
        rng.random_range(2.15..2.4)
    };
    c.c2 *= 1500f64.powf(2.0 - c.drag_exponent);
    c.force_offset = rng.random_range(0.003..0.01);
    // Two torque shapes: over the band of speeds of lo = 0.1 (800–2450 rad/s) an exponent and
    // an offset are nearly one curve with a viscous term and a friction; the run diagnose
    // advises for torque shapes reaches low speeds (lo = 0.02).
    out.push(Pair {
        name: "drag exponent + offset",
        config: c,
        excitation: run(rng, 0.02),
        expected: vec![
            expected(DragExponent, c.drag_exponent),
            expected(ForceOffset, c.force_offset),
        ],
        ties: TORQUE_SHAPES.to_vec(),
    });
    let mut c = stand(rng);
    c.braking = rng.random_range(0.003..0.008);
    c.torque_lag = rng.random_range(0.008..0.02);
    out.push(Pair {
        name: "braking + lag",
        config: c,
        excitation: run(rng, 0.1),
        expected: vec![
            expected(BrakingTorque, c.braking),
            expected(TorqueLag, c.torque_lag),
        ],
        ties: vec![],
    });
    let mut c = stand(rng);
    c.force_sensor_lag = rng.random_range(0.008..0.02);
    c.drag_exponent = if rng.random_bool(0.5) {
        rng.random_range(1.7..1.9)
    } else {
        rng.random_range(2.15..2.4)
    };
    c.c2 *= 1500f64.powf(2.0 - c.drag_exponent);
    out.push(Pair {
        name: "sensor filter + drag exponent",
        config: c,
        excitation: run(rng, 0.1),
        expected: vec![
            expected(ForceSensorLag, c.force_sensor_lag),
            expected(DragExponent, c.drag_exponent),
        ],
        ties: TORQUE_SHAPES.to_vec(),
    });
    out
}

/// What is wrong with the diagnosis of `pair` (empty: right).
fn check_pair(pair: &Pair, seed: u64) -> Vec<String> {
    diagnose_pair(pair, seed).0
}

/// PROPID_DUMP=dir: writes each pair's draw as a TSV there (propid-io's canonical writer), to
/// read it with `propid diagnose`.
fn dump(pair: &Pair, seed: u64, samples: &[propid_io::tsv::Sample]) {
    use propid_io::tsv::{Row, TsvWriter};
    let Ok(dir) = std::env::var("PROPID_DUMP") else {
        return;
    };
    let name = pair.name.replace([' ', '+', ','], "_");
    let path = format!("{dir}/{name}-{:?}-{seed}.tsv", pair.excitation.pattern);
    let file = std::fs::File::create(path).expect("PROPID_DUMP writable");
    let mut w = TsvWriter::new(std::io::BufWriter::new(file), false).unwrap();
    for x in samples {
        w.write(&Row::new(f64::NAN, *x)).unwrap();
    }
    w.into_inner().unwrap();
}

/// What is wrong with the diagnosis of `pair` (empty: right), and whether it is silently
/// wrong (says the model explains the data while J or the drag is more than 2 % off).
fn diagnose_pair(pair: &Pair, seed: u64) -> (Vec<String>, bool) {
    let c = &pair.config;
    let samples = simulate(*c, &pair.excitation, seed);
    dump(pair, seed, &samples);
    let r = diagnose(&samples, Options::default()).unwrap();
    let mid = 0.5 * (pair.excitation.lo.max(0.1) + pair.excitation.hi);
    let bad = judge(
        &r,
        &pair.expected,
        Ties::Only(&pair.ties),
        Some(truth(c, mid)),
    );
    let silent = silently_wrong(&r, truth(c, mid));
    say(format!(
        "  {:<30} {:?} {} Hz: {} {}",
        pair.name,
        pair.excitation.pattern,
        c.rate,
        describe(&r),
        if bad.is_empty() {
            "ok".to_string()
        } else {
            format!("WRONG: {}", bad.join("; "))
        }
    ));
    verbose(&r);
    (bad, silent)
}

/// The two-effect cases on `pattern` drawn from generator seed `seed`: what is wrong with each.
fn two_effects(seed: u64, pattern: Pattern) -> Vec<String> {
    say(format!(
        "two effects at once on the {pattern:?} (rng seed {seed}):"
    ));
    let mut rng = StdRng::seed_from_u64(seed);
    let mut failures = Vec::new();
    for pair in pairs(&mut rng, pattern) {
        let sim_seed = rng.random();
        // PROPID_ONLY=text: only the pairs whose name contains it (to read one draw).
        if std::env::var("PROPID_ONLY").is_ok_and(|o| !pair.name.contains(o.as_str())) {
            continue;
        }
        failures.extend(
            check_pair(&pair, sim_seed)
                .into_iter()
                .map(|b| format!("{} {pattern:?}: {b}", pair.name)),
        );
    }
    failures
}

/// Two effects at once on a chirp, 100–1000 Hz: both found jointly, each within 10 %, the
/// extended J and drag within 2 % (where the chirp's band of speeds cannot tell two torque shapes
/// apart, ambiguous with the right model among those the report gives).
#[test]
fn two_effects_at_once_are_found_jointly_on_a_chirp() {
    let failures = two_effects(20261201, Pattern::Chirp);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Pairs the seed's sine does not get right today (docs/SCIENCE.md, "Two effects at once on the
/// seed's sine"), by name and generator seed, with why. Each must still end honestly.
const SINE_PAIR_LIMITS: &[(&str, u64, &str)] = &[
    ("lag + viscous", 20261201, LAG_TAKEN),
    ("drag exponent + offset", 20261201, SHAPES_TRADED),
    ("sensor filter + drag exponent", 20261201, SHAPES_TRADED),
    ("sensor filter + drag exponent", 20261202, SHAPES_TRADED),
];

/// A constant torque named in the first round takes most of the lag's effect on one sinusoid;
/// the lag, re-tuned on top of it, no longer passes (as on the independent stand's
/// `lag_viscous`). Rule 10 exchanges the constant for the lag and the viscous term on the other
/// draw (right there); on this one it makes no exchange, and the verdict is ambiguous.
const LAG_TAKEN: &str = "a constant torque takes the lag beside a viscous term";

/// Over the sine's band of speeds a constant, ω and ω^p (and, beside a sensor filter, the
/// filter's length) trade against each other: the exponent or the filter is named off by more
/// than 10 %, beside a torque shape that is not there.
const SHAPES_TRADED: &str = "torque shapes traded over the sine's band of speeds";

/// The same pairs on the seed's sine, on two draws, where one 0.5 Hz sinusoid spans a lag, a
/// constant and the torque shapes with the same few harmonics: every pair right (both named within
/// 10 %, or tied only as the chirp's pairs may be, J and the drag within 2 %) except those in
/// [`SINE_PAIR_LIMITS`], and those never silently wrong. The test fails when a listed pair becomes
/// right, so the list and the docs cannot drift.
#[test]
fn two_effects_at_once_on_the_seeds_sine() {
    let mut failures = Vec::new();
    for seed in [20261201u64, 20261202] {
        say(format!(
            "two effects at once on the seed's sine (rng seed {seed}):"
        ));
        let mut rng = StdRng::seed_from_u64(seed);
        for pair in pairs(&mut rng, Pattern::Sine) {
            let sim_seed = rng.random();
            let (bad, silent) = diagnose_pair(&pair, sim_seed);
            let limit = SINE_PAIR_LIMITS
                .iter()
                .any(|&(n, s, _)| n == pair.name && s == seed);
            failures.extend(against_ledger(
                &format!("{} (seed {seed})", pair.name),
                bad,
                limit,
                silent,
                false,
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The effect added as one new file: a second-order stage between the commanded torque and
/// the torque the load feels. On a chirp reaching a fifth of its natural frequency it is named
/// with that frequency within 10 %; on the seed's sine, where it is a delay of 2ζ/ω_n, the
/// simpler first-order torque lag of that length is named instead.
#[test]
fn a_second_order_stage_is_named_where_a_chirp_shows_its_shape() {
    let mut rng = StdRng::seed_from_u64(5);
    let mut failures = Vec::new();
    for _ in 0..2 {
        let c = StandConfig {
            second_order_hz: rng.random_range(8.0..16.0),
            second_order_damping: rng.random_range(0.55..0.85),
            rate: [250.0, 500.0, 1000.0][rng.random_range(0..3)],
            ..StandConfig::default()
        };
        let chirp = Excitation {
            duration: 60.0,
            ..excitation(&mut rng)
        };
        let r = diagnose(&simulate(c, &chirp, rng.random()), Options::default()).unwrap();
        say(format!(
            "  second-order stage {:.2} Hz ζ {:.2}, chirp at {} Hz: {}",
            c.second_order_hz,
            c.second_order_damping,
            c.rate,
            describe(&r)
        ));
        let mut bad = judge(
            &r,
            &[Expected {
                kind: SecondOrderLag,
                value: c.second_order_hz,
                tolerance: 0.10,
            }],
            Ties::Only(&[]),
            Some(truth(&c, 0.5)),
        );
        if r.effects.first().and_then(|e| e.lag_form) != Some(LagShape::SecondOrder) {
            bad.push("lag_form is not second_order".into());
        }
        let delay = 2.0 * c.second_order_damping / (std::f64::consts::TAU * c.second_order_hz);
        let r = diagnose(&simulate(c, &sine(60.0), rng.random()), Options::default()).unwrap();
        say(format!("    on the sine: {}", describe(&r)));
        bad.extend(
            judge(
                &r,
                &[Expected {
                    kind: TorqueLag,
                    value: delay,
                    tolerance: 0.10,
                }],
                Ties::Only(&[]),
                Some(truth(&c, 0.5)),
            )
            .into_iter()
            .map(|b| format!("sine: {b}")),
        );
        failures.extend(bad);
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The progress callback sees the base model, every candidate of every round (counted up to the
/// round's size, whatever thread tried it) and the extended model, in that order.
#[test]
fn progress_reports_every_stage_in_order() {
    use propid_science::diagnose::{diagnose_rows_observed, Stage};
    use std::sync::Mutex;
    let excitation = Excitation {
        lo: 0.1,
        hi: 0.9,
        period: 2.0,
        duration: 20.0,
        init_duration: 1.0,
        pattern: Pattern::Chirp,
    };
    let stand = StandConfig {
        torque_lag: 0.01,
        ..StandConfig::default()
    };
    let rows: Vec<propid_io::tsv::Row> = simulate(stand, &excitation, 9)
        .into_iter()
        .map(|sample| propid_io::tsv::Row::new(f64::NAN, sample))
        .collect();
    let seen = Mutex::new(Vec::new());
    let report = diagnose_rows_observed(rows, Options::default(), &|stage| {
        seen.lock().unwrap().push(stage)
    })
    .unwrap();
    let seen = seen.into_inner().unwrap();
    assert_eq!(seen.first(), Some(&Stage::Base), "{seen:?}");
    assert_eq!(seen.last(), Some(&Stage::Extended), "{seen:?}");
    let rounds = report.effects.len() + 1;
    for round in 1..=rounds.min(Options::default().max_effects) {
        let of = seen
            .iter()
            .find_map(|s| match s {
                Stage::Candidates { round: r, of, .. } if *r == round => Some(*of),
                _ => None,
            })
            .unwrap_or_else(|| panic!("round {round} not reported: {seen:?}"));
        let done: Vec<usize> = seen
            .iter()
            .filter_map(|s| match s {
                Stage::Candidates { round: r, done, .. } if *r == round => Some(*done),
                _ => None,
            })
            .collect();
        let mut sorted = done.clone();
        sorted.sort_unstable();
        assert_eq!(
            sorted,
            (0..=of).collect::<Vec<_>>(),
            "round {round}: {done:?}"
        );
    }
}
