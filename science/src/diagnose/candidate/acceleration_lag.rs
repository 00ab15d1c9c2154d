//! `acceleration_lag`: the reported acceleration lags the true one (the drive's estimator
//! filter). Inverting a first-order lag, true = a + L·ȧ: the regressor −ȧ (a ±10 ms slope,
//! estimated with its instrument), whose coefficient is L. A sensor's lag, not the load's: the
//! simulation leaves it out.
//!
//! Where the force steps, the slope of the acceleration breaks at every step: the lag is then
//! also passed through the model's side (every regressor through it, no slope), tuned like a
//! torque lag with the steps placed both ways, and the held-out error chooses (a 23 ms
//! acceleration filter on the staircase read as a torque lag that left J 6 % low otherwise).

use super::{EffectKind, 
    admissible_lag, lag_grid, BaseTerm, Candidate, Design, Enters, Estimate, Fitted, Inadmissible,
    Shape, Slot, CHIRP_FOR_A_LAG,
};
use crate::diagnose::model::{At, Effect, LagForm, Lag, Prepared, impulse_gain};
use crate::diagnose::signals::{first_order_lag, Signals};
use crate::diagnose::tune::{objective_of, Tuned, Tuner};
use crate::diagnose::SeparatingRun;

/// See the module documentation.
pub(crate) struct AccelerationLag;

impl Candidate for AccelerationLag {
    fn name(&self) -> &'static str {
        "acceleration_lag"
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
    fn columns(&self, e: &Effect) -> usize {
        usize::from(!e.form.on_model_side())
    }
    fn prepare(&self, e: &Effect, s: &Signals, p: &mut Prepared) {
        if e.form.on_model_side() {
            p.model_side_lag = Some((e.param, e.form.steps_at_samples()));
            p.force_noise_gain = impulse_gain(1.0 / s.rate, e.param, |t, x| {
                first_order_lag(t, x, e.param, |_| false)
            });
        }
    }
    fn row(&self, _: &Effect, at: &At, out: &mut [f64]) {
        if let Some(x) = out.first_mut() {
            *x = if at.dynamics_only {
                0.0
            } else {
                -at.s.jerk[at.i]
            };
        }
    }
    fn differentiated(&self, e: &Effect) -> bool {
        !e.form.on_model_side()
    }
    fn instrument(&self, _: &Effect, s: &Signals, i: usize, out: &mut [f64]) {
        out[0] = -s.jerk_instrument(i);
    }
    fn held_in_simulation(&self) -> bool {
        false
    }
    fn refines(&self) -> Option<EffectKind> {
        None
    }
    fn tune(&self, t: &Tuner) -> Option<Tuned> {
        let slope = Effect::new(t.kind, 0.0);
        if !t.s.has_force_steps() {
            return Some((slope, None));
        }
        let slope_cv = t.cv(slope);
        let best = [
            LagForm::FirstOrderOnModelSide,
            LagForm::FirstOrderOnModelSideStepsAtSamples,
        ]
        .into_iter()
        .filter_map(|form| t.grid_then_golden(&lag_grid(), |x| Effect::with_form(t.kind, x, form)))
        .min_by(|a, b| objective_of(&a.1).total_cmp(&objective_of(&b.1)));
        Some(match best {
            Some(b) if objective_of(&b.1) < objective_of(&slope_cv) => b,
            _ => (slope, slope_cv),
        })
    }
    fn retune(&self, e: &Effect, t: &Tuner) -> Option<Tuned> {
        e.form
            .on_model_side()
            .then(|| t.golden_around(e.param / 1.6, e.param * 1.6, |x| Effect { param: x, ..*e }))
    }
    fn estimate(&self, e: &Effect, f: &Fitted) -> Estimate {
        if e.form.on_model_side() {
            Estimate::new(e.param, (f.profile)())
        } else {
            Estimate::new(f.theta[f.column], f.stderr[f.column])
        }
    }
    fn admissible(&self, _: &Effect, v: Estimate, _: &Fitted) -> Result<(), Inadmissible> {
        admissible_lag(v)
    }
    fn explanation(&self, _: &Effect, value: f64) -> String {
        format!(
            "the reported acceleration lags the true one by {:.1} ms (the drive's estimator filter)",
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
    fn tuned_by_simulation(&self) -> bool {
        false
    }
    fn base_term(&self, _: &Effect, _: Estimate) -> BaseTerm {
        BaseTerm::None
    }
    fn design_column(&self, d: &Design) -> Option<Vec<f64>> {
        Some(d.jerk.to_vec())
    }
}
