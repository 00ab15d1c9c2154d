//! `force_offset`: the reported force reads F₀ when no torque acts (a current-sense or load-cell
//! zero). Regressor −1: on a rotor that never reverses, the same column as a Coulomb friction.

use super::{EffectKind, 
    admissible_torque, BaseTerm, Candidate, Design, Enters, Estimate, Fitted, Inadmissible, Shape,
    Slot, LOW_SPEED_STEPS,
};
use crate::diagnose::model::{At, Effect, Lag, Prepared};
use crate::diagnose::signals::Signals;
use crate::diagnose::tune::{Tuned, Tuner};
use crate::diagnose::SeparatingRun;

/// See the module documentation.
pub(crate) struct ForceOffset;

impl Candidate for ForceOffset {
    fn name(&self) -> &'static str {
        "force_offset"
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
    fn parameters(&self) -> usize {
        1
    }
    fn columns(&self, _: &Effect) -> usize {
        1
    }
    fn prepare(&self, _: &Effect, _: &Signals, _: &mut Prepared) {}
    fn row(&self, _: &Effect, _: &At, out: &mut [f64]) {
        out[0] = -1.0;
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
        admissible_torque(v, false)
    }
    fn explanation(&self, _: &Effect, value: f64) -> String {
        format!("the reported force reads {value:+.3e} N·m when no torque acts (a current-sense or load-cell zero offset)")
    }
    fn shape(&self) -> Shape {
        Shape::Constant { odd: false }
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
    fn base_term(&self, _: &Effect, _: Estimate) -> BaseTerm {
        BaseTerm::None
    }
    fn design_column(&self, d: &Design) -> Option<Vec<f64>> {
        Some(vec![1.0; d.speed.len()])
    }
}
