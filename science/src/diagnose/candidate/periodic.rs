//! `periodic_disturbance`: a torque periodic in time, sin and cos of 2π·f·t at the residual's
//! spectral peak. Never named: it is the probe for structure no candidate explains (a vibrating
//! fixture, a wake), reported as unexplained with its frequency when it passes the selection's
//! test.

use super::ripple::{admissible_amplitude, amplitude};
use super::{EffectKind, BaseTerm, Candidate, Design, Enters, Estimate, Fitted, Inadmissible, Shape, Slot};
use crate::diagnose::model::{At, Effect, Lag, Prepared};
use crate::diagnose::signals::Signals;
use crate::diagnose::tune::{Tuned, Tuner};
use crate::diagnose::SeparatingRun;
use crate::excitation::Pattern;

/// See the module documentation.
pub(crate) struct PeriodicDisturbance;

impl Candidate for PeriodicDisturbance {
    fn name(&self) -> &'static str {
        "periodic_disturbance"
    }
    fn unit(&self) -> &'static str {
        "N·m"
    }
    fn enters(&self) -> Enters {
        Enters::Probe
    }
    fn slot(&self) -> Slot {
        Slot::Term
    }
    fn parameters(&self) -> usize {
        3
    }
    fn columns(&self, _: &Effect) -> usize {
        2
    }
    fn prepare(&self, _: &Effect, _: &Signals, _: &mut Prepared) {}
    fn row(&self, e: &Effect, at: &At, out: &mut [f64]) {
        let x = std::f64::consts::TAU * e.param * at.s.t[at.i];
        out[0] = x.sin();
        out[1] = x.cos();
    }
    fn differentiated(&self, _: &Effect) -> bool {
        false
    }
    fn instrument(&self, _: &Effect, _: &Signals, _: usize, _: &mut [f64]) {}
    fn held_in_simulation(&self) -> bool {
        false
    }
    /// Its frequency comes from the residual's spectrum, not from a search.
    fn refines(&self) -> Option<EffectKind> {
        None
    }
    fn tune(&self, _: &Tuner) -> Option<Tuned> {
        None
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
            "a torque of {value:.3e} N·m periodic in time at {:.3} Hz",
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
            lo: None,
            hi: None,
            why: "held speeds, where a torque periodic in time stands apart from anything tied to speed or force",
        }
    }
    fn simulation_sees(&self) -> bool {
        true
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
