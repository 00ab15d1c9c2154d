//! `second_order_lag`: the load feels the reported force through a second-order stage
//! ω_n²/(s² + 2ζω_n s + ω_n²) — a velocity observer or PLL (its reported velocity and
//! acceleration pass such a stage, which in the data is the force felt late), or a current loop
//! that overshoots. The force column is replaced by the force through that stage; the value is
//! its natural frequency f_n [Hz], the damping ζ is tuned beside it.
//!
//! At frequencies well below f_n it is a delay of 2ζ/ω_n, as a first-order `torque_lag` of that
//! length is: one sinusoid cannot tell the two apart, and the selection then names the simpler
//! first-order lag (fewer parameters). A chirp reaching a fifth of f_n shows the difference (a
//! first-order lag also attenuates, a second-order stage with ζ ≈ 0.7 hardly does).

use std::borrow::Cow;

use super::{
    BaseTerm, Candidate, Design, Enters, Estimate, Fitted, Inadmissible, Shape, Slot,
    CHIRP_FOR_A_LAG, RESOLVED,
};
use crate::diagnose::model::{At, Effect, LagShape, Prepared, impulse_gain};
use crate::diagnose::signals::Signals;
use crate::diagnose::tune::{Tuned, Tuner};
use crate::diagnose::SeparatingRun;

/// See the module documentation.
pub(crate) struct SecondOrderLag;

/// Natural frequencies tried first [Hz]: 3–30 Hz. Above, the stage is a delay of a few
/// milliseconds over the band a stand excites (0.5–5 Hz), which a first-order lag already
/// describes as well.
fn frequencies() -> Vec<f64> {
    (0..=4).map(|k| 3.0 * 10f64.powf(k as f64 / 4.0)).collect()
}

/// Dampings tried first.
const DAMPINGS: [f64; 3] = [0.4, 0.65, 0.9];

/// `x` (at times `t`) through a second-order low-pass ω_n²/(s² + 2ζω_n s + ω_n²) of natural
/// frequency `hz` and damping `zeta`, the input linear between samples, integrated with steps
/// of at most a twentieth of the stage's period (RK4), from rest at x[0].
fn second_order(t: &[f64], x: &[f64], hz: f64, zeta: f64) -> Vec<f64> {
    let n = x.len();
    let mut out = Vec::with_capacity(n);
    if n == 0 {
        return out;
    }
    let wn = std::f64::consts::TAU * hz;
    let (mut y, mut v) = (x[0], 0.0);
    out.push(y);
    let h_max = 0.05 / hz;
    for i in 1..n {
        let dt = t[i] - t[i - 1];
        if dt > 0.0 {
            let steps = (dt / h_max).ceil().max(1.0) as usize;
            let h = dt / steps as f64;
            let (x0, slope) = (x[i - 1], (x[i] - x[i - 1]) / dt);
            let f = |tau: f64, y: f64, v: f64| {
                let u = x0 + slope * tau;
                (v, wn * wn * (u - y) - 2.0 * zeta * wn * v)
            };
            for k in 0..steps {
                let tau = k as f64 * h;
                let (a1, b1) = f(tau, y, v);
                let (a2, b2) = f(tau + 0.5 * h, y + 0.5 * h * a1, v + 0.5 * h * b1);
                let (a3, b3) = f(tau + 0.5 * h, y + 0.5 * h * a2, v + 0.5 * h * b2);
                let (a4, b4) = f(tau + h, y + h * a3, v + h * b3);
                y += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
                v += h / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4);
            }
        }
        out.push(y);
    }
    out
}

fn stage(t: &Tuner, hz: f64, zeta: f64) -> Effect {
    Effect {
        aux: zeta,
        ..Effect::new(t.kind, hz)
    }
}

impl Candidate for SecondOrderLag {
    fn name(&self) -> &'static str {
        "second_order_lag"
    }
    fn unit(&self) -> &'static str {
        "Hz"
    }
    fn enters(&self) -> Enters {
        Enters::Equation
    }
    fn slot(&self) -> Slot {
        Slot::Lag
    }
    /// The natural frequency and the damping.
    fn parameters(&self) -> usize {
        2
    }
    fn columns(&self, _: &Effect) -> usize {
        0
    }
    fn prepare(&self, e: &Effect, s: &Signals, p: &mut Prepared) {
        p.force = Cow::Owned(second_order(&s.t, &p.force, e.param, e.aux));
        let span = 1.0 / (std::f64::consts::TAU * e.param * e.aux.max(0.05));
        p.force_noise_gain = impulse_gain(1.0 / s.rate, span, |t, x| {
            second_order(t, x, e.param, e.aux)
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
    fn tune(&self, t: &Tuner) -> Option<Tuned> {
        // A coarse grid over both parameters, then each refined near the best point.
        let grid = frequencies()
            .into_iter()
            .flat_map(|f| DAMPINGS.map(|z| stage(t, f, z)));
        let (best, _) = t.best(grid)?;
        self.retune(&best, t)
    }
    fn retune(&self, e: &Effect, t: &Tuner) -> Option<Tuned> {
        let (f, _) = t.golden_around(e.param / 1.5, e.param * 1.5, |x| Effect { param: x, ..*e });
        Some(t.golden_around((f.aux - 0.15).max(0.2), f.aux + 0.15, |z| Effect { aux: z, ..f }))
    }
    fn estimate(&self, e: &Effect, f: &Fitted) -> Estimate {
        Estimate::new(e.param, (f.profile)())
    }
    fn admissible(&self, _: &Effect, v: Estimate, _: &Fitted) -> Result<(), Inadmissible> {
        let top = frequencies().last().copied().unwrap_or(f64::INFINITY);
        if !v.value.is_finite() {
            Err(Inadmissible::NotFinite)
        } else if v.value <= 0.0 {
            Err(Inadmissible::WrongSign)
        } else if v.value > 0.95 * top {
            Err(Inadmissible::OutOfRange { value: v.value })
        } else if !v.resolved_from(0.0, RESOLVED) {
            Err(Inadmissible::NotResolved {
                value: v.value,
                stderr: v.stderr,
            })
        } else {
            Ok(())
        }
    }
    fn explanation(&self, e: &Effect, value: f64) -> String {
        let delay = 2.0 * e.aux / (std::f64::consts::TAU * value);
        format!(
            "the load feels the reported force through a second-order stage at {value:.1} Hz, damping {:.2} (a delay of {:.1} ms at low frequency): a velocity observer or PLL, or a current loop that overshoots",
            e.aux,
            delay * 1e3
        )
    }
    fn shape(&self) -> Shape {
        Shape::Lag
    }
    fn lag_shape(&self, _: &Effect) -> Option<LagShape> {
        Some(LagShape::SecondOrder)
    }
    fn revealing_run(&self) -> SeparatingRun {
        CHIRP_FOR_A_LAG
    }
    fn simulation_sees(&self) -> bool {
        true
    }
    fn base_term(&self, _: &Effect, _: Estimate) -> BaseTerm {
        BaseTerm::None
    }
    fn design_column(&self, _: &Design) -> Option<Vec<f64>> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::second_order;
    use crate::diagnose::model::impulse_gain;

    #[test]
    fn a_second_order_stage_follows_a_slow_input_late_by_two_zeta_over_omega() {
        let (hz, zeta) = (20.0, 0.7);
        let dt = 1e-3;
        let t: Vec<f64> = (0..4000).map(|i| i as f64 * dt).collect();
        let w = std::f64::consts::TAU * 0.5;
        let x: Vec<f64> = t.iter().map(|t| (w * t).sin()).collect();
        let y = second_order(&t, &x, hz, zeta);
        let delay = 2.0 * zeta / (std::f64::consts::TAU * hz);
        for i in 2000..4000 {
            let late = (w * (t[i] - delay)).sin();
            assert!((y[i] - late).abs() < 2e-3, "{i}: {} vs {late}", y[i]);
        }
    }

    /// White noise through the stage keeps its noise bandwidth: ω_n·dt/(4ζ) of its variance.
    #[test]
    fn the_noise_a_second_order_stage_keeps() {
        let (hz, zeta, dt) = (5.0, 0.7, 1e-3);
        let span = 1.0 / (std::f64::consts::TAU * hz * zeta);
        let g = impulse_gain(dt, span, |t, x| second_order(t, x, hz, zeta));
        let expected = std::f64::consts::TAU * hz * dt / (4.0 * zeta);
        assert!((g / expected - 1.0).abs() < 0.05, "{g} vs {expected}");
    }
}
