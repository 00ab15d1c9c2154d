//! `drag_exponent`: the drag torque grows as |ω|^p, not ω² (a torque coefficient that depends on
//! speed: Reynolds number, blade flex). The drag column becomes −|ω|^p·sgn ω, p searched in
//! 1.2–3.2; the seed's c2 is then the k of k·|ω|^p.

use super::{EffectKind, 
    BaseTerm, Candidate, Design, Enters, Estimate, Fitted, Inadmissible, Shape, Slot,
    LOW_SPEED_STEPS, RESOLVED,
};
use crate::diagnose::model::{At, Effect, Lag, Prepared};
use crate::diagnose::signals::Signals;
use crate::diagnose::tune::{Tuned, Tuner};
use crate::diagnose::SeparatingRun;

/// See the module documentation.
pub(crate) struct DragExponent;

/// Exponents within this of 2 are the seed's law.
pub(crate) const SEED_LAW_WITHIN: f64 = 0.02;

/// The exponents tried first.
pub(crate) fn grid() -> Vec<f64> {
    (0..=10).map(|k| 1.2 + 0.2 * k as f64).collect()
}

/// An exponent is the seed's law unless it lies beyond [`SEED_LAW_WITHIN`] of 2 and
/// [`RESOLVED`] standard errors from it.
pub(crate) fn admissible_exponent(v: Estimate) -> Result<(), Inadmissible> {
    if !v.value.is_finite() {
        Err(Inadmissible::NotFinite)
    } else if (v.value - 2.0).abs() <= SEED_LAW_WITHIN || !v.resolved_from(2.0, RESOLVED) {
        Err(Inadmissible::NotResolved {
            value: v.value,
            stderr: v.stderr,
        })
    } else {
        Ok(())
    }
}

impl Candidate for DragExponent {
    fn name(&self) -> &'static str {
        "drag_exponent"
    }
    fn unit(&self) -> &'static str {
        "1"
    }
    fn enters(&self) -> Enters {
        Enters::Equation
    }
    fn slot(&self) -> Slot {
        Slot::Term
    }
    fn parameters(&self) -> usize {
        1
    }
    fn columns(&self, _: &Effect) -> usize {
        0
    }
    fn prepare(&self, e: &Effect, _: &Signals, p: &mut Prepared) {
        p.exponent = e.param;
    }
    fn row(&self, _: &Effect, _: &At, _: &mut [f64]) {}
    fn differentiated(&self, _: &Effect) -> bool {
        false
    }
    fn instrument(&self, _: &Effect, _: &Signals, _: usize, _: &mut [f64]) {}
    fn held_in_simulation(&self) -> bool {
        false
    }
    fn refines(&self) -> Option<EffectKind> {
        None
    }
    fn tune(&self, t: &Tuner) -> Option<Tuned> {
        t.grid_then_golden(&grid(), |p| Effect::new(t.kind, p))
    }
    fn retune(&self, e: &Effect, t: &Tuner) -> Option<Tuned> {
        Some(t.golden_around(e.param - 0.15, e.param + 0.15, |p| Effect { param: p, ..*e }))
    }
    fn estimate(&self, e: &Effect, f: &Fitted) -> Estimate {
        Estimate::new(e.param, (f.profile)())
    }
    fn admissible(&self, _: &Effect, v: Estimate, _: &Fitted) -> Result<(), Inadmissible> {
        admissible_exponent(v)
    }
    fn explanation(&self, _: &Effect, value: f64) -> String {
        format!("the drag torque grows as |ω|^{value:.3}, not ω²: the torque coefficient depends on speed (Reynolds number, blade flex)")
    }
    fn shape(&self) -> Shape {
        Shape::SpeedLaw
    }
    fn lag(&self, _: &Effect, _: f64) -> Option<Lag> {
        None
    }
    fn revealing_run(&self) -> SeparatingRun {
        LOW_SPEED_STEPS
    }
    fn simulation_sees(&self) -> bool {
        true
    }
    /// A torque term: tuned by the equation.
    fn tuned_by_simulation(&self) -> bool {
        false
    }
    fn base_term(&self, e: &Effect, _: Estimate) -> BaseTerm {
        BaseTerm::Exponent(e.param)
    }
    /// d(|ω|^p·sgn ω)/dp at p = 2: ω|ω|·ln|ω|.
    fn design_column(&self, d: &Design) -> Option<Vec<f64>> {
        Some(
            d.speed
                .iter()
                .map(|w| if *w == 0.0 { 0.0 } else { w * w.abs() * w.abs().ln() })
                .collect(),
        )
    }
}
