//! Hidden effects on the mechanism-level stand (`propid-mechsim`, written independently of the
//! diagnosis): one mechanism at a random magnitude, a random feedback rate (100–1000 Hz), the
//! seed's sine, a chirp and (for the mechanisms that are not lags) a staircase, and what a
//! correct diagnosis must report as the scenario states it (derived from the mechanism, not from
//! the diagnosis's equations). Each effect named alone, or,
//! where the scenario says the pattern cannot separate it from another, "ambiguous" between the
//! two with the right one among them; its parameter within 10 % (plus the scenario's stated
//! derivation error); the extended J and c2 within 2 % of what the scenario says the data hold.
//! Seeds are drawn from a fixed seed (printed), so a failure is reproducible.

mod expect;

use expect::{
    against_ledger, describe, judge, judge_fit, say, silently_wrong, verbose, Expected, Ties,
    Truth, CONSTANT_TWINS,
};
use propid_io::tsv::{Row, Sample};
use propid_mechsim::scenarios::{Bench, Expect, ExpectedEffect, Hidden, Scenario};
use propid_mechsim::{pattern, MechConfig, Record};
use propid_science::diagnose::{
    diagnose_rows, EffectKind, LagShape, NearMiss, Options, Report, SeparatingRun, Verdict,
};
use propid_science::excitation::Pattern as Drive;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

const DURATION: f64 = 60.0;
const PERIOD: f64 = 2.0;

#[derive(Clone, Copy, Debug)]
enum Pattern {
    Sine,
    Chirp,
    Steps,
    /// The run an ambiguous report advises (`Ambiguity::separating_run`).
    Advised(SeparatingRun),
}

fn rows(records: &[Record]) -> Vec<Row> {
    records
        .iter()
        .map(|r| {
            Row::new(
                r.ts_local,
                Sample {
                    t: r.t,
                    force: r.force,
                    velocity: r.velocity,
                    acceleration: r.acceleration,
                    position: r.position,
                },
            )
        })
        .collect()
}

fn bench(rate: f64, pattern: Pattern) -> Bench {
    let mut base = MechConfig::default().with_typical_noise();
    base.link.rate = rate;
    Bench {
        base,
        lo: 0.1,
        hi: 0.9,
        duration: DURATION,
        max_hz: match pattern {
            Pattern::Sine => 1.0 / PERIOD,
            Pattern::Chirp | Pattern::Steps | Pattern::Advised(_) => 10.0 / PERIOD,
        },
    }
}

fn run(s: &Scenario, p: Pattern, seed: u64) -> Report {
    let b = &s.bench;
    let records = match p {
        Pattern::Sine => s.simulate(pattern::sine(b.lo, b.hi, PERIOD), seed),
        Pattern::Chirp => s.simulate(pattern::chirp(b.lo, b.hi, PERIOD, b.duration), seed),
        Pattern::Steps => s.simulate(pattern::steps(b.lo, b.hi, PERIOD), seed),
        Pattern::Advised(run) => {
            let (lo, hi) = (run.lo.unwrap_or(b.lo), run.hi.unwrap_or(b.hi));
            match run.pattern {
                Drive::Steps => s.simulate(pattern::steps(lo, hi, PERIOD), seed),
                Drive::Sine => s.simulate(pattern::sine(lo, hi, PERIOD), seed),
                Drive::Chirp | Drive::Square | Drive::Prbs | Drive::Multisine => {
                    s.simulate(pattern::chirp(lo, hi, PERIOD, b.duration), seed)
                }
            }
        }
    }
    .expect("scenario simulates");
    diagnose_rows(rows(&records), Options::default()).expect("diagnosis runs")
}

/// The effect named `name` in propid's reports.
fn kind(name: &str) -> EffectKind {
    name.parse().unwrap_or_else(|e| panic!("{e}"))
}

/// The J and drag law the scenario's data hold, the drag compared by its torque at the steady
/// speed of the middle command, inside the data: k alone is the torque at 1 rad/s, three
/// decades below them, where an exponent read 2.1758 for 2.1723 (0.16 %) moves it by 2.6 %.
fn truth(s: &Scenario) -> Truth {
    let (k, p) = (s.fit.c2, s.fit.drag_exponent);
    let mid = 0.5 * (s.bench.lo.max(0.1) + s.bench.hi) * s.bench.base.drive.max_torque;
    Truth {
        inertia: s.fit.inertia,
        c1: s.config.rotor.bearing.viscous,
        k,
        p,
        speed: (mid / k).powf(1.0 / p),
    }
}

/// The torque shapes beside c2·ω² that a narrow band of speeds may not tell apart: a constant
/// (friction or offset), ω and ω^p.
const TORQUE_SHAPES: [(EffectKind, EffectKind); 6] = [
    CONSTANT_TWINS,
    (EffectKind::CoulombFriction, EffectKind::ViscousFriction),
    (EffectKind::ForceOffset, EffectKind::ViscousFriction),
    (EffectKind::ViscousFriction, EffectKind::DragExponent),
    (EffectKind::CoulombFriction, EffectKind::DragExponent),
    (EffectKind::ForceOffset, EffectKind::DragExponent),
];

/// The ambiguities a report may give for `effects` (on the seed's sine any pair with a named
/// effect: a lag and a constant torque are spanned by the same harmonics): the scenarios' own
/// stated equivalents, the constant twins on a rotor that never reverses, and the torque shapes
/// over the band of speeds when an effect is one.
fn ties_for(effects: &[ExpectedEffect]) -> Vec<(EffectKind, EffectKind)> {
    let mut ties = vec![CONSTANT_TWINS];
    for e in effects {
        if let Some((other, _)) = e.ambiguous_with {
            ties.push((kind(e.name), kind(other)));
        }
        if TORQUE_SHAPES
            .iter()
            .any(|(a, b)| *a == kind(e.name) || *b == kind(e.name))
        {
            ties.extend(TORQUE_SHAPES);
        }
    }
    ties
}

/// What is wrong with report `r` for the expected `effects` on a scenario whose data hold the
/// J and drag law `truth`, on pattern `p` (empty: right).
fn judge_effects(effects: &[ExpectedEffect], truth: Truth, p: Pattern, r: &Report) -> Vec<String> {
    let expected: Vec<Expected> = effects
        .iter()
        .map(|e| Expected {
            kind: kind(e.name),
            value: e.value,
            tolerance: tolerance(e),
        })
        .collect();
    let ties = ties_for(effects);
    let ties = match p {
        Pattern::Sine => Ties::Any,
        _ => Ties::Only(&ties),
    };
    judge(r, &expected, ties, Some(truth))
}

/// What is wrong with report `r` for scenario `s` on pattern `p` (empty: right).
fn judge_scenario(s: &Scenario, p: Pattern, r: &Report) -> Vec<String> {
    match s.expect {
        Expect::Nothing | Expect::NotIdentifiable { .. } => {
            let mut bad = judge(r, &[], Ties::Only(&[]), Some(truth(s)));
            if r.verdict != Verdict::NothingWrong {
                bad.push(format!("expected nothing, got {:?}", r.verdict));
            }
            // Nor a hint of something: a near miss here would send the user on a needless run.
            let near: Vec<String> = r.near_misses.iter().map(|m| m.effect.to_string()).collect();
            if !near.is_empty() {
                bad.push(format!("expected nothing, got near misses {near:?}"));
            }
            bad
        }
        Expect::Effect(e) => judge_effects(&[e], truth(s), p, r),
        Expect::Unexplained { .. } => unreachable!("not drawn here"),
    }
}

/// How far an estimate of `e` may be off, relatively: 10 %, plus what the scenario's own
/// derivation of the expected value may miss by.
fn tolerance(e: &ExpectedEffect) -> f64 {
    0.10 + e.derivation_error
}

/// The expected effect among the near misses of a report that names nothing, at the right value
/// (within the tolerance `judge` gives a named one).
fn near_miss_of<'r>(s: &Scenario, r: &'r Report) -> Option<&'r NearMiss> {
    let Expect::Effect(e) = s.expect else {
        return None;
    };
    let tolerance = tolerance(&e);
    (r.verdict == Verdict::NothingWrong)
        .then(|| {
            r.near_misses.iter().find(|m| {
                m.effect.name() == e.name && ((m.value - e.value) / e.value).abs() <= tolerance
            })
        })
        .flatten()
}

/// What is wrong with each of `hidden`, drawn in turn from the generator seeded `seed`, on each
/// of `patterns`.
fn check(hidden: &[Hidden], seed: u64, patterns: &[Pattern]) -> Vec<String> {
    let mut rng = StdRng::seed_from_u64(seed);
    say(format!("mechanism stand, rng seed {seed}:"));
    let mut failures = Vec::new();
    for &h in hidden {
        for &p in patterns {
            let rate = [100.0, 250.0, 500.0, 1000.0][rng.random_range(0..4)];
            let s = h.draw(&bench(rate, p), &mut rng);
            let sim_seed = rng.random();
            let mut r = run(&s, p, sim_seed);
            let mut bad = judge_scenario(&s, p, &r);
            // Ambiguous with the right effect among the two where the pattern should have told
            // them apart: the report advises a run that would; a user would do it, and then the
            // effect must be named alone.
            let mut advised = String::new();
            if let Some(a) = r.ambiguities.iter().find(|a| {
                !bad.is_empty()
                    && matches!(s.expect, Expect::Effect(e) if a.between.contains(&kind(e.name)))
            }) {
                let next = Pattern::Advised(a.separating_run);
                advised = format!(" → advised `{}`", a.separating_run.flags());
                r = run(&s, next, sim_seed);
                bad = judge_scenario(&s, next, &r);
            } else if let Some(m) = near_miss_of(&s, &r).filter(|_| !bad.is_empty()) {
                // Not named, below the threshold, but listed as a near miss at the right value
                // with the run that would show it: a user would do that run, and then the
                // effect must be named alone.
                let next = Pattern::Advised(m.revealing_run);
                advised = format!(" → near miss, then `{}`", m.revealing_run.flags());
                r = run(&s, next, sim_seed);
                bad = judge_scenario(&s, next, &r);
            }
            let p_name = format!("{p:?}").chars().take(5).collect::<String>();
            say(format!(
                "  {:<22} {p_name}{advised} {rate} Hz magnitude {:.4e}: {} {}",
                h.name(),
                s.magnitude,
                describe(&r),
                if bad.is_empty() {
                    "ok".into()
                } else {
                    format!("WRONG: {}", bad.join("; "))
                }
            ));
            verbose(&r);
            failures.extend(
                bad.into_iter()
                    .map(|b| format!("{} {p_name}{advised} {rate} Hz: {b}", h.name())),
            );
        }
    }
    failures
}

/// The generator seeds of the asserted tests: four independent draws of each mechanism.
const DRAWS: [u64; 4] = [20261123, 1, 2, 3];

/// The mechanisms that are not lags and that diagnose gets right on every pattern.
const NOT_LAGS: [Hidden; 9] = [
    Hidden::Clean,
    Hidden::ForceOffset,
    Hidden::ClockRate,
    Hidden::KtError,
    Hidden::Stribeck,
    Hidden::Viscous,
    Hidden::ReynoldsDrag,
    Hidden::DroppedMessages,
    Hidden::TimestampJitter,
];

/// `hidden` on `patterns` over [`DRAWS`]; panics with every failure.
fn assert_right(hidden: &[Hidden], patterns: &[Pattern]) {
    let failures: Vec<String> = DRAWS
        .iter()
        .flat_map(|&seed| check(hidden, seed, patterns))
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The mechanisms diagnose gets right on the sine and on a chirp, on four independent draws each
/// (magnitudes, rates and noise; the `sweep` below found them right on ten draws per mechanism).
#[test]
fn mechanisms_are_named_and_measured() {
    let mut hidden = vec![
        Hidden::CurrentLoopDemand,
        Hidden::CurrentLoopMeasured,
        Hidden::CurrentSenseFilter,
        Hidden::AccelerationFilter,
        Hidden::Braking,
    ];
    hidden.extend(NOT_LAGS);
    hidden.push(Hidden::Cogging);
    assert_right(&hidden, &[Pattern::Sine, Pattern::Chirp]);
}

/// On a chirp, a held load cell (40–100 Hz, its readings repeated in 100–1000 Hz rows), on the
/// same four draws. (On the sine, a held cell in 1 kHz rows lags 1–2 ms, at the limit of what a
/// 0.5 Hz sine resolves: see the ignored test below.)
#[test]
fn held_load_cell_on_a_chirp() {
    assert_right(&[Hidden::LoadCell], &[Pattern::Chirp]);
}

/// On the staircase (lo, ¼, ½, ¾, hi, ¾, ½, ¼, each held 1 s) the mechanisms that are not lags,
/// braking included, and an acceleration filter (estimated on the model's side where the force
/// steps), on the same four draws each. (The other lags are not asserted on it: a first-order
/// force sensor's lag is read from the force's slope, which a step breaks, and a held load
/// cell cannot place a step within its update interval — docs/SCIENCE.md.)
#[test]
fn mechanisms_on_steps_are_named_and_measured() {
    let mut hidden = vec![Hidden::Braking, Hidden::AccelerationFilter];
    hidden.extend(NOT_LAGS);
    assert_right(&hidden, &[Pattern::Steps]);
}

/// A fast velocity observer (60–80 Hz) on the sine, and a held load cell in 1 kHz rows on the
/// sine, lag by 1–3.5 ms, which one 0.5 Hz sinusoid hardly shows in the acceleration equation
/// (held-out gains of 0.8–2.9 %). The simulated velocity shows it: the lag is named, or where the
/// data cannot tell it from a constant torque, ambiguous with one; where nothing is named, the
/// report lists it as a near miss at the right value with the run that shows it (a chirp), and
/// that run names it alone. On the chirp it is named directly.
#[test]
fn a_lag_below_the_equations_threshold_is_named_or_pointed_to() {
    let mut failures: Vec<String> = DRAWS
        .iter()
        .flat_map(|&seed| {
            check(
                &[Hidden::VelocityObserver],
                seed,
                &[Pattern::Sine, Pattern::Chirp],
            )
        })
        .collect();
    failures.extend(
        DRAWS
            .iter()
            .flat_map(|&seed| check(&[Hidden::LoadCell], seed, &[Pattern::Sine])),
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));

    // One draw in detail (seed 1: a 69 Hz observer in 1 kHz rows): the acceleration equation
    // gains 1.4 %, under the 3 % the selection asks, and the simulated velocity 97 %; the lag is
    // named alone, at its value, and the text says so.
    let mut rng = StdRng::seed_from_u64(1);
    let rate = [100.0, 250.0, 500.0, 1000.0][rng.random_range(0..4)];
    let s = Hidden::VelocityObserver.draw(&bench(rate, Pattern::Sine), &mut rng);
    let r = run(&s, Pattern::Sine, rng.random());
    let bad = judge_scenario(&s, Pattern::Sine, &r);
    assert!(bad.is_empty(), "{bad:?}: {}", describe(&r));
    let lag = r
        .effects
        .iter()
        .find(|e| e.effect == EffectKind::TorqueLag)
        .unwrap_or_else(|| panic!("not named: {}", describe(&r)));
    assert!(lag.cv_gain_percent < 3.0, "{}", describe(&r));
    let text = propid_science::diagnose::to_text(&r, "observer.tsv");
    assert!(
        text.contains("torque_lag: torque_lag = ") && !text.contains("Nothing is wrong"),
        "{text}"
    );
}

/// Every mechanism over several rng seeds (`PROPID_SWEEP=N`, default 4, from seed 1): how often
/// each is right, for finding the draws a fixed seed does not reach. Never asserts; run with
/// `-- --ignored --nocapture sweep`.
#[test]
#[ignore = "an exploration aid: prints a table, asserts nothing"]
fn sweep() {
    let n: u64 = std::env::var("PROPID_SWEEP")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(4);
    let only = std::env::var("PROPID_SWEEP_ONLY").ok();
    // PROPID_SWEEP_STEPS=1 adds the staircase; =only runs it alone.
    let patterns: &[Pattern] = match std::env::var("PROPID_SWEEP_STEPS").as_deref() {
        Ok("only") => &[Pattern::Steps],
        Ok(_) => &[Pattern::Sine, Pattern::Chirp, Pattern::Steps],
        Err(_) => &[Pattern::Sine, Pattern::Chirp],
    };
    let from: u64 = std::env::var("PROPID_SWEEP_FROM")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1);
    // PROPID_SWEEP_SEQUENCE=a,b,…: those mechanisms drawn in turn from one generator, as the
    // asserted tests draw them (to reproduce one of their draws).
    if let Ok(list) = std::env::var("PROPID_SWEEP_SEQUENCE") {
        let hidden: Vec<Hidden> = list
            .split(',')
            .filter_map(|name| Hidden::ALL.into_iter().find(|h| h.name() == name))
            .collect();
        for seed in from..from + n {
            check(&hidden, seed, patterns);
        }
        return;
    }
    let mut table = Vec::new();
    for h in Hidden::ALL {
        // Effects outside the library are judged by another test (the report says "unexplained").
        if matches!(
            h,
            Hidden::PeriodicDisturbance | Hidden::Gust | Hidden::VoltageLimit
        ) {
            continue;
        }
        if only
            .as_deref()
            .is_some_and(|o| !o.split(',').any(|x| x == h.name()))
        {
            continue;
        }
        let mut wrong = 0;
        for seed in from..from + n {
            wrong += usize::from(!check(&[h], seed, patterns).is_empty());
        }
        table.push(format!("{:<22} wrong on {wrong} of {n} seeds", h.name()));
    }
    say(table.join("\n"));
}

/// A current-sense filter is a first-order lag, and the chirp tells that shape from a pure delay
/// (`lag_form`), on the same four draws. (On the sine it cannot: see `LagForm`.)
#[test]
fn a_chirp_tells_a_filter_from_a_delay() {
    for seed in DRAWS {
        let mut rng = StdRng::seed_from_u64(seed);
        let rate = [100.0, 250.0, 500.0, 1000.0][rng.random_range(0..4)];
        let s = Hidden::CurrentSenseFilter.draw(&bench(rate, Pattern::Chirp), &mut rng);
        let r = run(&s, Pattern::Chirp, rng.random());
        say(format!("seed {seed}: {}", describe(&r)));
        let lag = r
            .effects
            .iter()
            .find(|e| e.effect == EffectKind::ForceSensorLag);
        assert_eq!(
            lag.and_then(|e| e.lag_form),
            Some(LagShape::FirstOrder),
            "seed {seed}: {}",
            describe(&r)
        );
    }
}

/// A lag must earn its held-out gain by its phase, not by averaging the force's noise away: on
/// the clean stand's sine at 1 kHz rows (where a lag averages most), no candidate gains 1 % on
/// held-out acceleration, on the same four draws. (Before the force's noise was put back into
/// the score, a 1 ms torque lag gained 11.6 % there, and read current loops 0.16 ms long.)
#[test]
fn a_lag_earns_nothing_for_smoothing_the_force() {
    for seed in DRAWS {
        let mut rng = StdRng::seed_from_u64(seed);
        let s = Hidden::Clean.draw(&bench(1000.0, Pattern::Sine), &mut rng);
        let r = run(&s, Pattern::Sine, rng.random());
        // (Effects measured from the rows, the clock, have no held-out gain.)
        for c in r
            .candidates
            .iter()
            .filter(|c| c.cv_gain_percent.is_finite())
        {
            assert!(
                c.cv_gain_percent < 1.0,
                "seed {seed}: {} gains {:.2} % on clean data ({})",
                c.effect,
                c.cv_gain_percent,
                describe(&r)
            );
        }
    }
}

/// The draws of the `sweep` (each mechanism alone from rng seed K, sine then chirp) that were
/// wrong before this file's last round of changes, each right now, so that none of those
/// failures comes back unseen (docs/SCIENCE.md has what each was).
#[test]
fn draws_that_were_wrong_are_right() {
    let fixed: [(Hidden, u64, &str); 12] = [
        // The force's noise, averaged by the lag, paid for a longer one: 2.87 ms for 2.59.
        (Hidden::CurrentLoopDemand, 3, "sine read 11 % long"),
        (Hidden::CurrentLoopDemand, 8, "sine read 12 % long"),
        // Then, without that bonus, only the constant's twin pair was reported.
        (
            Hidden::CurrentLoopDemand,
            20,
            "coulomb_friction or force_offset",
        ),
        (
            Hidden::CurrentLoopDemand,
            31,
            "coulomb_friction or force_offset",
        ),
        (
            Hidden::CurrentLoopDemand,
            32,
            "coulomb_friction or force_offset",
        ),
        // A second-round torque of 10⁻⁵–10⁻⁴ N·m, within its standard errors of zero.
        (
            Hidden::AccelerationFilter,
            13,
            "a 7.5e-5 N·m offset beside the lag",
        ),
        (
            Hidden::AccelerationFilter,
            14,
            "an 8e-6 N·m offset, ambiguous",
        ),
        (
            Hidden::AccelerationFilter,
            26,
            "a 1.2e-4 N·m offset, ambiguous with its twin",
        ),
        // Braking at 100 Hz on the chirp: 12–13 % short, then a second-round ambiguity.
        (Hidden::Braking, 3, "chirp: braking 13 % short"),
        (Hidden::Braking, 7, "chirp: braking 12 % short"),
        (Hidden::Braking, 16, "chirp: braking 12 % short"),
        // An 84 Hz cell in 100 Hz rows (16 % repeated) read row by row: 6.24 ms for 5.45.
        (Hidden::LoadCell, 6, "sine read 14 % long"),
    ];
    let mut failures = Vec::new();
    for (hidden, seed, was) in fixed {
        for bad in check(&[hidden], seed, &[Pattern::Sine, Pattern::Chirp]) {
            failures.push(format!("seed {seed} (was: {was}): {bad}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Two mechanisms at once on one bench: `a` drawn on it, `b` drawn on the stand `a` made, the
/// current sense's filter and offset merged where both set them. What a right diagnosis reports
/// is both scenarios' effects, and the J and drag law of the last (which sees the first's).
fn combined(
    a: Hidden,
    b: Hidden,
    bench: &Bench,
    rng: &mut StdRng,
) -> (Scenario, Vec<ExpectedEffect>) {
    use propid_mechsim::config::TorqueReport;
    let first = a.draw(bench, rng);
    let mut second = b.draw(
        &Bench {
            base: first.config,
            ..*bench
        },
        rng,
    );
    if let (
        TorqueReport::Current {
            filter: fa,
            offset: oa,
            ..
        },
        TorqueReport::Current {
            filter: fb,
            offset: ob,
            noise,
        },
    ) = (first.config.sensing.torque, second.config.sensing.torque)
    {
        second.config.sensing.torque = TorqueReport::Current {
            filter: fa.max(fb),
            offset: oa + ob,
            noise,
        };
    }
    let effects = [first.expect, second.expect]
        .into_iter()
        .filter_map(|e| match e {
            Expect::Effect(e) => Some(e),
            _ => None,
        })
        .collect();
    (second, effects)
}

/// Two mechanisms at once on the mechanism-level stand, on a chirp, 100–1000 Hz: both found
/// jointly, each within 10 % (plus the scenarios' derivation error), the extended J and drag law
/// within 2 % of what the data hold.
#[test]
fn two_mechanisms_at_once_are_found_jointly_on_a_chirp() {
    let failures: Vec<String> = two_mechanisms(20261202, Pattern::Chirp)
        .into_iter()
        .flat_map(|o| o.wrong.into_iter().map(move |w| format!("{}: {w}", o.what)))
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Pairs the seed's sine does not get right on the mechanism stand (docs/SCIENCE.md, "Two
/// effects at once"), with why. Each must still end honestly. (`lag + coulomb, reversing` was
/// here: a braking torque and an offset named for the lag and the friction at 1000 Hz, J 6.9 %
/// high. The Coulomb friction, tied with the viscous term named in round 1, was never tried again:
/// rule 8 tried only the viscous term's rivals in its place once the lag was named, and braking
/// took it. Rule 8 now tries the effects tied with a term too: the Coulomb friction replaces the
/// viscous term beside the lag, 13.52 ms and 4.12 mN·m for 13.48 and 4.13, J within 0.01 %.)
const SINE_PAIR_LIMITS: &[(&str, &str)] = &[(
    "sensor filter + drag exponent",
    "the filter named 25 % short beside the right exponent (over the sine's band they trade)",
)];

/// Pairs of [`SINE_PAIR_LIMITS`] that are worse than a miss: the verdict says the model explains
/// the data while J or the drag is more than 2 % off. None today: `lag + offset` was (a viscous
/// friction named alone, J 4.8 % low, said explained) until rule 10 exchanged a term named first
/// for a lag and one of its rivals; `lag + viscous` became right by the same rule. The test fails
/// when one stops being silent (or another starts), so the docs cannot drift.
const SINE_SILENTLY_WRONG: &[&str] = &[];

/// The same pairs on the seed's sine: every pair right except those in [`SINE_PAIR_LIMITS`], and
/// none silently wrong (the model said to explain the data while J or the drag is more than 2 %
/// off) but those in [`SINE_SILENTLY_WRONG`]. The test fails when a listed pair becomes right.
#[test]
fn two_mechanisms_at_once_on_the_seeds_sine() {
    let failures: Vec<String> = two_mechanisms(20261202, Pattern::Sine)
        .into_iter()
        .flat_map(|o| {
            against_ledger(
                &o.what,
                o.wrong,
                SINE_PAIR_LIMITS.iter().any(|&(n, _)| n == o.name),
                o.silent,
                SINE_SILENTLY_WRONG.contains(&o.name),
            )
        })
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// How one pair of mechanisms was diagnosed.
struct PairOutcome {
    name: &'static str,
    /// The pair, pattern and rate, for messages.
    what: String,
    /// What is wrong (empty: right).
    wrong: Vec<String>,
    /// Whether the verdict says the model explains the data while J or the drag is off.
    silent: bool,
}

/// The pairs of mechanisms on pattern `p`, drawn from generator seed `seed`: how each was
/// diagnosed.
fn two_mechanisms(seed: u64, p: Pattern) -> Vec<PairOutcome> {
    say(format!(
        "two mechanisms at once on the {p:?} (rng seed {seed}):"
    ));
    let mut rng = StdRng::seed_from_u64(seed);
    // (name, first, second, lo): a pattern that reverses the rotor (lo = −0.5, the run diagnose
    // advises to tell a Coulomb friction from an offset), one that reaches low speeds for two
    // torque shapes (lo = 0.02: over 800–2450 rad/s an exponent and an offset are nearly one
    // curve with a viscous term and a friction), the seed's lo = 0.1 otherwise.
    let pairs = [
        (
            "lag + offset",
            Hidden::CurrentSenseFilter,
            Hidden::ForceOffset,
            0.1,
        ),
        (
            "lag + viscous",
            Hidden::CurrentLoopDemand,
            Hidden::Viscous,
            0.1,
        ),
        (
            "lag + coulomb, reversing",
            Hidden::CurrentLoopDemand,
            Hidden::Stribeck,
            -0.5,
        ),
        (
            "drag exponent + offset",
            Hidden::ReynoldsDrag,
            Hidden::ForceOffset,
            0.02,
        ),
        (
            "braking + lag",
            Hidden::Braking,
            Hidden::CurrentLoopDemand,
            0.1,
        ),
        (
            "sensor filter + drag exponent",
            Hidden::CurrentSenseFilter,
            Hidden::ReynoldsDrag,
            0.1,
        ),
    ];
    let mut outcomes = Vec::new();
    {
        for (name, a, b, lo) in pairs {
            let rate = [100.0, 250.0, 500.0, 1000.0][rng.random_range(0..4)];
            let bench = Bench {
                lo,
                ..bench(rate, p)
            };
            let reverse = lo < 0.0;
            let (mut s, effects) = combined(a, b, &bench, &mut rng);
            if reverse {
                // A plain Coulomb friction: the Stribeck dip, invisible at stand speeds, is not
                // when the rotor reverses (the scenario's expected value is F_c without it).
                s.config.rotor.bearing.breakaway = 0.0;
            }
            let sim_seed = rng.random();
            if std::env::var("PROPID_ONLY").is_ok_and(|o| !name.contains(o.as_str())) {
                continue;
            }
            let r = run(&s, p, sim_seed);
            let bad = judge_effects(&effects, truth(&s), p, &r);
            let p_name = format!("{p:?}");
            say(format!(
                "  {name:<30} {p_name:<5} {rate} Hz truth [{}]: {} {}",
                effects
                    .iter()
                    .map(|e| format!("{}={:.4e}", e.name, e.value))
                    .collect::<Vec<_>>()
                    .join(", "),
                describe(&r),
                if bad.is_empty() {
                    "ok".to_string()
                } else {
                    format!("WRONG: {}", bad.join("; "))
                }
            ));
            verbose(&r);
            outcomes.push(PairOutcome {
                name,
                what: format!("{name} {p_name} {rate} Hz"),
                wrong: bad,
                silent: silently_wrong(&r, truth(&s)),
            });
        }
    }
    outcomes
}

/// A load transient — a raised-cosine bump of 4 mN·m for 3 s, its peak ten times the reported
/// acceleration's noise (J·a = 2·10⁻⁵ kg·m² × 20 rad/s²), its mean five — early in a 120 s run
/// (t = 15 s) and at t = 70 s (outside the held-out last 30 % that was searched before):
/// reported as unexplained, localised in a window of time that holds it, nothing named, and its
/// span left out of the fit, so J and the drag are within 2 % of the stand's.
#[test]
fn a_load_transient_is_unexplained_and_localised_in_time() {
    use propid_mechsim::config::Disturbance;
    let mut failures = Vec::new();
    for (start, seed) in [(15.0, 1u64), (70.0, 2)] {
        let mut b = bench(500.0, Pattern::Sine);
        b.duration = 120.0;
        let mut s = Hidden::Clean.draw(&b, &mut StdRng::seed_from_u64(seed));
        s.config.disturbance = Disturbance::Bump {
            amplitude: 0.004,
            start,
            width: 3.0,
        };
        let r = run(&s, Pattern::Sine, seed);
        say(format!(
            "  bump at {start} s: {}; J {:.4e}, left out {:?}",
            describe(&r),
            r.extended.inertia,
            r.left_out.as_ref().map(|l| (l.from_s, l.to_s))
        ));
        verbose(&r);
        let c = r.concentration.as_ref();
        let held = c.is_some_and(|c| {
            c.condition == propid_science::diagnose::Condition::TimeWindow
                && c.from_s <= start + 1.0
                && c.to_s >= start + 2.0
                && c.to_s - c.from_s <= 10.0
        });
        // Its span — the bump's peak, within the bump (a raised cosine's tails are below the
        // noise) — is left out of the fit: J and the drag as without the bump.
        let left_out = r.left_out.as_ref().is_some_and(|l| {
            l.from_s >= start - 0.5
                && l.from_s <= start + 1.5
                && l.to_s >= start + 1.5
                && l.to_s <= start + 3.5
        });
        let fit = judge_fit(&r, truth(&s));
        if !held || !left_out || r.verdict != Verdict::Unexplained || !r.effects.is_empty() {
            failures.push(format!("bump at {start} s: {}", describe(&r)));
        }
        failures.extend(fit.into_iter().map(|b| format!("bump at {start} s: {b}")));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
