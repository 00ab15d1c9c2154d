//! A model: the seed's two terms plus some effects, and its regression rows.
//!
//! The rows are what every fit, cross-validation and simulation reads: column 0 the force as the
//! load feels it (θ₀ = 1/J), column 1 the drag −|ω|^p·sgn ω (θ₁ = c2/J), then each effect's
//! columns as its [`Candidate`](super::candidate::Candidate) writes them.

use std::borrow::Cow;
use std::ops::Range;

use serde::Serialize;

use super::candidate::{Candidate, EffectKind, Slot};
use super::signals::Signals;

/// Columns a model may have (the base's two plus the effects').
pub(crate) const MAX_COLUMNS: usize = 10;

/// An effect with its nonlinear parameters (unused by the purely linear ones).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Effect {
    /// Which effect.
    pub kind: EffectKind,
    /// Its nonlinear parameter (an exponent, a lag, a harmonic, a threshold, a frequency).
    pub param: f64,
    /// A second one (the damping of a second-order stage).
    pub aux: f64,
    /// How a lag acts.
    pub form: LagForm,
}

impl Effect {
    /// `kind` with parameter `param` (a first-order lag, if a lag).
    pub fn new(kind: EffectKind, param: f64) -> Effect {
        Effect {
            kind,
            param,
            aux: 0.0,
            form: LagForm::FirstOrder,
        }
    }

    /// `kind` with parameter `param` in `form`.
    pub fn with_form(kind: EffectKind, param: f64, form: LagForm) -> Effect {
        Effect {
            form,
            ..Effect::new(kind, param)
        }
    }

    /// Its candidate.
    pub fn candidate(&self) -> &'static dyn Candidate {
        self.kind.candidate()
    }

    /// Regression columns it adds.
    pub fn columns(&self) -> usize {
        self.candidate().columns(self)
    }
}

/// How a lag acts. A filter (an RC on the current sense, a current loop) is first-order; a
/// sample held until the next one (a load cell read at 40 Hz beside 500 Hz telemetry) or carried
/// late over a bus is a pure delay. Both shift the phase alike at low frequency, but a
/// first-order lag also attenuates, as ω²L²/2: on a chirp to 5 Hz a 10 ms held load cell read
/// as a first-order lag came out right and left J 2.5 % high, since the inverse filter
/// amplified the force the delay had not attenuated. The held-out error chooses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub(crate) enum LagForm {
    /// A first-order lag; the force's steps anywhere in the interval before the sample that
    /// shows them.
    #[default]
    FirstOrder,
    /// A first-order lag with the force's steps at the samples that first show them (a drive
    /// that changes its demand in step with its reports; see [`first_order_lag`](super::signals::first_order_lag)).
    FirstOrderStepsAtSamples,
    /// A pure delay: the force sensor reports the torque of `param` seconds ago.
    Delay,
    /// A first-order lag of the reported acceleration, passed through the model's side (every
    /// regressor through the lag) instead of adding the noisy slope of the acceleration as a
    /// column; tried where the force steps and the slope breaks.
    FirstOrderOnModelSide,
    /// [`LagForm::FirstOrderOnModelSide`] with the force's steps at the samples that show them.
    FirstOrderOnModelSideStepsAtSamples,
}

impl LagForm {
    /// Whether the force's steps are taken at the samples that first show them.
    pub fn steps_at_samples(self) -> bool {
        matches!(
            self,
            LagForm::FirstOrderStepsAtSamples | LagForm::FirstOrderOnModelSideStepsAtSamples
        )
    }

    /// Whether the lag acts on the model's side (every column through it).
    pub fn on_model_side(self) -> bool {
        matches!(
            self,
            LagForm::FirstOrderOnModelSide | LagForm::FirstOrderOnModelSideStepsAtSamples
        )
    }

    /// Its shape in reports.
    pub fn shape(self) -> LagShape {
        match self {
            LagForm::FirstOrder
            | LagForm::FirstOrderStepsAtSamples
            | LagForm::FirstOrderOnModelSide
            | LagForm::FirstOrderOnModelSideStepsAtSamples => LagShape::FirstOrder,
            LagForm::Delay => LagShape::Delay,
        }
    }
}

/// A lag as reported: how it acts, and its delay at low frequency (what a first-order lag of the
/// same data would measure: its time constant, a delay's length, a second-order stage's
/// 2ζ/ω_n).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lag {
    /// How it acts.
    pub shape: LagShape,
    /// Its delay at low frequency [s].
    pub delay: f64,
}

/// How a named lag acts, in reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LagShape {
    /// A first-order filter.
    FirstOrder,
    /// A pure delay (a held or late sample).
    Delay,
    /// A second-order stage.
    SecondOrder,
}

impl LagShape {
    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            LagShape::FirstOrder => "first_order",
            LagShape::Delay => "delay",
            LagShape::SecondOrder => "second_order",
        }
    }
}

/// An effect's place among a model's columns, resolved once per model (the rows are built for
/// every sample of every cross-validation: no lookup there).
#[derive(Clone, Copy)]
pub(crate) struct Part {
    /// The effect.
    pub effect: Effect,
    /// Its candidate.
    pub candidate: &'static dyn Candidate,
    /// Its first column.
    pub column: usize,
    /// Its number of columns (> 0).
    pub columns: usize,
    /// Whether its columns have instruments.
    pub differentiated: bool,
}

/// Per-model precomputation: the torque input F̃ (the measured force itself, borrowed, unless
/// an effect transforms it), the drag exponent, where braking acts, a lag on the model's side.
pub(crate) struct Prepared<'s> {
    /// The force as the load feels it.
    pub force: Cow<'s, [f64]>,
    /// The drag law's exponent.
    pub exponent: f64,
    /// How much of a braking torque acts at each sample (empty without braking).
    pub braking: Vec<f64>,
    /// A first-order lag every column passes through (time constant, steps at samples).
    pub model_side_lag: Option<(f64, bool)>,
    /// The share of the force's white noise its transformation lets through (1: none; see
    /// [`impulse_gain`]). A model holds one lag, so the force has one transformation at most.
    pub force_noise_gain: f64,
    /// The effects that add columns, with their places.
    pub parts: Vec<Part>,
}

/// The speed a regression row is evaluated at.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Speed {
    /// The measured speed at the row's sample (its logarithm is kept in the signals).
    Measured,
    /// A simulated speed and its drag term |ω|^p·sgn ω.
    Simulated {
        /// ω [rad/s].
        omega: f64,
        /// |ω|^p·sgn ω.
        drag: f64,
    },
}

/// Where a regression row is evaluated: what an effect's columns read.
pub(crate) struct At<'a> {
    /// The signals.
    pub s: &'a Signals,
    /// The model's prepared inputs.
    pub p: &'a Prepared<'a>,
    /// The sample.
    pub i: usize,
    /// The speed (measured or simulated) [rad/s].
    pub omega: f64,
    /// Its sign (0 at rest).
    pub sgn: f64,
    /// In a simulation, the step's length [s] (0 otherwise).
    pub step: f64,
    /// Whether only terms of the load's dynamics count (a simulation: a sensor's lag is not one).
    pub dynamics_only: bool,
}

/// A model: the base plus some effects.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Model {
    /// Its effects, in the order they were added.
    pub effects: Vec<Effect>,
}

impl Model {
    /// The model plus `e`; `None` when it would need more than [`MAX_COLUMNS`] columns or the
    /// place `e` needs is taken.
    pub fn with(&self, e: Effect) -> Option<Model> {
        if self.has(e.kind) || (e.candidate().slot() == Slot::Lag && self.has_lag()) {
            return None;
        }
        let mut m = self.clone();
        m.effects.push(e);
        (m.columns() <= MAX_COLUMNS).then_some(m)
    }

    /// The model without its effect `index`.
    pub fn without(&self, index: usize) -> Model {
        let mut m = self.clone();
        m.effects.remove(index);
        m
    }

    /// Whether it holds `kind`.
    pub fn has(&self, kind: EffectKind) -> bool {
        self.effects.iter().any(|e| e.kind == kind)
    }

    /// Whether it holds a lag.
    pub fn has_lag(&self) -> bool {
        self.effects
            .iter()
            .any(|e| e.candidate().slot() == Slot::Lag)
    }

    /// Regression columns.
    pub fn columns(&self) -> usize {
        2 + self.effects.iter().map(Effect::columns).sum::<usize>()
    }

    /// Effect `index`'s first column.
    pub fn column_of(&self, index: usize) -> usize {
        2 + self.effects[..index]
            .iter()
            .map(Effect::columns)
            .sum::<usize>()
    }

    /// Whether a column is a slope of a noisy signal (then the fit uses instruments).
    pub fn differentiated(&self) -> bool {
        self.effects.iter().any(|e| e.candidate().differentiated(e))
    }

    /// Which columns the simulation holds over a step.
    pub fn held_columns(&self) -> [bool; MAX_COLUMNS] {
        let mut mask = [false; MAX_COLUMNS];
        for (k, e) in self.effects.iter().enumerate() {
            if e.candidate().held_in_simulation() {
                let c = self.column_of(k);
                for m in &mut mask[c..c + e.columns()] {
                    *m = true;
                }
            }
        }
        mask
    }

    /// The model's inputs as its effects transform them.
    pub fn prepare<'s>(&self, s: &'s Signals) -> Prepared<'s> {
        let mut p = Prepared {
            force: Cow::Borrowed(&s.force[..]),
            exponent: 2.0,
            braking: Vec::new(),
            model_side_lag: None,
            force_noise_gain: 1.0,
            parts: Vec::new(),
        };
        let mut column = 2;
        for e in &self.effects {
            let candidate = e.candidate();
            candidate.prepare(e, s, &mut p);
            let columns = candidate.columns(e);
            if columns > 0 {
                p.parts.push(Part {
                    effect: *e,
                    candidate,
                    column,
                    columns,
                    differentiated: candidate.differentiated(e),
                });
            }
            column += columns;
        }
        p
    }

    /// The drag term |ω|^p·sgn ω of a simulated speed.
    pub fn drag(p: &Prepared, omega: f64) -> f64 {
        if p.exponent == 2.0 {
            omega * omega.abs()
        } else if omega == 0.0 {
            0.0
        } else {
            omega.abs().powf(p.exponent) * omega.signum()
        }
    }

    /// The regression row at sample `i` at `speed`. With `dynamics_only`, terms that describe a
    /// sensor rather than the load are zero; with `step` > 0 (a simulation), a torque periodic
    /// in angle is its mean over the angle swept in one step.
    pub fn row(
        &self,
        p: &Prepared,
        s: &Signals,
        i: usize,
        speed: Speed,
        dynamics_only: bool,
        step: f64,
    ) -> [f64; MAX_COLUMNS] {
        let mut r = [0.0; MAX_COLUMNS];
        let (omega, drag) = match speed {
            Speed::Measured => {
                let omega = s.velocity[i];
                let drag = if p.exponent == 2.0 {
                    omega * omega.abs()
                } else {
                    // |ω|^p as exp(p·ln|ω|) from the logarithm kept in the signals (a third of
                    // `powf`'s cost, in every pass of the exponent's tuning).
                    (p.exponent * s.log_speed[i]).exp() * omega.signum()
                };
                (omega, if omega == 0.0 { 0.0 } else { drag })
            }
            Speed::Simulated { omega, drag } => (omega, drag),
        };
        let sgn = if omega > 0.0 {
            1.0
        } else if omega < 0.0 {
            -1.0
        } else {
            0.0
        };
        r[0] = p.force[i];
        r[1] = -drag;
        let at = At {
            s,
            p,
            i,
            omega,
            sgn,
            step,
            dynamics_only,
        };
        for part in &p.parts {
            part.candidate.row(
                &part.effect,
                &at,
                &mut r[part.column..part.column + part.columns],
            );
        }
        r
    }

    /// The instruments at sample `i`: the row with each differentiated column replaced by its
    /// instrument.
    pub fn instruments(
        p: &Prepared,
        s: &Signals,
        i: usize,
        mut row: [f64; MAX_COLUMNS],
    ) -> [f64; MAX_COLUMNS] {
        for part in p.parts.iter().filter(|part| part.differentiated) {
            part.candidate.instrument(
                &part.effect,
                s,
                i,
                &mut row[part.column..part.column + part.columns],
            );
        }
        row
    }
}

/// The share of a white noise's variance (one sample every `dt`) that a transformation of the
/// force lets through, from its impulse response on a regular grid: Σ h². `apply` transforms a
/// signal given its times; `span` is the transformation's slowest time constant [s]. 1 for none;
/// towards dt/(2L) for a lag L ≫ dt; (1 − f)² + f² for a delay of f samples.
///
/// Why: a lag or a delay of the force also averages its noise away, and the predicted
/// acceleration θ₀·F̃ then carries less of it: a gain in held-out error that any lag earns on
/// any data (a 1 ms torque lag gained 11.6 % on a clean 0.5 Hz sine at 1 kHz). The noise the
/// model took out, θ₀²·σ_F²·(1 − gain) per sample, is put back into every score, so that only
/// the transformation's phase is scored.
pub(crate) fn impulse_gain(dt: f64, span: f64, apply: impl Fn(&[f64], &[f64]) -> Vec<f64>) -> f64 {
    if dt.is_nan() || dt <= 0.0 || span.is_nan() || span <= 0.0 {
        return 1.0;
    }
    // Long enough for the stage to decay to e⁻³⁰; bounded far above the sample.
    let len = ((span / dt * 30.0).ceil() as usize + 4).min(200_000);
    // The impulse at the second point: a transformation starts from its input's first value.
    let t: Vec<f64> = (0..len + 1).map(|i| i as f64 * dt).collect();
    let mut x = vec![0.0; len + 1];
    x[1] = 1.0;
    apply(&t, &x).iter().map(|v| v * v).sum()
}

/// The regression rows at the measured speeds of the samples in `range`, with their indices.
/// With a lag on the model's side every column passes through that lag, run from the first
/// sample (its warm-up) and discretised like [`first_order_lag`](super::signals::first_order_lag).
pub(crate) fn measured_rows<'a>(
    model: &'a Model,
    p: &'a Prepared,
    s: &'a Signals,
    range: Range<usize>,
) -> impl Iterator<Item = (usize, [f64; MAX_COLUMNS])> + 'a {
    let lag = p.model_side_lag;
    let from = if lag.is_some() { 0 } else { range.start };
    let mut state: Option<(f64, [f64; MAX_COLUMNS], [f64; MAX_COLUMNS])> = None;
    let mut decay = super::signals::Decay::new(lag.map_or(1.0, |(l, _)| l));
    (from..range.end).filter_map(move |i| {
        let x = model.row(p, s, i, Speed::Measured, false, 0.0);
        let row = match lag {
            None => x,
            Some((l, steps_at_samples)) => {
                let y = match state {
                    Some((t0, x0, y0)) if s.t[i] > t0 && l > 0.0 => {
                        let dt = s.t[i] - t0;
                        let e = decay.at(dt);
                        let step = steps_at_samples && s.force_steps_at(i);
                        core::array::from_fn(|k| {
                            if k == 0 && step {
                                // The old force held over the interval, the step at sample i.
                                x0[k] + e * (y0[k] - x0[k])
                            } else {
                                let slope = (x[k] - x0[k]) / dt;
                                x[k] - l * slope + e * (y0[k] - x0[k] + l * slope)
                            }
                        })
                    }
                    Some((_, _, y0)) => y0,
                    None => x,
                };
                state = Some((s.t[i], x, y));
                y
            }
        };
        (i >= range.start).then_some((i, row))
    })
}

#[cfg(test)]
mod tests {
    use super::impulse_gain;
    use crate::diagnose::signals::{advanced, first_order_lag};

    #[test]
    fn the_noise_a_transformed_force_keeps() {
        let dt = 1e-3;
        let lag = |l: f64| move |t: &[f64], x: &[f64]| first_order_lag(t, x, l, |_| false);
        let delay = |d: f64| move |t: &[f64], x: &[f64]| advanced(t, x, -d);
        assert_eq!(impulse_gain(dt, 0.0, lag(0.0)), 1.0);
        // Half a sample's delay, read between two samples: (½)² + (½)².
        assert!((impulse_gain(dt, 2.5e-3, delay(2.5e-3)) - 0.5).abs() < 1e-12);
        // A lag far above the sample averages like a continuous one: dt/(2L).
        let slow = impulse_gain(dt, 0.1, lag(0.1));
        assert!((slow / (dt / 0.2) - 1.0).abs() < 0.01, "{slow}");
        // A lag of one sample, the recursion written out: h₀ = 1 − b(1 − e), then
        // h_k = (h₀·e + b(1 − e) − e)·e^(k−1) with b = 1.
        let e = (-1.0f64).exp();
        let h0 = 1.0 - (1.0 - e);
        let h1 = h0 * e + (1.0 - e) - e;
        let exact = h0 * h0 + h1 * h1 / (1.0 - e * e);
        let one = impulse_gain(dt, dt, lag(dt));
        assert!((one - exact).abs() < 1e-9, "{one} vs {exact}");
        // Two lags in cascade keep less than either alone.
        let both = impulse_gain(dt, 2.0 * dt, |t, x| lag(2.0 * dt)(t, &lag(dt)(t, x)));
        assert!(both < one && both < impulse_gain(dt, 2.0 * dt, lag(2.0 * dt)));
    }
}
