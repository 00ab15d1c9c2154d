//! The drag law from steady-state data, when the inertia cannot be identified.
//!
//! A stand whose torque is sampled slowly (an RCbenchmark load cell at ~6.7 Hz) and driven in held
//! steps says almost nothing about J, but a lot about the drag law: at each plateau the torque is
//! the aerodynamic torque. Two laws are compared on the samples above 10 % of the top speed:
//!
//! ```text
//!  seed:     F = c2·ω² + F₀          (F₀ absorbs the load cell's zero offset)
//!  extended: F = k·|ω|^p + F₀        (p by the held-out error: grid, then golden section)
//! ```
//! by cross-validation with interleaved folds (every tenth sample in one fold), because held
//! steps put each speed in one contiguous block. The exponent is the `drag_exponent` candidate,
//! and it is named as every candidate is: by `select` (rules 1–4; no simulation here, so the
//! torque equation's held-out error is the whole score).

use propid_core::estimate::NormalEquations;

use super::candidate::{admissible_measured, EffectKind, Estimate};
use super::model::Effect;
use super::report::{
    BaseModel, DragLaw, NamedEffect, Report, ResidualAnalysis, SimulationRms, Traces, Unidentified,
};
use super::select::{judge, Decision, Evidence, FoldErrors, Gain};
use super::signals::Signals;
use super::tune::golden;
use super::FOLDS;
use propid_io::InputError;

fn folds(s: &Signals, idx: &[usize], p: f64) -> [NormalEquations<f64, 2>; FOLDS] {
    let mut eqs = [NormalEquations::<f64, 2>::new(); FOLDS];
    for (n, &i) in idx.iter().enumerate() {
        let w = s.velocity[i].abs();
        eqs[n % FOLDS].update(&[w.powf(p), 1.0], s.force[i]);
    }
    eqs
}

/// How a law with exponent p scores.
struct Score {
    /// Pooled held-out mean squared error.
    mse: f64,
    /// Held-out MSE per fold.
    folds: [f64; FOLDS],
    /// (k, F₀) fitted to all samples.
    theta: [f64; 2],
    /// Their standard errors.
    stderr: [f64; 2],
    /// In-sample residual sum of squares.
    rss: f64,
    /// Samples.
    n: f64,
}

fn score(s: &Signals, idx: &[usize], p: f64) -> Option<Score> {
    let eqs = folds(s, idx, p);
    let mut per = [0.0; FOLDS];
    let (mut total, mut count) = (0.0, 0.0);
    let mut all = NormalEquations::<f64, 2>::new();
    for e in &eqs {
        all.merge(e);
    }
    for k in 0..FOLDS {
        let mut train = NormalEquations::<f64, 2>::new();
        for (j, e) in eqs.iter().enumerate() {
            if j != k {
                train.merge(e);
            }
        }
        let theta = train.solve().ok()?.theta;
        let rss = eqs[k].residual_sum_of_squares(&theta);
        per[k] = rss / eqs[k].count().max(1.0);
        total += rss;
        count += eqs[k].count();
    }
    let sol = all.solve().ok()?;
    let rss = all.residual_sum_of_squares(&sol.theta);
    Some(Score {
        mse: total / count.max(1.0),
        folds: per,
        theta: sol.theta,
        stderr: sol.stderr,
        rss,
        n: all.count(),
    })
}

/// Fits both laws; `None` if there are too few usable samples.
pub fn drag_law(s: &Signals) -> Option<DragLaw> {
    let top = s.velocity.iter().map(|w| w.abs()).fold(0.0, f64::max);
    let idx: Vec<usize> = (0..s.len())
        .filter(|&i| s.force[i].is_finite() && s.velocity[i].abs() > 0.1 * top)
        .collect();
    if idx.len() < 2 * FOLDS {
        return None;
    }
    let seed = score(s, &idx, 2.0)?;
    let cv = |p: f64| score(s, &idx, p).map_or(f64::INFINITY, |x| x.mse);
    let grid = super::candidate::drag_exponent_grid();
    let scores: Vec<f64> = grid.iter().map(|&p| cv(p)).collect();
    let k = (0..grid.len()).min_by(|a, b| scores[*a].total_cmp(&scores[*b]))?;
    let p = golden(
        grid[k.saturating_sub(1)],
        grid[(k + 1).min(grid.len() - 1)],
        cv,
        24,
    );
    let free = score(s, &idx, p)?;
    // Standard error of p from the curvature of the in-sample residual.
    let h = 0.01;
    let rss_at = |q: f64| score(s, &idx, q).map_or(f64::NAN, |x| x.rss);
    let curvature = (rss_at(p + h) - 2.0 * free.rss + rss_at(p - h)) / (h * h);
    let sigma2 = free.rss / (free.n - 3.0).max(1.0);
    let stderr = if curvature > 0.0 {
        (2.0 * sigma2 / curvature).sqrt()
    } else {
        f64::NAN
    };
    let kind = EffectKind::DragExponent;
    let estimate = Estimate::new(p, stderr);
    let errors = |x: &Score| FoldErrors {
        equation: x.folds,
        simulation: None,
    };
    let evidence = Evidence {
        effect: kind,
        parameters: kind.candidate().parameters(),
        estimate,
        admissible: admissible_measured(kind, estimate),
        errors: errors(&free),
        simulation_sees: false,
        lag_in_samples: None,
    };
    let decision = judge(&errors(&seed), &evidence).unwrap_or(Decision::Named);
    Some(DragLaw {
        samples: idx.len(),
        c2: seed.theta[0],
        c2_stderr: seed.stderr[0],
        offset: seed.theta[1],
        exponent: p,
        exponent_stderr: stderr,
        k: free.theta[0],
        cv_gain_percent: 100.0 * (1.0 - free.mse / seed.mse),
        gain: Gain::of(&errors(&seed), &errors(&free)),
        rms_seed: (seed.rss / seed.n).sqrt(),
        rms_extended: (free.rss / free.n).sqrt(),
        decision,
    })
}

/// The report of steady-state data: the drag law, J not identified.
pub(crate) fn report(s: &Signals, law: DragLaw, why: InputError) -> Report {
    let mut effects = Vec::new();
    let kind = EffectKind::DragExponent;
    if law.decision == Decision::Named {
        let e = Effect::new(kind, law.exponent);
        effects.push(NamedEffect {
            effect: kind,
            value: law.exponent,
            unit: kind.unit(),
            stderr: law.exponent_stderr,
            gain_percent: 100.0 * (1.0 - law.rms_extended / law.rms_seed),
            cv_gain_percent: law.cv_gain_percent,
            gain: law.gain,
            lag_form: None,
            lag_delay_s: None,
            explanation: kind.candidate().explanation(&e, law.exponent),
        });
    }
    let n = s.len();
    let base = BaseModel {
        c1: 0.0,
        c2: law.c2,
        c2_stderr: law.c2_stderr,
        ..BaseModel::unknown()
    };
    // The extended model is the free exponent's law only where the selection names it;
    // otherwise the seed's law stands.
    let extended = if law.decision == Decision::Named {
        BaseModel {
            c1: 0.0,
            ..BaseModel::unknown()
        }
        .power_law(law.k, f64::NAN, law.exponent, super::rms(&s.velocity))
    } else {
        base.clone()
    };
    let mut r = Report::cannot_judge(n, s.t[n - 1] - s.t[0], Vec::new());
    r.rate_hz = s.rate;
    r.unidentified = Unidentified::of(&base)
        .into_iter()
        .filter(|u| u.parameter == super::report::Parameter::Inertia)
        .collect();
    r.notes = vec![format!(
        "steady-state data: the dynamics cannot be fitted ({}); the drag law is diagnosed from {} torque samples instead, \
         and simulation_rms holds the torque residual [N·m] of the seed's law (F = c2·ω² + F₀) and of F = k·|ω|^p + F₀",
        why, law.samples
    )];
    r.simulation_rms = SimulationRms {
        base: law.rms_seed,
        extended: law.rms_extended,
        gain_percent: 100.0 * (1.0 - law.rms_extended / law.rms_seed),
    };
    r.residual_analysis = ResidualAnalysis {
        correlations: Vec::new(),
        dominant_frequency_hz: f64::NAN,
        peak_to_median: f64::NAN,
    };
    r.base = base;
    r.extended = extended;
    r.effects = effects;
    r.steady_state = Some(law);
    r.steady_share = 1.0;
    r.traces = Traces::default();
    r.verdict = super::report::Verdict::NothingWrong;
    r.conclude();
    r
}
