//! `propid plan`'s promise, checked end to end with the diagnosis: on the seed's sine a hidden
//! Coulomb friction cannot be told from a torque lag, and on the planned pattern it is named,
//! alone, with its magnitude; a hidden torque lag is named on the planned pattern too.

use propid_science::diagnose::{diagnose, EffectKind, Options};
use propid_science::excitation::{Excitation, Pattern};
use propid_science::plan::{design, Constraints, Prior};
use propid_science::stand::{simulate, StandConfig};

/// The effects named and — where the diagnosis reports another as ambiguous with one of them —
/// that other too, each with its estimate.
fn named(samples: &[propid_io::tsv::Sample]) -> Vec<(String, f64)> {
    let report = diagnose(samples, Options::default()).expect("diagnosable");
    let mut out: Vec<(String, f64)> = report
        .effects
        .iter()
        .map(|e| (e.effect.to_string(), e.value))
        .collect();
    out.extend(
        report
            .ambiguities
            .iter()
            .map(|a| (a.between[1].to_string(), a.values[1])),
    );
    out
}

/// Coulomb friction named with its magnitude: alone, or beside a constant torque offset, which it
/// equals when the speed never reverses (no pattern within lo..hi > 0 can tell them apart), or
/// beside one of `inseparable`, the effects the plan itself says its pattern cannot tell from it.
fn coulomb_of(found: &[(String, f64)], inseparable: &[String]) -> Option<f64> {
    let alone = found.len() == 1;
    let with_offset = found.len() == 2
        && found
            .iter()
            .any(|(n, _)| n == "force_offset" || inseparable.contains(n));
    found
        .iter()
        .find(|(n, _)| n == "coulomb_friction")
        .filter(|_| alone || with_offset)
        .map(|(_, v)| *v)
}

#[test]
fn the_planned_pattern_names_coulomb_friction_where_the_sine_cannot() {
    let stand = StandConfig::default();
    let plan = design(
        &Prior::new(stand.inertia, stand.c2, stand.max_torque),
        &Constraints {
            lo: 0.1,
            hi: 0.9,
            max_speed: None,
            max_duration: 200.0,
        },
        None,
    )
    .unwrap();
    // What the plan says its pattern cannot tell from a Coulomb friction (on its square wave, a
    // braking torque acting while the rotor slows: regressor correlation 1.00); it must separate
    // the torque lag, which the sine cannot.
    let inseparable: Vec<String> = plan
        .separations
        .iter()
        .filter(|s| !s.separable && s.effects.0 == EffectKind::CoulombFriction)
        .map(|s| s.effects.1.to_string())
        .collect();
    assert!(
        !inseparable.iter().any(|e| e == "torque_lag"),
        "{:?}",
        plan.separations
    );
    let planned = Excitation {
        duration: 60.0,
        ..plan.excitation
    };
    let sine = Excitation {
        pattern: Pattern::Sine,
        period: 2.0,
        ..planned
    };
    for seed in [3, 4] {
        let coulomb = StandConfig {
            coulomb: 0.002,
            ..stand
        };
        // On the sine the friction is at best one of two ambiguous candidates (beside a lag),
        // never named alone.
        let on_sine = named(&simulate(coulomb, &sine, seed));
        assert!(
            on_sine != [("coulomb_friction".to_string(), on_sine[0].1)],
            "seed {seed}: the sine was expected to confuse friction with a lag: {on_sine:?}"
        );
        let on_plan = named(&simulate(coulomb, &planned, seed));
        let value = coulomb_of(&on_plan, &inseparable)
            .unwrap_or_else(|| panic!("seed {seed}: {on_plan:?}"));
        assert!((value / 0.002 - 1.0).abs() < 0.1, "{on_plan:?}");

        let lag = StandConfig {
            torque_lag: 0.012,
            ..stand
        };
        let on_plan = named(&simulate(lag, &planned, seed));
        assert_eq!(on_plan.len(), 1, "seed {seed}: {on_plan:?}");
        assert_eq!(on_plan[0].0, "torque_lag", "seed {seed}: {on_plan:?}");
        assert!((on_plan[0].1 / 0.012 - 1.0).abs() < 0.1, "{on_plan:?}");
    }
}

/// The plan's predicted errors against the scatter of estimates on the independent,
/// mechanism-level stand (its white report noise set like the formula-level stand's).
#[test]
fn predicted_errors_hold_on_the_mechanism_level_stand() {
    use propid_core::estimate::{LoadBounds, LoadEstimator};
    use propid_mechsim::{MechConfig, Run};
    let config = MechConfig::default().with_typical_noise();
    let prior = Prior::new(
        config.rotor.inertia,
        config.rotor.drag.k,
        config.drive.max_torque,
    );
    let plan = design(
        &prior,
        &Constraints {
            lo: 0.1,
            hi: 0.9,
            max_speed: None,
            max_duration: 200.0,
        },
        None,
    )
    .unwrap();
    let planned = Excitation {
        duration: 20.0,
        ..plan.excitation
    };
    let sine = Excitation {
        pattern: Pattern::Sine,
        period: 2.0,
        ..planned
    };
    for excitation in [planned, sine] {
        let (predicted, _, _) = propid_science::plan::evaluate(&prior, &excitation, 1).unwrap();
        let run = Run {
            init_setpoint: excitation.hi,
            init_duration: excitation.init_duration,
            duration: excitation.duration,
        };
        let (mut js, mut cs) = (Vec::new(), Vec::new());
        for seed in 0..24 {
            let records =
                propid_mechsim::simulate(config, &run, |t| excitation.setpoint(t), seed).unwrap();
            let mut est = LoadEstimator::<f64>::new();
            for r in &records {
                est.update(r.force, r.velocity, r.acceleration);
            }
            let e = est.estimate(&LoadBounds::default()).unwrap();
            js.push(e.mass);
            cs.push(e.c2);
        }
        let rel_sd = |v: &[f64]| {
            let n = v.len() as f64;
            let m = v.iter().sum::<f64>() / n;
            (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt() / m
        };
        let rj = rel_sd(&js) / predicted.rel_stderr_j;
        let rc = rel_sd(&cs) / predicted.rel_stderr_c2;
        // 24 seeds: the sample standard deviation scatters by ~15 % by itself.
        assert!(
            (0.75..=1.25).contains(&rj),
            "{}: J {rj}",
            excitation.pattern
        );
        assert!(
            (0.75..=1.25).contains(&rc),
            "{}: c2 {rc}",
            excitation.pattern
        );
    }
}
