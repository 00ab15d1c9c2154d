//! One more column in the torque balance: a coefficient times a function of the state. Coulomb
//! friction (−sgn ω), a force offset (−1) and viscous friction (−ω) have this shape and differ
//! only in their column, unit, sign rule, design column and meaning, so each of their files
//! declares one [`TorqueTerm`] and this file implements [`Candidate`] for all three.

use super::{
    admissible_torque, BaseTerm, Candidate, Design, EffectKind, Enters, Estimate, Fitted,
    Inadmissible, Shape, Slot, LOW_SPEED_STEPS,
};
use crate::diagnose::model::{At, Effect, Lag, Prepared};
use crate::diagnose::signals::Signals;
use crate::diagnose::tune::{Tuned, Tuner};
use crate::diagnose::SeparatingRun;

/// A torque term linear in its one parameter.
pub(crate) struct TorqueTerm {
    /// Its name in reports.
    pub name: &'static str,
    /// The unit of its value.
    pub unit: &'static str,
    /// Its regression column at a sample.
    pub column: fn(&At) -> f64,
    /// Its column on a designed pattern, from the speed (for `propid plan`).
    pub design: fn(f64) -> f64,
    /// Only a positive value is physical (a friction; an offset may have either sign).
    pub positive: bool,
    /// What it looks like, for the run that separates it.
    pub shape: Shape,
    /// What it changes in the seed's parameters.
    pub base_term: fn(Estimate) -> BaseTerm,
    /// What a value means, in a sentence.
    pub explanation: fn(f64) -> String,
}

impl Candidate for TorqueTerm {
    fn name(&self) -> &'static str {
        self.name
    }
    fn unit(&self) -> &'static str {
        self.unit
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
        1
    }
    fn prepare(&self, _: &Effect, _: &Signals, _: &mut Prepared) {}
    fn row(&self, _: &Effect, at: &At, out: &mut [f64]) {
        out[0] = (self.column)(at);
    }
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
        t.linear()
    }
    fn retune(&self, _: &Effect, _: &Tuner) -> Option<Tuned> {
        None
    }
    fn estimate(&self, _: &Effect, f: &Fitted) -> Estimate {
        f.torque(0)
    }
    fn admissible(&self, _: &Effect, v: Estimate, _: &Fitted) -> Result<(), Inadmissible> {
        admissible_torque(v, self.positive)
    }
    fn explanation(&self, _: &Effect, value: f64) -> String {
        (self.explanation)(value)
    }
    fn shape(&self) -> Shape {
        self.shape
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
    fn base_term(&self, _: &Effect, v: Estimate) -> BaseTerm {
        (self.base_term)(v)
    }
    fn design_column(&self, d: &Design) -> Option<Vec<f64>> {
        Some(d.speed.iter().map(|w| (self.design)(*w)).collect())
    }
}
