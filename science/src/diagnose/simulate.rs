//! Open-loop simulation of the velocity from the measured force, and the held-out simulation
//! error of every fold.
//!
//! A model is simulated as a model-based controller would use it: from the measured inputs, its
//! own velocity integrated (RK4, the inputs linear between samples), started at the measured
//! velocity. On held-out data that is the second criterion of the selection beside the
//! acceleration equation: an effect that fits the acceleration by smoothing noise simulates
//! worse, and a lag and a constant torque that fit one sinusoid alike simulate differently.
//!
//! Each fold is simulated with the parameters fitted without it, restarted from the measured
//! velocity every [`WINDOW`] seconds so that it never drifts away and every fold counts.

use std::ops::Range;

use super::engine::{cross_fit, cross_fit_for_tuning, CrossFit, Cv};
use super::model::{Model, Prepared, Speed, MAX_COLUMNS};
use super::signals::Signals;
use super::FOLDS;

/// Length of a simulated stretch before it restarts from the measured velocity [s]: a few
/// times a propeller's speed time constant J/(2·c2·ω) (0.3–1 s on the stands tested), so a
/// wrong drag or inertia shows, short enough that a model never drifts far.
pub const WINDOW: f64 = 2.0;

/// Most samples simulated per model: on a long log, windows spread evenly over each fold (an
/// hour at 500 Hz would otherwise cost two million RK4 steps per model tried).
pub const BUDGET: usize = 200_000;

/// The stretches simulated in each fold.
pub(crate) struct SimPlan {
    windows: Vec<Vec<Range<usize>>>,
}

impl SimPlan {
    /// Windows of [`WINDOW`] seconds in each of the [`FOLDS`] blocks after the warm-up, at most
    /// [`BUDGET`] samples in all.
    pub fn new(s: &Signals) -> SimPlan {
        let (start, n) = (s.first, s.len());
        let len = (n - start).max(1);
        let per_window = ((WINDOW * s.rate).round() as usize).max(10);
        let per_fold_budget = (BUDGET / FOLDS).max(per_window);
        let windows = (0..FOLDS)
            .map(|k| {
                let (a, b) = (start + k * len / FOLDS, start + (k + 1) * len / FOLDS);
                let all: Vec<Range<usize>> = (a..b)
                    .step_by(per_window)
                    .map(|w| w..(w + per_window).min(b))
                    .filter(|r| r.len() >= 3)
                    // A window through an excluded event would score the event.
                    .filter(|r| r.end <= s.excluded.start || r.start >= s.excluded.end)
                    .collect();
                let keep = (per_fold_budget / per_window).max(1);
                if all.len() <= keep {
                    all
                } else {
                    (0..keep)
                        .map(|j| all[j * all.len() / keep].clone())
                        .collect()
                }
            })
            .collect();
        SimPlan { windows }
    }
}

/// A model's held-out errors, fold by fold.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct FoldScores {
    /// Acceleration equation: mean squared error per fold [(rad/s²)²].
    pub equation: [f64; FOLDS],
    /// Simulated velocity: mean squared error per fold [(rad/s)²].
    pub simulation: [f64; FOLDS],
    /// The pooled acceleration error.
    pub equation_pooled: f64,
}

/// The held-out acceleration and simulation errors of `model` in every fold.
pub(crate) fn fold_scores(model: &Model, s: &Signals, plan: &SimPlan) -> Option<FoldScores> {
    let p = model.prepare(s);
    let cf = cross_fit(model, &p, s)?;
    Some(scores_of(model, &p, &cf, s, plan))
}

/// The held-out scores a tuning reads, the simulation's included: the equation's on the rows a
/// tuning reads, each fold simulated with the parameters fitted on those rows of the others.
pub(crate) fn tuning_scores(model: &Model, s: &Signals, plan: &SimPlan) -> Option<Cv> {
    let p = model.prepare(s);
    let cf = cross_fit_for_tuning(model, &p, s)?;
    let scores = scores_of(model, &p, &cf, s, plan);
    Some(Cv {
        simulation: Some(scores.simulation),
        ..cf.cv
    })
}

fn scores_of(
    model: &Model,
    p: &Prepared,
    cf: &CrossFit,
    s: &Signals,
    plan: &SimPlan,
) -> FoldScores {
    let mut simulation = [0.0; FOLDS];
    for (k, windows) in plan.windows.iter().enumerate() {
        let (mut sum, mut count) = (0.0, 0usize);
        for w in windows {
            let v = simulate(model, p, &cf.thetas[k], s, w.clone());
            sum += v
                .iter()
                .zip(&s.velocity[w.clone()])
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>();
            count += v.len();
        }
        simulation[k] = sum / count.max(1) as f64;
    }
    FoldScores {
        equation: cf.cv.folds,
        simulation,
        equation_pooled: cf.cv.mse,
    }
}

/// Samples simulated (a profiling count).
pub static SIMULATED: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// Open-loop simulation of the velocity over `range` from the measured inputs, starting at the
/// measured velocity (its mean over the five samples centred on the first: unbiased where the
/// rotor accelerates).
pub(crate) fn simulate(
    model: &Model,
    p: &Prepared,
    theta: &[f64],
    s: &Signals,
    range: Range<usize>,
) -> Vec<f64> {
    SIMULATED.fetch_add(range.len(), std::sync::atomic::Ordering::Relaxed);
    let start = range.start;
    let (a, b) = (start.saturating_sub(2), (start + 3).min(s.len()));
    let mut w = s.velocity[a..b].iter().sum::<f64>() / (b - a).max(1) as f64;
    // The model's acceleration at fraction `x` ∈ [0, 1] of the step from sample i to i + 1: the
    // regressors (force, angle, …) taken as linear between the samples (first-order hold). Held
    // at sample i for the whole step (zero-order hold), every simulation would carry a
    // half-sample delay of the input: 5 ms at 100 Hz, as large as the lags being judged.
    let held = model.held_columns();
    // A simulation that leaves four times the record's largest speed has diverged (an unstable
    // fitted model, a negative drag): it is held there, a large error but a finite one.
    let bound = 4.0 * s.top_speed;
    let accel = |i: usize, x: f64, w: f64| -> f64 {
        let step = s.t[i + 1] - s.t[i];
        let speed = Speed::Simulated {
            omega: w,
            drag: Model::drag(p, w),
        };
        let r0 = model.row(p, s, i, speed, true, step);
        let r = if x > 0.0 {
            let r1 = model.row(p, s, i + 1, speed, true, step);
            core::array::from_fn::<f64, MAX_COLUMNS, _>(|k| {
                if held[k] {
                    r0[k]
                } else {
                    r0[k] + x * (r1[k] - r0[k])
                }
            })
        } else {
            r0
        };
        theta.iter().zip(r).map(|(a, b)| a * b).sum()
    };
    let mut out = Vec::with_capacity(range.len());
    for i in range.clone() {
        out.push(w);
        if i + 1 >= range.end {
            break;
        }
        // The midpoint rule: a step is a few hundredths of the rotor's speed time constant
        // J/(2·c2·ω) at most (1–10 ms against 0.3–1 s), where its error, of third order in the
        // step, is far below the velocity's noise; it evaluates three regression rows per step,
        // RK4 seven.
        let dt = s.t[i + 1] - s.t[i];
        let k1 = accel(i, 0.0, w);
        let k2 = accel(i, 0.5, w + 0.5 * dt * k1);
        w += dt * k2;
        if !w.is_finite() {
            w = 0.0;
        }
        w = w.clamp(-bound, bound);
    }
    out
}

/// Root-mean-square difference.
pub(crate) fn rms_error(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len()).max(1) as f64;
    (a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>() / n).sqrt()
}
