//! `braking_torque`: while the rotor slows, a torque brakes it that the reported force does not
//! show (active or regenerative braking the current sense misses). Regressor −sgn ω where braking
//! acts.
//!
//! A drive brakes on its own deceleration estimate past a threshold `on` [rad/s²], with
//! hysteresis (a braking torque steps the deceleration up by B/J as it engages, so a single
//! threshold would chatter), until the rotor no longer slows: releasing the brake steps the
//! acceleration back by B/J, through zero, whatever the drive's own release threshold below
//! that, so the release is sharp in the data. That state is followed on the reported
//! accelerations, and sample i takes the mean of its neighbours' states: its own acceleration,
//! the equation's left-hand side, does not choose it (its noise would select the samples it is
//! compared on). Beside a switch the neighbours disagree; there the sample's own acceleration
//! decides only where it lies three noise σ beyond the level the switch crosses, and the sample
//! gets ½ otherwise. Where the reported acceleration is too noisy for any threshold (ESC32
//! telemetry: σ ≈ 380 rad/s²), braking acts while the measured velocity's ±20 ms slope opposes
//! it ([`SLOPE_BRAKING`]), or in those spells with each start and end moved to where the velocity
//! kinks ([`KINK_BRAKING`]: the slope turns with the braking's own step before the step is
//! reached, 12 ms early on a 0.5 Hz sine at 500 Hz). The threshold is a choice between
//! indicators, tuned on a grid.

use super::{EffectKind, 
    admissible_torque, BaseTerm, Candidate, Design, Enters, Estimate, Fitted, Inadmissible, Shape,
    Slot,
};
use crate::diagnose::model::{At, Effect, Lag, Prepared};
use crate::diagnose::signals::Signals;
use crate::diagnose::tune::{Tuned, Tuner};
use crate::diagnose::SeparatingRun;
use crate::excitation::Pattern;

/// See the module documentation.
pub(crate) struct BrakingTorque;

/// The parameter for "while the velocity's ±20 ms slope falls" (any other value is a
/// deceleration threshold ≥ 0).
const SLOPE_BRAKING: f64 = -1.0;

/// The parameter for "while the velocity's ±20 ms slope falls", each spell's start and end moved
/// to where the velocity kinks (`Signals::decelerating_at_kinks`).
const KINK_BRAKING: f64 = -2.0;

/// How much of a braking torque acts at each sample: 1, 0, or ½ next to a switch.
fn braking_samples(s: &Signals, on: f64) -> Vec<f64> {
    if on == SLOPE_BRAKING || on == KINK_BRAKING {
        let spells = if on == SLOPE_BRAKING {
            &s.decelerating
        } else {
            &s.decelerating_at_kinks
        };
        return spells
            .iter()
            .map(|&d| if d { 1.0 } else { 0.0 })
            .collect();
    }
    let mut active = false;
    let state: Vec<bool> = (0..s.len())
        .map(|i| {
            let slowing = s.slowing(i);
            active = if active { slowing > 0.0 } else { slowing > on };
            active
        })
        .collect();
    let n = state.len();
    let margin = 3.0 * s.acceleration_noise;
    (0..n)
        .map(|i| {
            let (before, after) = (state[i.saturating_sub(1)], state[(i + 1).min(n - 1)]);
            if before == after {
                return if before { 1.0 } else { 0.0 };
            }
            // A switch beside sample i: the level it crosses (the threshold when the brake
            // engages, zero when it releases) decides, where the sample's own acceleration is
            // three noise σ beyond it.
            let level = if after { on } else { 0.0 };
            let slowing = s.slowing(i);
            if slowing > level + margin {
                1.0
            } else if slowing < level - margin {
                0.0
            } else {
                0.5
            }
        })
        .collect()
}

impl Candidate for BrakingTorque {
    fn name(&self) -> &'static str {
        "braking_torque"
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
    /// The torque and the indicator of when it acts.
    fn parameters(&self) -> usize {
        2
    }
    fn columns(&self, _: &Effect) -> usize {
        1
    }
    fn prepare(&self, e: &Effect, s: &Signals, p: &mut Prepared) {
        p.braking = braking_samples(s, e.param);
    }
    fn row(&self, _: &Effect, at: &At, out: &mut [f64]) {
        out[0] = -at.sgn * at.p.braking[at.i];
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
        // Thresholds from twice the reported acceleration's noise up to 200 rad/s² (a drive acts
        // on its own, filtered estimate, with a threshold against its noise): below 2σ the state
        // would flicker with the noise wherever the speed is steady.
        let floor = 2.0 * t.s.acceleration_noise;
        let grid = [SLOPE_BRAKING, KINK_BRAKING].into_iter().chain(
            (0..=8)
                .map(|k| floor + 25.0 * k as f64)
                .filter(|&x| x <= 200.0),
        );
        t.best(grid.map(|x| Effect::new(t.kind, x)))
    }
    /// The indicator is a choice made when it entered.
    fn retune(&self, _: &Effect, _: &Tuner) -> Option<Tuned> {
        None
    }
    fn estimate(&self, _: &Effect, f: &Fitted) -> Estimate {
        f.torque(0)
    }
    fn admissible(&self, e: &Effect, v: Estimate, f: &Fitted) -> Result<(), Inadmissible> {
        admissible_torque(v, true)?;
        // With a threshold on the reported acceleration the braking must step it by more than
        // the residual noise: below it the samples it acts on are chosen by noise (a filtered
        // acceleration's noise is correlated from sample to sample, and a 0.04 mN·m "braking"
        // gained 3 % on held-out data).
        let step = v.value * f.theta[0];
        if e.param >= 0.0 && step < f.rms {
            return Err(Inadmissible::BelowNoise {
                step,
                noise: f.rms,
            });
        }
        Ok(())
    }
    fn explanation(&self, _: &Effect, value: f64) -> String {
        format!("while the rotor slows, a torque of {value:.3e} N·m brakes it that the reported force does not show (active or regenerative braking the current sense misses)")
    }
    fn shape(&self) -> Shape {
        Shape::Slowing
    }
    fn lag(&self, _: &Effect, _: f64) -> Option<Lag> {
        None
    }
    fn revealing_run(&self) -> SeparatingRun {
        SeparatingRun {
            pattern: Pattern::Steps,
            lo: None,
            hi: None,
            why: "held speeds, then sudden slowing, where only braking acts",
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
    /// A braking torque acting whenever the rotor slows: on a pattern that slows half the time
    /// and never rests, half a Coulomb friction plus a term in sgn(a).
    fn design_column(&self, d: &Design) -> Option<Vec<f64>> {
        Some(
            d.speed
                .iter()
                .zip(d.acceleration)
                .map(|(v, a)| if a * v < 0.0 { v.signum() } else { 0.0 })
                .collect(),
        )
    }
}
