//! Hidden effects on the mechanism-level stand (`propid-mechsim`, written independently of the
//! diagnosis): one mechanism at a random magnitude, a random feedback rate (100–1000 Hz), the
//! seed's sine, a chirp and (for the mechanisms that are not lags) a staircase, and what a
//! correct diagnosis must report as the scenario states it (derived from the mechanism, not from
//! the diagnosis's equations). Each effect named alone, or,
//! where the scenario says the pattern cannot separate it from another, "ambiguous" between the
//! two with the right one among them; its parameter within 10 % (plus the scenario's stated
//! derivation error); the extended J and c2 within 2 % of what the scenario says the data hold.
//! Seeds are drawn from a fixed seed (printed), so a failure is reproducible.

use propid_io::tsv::{Row, Sample};
use propid_mechsim::scenarios::{Bench, Expect, ExpectedEffect, Hidden, Scenario};
use propid_mechsim::{pattern, MechConfig, Record};
use propid_science::diagnose::{diagnose_rows, NearMiss, Options, Report, SeparatingRun, Verdict};
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
                "steps" => s.simulate(pattern::steps(lo, hi, PERIOD), seed),
                _ => s.simulate(pattern::chirp(lo, hi, PERIOD, b.duration), seed),
            }
        }
    }
    .expect("scenario simulates");
    diagnose_rows(rows(&records), Options::default()).expect("diagnosis runs")
}

fn describe(r: &Report) -> String {
    let effects: Vec<String> = r
        .effects
        .iter()
        .map(|e| match e.lag_form {
            Some(form) => format!("{}={:.4e} ({form})", e.name, e.value),
            None => format!("{}={:.4e}", e.name, e.value),
        })
        .collect();
    let near: Vec<String> = r
        .near_misses
        .iter()
        .map(|m| format!("{}={:.4e} ({:.2} %)", m.name, m.value, m.cv_gain_percent))
        .collect();
    format!(
        "{:?} [{}] near [{}] ambiguous {:?}, J {:.4e}, c2 {:.4e}, sim {:.2} → {:.2}",
        r.verdict,
        effects.join(", "),
        near.join(", "),
        r.ambiguity.as_ref().map(|a| (a.between, a.values)),
        r.extended.mass,
        r.extended.c2,
        r.simulation_rms.base,
        r.simulation_rms.extended,
    )
}

fn say(line: String) {
    std::io::Write::write_all(&mut std::io::stderr(), (line + "\n").as_bytes()).unwrap();
}

/// What is wrong with report `r` for scenario `s` on pattern `p` (empty: right).
fn judge(s: &Scenario, p: Pattern, r: &Report) -> Vec<String> {
    let mut bad = Vec::new();
    let names: Vec<&str> = r.effects.iter().map(|e| e.name).collect();
    match s.expect {
        Expect::Nothing | Expect::NotIdentifiable { .. } => {
            if r.verdict != Verdict::NothingWrong {
                bad.push(format!("expected nothing, got {:?} {names:?}", r.verdict));
            }
            // Nor a hint of something: a near miss here would send the user on a needless run.
            let near: Vec<&str> = r.near_misses.iter().map(|m| m.name).collect();
            if !near.is_empty() {
                bad.push(format!("expected nothing, got near misses {near:?}"));
            }
        }
        Expect::Effect(e) => {
            let tolerance = tolerance(&e);
            let found = if let Some(a) = &r.ambiguity {
                // A rotor that never reverses (lo > 0) cannot tell a Coulomb friction from a
                // force offset: both are one constant torque, on any pattern.
                let constant =
                    a.between.contains(&"coulomb_friction") && a.between.contains(&"force_offset");
                // On the seed's sine a lag and a constant torque are spanned by the same
                // harmonics (docs/SCIENCE.md): any ambiguity with the right one among the two.
                let allowed = match (e.ambiguous_with, p) {
                    (_, Pattern::Sine) => true,
                    (Some((other, _)), _) => a.between.contains(&other),
                    _ if constant => true,
                    (None, _) => false,
                };
                // The scenario's stated equivalent stands in for the effect (a positive offset
                // is a Coulomb friction of the same size on a rotor that never reverses).
                let stand_in = e.ambiguous_with.map(|(other, _)| other);
                match a
                    .between
                    .iter()
                    .position(|n| *n == e.name)
                    .or_else(|| a.between.iter().position(|n| Some(*n) == stand_in))
                {
                    Some(k) if allowed => Some(a.values[k]),
                    _ => {
                        bad.push(format!(
                            "ambiguous {:?} where {} is expected",
                            a.between, e.name
                        ));
                        None
                    }
                }
            } else if names == [e.name] {
                Some(r.effects[0].value)
            } else {
                bad.push(format!("named {names:?}, expected [{}]", e.name));
                None
            };
            if let Some(v) = found {
                if ((v - e.value) / e.value).abs() > tolerance {
                    bad.push(format!(
                        "{} = {v:.4e}, expected {:.4e} within {:.0} %",
                        e.name,
                        e.value,
                        tolerance * 100.0
                    ));
                }
            }
        }
        Expect::Unexplained { .. } => unreachable!("not drawn here"),
    }
    if r.ambiguity.is_none() && !matches!(r.verdict, Verdict::CannotJudge { .. }) {
        // A drag law k·|ω|^p is compared by its torque at the steady speed of the middle
        // command, inside the data: k alone is the torque at 1 rad/s, three decades below them,
        // where an exponent off by 0.0035 (2.1758 for 2.1723, 0.16 %) moves it by 2.6 %.
        let j = r.extended.mass;
        let (k, p) = (s.fit.c2, s.fit.drag_exponent);
        let mid = 0.5 * (s.bench.lo + s.bench.hi) * s.bench.base.drive.max_torque;
        let w = (mid / k).powf(1.0 / p);
        let (k_hat, p_hat) = match (r.extended.k, r.extended.p) {
            (Some(k_hat), Some(p_hat)) => (k_hat, p_hat),
            _ => (r.extended.c2, 2.0),
        };
        let drag = k_hat * w.powf(p_hat) / (k * w.powf(p));
        if (j / s.fit.inertia - 1.0).abs() > 0.02 || (drag - 1.0).abs() > 0.02 {
            bad.push(format!(
                "extended J {j:.4e} (expected {:.4e}), drag law {k_hat:.4e}·|ω|^{p_hat:.4} \
                 (expected {k:.4e}·|ω|^{p:.4}: {:+.1} % at {w:.0} rad/s)",
                s.fit.inertia,
                (drag - 1.0) * 100.0
            ));
        }
    }
    bad
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
            r.near_misses
                .iter()
                .find(|m| m.name == e.name && ((m.value - e.value) / e.value).abs() <= tolerance)
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
            let mut bad = judge(&s, p, &r);
            // Ambiguous with the right effect among the two where the pattern should have told
            // them apart: the report advises a run that would; a user would do it, and then the
            // effect must be named alone.
            let mut advised = String::new();
            if let Some(a) = r.ambiguity.as_ref().filter(|a| {
                !bad.is_empty()
                    && matches!(s.expect, Expect::Effect(e) if a.between.contains(&e.name))
            }) {
                let next = Pattern::Advised(a.separating_run);
                advised = format!(" → advised `{}`", a.separating_run.flags());
                r = run(&s, next, sim_seed);
                bad = judge(&s, next, &r);
            } else if let Some(m) = near_miss_of(&s, &r).filter(|_| !bad.is_empty()) {
                // Not named, below the threshold, but listed as a near miss at the right value
                // with the run that would show it: a user would do that run, and then the
                // effect must be named alone.
                let next = Pattern::Advised(m.revealing_run);
                advised = format!(" → near miss, then `{}`", m.revealing_run.flags());
                r = run(&s, next, sim_seed);
                bad = judge(&s, next, &r);
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
            let verbose = std::env::var("PROPID_SWEEP_VERBOSE").ok();
            if verbose.as_deref() == Some("all") || (!bad.is_empty() && verbose.is_some()) {
                for c in &r.candidates {
                    say(format!(
                        "      {:<18} cv {:+7.2} % folds {} value {:.4e} sim {:+7.2} % {}{}",
                        c.name,
                        c.cv_gain_percent,
                        c.folds_better,
                        c.value,
                        c.simulation_gain_percent,
                        if c.selected { "SELECTED " } else { "" },
                        c.note
                    ));
                }
                for n in &r.notes {
                    say(format!("      note: {n}"));
                }
            }
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

/// Below the threshold: a fast velocity observer (60–80 Hz) on the sine, and a held load cell
/// in 1 kHz rows on the sine, lag by 1–3.5 ms, which one 0.5 Hz sinusoid hardly shows (held-out
/// gains of 0.8–2.9 %, under the 3 % threshold; docs/SCIENCE.md). Where nothing is named, the
/// report must list the effect as a near miss at the right value with the run that shows it (a
/// chirp), and that run must name it alone; on the chirp it is named directly.
#[test]
fn below_the_threshold_a_near_miss_points_to_the_run_that_names_it() {
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

    // The route itself, on one draw where the sine names nothing (seed 1: a 69 Hz observer in
    // 1 kHz rows): the near miss, its value, and its advice.
    let mut rng = StdRng::seed_from_u64(1);
    let rate = [100.0, 250.0, 500.0, 1000.0][rng.random_range(0..4)];
    let s = Hidden::VelocityObserver.draw(&bench(rate, Pattern::Sine), &mut rng);
    let r = run(&s, Pattern::Sine, rng.random());
    assert_eq!(r.verdict, Verdict::NothingWrong, "{}", describe(&r));
    let m = near_miss_of(&s, &r).unwrap_or_else(|| panic!("no near miss: {}", describe(&r)));
    assert_eq!(m.revealing_run.pattern, "chirp");
    assert!(
        m.cv_gain_percent >= 0.5 && m.cv_gain_percent < 3.0 && m.simulation_gain_percent > 0.0,
        "{m:?}"
    );
    let text = propid_science::diagnose::to_text(&r, "observer.tsv");
    assert!(
        text.contains("Nothing is named")
            && text.contains("torque_lag = ")
            && !text.contains("Nothing is wrong"),
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
        let lag = r.effects.iter().find(|e| e.name == "force_sensor_lag");
        assert_eq!(
            lag.and_then(|e| e.lag_form),
            Some("first_order"),
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
        for c in &r.candidates {
            assert!(
                c.cv_gain_percent < 1.0,
                "seed {seed}: {} gains {:.2} % on clean data ({})",
                c.name,
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
