//! Issue 26's property: no plausible mistake reaches a verdict that the model explains the data,
//! and no Result carries NaN or a zero standard error. Random simulated runs (formula-level stand:
//! J, c2, rate, noise seed drawn) get one random mistake — a reversed torque sign, a velocity
//! logged in rpm, rev/s or deg/s, time in milliseconds, a rotor that is never accelerated enough
//! to identify J, a speed held nearly constant so that c2 is not identified, J held on the fit's
//! bound — and both `fit` (through its file path, as the command runs it) and `diagnose` must
//! refuse, or say what is not identified; whatever Result they give must hold only finite numbers
//! and no standard error of zero.

use propid_io::tsv::{Row, Sample, TsvWriter};
use propid_science::diagnose::{diagnose, Options, Verdict};
use propid_science::excitation::{Excitation, Pattern};
use propid_science::fit::{fit_path, FitOptions};
use propid_science::result::{Outcome, Value};
use propid_science::stand::{simulate, StandConfig};
use proptest::prelude::*;

/// One plausible mistake.
#[derive(Clone, Copy, Debug)]
enum Mistake {
    FlippedTorque,
    /// The velocity column in this many units per rad/s.
    VelocityUnit(f64),
    TimeInMilliseconds,
    /// An excitation too small to identify J (the setpoint moves by a hundredth of full scale).
    TinyExcitation,
    /// J's bound set below the truth: the fit ends on it.
    InertiaOnBound,
}

fn mistake() -> impl Strategy<Value = Mistake> {
    prop_oneof![
        Just(Mistake::FlippedTorque),
        Just(Mistake::VelocityUnit(60.0 / std::f64::consts::TAU)),
        Just(Mistake::VelocityUnit(1.0 / std::f64::consts::TAU)),
        Just(Mistake::VelocityUnit(180.0 / std::f64::consts::PI)),
        Just(Mistake::TimeInMilliseconds),
        Just(Mistake::TinyExcitation),
        Just(Mistake::InertiaOnBound),
    ]
}

fn run(config: StandConfig, mistake: Mistake, seed: u64) -> Vec<Sample> {
    let (lo, hi) = match mistake {
        Mistake::TinyExcitation => (0.495, 0.505),
        _ => (0.1, 0.9),
    };
    let excitation = Excitation {
        lo,
        hi,
        period: 2.0,
        duration: 12.0,
        init_duration: 2.0,
        pattern: Pattern::Sine,
    };
    let mut samples = simulate(config, &excitation, seed);
    for s in &mut samples {
        match mistake {
            Mistake::FlippedTorque => s.force = -s.force,
            Mistake::VelocityUnit(k) => s.velocity *= k,
            Mistake::TimeInMilliseconds => s.t *= 1e3,
            Mistake::TinyExcitation | Mistake::InertiaOnBound => {}
        }
    }
    samples
}

/// The samples as the TSV `propid fit` reads, by propid-io's canonical writer (removed when
/// dropped).
fn tsv(samples: &[Sample]) -> tempfile::TempPath {
    let file = tempfile::Builder::new().suffix(".tsv").tempfile().unwrap();
    let mut w = TsvWriter::new(std::io::BufWriter::new(file.as_file()), false).unwrap();
    for s in samples {
        w.write(&Row::new(f64::NAN, *s)).unwrap();
    }
    w.into_inner().unwrap();
    file.into_temp_path()
}

/// What is wrong with a Result's numbers (empty: every value finite, no zero standard error).
fn bad_numbers(o: &Outcome) -> Vec<String> {
    let mut bad = Vec::new();
    let mut check = |what: &str, v: &Value| {
        if !v.value.is_finite() {
            bad.push(format!("{what} = {}", v.value));
        }
        if let Some(se) = v.stderr {
            if !(se.is_finite() && se > 0.0) {
                bad.push(format!("{what} ± {se}"));
            }
        }
        if let Some(spread) = v.model_spread {
            if !spread.is_finite() {
                bad.push(format!("{what} spread {spread}"));
            }
        }
    };
    check("J", &o.inertia);
    check("c2", &o.c2);
    if let Some(c1) = &o.c1 {
        check("c1", c1);
    }
    if let Some(c_q) = &o.c_q {
        check("C_Q", c_q);
    }
    for e in &o.effects {
        check(&e.name, &e.value);
    }
    bad
}

proptest! {
    // A fixed seed: the same draws on every run (a failure reproduces; PROPTEST_CASES=300 widens).
    #![proptest_config(ProptestConfig {
        cases: 24,
        failure_persistence: None,
        rng_seed: proptest::test_runner::RngSeed::Fixed(20261126),
        ..ProptestConfig::default()
    })]

    #[test]
    fn no_plausible_mistake_is_explained(
        mistake in mistake(),
        inertia in 1.5e-5f64..3.0e-5,
        c2 in 1.0e-8f64..2.0e-8,
        rate in prop_oneof![Just(250.0f64), Just(500.0), Just(1000.0)],
        seed in any::<u64>(),
    ) {
        let config = StandConfig { inertia, c2, rate, ..StandConfig::default() };
        let samples = run(config, mistake, seed);

        // diagnose: refused, cannot judge, or a verdict that does not say the model explains
        // the data; any Result it gives holds only numbers.
        match diagnose(&samples, Options::default()) {
            Err(_) => {}
            Ok(r) => {
                let explained = matches!(r.verdict, Verdict::NothingWrong | Verdict::Explained);
                // A tiny swing leaves the seed's model right and J biased by the torque's noise:
                // a verdict that the model explains the data must then say by how much.
                let disclosed = matches!(mistake, Mistake::TinyExcitation)
                    && r.notes.iter().any(|n| n.contains("torque's noise"));
                let mistaken = !matches!(mistake, Mistake::InertiaOnBound) && !disclosed;
                prop_assert!(
                    !(explained && mistaken),
                    "{mistake:?}: diagnose says {:?} (J {:.4e}, c2 {:.4e})",
                    r.verdict, r.extended.inertia, r.extended.c2
                );
                if let Some(o) = Outcome::from_diagnosis(&r, 0, None) {
                    let bad = bad_numbers(&o);
                    prop_assert!(bad.is_empty(), "{mistake:?}: diagnose's Result: {bad:?}");
                }
            }
        }

        // fit, as the command runs it: refused, or a Result whose numbers are numbers and whose
        // unidentified parameters are said so (never a standard error of 0).
        let file = tsv(&samples);
        let options = match mistake {
            Mistake::InertiaOnBound => FitOptions { mass_max: 0.5 * inertia, ..FitOptions::default() },
            _ => FitOptions::default(),
        };
        if let Ok((report, _)) = fit_path(&file, &options, &mut |_, _| {}) {
            let o = Outcome::from_fit(&report, false, None);
            let bad = bad_numbers(&o);
            prop_assert!(bad.is_empty(), "{mistake:?}: fit's Result: {bad:?}");
            if matches!(mistake, Mistake::InertiaOnBound | Mistake::TinyExcitation) {
                prop_assert!(
                    o.not_identified.iter().any(|p| p.contains('J') || p.contains("mass") || p.contains("inertia")),
                    "{mistake:?}: fit gives J = {:.4e} ± {:?} without saying it is not identified ({:?}; warnings {:?})",
                    o.inertia.value, o.inertia.stderr, o.not_identified, o.warnings
                );
            } else {
                prop_assert!(
                    false,
                    "{mistake:?}: fit accepted the data (J = {:.4e} ± {:?})",
                    o.inertia.value, o.inertia.stderr
                );
            }
        }
    }
}

/// A swing small beside the torque's noise (the setpoint between 0.4 and 0.6, 2 mN·m of white
/// torque noise, 30 s at 500 Hz): least squares reads J high by what that noise predicts, and
/// `fit` says so; `diagnose` takes the noise's variance out of the force's own sums, gives J
/// within 1 % of the truth on four noise draws (fit: 14 % high), and says that its J is
/// corrected and on what the correction rests (README, "Plausible mistakes stop before a
/// verdict").
#[test]
fn a_small_swing_beside_the_torque_noise_is_corrected_by_diagnose() {
    let config = StandConfig {
        noise_force: 2e-3,
        ..StandConfig::default()
    };
    let excitation = Excitation {
        lo: 0.4,
        hi: 0.6,
        period: 2.0,
        duration: 30.0,
        init_duration: 2.0,
        pattern: Pattern::Sine,
    };
    for seed in 1..=4u64 {
        let samples = simulate(config, &excitation, seed);
        let file = tsv(&samples);
        let (report, _) = fit_path(&file, &FitOptions::default(), &mut |_, _| {}).unwrap();
        let fitted = Outcome::from_fit(&report, false, None).inertia.value / config.inertia - 1.0;
        // README: "`fit` reads J 14 % high" (13.9–14.5 % on these four draws).
        assert!(
            (0.135..0.145).contains(&fitted),
            "seed {seed}: fit's J {:+.1} % (least squares, 14 % predicted)",
            100.0 * fitted
        );
        let r = diagnose(&samples, Options::default()).unwrap();
        let corrected = r.extended.inertia / config.inertia - 1.0;
        assert!(
            corrected.abs() < 0.01,
            "seed {seed}: diagnose's J {:+.2} %",
            100.0 * corrected
        );
        assert!(
            r.notes
                .iter()
                .any(|n| n.contains("the J given is corrected for it")),
            "seed {seed}: {:?}",
            r.notes
        );
    }
}
