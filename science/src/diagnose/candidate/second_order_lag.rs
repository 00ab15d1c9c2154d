//! `second_order_lag`: the load feels the reported force through a second-order stage
//! ω_n²/(s² + 2ζω_n s + ω_n²) — a velocity observer or PLL (its reported velocity and
//! acceleration pass such a stage, which in the data is the force felt late), or a current loop
//! that overshoots. The force column is replaced by the force through that stage; the value is
//! its natural frequency f_n [Hz], the damping ζ is tuned beside it.
//!
//! At frequencies well below f_n it is a delay of 2ζ/ω_n, as a first-order `torque_lag` of that
//! length is: one sinusoid cannot tell the two apart, and the selection then names the simpler
//! first-order lag (fewer parameters). It refines that lag: tried where the lag passes, its
//! delay started at the lag's length. A chirp reaching a fifth of f_n shows the difference (a
//! first-order lag also attenuates, a second-order stage with ζ ≈ 0.7 hardly does).

use std::borrow::Cow;

use super::{EffectKind, 
    lag_grid, BaseTerm, Candidate, Design, Enters, Estimate, Fitted, Inadmissible, Shape, Slot,
    CHIRP_FOR_A_LAG, RESOLVED,
};
use crate::diagnose::model::{At, Effect, Lag, LagShape, Prepared, impulse_gain};
use crate::diagnose::signals::Signals;
use crate::diagnose::tune::{Tuned, Tuner};
use crate::diagnose::SeparatingRun;

/// See the module documentation.
pub(crate) struct SecondOrderLag;

/// The lightest damping searched: a stage tuned to it is on the search's bound (a resonance the
/// data do not place, fitting an amplitude error at the excitation's frequency instead).
const LIGHTEST: f64 = 0.2;

/// Highest natural frequency taken for a second-order stage [Hz]: above, the stage is a delay
/// of a few milliseconds over the band a stand excites (0.5–5 Hz), which a first-order lag
/// describes as well.
const TOP: f64 = 60.0;

/// `x` (at times `t`) through a second-order low-pass ω_n²/(s² + 2ζω_n s + ω_n²) of natural
/// frequency `hz` and damping `zeta`, from rest at x[0], the input linear between samples.
///
/// Each interval is solved exactly: the state (y, ẏ) moves by the transition matrix e^{A·dt}
/// and the input's slope by its own response, computed once for the first interval and, for an
/// interval that differs from it by a small part of the stage's period (a log's timestamps
/// jitter far less), by the series of the difference: a few dozen multiplications per sample.
fn second_order(t: &[f64], x: &[f64], hz: f64, zeta: f64) -> Vec<f64> {
    let n = x.len();
    let mut out = Vec::with_capacity(n);
    if n == 0 {
        return out;
    }
    let wn = std::f64::consts::TAU * hz;
    let (mut y, mut v) = (x[0], 0.0);
    out.push(y);
    let a = [[0.0, 1.0], [-wn * wn, -2.0 * zeta * wn]];
    let mut base: Option<Step> = None;
    for i in 1..n {
        let dt = t[i] - t[i - 1];
        if dt > 0.0 {
            let step = match base {
                // Near the first interval: its step times that of the difference, by series.
                Some(b) if ((dt - b.dt) * wn).abs() < 0.1 => b.shifted(a, dt - b.dt),
                Some(_) => Step::new(wn, zeta, dt),
                None => {
                    let b = Step::new(wn, zeta, dt);
                    base = Some(b);
                    b
                }
            };
            // Deviation from the input's line: e = y − u, with u = x0 + slope·τ, and
            // ë = −ω²e − 2ζωė − 2ζω·slope.
            let slope = (x[i] - x[i - 1]) / dt;
            let (e, ev) = (y - x[i - 1], v - slope);
            let force = -2.0 * zeta * wn * slope;
            let e1 = step.phi[0][0] * e + step.phi[0][1] * ev + step.gamma[0] * force;
            let ev1 = step.phi[1][0] * e + step.phi[1][1] * ev + step.gamma[1] * force;
            y = x[i] + e1;
            v = ev1 + slope;
        }
        out.push(y);
    }
    out
}

/// The exact step of ë = −ω²e − 2ζωė + f (f constant over the step): e(dt) = Φ·(e, ė) + Γ·f.
#[derive(Clone, Copy, Debug, Default)]
struct Step {
    dt: f64,
    phi: [[f64; 2]; 2],
    gamma: [f64; 2],
}

impl Step {
    /// The step over dt + δ: Φ(dt + δ) = Φ(dt)·Φ(δ), Γ(dt + δ) = Γ(dt) + Φ(dt)·Γ(δ), with Φ(δ)
    /// and Γ(δ) by their series to fourth order (|ω·δ| < 0.1: error below 10⁻⁷).
    fn shifted(&self, a: [[f64; 2]; 2], d: f64) -> Step {
        let mul = |p: [[f64; 2]; 2], q: [[f64; 2]; 2]| -> [[f64; 2]; 2] {
            core::array::from_fn(|r| core::array::from_fn(|c| p[r][0] * q[0][c] + p[r][1] * q[1][c]))
        };
        let a2 = mul(a, a);
        let a3 = mul(a2, a);
        let id = |r: usize, c: usize| if r == c { 1.0 } else { 0.0 };
        let phi_d: [[f64; 2]; 2] = core::array::from_fn(|r| {
            core::array::from_fn(|c| {
                id(r, c) + a[r][c] * d + a2[r][c] * d * d / 2.0 + a3[r][c] * d * d * d / 6.0
            })
        });
        // Γ(δ) = (Iδ + Aδ²/2 + A²δ³/6 + A³δ⁴/24)·(0, 1).
        let gamma_d: [f64; 2] = core::array::from_fn(|r| {
            id(r, 1) * d + a[r][1] * d * d / 2.0 + a2[r][1] * d * d * d / 6.0 + a3[r][1] * d.powi(4) / 24.0
        });
        let phi = mul(self.phi, phi_d);
        let gamma = core::array::from_fn(|r| {
            self.gamma[r] + self.phi[r][0] * gamma_d[0] + self.phi[r][1] * gamma_d[1]
        });
        Step {
            dt: self.dt + d,
            phi,
            gamma,
        }
    }

    fn new(wn: f64, zeta: f64, dt: f64) -> Step {
        // Φ = e^{A dt} for A = [[0, 1], [−ω², −2ζω]], by scaling and squaring of its Taylor
        // series (exact to rounding for ω·dt well below one after scaling).
        let a = [[0.0, 1.0], [-wn * wn, -2.0 * zeta * wn]];
        let norm = (wn * wn + 2.0 * zeta * wn + 1.0) * dt;
        let squarings = norm.log2().ceil().max(0.0) as i32 + 4;
        let h = dt / 2f64.powi(squarings);
        let mul = |p: [[f64; 2]; 2], q: [[f64; 2]; 2]| -> [[f64; 2]; 2] {
            core::array::from_fn(|r| core::array::from_fn(|c| p[r][0] * q[0][c] + p[r][1] * q[1][c]))
        };
        // exp(A h) and ∫₀ʰ exp(A s) ds·B by their series (B = (0, 1)).
        let ah: [[f64; 2]; 2] = core::array::from_fn(|r| core::array::from_fn(|c| a[r][c] * h));
        let mut term = [[1.0, 0.0], [0.0, 1.0]];
        let mut phi = term;
        let mut integral = [[h, 0.0], [0.0, h]];
        for k in 1..12 {
            term = mul(term, ah);
            term = core::array::from_fn(|r| core::array::from_fn(|c| term[r][c] / k as f64));
            for r in 0..2 {
                for c in 0..2 {
                    phi[r][c] += term[r][c];
                    integral[r][c] += term[r][c] * h / (k + 1) as f64;
                }
            }
        }
        // Squaring: Φ(2h) = Φ(h)², ∫₀^{2h} = ∫₀^h + Φ(h)·∫₀^h.
        for _ in 0..squarings {
            let shifted = mul(phi, integral);
            integral = core::array::from_fn(|r| core::array::from_fn(|c| integral[r][c] + shifted[r][c]));
            phi = mul(phi, phi);
        }
        Step {
            dt,
            phi,
            gamma: [integral[0][1], integral[1][1]],
        }
    }
}

/// The low-frequency delay 2ζ/ω_n of a stage [s].
fn delay(e: &Effect) -> f64 {
    e.aux / (std::f64::consts::PI * e.param)
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
    fn refines(&self) -> Option<EffectKind> {
        Some(EffectKind::TorqueLag)
    }
    fn tune(&self, t: &Tuner) -> Option<Tuned> {
        // By its low-frequency delay d = 2ζ/ω_n (what every pattern shows, and what the
        // first-order lag it refines measured) and its damping (its shape, which only a chirp
        // shows): in (f_n, ζ) the two are nearly a ridge. A grid around the lag's delay, then each
        // refined in turn, twice.
        let at = |d: f64, zeta: f64| stage(t, zeta / (std::f64::consts::PI * d), zeta);
        let d = match t.seed {
            Some(lag) => lag.param,
            None => delay(&t.grid_then_golden(&lag_grid(), |d| at(d, 0.7))?.0),
        };
        let grid = [0.8, 1.0, 1.25]
            .into_iter()
            .flat_map(|k| [0.35, 0.55, 0.75, 0.95].map(|z| at(k * d, z)));
        let (mut e, mut cv) = t.best(grid)?;
        for _ in 0..2 {
            let d = delay(&e);
            (e, _) = t.golden_around(d / 1.25, d * 1.25, |d| at(d, e.aux));
            let d = delay(&e);
            (e, cv) = t.golden_around((e.aux - 0.15).max(LIGHTEST), e.aux + 0.15, |z| at(d, z));
        }
        Some((e, cv))
    }
    fn retune(&self, e: &Effect, t: &Tuner) -> Option<Tuned> {
        let d = delay(e);
        Some(t.golden_around(d / 1.3, d * 1.3, |d| {
            stage(t, e.aux / (std::f64::consts::PI * d), e.aux)
        }))
    }
    fn estimate(&self, e: &Effect, f: &Fitted) -> Estimate {
        Estimate::new(e.param, (f.profile)())
    }
    fn admissible(&self, e: &Effect, v: Estimate, _: &Fitted) -> Result<(), Inadmissible> {
        let top = TOP;
        if e.aux <= LIGHTEST * 1.05 {
            return Err(Inadmissible::OnBound { value: e.aux });
        }
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
    fn lag(&self, e: &Effect, value: f64) -> Option<Lag> {
        Some(Lag {
            shape: LagShape::SecondOrder,
            delay: e.aux / (std::f64::consts::PI * value),
        })
    }
    fn revealing_run(&self) -> SeparatingRun {
        CHIRP_FOR_A_LAG
    }
    fn simulation_sees(&self) -> bool {
        true
    }
    /// A stage between the reported force and the rotor: the simulation sees its phase.
    fn tuned_by_simulation(&self) -> bool {
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
        // Timestamps that jitter by up to ±0.3 of an interval, as a log's do.
        let t: Vec<f64> = (0..4000)
            .map(|i| (i as f64 + 0.3 * ((i * 7919 % 13) as f64 / 6.0 - 1.0)) * dt)
            .collect();
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
