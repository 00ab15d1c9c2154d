//! `torque_ripple`: a torque periodic in rotor angle (cogging, a commutation ripple): regressors
//! sin kθ and cos kθ, the harmonic k searched in 1–24. It turns faster than the samples resolve
//! (6–12 periods a turn at 1500 rad/s: tens of radians of ripple phase per sample), so the
//! simulation sees its mean over each step, about nothing: the acceleration evidence decides.

use super::{EffectKind, 
    BaseTerm, Candidate, Design, Enters, Estimate, Fitted, Inadmissible, Shape, Slot, RESOLVED,
};
use crate::diagnose::engine::{fit_on_all, residuals};
use crate::diagnose::model::{At, Effect, Lag, Prepared};
use crate::diagnose::signals::Signals;
use crate::diagnose::structure::harmonic_correlations;
use crate::diagnose::tune::{Tuned, Tuner};
use crate::diagnose::SeparatingRun;
use crate::excitation::Pattern;

/// See the module documentation.
pub(crate) struct TorqueRipple;

/// The amplitude of a sin/cos pair at column `k` and `k + 1`, over θ₀, with its standard error.
pub(crate) fn amplitude(f: &Fitted) -> Estimate {
    let (c, t0) = (f.column, f.theta[0]);
    let (a, b) = (f.theta[c], f.theta[c + 1]);
    let amp = (a * a + b * b).sqrt();
    let se = (f.stderr[c].powi(2) + f.stderr[c + 1].powi(2)).sqrt() / 2f64.sqrt();
    Estimate::new(amp / t0, se / t0.abs())
}

/// An amplitude is admissible when resolved from zero.
pub(crate) fn admissible_amplitude(v: Estimate) -> Result<(), Inadmissible> {
    if !v.value.is_finite() {
        Err(Inadmissible::NotFinite)
    } else if !(v.value > 0.0 && v.resolved_from(0.0, RESOLVED)) {
        Err(Inadmissible::NotResolved {
            value: v.value,
            stderr: v.stderr,
        })
    } else {
        Ok(())
    }
}

impl Candidate for TorqueRipple {
    fn name(&self) -> &'static str {
        "torque_ripple"
    }
    fn unit(&self) -> &'static str {
        "N·m"
    }
    fn enters(&self) -> Enters {
        Enters::Equation
    }
    fn slot(&self) -> Slot {
        Slot::Term
    }
    /// Two columns and the harmonic.
    fn parameters(&self) -> usize {
        3
    }
    fn columns(&self, _: &Effect) -> usize {
        2
    }
    fn prepare(&self, _: &Effect, _: &Signals, _: &mut Prepared) {}
    fn row(&self, e: &Effect, at: &At, out: &mut [f64]) {
        let x = e.param * at.s.position.as_ref().map_or(0.0, |p| p[at.i]);
        let sweep = e.param * at.omega * at.step;
        if sweep.abs() > 1e-6 {
            // The mean over the angle swept in a simulation step.
            out[0] = (x.cos() - (x + sweep).cos()) / sweep;
            out[1] = ((x + sweep).sin() - x.sin()) / sweep;
        } else {
            out[0] = x.sin();
            out[1] = x.cos();
        }
    }
    fn differentiated(&self, _: &Effect) -> bool {
        false
    }
    fn instrument(&self, _: &Effect, _: &Signals, _: usize, _: &mut [f64]) {}
    fn held_in_simulation(&self) -> bool {
        true
    }
    fn refines(&self) -> Option<EffectKind> {
        None
    }
    fn tune(&self, t: &Tuner) -> Option<Tuned> {
        // The harmonics of the rotor angle the current model's residual correlates with most (one
        // pass for all 24), then the held-out error of the best three: adding a sin/cos pair
        // gains about as much as its correlation with the residual.
        let position = t.s.position.as_ref()?;
        let f = fit_on_all(t.model, t.s)?;
        let r = residuals(t.model, &f, t.s);
        let mut by_strength: Vec<(f64, f64)> = harmonic_correlations::<24>(&r, position)
            .iter()
            .enumerate()
            .map(|(k, (cs, cc))| ((k + 1) as f64, cs * cs + cc * cc))
            .collect();
        by_strength.sort_by(|a, b| b.1.total_cmp(&a.1));
        t.best(
            by_strength
                .iter()
                .take(3)
                .map(|&(k, _)| Effect::new(t.kind, k)),
        )
    }
    fn retune(&self, _: &Effect, _: &Tuner) -> Option<Tuned> {
        None
    }
    fn estimate(&self, _: &Effect, f: &Fitted) -> Estimate {
        amplitude(f)
    }
    fn admissible(&self, _: &Effect, v: Estimate, _: &Fitted) -> Result<(), Inadmissible> {
        admissible_amplitude(v)
    }
    fn explanation(&self, e: &Effect, value: f64) -> String {
        format!(
            "a torque ripple of {value:.3e} N·m periodic in rotor angle, {} periods per turn",
            e.param
        )
    }
    fn shape(&self) -> Shape {
        Shape::Periodic
    }
    fn lag(&self, _: &Effect, _: f64) -> Option<Lag> {
        None
    }
    fn revealing_run(&self) -> SeparatingRun {
        SeparatingRun {
            pattern: Pattern::Steps,
            lo: Some(0.02),
            hi: None,
            why: "held low speeds, where a ripple periodic in angle is resolved sample by sample",
        }
    }
    fn simulation_sees(&self) -> bool {
        false
    }
    /// A torque term: tuned by the equation.
    fn tuned_by_simulation(&self) -> bool {
        false
    }
    fn base_term(&self, _: &Effect, _: Estimate) -> BaseTerm {
        BaseTerm::None
    }
    fn design_column(&self, _: &Design) -> Option<Vec<f64>> {
        None
    }
}
