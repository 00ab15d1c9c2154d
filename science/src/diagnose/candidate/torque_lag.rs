//! `torque_lag`: the torque the load feels lags the reported force (a current loop, a torque
//! ramp). The force column is replaced by the force through a first-order lag L (discretised with
//! a first-order hold: the torque linear between samples, exact for a continuous one), L searched
//! in 0.2–100 ms.
//!
//! Where the force steps: where in the interval before the sample that shows a step did it
//! happen? Anywhere (commands asynchronous to the reports: the first-order hold is right on
//! average), or at that sample (a drive that changes its demand in step with its reports: the
//! hold then places every step half a sample early, and every lag read from steps came out half a
//! sample long). The held-out error chooses, each way tuned alone.

use std::borrow::Cow;

use super::{EffectKind, 
    admissible_lag, lag_grid, BaseTerm, Candidate, Design, Enters, Estimate, Fitted, Inadmissible,
    Shape, Slot, CHIRP_FOR_A_LAG,
};
use crate::diagnose::model::{At, Effect, LagForm, Lag, Prepared, impulse_gain};
use crate::diagnose::signals::{first_order_lag, Signals};
use crate::diagnose::tune::{objective_of, Tuned, Tuner};
use crate::diagnose::SeparatingRun;

/// See the module documentation.
pub(crate) struct TorqueLag;

impl Candidate for TorqueLag {
    fn name(&self) -> &'static str {
        "torque_lag"
    }
    fn unit(&self) -> &'static str {
        "s"
    }
    fn enters(&self) -> Enters {
        Enters::Equation
    }
    fn slot(&self) -> Slot {
        Slot::Lag
    }
    fn parameters(&self) -> usize {
        1
    }
    fn columns(&self, _: &Effect) -> usize {
        0
    }
    fn prepare(&self, e: &Effect, s: &Signals, p: &mut Prepared) {
        p.force = Cow::Owned(s.lagged(&p.force, e.param, e.form.steps_at_samples()));
        p.force_noise_gain = impulse_gain(1.0 / s.rate, e.param, |t, x| {
            first_order_lag(t, x, e.param, |_| false)
        });
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
        let in_form = |form: LagForm| {
            t.grid_then_golden(&lag_grid(), |x| Effect::with_form(t.kind, x, form))
        };
        if !t.s.has_force_steps() {
            return in_form(LagForm::FirstOrder);
        }
        match (
            in_form(LagForm::FirstOrder),
            in_form(LagForm::FirstOrderStepsAtSamples),
        ) {
            (Some(a), Some(b)) => Some(if objective_of(&b.1) < objective_of(&a.1) { b } else { a }),
            (a, b) => a.or(b),
        }
    }
    fn retune(&self, e: &Effect, t: &Tuner) -> Option<Tuned> {
        Some(t.golden_around(e.param / 1.6, e.param * 1.6, |x| Effect { param: x, ..*e }))
    }
    fn estimate(&self, e: &Effect, f: &Fitted) -> Estimate {
        Estimate::new(e.param, (f.profile)())
    }
    fn admissible(&self, _: &Effect, v: Estimate, _: &Fitted) -> Result<(), Inadmissible> {
        admissible_lag(v)
    }
    fn explanation(&self, _: &Effect, value: f64) -> String {
        format!(
            "the torque the load feels lags the reported force by {:.1} ms (e.g. the current loop)",
            value * 1e3
        )
    }
    fn shape(&self) -> Shape {
        Shape::Lag
    }
    fn lag(&self, e: &Effect, value: f64) -> Option<Lag> {
        Some(Lag {
            shape: e.form.shape(),
            delay: value,
        })
    }
    fn revealing_run(&self) -> SeparatingRun {
        CHIRP_FOR_A_LAG
    }
    fn simulation_sees(&self) -> bool {
        true
    }
    /// A lag of what drives the rotor: the simulation sees its phase.
    fn tuned_by_simulation(&self) -> bool {
        true
    }
    fn base_term(&self, _: &Effect, _: Estimate) -> BaseTerm {
        BaseTerm::None
    }
    /// felt = F − L·Ḟ to first order.
    fn design_column(&self, d: &Design) -> Option<Vec<f64>> {
        Some(d.force_rate.to_vec())
    }
}
