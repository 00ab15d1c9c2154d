//! Hide an effect in simulated data and require `propid diagnose` to find it: the right name and
//! only it, its parameter within a stated tolerance, and the extended model's J and c2 within 2 %
//! of the truth. Clean data must name nothing; a periodic disturbance must be reported as
//! unexplained. Magnitudes, noise seeds, sample rates and durations are drawn at random from a
//! fixed seed (printed), so a failure is reproducible.
//!
//! The excitation is a chirp: a single sinusoid (the seed's pattern) cannot tell a constant
//! friction from a torque lag of ~20 ms (see docs/SCIENCE.md), and steps smear the acceleration
//! estimate's derivative, so an acceleration lag looks like a torque lag there.
//!
//! Tolerances: 5 % on friction, ripple and the torque lag, 1 % on the drag exponent, 10 % on the
//! force-sensor and acceleration lags. Those two are read from a derivative of a noisy signal
//! (Ḟ, ȧ); least squares would bias them towards zero (errors in variables: 4–16 % short here,
//! 50 % on other data), so diagnose estimates them with instrumental variables and corrects the
//! half-sample shift of a lag whose input is held between samples (docs/SCIENCE.md, "Lags").

use propid_science::diagnose::{diagnose, Options, Report, Verdict};
use propid_science::excitation::{Excitation, Pattern};
use propid_science::stand::{simulate, StandConfig};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

struct Case {
    name: &'static str,
    config: StandConfig,
    truth: f64,
    /// Relative tolerance on the effect's parameter.
    tolerance: f64,
}

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

fn describe(r: &Report) -> String {
    let effects: Vec<String> = r
        .effects
        .iter()
        .map(|e| format!("{}={:.4e}", e.name, e.value))
        .collect();
    format!(
        "{:?} {:?} named [{}], J {:.4e}, c2 {:.4e}, simulation {:.2} → {:.2} rad/s, unexplained {:?}",
        r.verdict,
        r.ambiguity.as_ref().map(|a| (a.between, a.values)),
        effects.join(", "),
        r.extended.mass,
        r.extended.c2,
        r.simulation_rms.base,
        r.simulation_rms.extended,
        r.unexplained.as_ref().map(|u| u.frequency_hz)
    )
}

fn say(line: String) {
    // Straight to the stderr handle, so the table shows even when libtest captures output.
    std::io::Write::write_all(&mut std::io::stderr(), (line + "\n").as_bytes()).unwrap();
}

#[test]
fn every_hidden_effect_is_found_named_and_measured() {
    let seed = 20261122;
    let mut rng = StdRng::seed_from_u64(seed);
    say(format!("hidden effects (rng seed {seed}):"));
    let mut cases = Vec::new();
    for name in [
        "coulomb_friction",
        "viscous_friction",
        "drag_exponent",
        "torque_lag",
        "force_sensor_lag",
        "acceleration_lag",
        "torque_ripple",
    ] {
        for _ in 0..2 {
            let mut c = base(&mut rng);
            let (truth, tolerance) = match name {
                "coulomb_friction" => {
                    c.coulomb = rng.random_range(0.002..0.005);
                    (c.coulomb, 0.05)
                }
                "viscous_friction" => {
                    c.c1 = rng.random_range(1.0e-6..3.0e-6);
                    (c.c1, 0.05)
                }
                "drag_exponent" => {
                    c.drag_exponent = if rng.random_bool(0.5) {
                        rng.random_range(1.7..1.9)
                    } else {
                        rng.random_range(2.15..2.4)
                    };
                    // c2 keeps the torque at 1500 rad/s as it was at p = 2.
                    c.c2 *= 1500f64.powf(2.0 - c.drag_exponent);
                    (c.drag_exponent, 0.01)
                }
                "torque_lag" => {
                    c.torque_lag = rng.random_range(0.005..0.025);
                    (c.torque_lag, 0.05)
                }
                "force_sensor_lag" => {
                    c.force_sensor_lag = rng.random_range(0.005..0.020);
                    (c.force_sensor_lag, 0.10)
                }
                "acceleration_lag" => {
                    c.acceleration_lag = rng.random_range(0.005..0.020);
                    (c.acceleration_lag, 0.10)
                }
                _ => {
                    c.ripple = rng.random_range(0.002..0.006);
                    (c.ripple, 0.05)
                }
            };
            cases.push(Case {
                name,
                config: c,
                truth,
                tolerance,
            });
        }
    }
    let mut failures = Vec::new();
    for case in &cases {
        let r = run(&case.config, &mut rng);
        let c = &case.config;
        say(format!(
            "  {:<17} truth {:.4e} at {} Hz: {}",
            case.name,
            case.truth,
            c.rate,
            describe(&r)
        ));
        let names: Vec<&str> = r.effects.iter().map(|e| e.name).collect();
        // A rotor that never reverses (lo > 0) cannot tell a Coulomb friction from a force-sensor
        // offset: both are a constant torque; and a small viscous term over a narrow speed range
        // looks like a drag exponent slightly below 2. When the held-out evidence cannot separate
        // two candidates the honest answer is "ambiguous", with both; it passes only with the
        // right one among them, its estimate within the tolerance.
        if let Some(a) = &r.ambiguity {
            match a.between.iter().position(|n| *n == case.name) {
                Some(k) if r.verdict == Verdict::Ambiguous && names.is_empty() => {
                    if ((a.values[k] - case.truth) / case.truth).abs() > case.tolerance {
                        failures.push(format!("{}: value {:.4e}", case.name, a.values[k]));
                    }
                }
                _ => failures.push(format!("{}: ambiguous {:?}", case.name, a.between)),
            }
            continue;
        }
        if case.name == "coulomb_friction" {
            failures.push(format!(
                "{}: not ambiguous with force_offset on a rotor that never reverses: {names:?}",
                case.name
            ));
            continue;
        }
        if names != [case.name] {
            failures.push(format!("{}: named {names:?}", case.name));
            continue;
        }
        let e = &r.effects[0];
        if ((e.value - case.truth) / case.truth).abs() > case.tolerance {
            failures.push(format!(
                "{}: value {:.4e}, truth {:.4e}, tolerance {} %",
                case.name,
                e.value,
                case.truth,
                case.tolerance * 100.0
            ));
        }
        // The stand's drag is c2·|ω|^p: with a drag exponent named, its coefficient is the law's
        // own k (extended.c2 is then the quadratic equivalent at the RMS speed).
        let c2_truth = c.c2;
        let c2_found = r.extended.k.unwrap_or(r.extended.c2);
        if (r.extended.mass / c.inertia - 1.0).abs() > 0.02
            || (c2_found / c2_truth - 1.0).abs() > 0.02
        {
            failures.push(format!(
                "{}: extended J {:.4e} (truth {:.4e}), c2 {:.4e} (truth {:.4e})",
                case.name, r.extended.mass, c.inertia, c2_found, c2_truth
            ));
        }
        if r.simulation_rms.gain_percent <= 0.0 {
            failures.push(format!("{}: no simulation gain", case.name));
        }
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
            assert!((r.base.mass / c.inertia - 1.0).abs() < 0.02);
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

/// On the seed's sinusoid a Coulomb friction and a torque lag fit alike (docs/SCIENCE.md): the
/// diagnosis must say "ambiguous" with the friction and its right value among the two, never name
/// the lag alone (it did: 17.5 ms, the lag better by 0.5 % in held-out gain, the simulation
/// preferring the friction), and not call the pattern's own frequency "unexplained".
#[test]
fn coulomb_friction_on_the_seeds_sine_is_ambiguous_not_a_lag() {
    let excitation = Excitation {
        lo: 0.1,
        hi: 0.9,
        period: 2.0,
        duration: 60.0,
        init_duration: 5.0,
        pattern: Pattern::Sine,
    };
    for seed in [1, 2] {
        let stand = StandConfig {
            coulomb: 3e-3,
            rate: 250.0,
            ..StandConfig::default()
        };
        let r = diagnose(&simulate(stand, &excitation, seed), Options::default()).unwrap();
        assert_eq!(
            r.verdict,
            Verdict::Ambiguous,
            "seed {seed}: {}",
            describe(&r)
        );
        let a = r.ambiguity.as_ref().unwrap();
        let k = a
            .between
            .iter()
            .position(|n| *n == "coulomb_friction")
            .unwrap_or_else(|| panic!("seed {seed}: {:?}", a.between));
        assert!((a.values[k] / 3e-3 - 1.0).abs() < 0.05, "{a:?}");
        assert!(r.unexplained.is_none(), "seed {seed}: {:?}", r.unexplained);
    }
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
