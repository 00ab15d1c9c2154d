//! Tuning an effect's nonlinear parameter by the held-out error itself: a grid, then a
//! golden-section refinement between the best point's neighbours. Each candidate chooses its
//! grid and forms; this is the toolbox it uses.
//!
//! What is minimised: for a term (a friction, an exponent, …) the held-out acceleration-equation
//! error. For a lag (every effect in [`Slot::Lag`]) the selection's own score, the equation's
//! and the held-out simulated velocity's errors together ([`Cv::objective`]): a lag moves the
//! phase of the torque, which the equation sees only against the acceleration's noise (on the
//! independent stand a 15 ms torque lag beside a constant torque lowers the equation's held-out
//! error by 0.02 % and the simulation's by 16 %, and the equation alone tuned it to 0.4 ms),
//! while the simulation integrates the torque over seconds, where the noise averages out and the
//! phase does not.

use super::candidate::{EffectKind, Estimate};
use super::engine::{cross_validate, fit_on_all, Cv, Fit};
use super::model::{Effect, Model};
use super::signals::Signals;
use super::simulate::{tuning_scores, SimPlan};

/// An effect's parameters as tuned, with the cross-validation of the model that adds it where
/// the tuning already ran it.
pub(crate) type Tuned = (Effect, Option<Cv>);

/// What a candidate's tuning works on: the model it is added to.
pub(crate) struct Tuner<'a> {
    /// The model the effect is added to.
    pub model: &'a Model,
    /// The signals.
    pub s: &'a Signals,
    /// The effect being tuned.
    pub kind: EffectKind,
    /// The held-out scores of `model`.
    pub parent: &'a Cv,
    /// The effect a refining candidate starts from (see `Candidate::refines`), as tuned on the
    /// same model.
    pub seed: Option<Effect>,
    /// The stretches simulated when a lag is tuned.
    pub plan: &'a SimPlan,
}

/// What a tuning minimises ([`Cv::objective`]) for a cross-validation that may have failed.
pub(crate) fn objective_of(cv: &Option<Cv>) -> f64 {
    cv.as_ref().map_or(f64::INFINITY, Cv::objective)
}

impl Tuner<'_> {
    /// The held-out scores of the model with `e` (the simulation's too for a lag: see the
    /// module documentation).
    pub fn cv(&self, e: Effect) -> Option<Cv> {
        let m = self.model.with(e)?;
        if self.kind.candidate().tuned_by_simulation() {
            tuning_scores(&m, self.s, self.plan)
        } else {
            cross_validate(&m, self.s)
        }
    }

    /// An effect without a nonlinear parameter: nothing to tune.
    pub fn linear(&self) -> Option<Tuned> {
        Some((Effect::new(self.kind, 0.0), None))
    }

    /// The best of `effects` by held-out error (tried on all cores: a refining candidate's grid
    /// runs after the candidate it refines, often while nothing else does).
    pub fn best(&self, effects: impl IntoIterator<Item = Effect>) -> Option<Tuned> {
        let effects: Vec<Effect> = effects.into_iter().collect();
        super::search::in_parallel(&effects, |&e| (e, self.cv(e)))
            .into_iter()
            .min_by(|a, b| objective_of(&a.1).total_cmp(&objective_of(&b.1)))
    }

    /// The parameter on `grid` (increasing), then refined between the best point's neighbours
    /// by golden section; `make` builds the effect at a parameter.
    pub fn grid_then_golden(&self, grid: &[f64], make: impl Fn(f64) -> Effect) -> Option<Tuned> {
        let score = |x: f64| objective_of(&self.cv(make(x)));
        let scores: Vec<f64> = grid.iter().map(|&x| score(x)).collect();
        let k = (0..grid.len()).min_by(|a, b| scores[*a].total_cmp(&scores[*b]))?;
        let lo = grid[k.saturating_sub(1)];
        let hi = grid[(k + 1).min(grid.len() - 1)];
        let x = golden(lo, hi, score, 15);
        let e = make(x);
        Some((e, self.cv(e)))
    }

    /// The parameter refined by golden section on [lo, hi] (a re-tuning near a known value).
    pub fn golden_around(&self, lo: f64, hi: f64, make: impl Fn(f64) -> Effect) -> Tuned {
        let x = golden(lo, hi, |x| objective_of(&self.cv(make(x))), 10);
        let e = make(x);
        (e, self.cv(e))
    }

    /// The model with `e` fitted on all samples, and `e`'s estimate from it.
    pub fn estimate(&self, e: Effect) -> Option<(Model, Fit, Estimate)> {
        let m = self.model.with(e)?;
        let f = fit_on_all(&m, self.s)?;
        let v = super::search::estimate_of(&m, m.effects.len() - 1, &f, self.s);
        Some((m, f, v))
    }
}

/// Golden-section minimisation of `f` on [lo, hi].
pub(crate) fn golden(mut lo: f64, mut hi: f64, f: impl Fn(f64) -> f64, iterations: usize) -> f64 {
    let g = 0.618_033_988_75;
    let (mut x1, mut x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..iterations {
        if f1 < f2 {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - g * (hi - lo);
            f1 = f(x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + g * (hi - lo);
            f2 = f(x2);
        }
    }
    if f1 < f2 {
        x1
    } else {
        x2
    }
}
