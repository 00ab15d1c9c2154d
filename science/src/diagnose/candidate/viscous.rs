//! `viscous_friction`: a torque ∝ ω opposing rotation (the seed's c1, which its defaults force to
//! zero). Regressor −ω.

use super::{EffectKind, 
    admissible_torque, BaseTerm, Candidate, Design, Enters, Estimate, Fitted, Inadmissible, Shape,
    Slot, LOW_SPEED_STEPS,
};
use crate::diagnose::model::{At, Effect, Lag, Prepared};
use crate::diagnose::signals::Signals;
use crate::diagnose::tune::{Tuned, Tuner};
use crate::diagnose::SeparatingRun;

/// See the module documentation.
pub(crate) struct ViscousFriction;

impl Candidate for ViscousFriction {
    fn name(&self) -> &'static str {
        "viscous_friction"
    }
    fn unit(&self) -> &'static str {
        "N·m·s/rad"
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
        out[0] = -at.omega;
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
        admissible_torque(v, true)
    }
    fn explanation(&self, _: &Effect, value: f64) -> String {
        format!("a torque of {value:.3e} N·m per rad/s opposes rotation (viscous friction; the seed's c1, which its defaults force to zero)")
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
    fn base_term(&self, _: &Effect, v: Estimate) -> BaseTerm {
        BaseTerm::C1(v)
    }
    fn design_column(&self, d: &Design) -> Option<Vec<f64>> {
        Some(d.speed.to_vec())
    }
}
