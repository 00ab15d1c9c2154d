//! The candidate effects: one file per effect, one trait.
//!
//! Every effect the diagnosis can name is a type implementing [`Candidate`]: how it enters the
//! acceleration equation (regression columns, or a transformation of the model's inputs), how its
//! nonlinear parameter is tuned, when its value is physically admissible, its value and unit, the
//! sentence that explains it, the run that reveals it and whether the held-out simulation of the
//! velocity can see it. The trait has no default methods, so an effect that forgets one does not
//! compile; the selection (`select`, `search`) never names an effect, it only reads what the
//! trait says.
//!
//! A new effect is one new file here plus one line in [`registry!`] below: the line declares the
//! module, adds the variant to [`EffectKind`] and the arm of the one exhaustive dispatch
//! ([`EffectKind::candidate`]). No `match` on the effect kind exists anywhere else.
//!
//! Every model is linear in its coefficients once the nonlinear parameters are fixed:
//!
//! ```text
//!  a = θ₀·F̃ − θ₁·|ω|^p·sgn ω + Σ_effects θ_e·column_e
//! ```
//! with F̃ the reported force, or what the load feels of it (through a lag, a delay, a
//! second-order stage), and p = 2 unless `drag_exponent` says otherwise.

use propid_io::tsv::{Row, Sample};
use serde::Serialize;

use super::model::{At, Effect, Lag, Prepared};
use super::signals::Signals;
use super::tune::{Tuned, Tuner};
use super::SeparatingRun;
use crate::excitation::Pattern;

/// A parameter estimate with its standard error.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Estimate {
    /// The value.
    pub value: f64,
    /// Its standard error (NaN where none can be computed).
    pub stderr: f64,
}

impl Estimate {
    /// `value` ± `stderr`.
    pub fn new(value: f64, stderr: f64) -> Estimate {
        Estimate { value, stderr }
    }

    /// Whether the value lies more than `k` standard errors from `zero` (a NaN standard error
    /// resolves nothing).
    pub fn resolved_from(&self, zero: f64, k: f64) -> bool {
        (self.value - zero).abs() > k * self.stderr
    }
}

/// Why an effect's fitted value cannot be the effect (typed: code matches on this).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "why", rename_all = "snake_case")]
pub enum Inadmissible {
    /// The value is not finite.
    NotFinite,
    /// The sign the mechanism cannot have (a negative friction, a negative lag).
    WrongSign,
    /// Within [`RESOLVED`] standard errors of "no effect" (zero, or the seed's exponent 2), or
    /// not longer than the shortest lag tried.
    NotResolved {
        /// The value.
        value: f64,
        /// Its standard error.
        stderr: f64,
    },
    /// It would step the acceleration by less than the reported acceleration's noise: the
    /// samples it acts on would be chosen by that noise.
    BelowNoise {
        /// The step [rad/s²].
        step: f64,
        /// The noise [rad/s²].
        noise: f64,
    },
    /// Outside the range the mechanism can have (a clock off by more than a few per cent is a
    /// unit, not a clock).
    OutOfRange {
        /// The value.
        value: f64,
    },
    /// A parameter sits on the bound of its search: the data do not place it.
    OnBound {
        /// The parameter's value.
        value: f64,
    },
    /// Fitted jointly with it, another effect of the model takes a value that effect cannot
    /// have (a negative friction, a negative lag): the two trade one column against the other
    /// (on a square wave a Coulomb friction and a braking torque are one signal), and a model is
    /// physical only when every one of its effects is.
    Spoils {
        /// The effect whose value turns impossible.
        effect: EffectKind,
    },
}

impl std::fmt::Display for Inadmissible {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Inadmissible::NotFinite => write!(f, "its fitted value is not finite"),
            Inadmissible::WrongSign => write!(f, "its fitted value has a sign the mechanism cannot have"),
            Inadmissible::NotResolved { value, stderr } => write!(
                f,
                "{value:.4e} ± {stderr:.1e} is not resolved from no effect ({RESOLVED} standard errors)"
            ),
            Inadmissible::BelowNoise { step, noise } => write!(
                f,
                "it would step the acceleration by {step:.3e} rad/s², below the noise of the reported acceleration ({noise:.3e} rad/s²)"
            ),
            Inadmissible::OutOfRange { value } => {
                write!(f, "{value:.4e} is outside the range the mechanism can have")
            }
            Inadmissible::OnBound { value } => write!(
                f,
                "a parameter sits on the bound of its search ({value:.3}): the data do not place it"
            ),
            Inadmissible::Spoils { effect } => write!(
                f,
                "fitted with it, {effect} takes a value that mechanism cannot have: the two trade one signal between them"
            ),
        }
    }
}

/// Standard errors an effect's value must lie from "no effect" to be named.
pub const RESOLVED: f64 = 3.0;

/// How an effect enters the diagnosis.
#[derive(Clone, Copy)]
pub(crate) enum Enters {
    /// A term of the acceleration equation: searched by the selection.
    Equation,
    /// Only the probe for periodic structure no candidate explains: never named by the search.
    Probe,
    /// Measured from the rows (with the host's receive times) before any fit, and corrected in
    /// the samples.
    Rows(&'static dyn RowEffect),
}

/// An effect measured from the rows before the fit (a device clock against the host's).
pub(crate) trait RowEffect: Sync {
    /// Its estimate, `None` when the rows cannot show it.
    fn measure(&self, rows: &[Row]) -> Option<Estimate>;
    /// The sample as it would read without the effect of size `value`.
    fn correct(&self, value: f64, sample: &mut Sample);
}

/// Which place of a model an effect occupies: a model holds at most one effect per place other
/// than [`Slot::Term`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Slot {
    /// An added torque: any number of them.
    Term,
    /// A lag between the reported force and the acceleration (of the torque, the force sensor,
    /// the acceleration estimate). Two in series split one delay between them (on the formula
    /// stand a 12 ms force-sensor lag came out as 14 ms plus a 4 ms acceleration lag), so a
    /// model holds one.
    Lag,
}

/// What an effect looks like, for the run that tells two effects apart (see [`separating_run`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Shape {
    /// A torque that does not depend on speed; `odd`: it changes sign with the rotation.
    Constant {
        /// Whether it changes sign with the rotation (a friction) or not (a sensor offset).
        odd: bool,
    },
    /// A torque that grows with speed (ω, ω^p).
    SpeedLaw,
    /// A torque acting only while the rotor slows.
    Slowing,
    /// A lag (its effect grows with frequency); `of_torque`: it delays the velocity too.
    Lag,
    /// A torque periodic in angle or time.
    Periodic,
    /// The device clock.
    Clock,
}

/// What an effect changes in the seed's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum BaseTerm {
    /// Nothing.
    None,
    /// The seed's c1.
    C1(Estimate),
    /// The drag law's exponent: c2·ω² becomes k·|ω|^p.
    Exponent(f64),
}

/// What a design (`propid plan`) knows of a pattern: the commanded torque's rate, the noise-free
/// speed and its derivatives, at a regular interval.
pub(crate) struct Design<'a> {
    /// The commanded torque's time derivative.
    pub force_rate: &'a [f64],
    /// Speed [rad/s].
    pub speed: &'a [f64],
    /// Acceleration [rad/s²].
    pub acceleration: &'a [f64],
    /// Jerk [rad/s³].
    pub jerk: &'a [f64],
}

/// A fitted model, as one effect reads its value from it.
pub(crate) struct Fitted<'a> {
    /// The model's coefficients (θ₀ multiplies the force: 1/J).
    pub theta: &'a [f64],
    /// Their standard errors.
    pub stderr: &'a [f64],
    /// The effect's first column.
    pub column: usize,
    /// Root-mean-square residual of the fit [rad/s²].
    pub rms: f64,
    /// The standard error of the effect's nonlinear parameter, from the curvature of the residual
    /// sum of squares around it (refits the model).
    pub profile: &'a dyn Fn() -> f64,
}

impl Fitted<'_> {
    /// The torque of the effect's column k [N·m]: its coefficient over θ₀ (= its coefficient
    /// times J), with its standard error.
    pub fn torque(&self, k: usize) -> Estimate {
        let t0 = self.theta[0];
        Estimate::new(
            self.theta[self.column + k] / t0,
            self.stderr[self.column + k] / t0.abs(),
        )
    }
}

/// One effect the diagnosis can name. Every method is required.
pub(crate) trait Candidate: Sync {
    /// Its name in reports (`torque_lag`, …).
    fn name(&self) -> &'static str;
    /// The unit of its value.
    fn unit(&self) -> &'static str;
    /// How it enters the diagnosis.
    fn enters(&self) -> Enters;
    /// The place it occupies in a model.
    fn slot(&self) -> Slot;
    /// How many numbers it adds to the model (its columns and nonlinear parameters): between two
    /// candidates the data cannot tell apart, the one with fewer is named.
    fn parameters(&self) -> usize;
    /// Regression columns it adds in form `e` (0 for a transformation of the inputs).
    fn columns(&self, e: &Effect) -> usize;
    /// What it does to the model's inputs (a filtered force, a drag exponent, when braking acts).
    fn prepare(&self, e: &Effect, s: &Signals, p: &mut Prepared);
    /// Writes its columns of the regression row at `at` into `out` (as many as
    /// [`Candidate::columns`]).
    fn row(&self, e: &Effect, at: &At, out: &mut [f64]);
    /// Whether its columns are slopes of noisy signals, estimated with instruments.
    fn differentiated(&self, e: &Effect) -> bool;
    /// Writes the instruments of its columns at sample `i` (only called where
    /// [`Candidate::differentiated`]).
    fn instrument(&self, e: &Effect, s: &Signals, i: usize, out: &mut [f64]);
    /// Whether the simulation holds its columns over a step instead of interpolating them (a
    /// torque periodic in angle, already the mean over the step's sweep).
    fn held_in_simulation(&self) -> bool;
    /// The effect it refines, if any: it is then tried only where that effect passes rules 1–4
    /// in the same round, and tuned from its value (the tuner's `seed`).
    fn refines(&self) -> Option<EffectKind>;
    /// Tunes its nonlinear parameter (and form) on the tuner's model; `None` when it cannot be
    /// tried (no position column for a ripple).
    fn tune(&self, t: &Tuner) -> Option<Tuned>;
    /// Refines its nonlinear parameters near their values in `e`, on the tuner's model (the
    /// others of a model that holds `e`, re-tuned jointly after an addition); `None` when it has
    /// none to refine.
    fn retune(&self, e: &Effect, t: &Tuner) -> Option<Tuned>;
    /// Its value and standard error from a fit of a model that contains it.
    fn estimate(&self, e: &Effect, f: &Fitted) -> Estimate;
    /// Whether that value can be the effect.
    fn admissible(&self, e: &Effect, v: Estimate, f: &Fitted) -> Result<(), Inadmissible>;
    /// One sentence on what it means, with its value.
    fn explanation(&self, e: &Effect, value: f64) -> String;
    /// What it looks like (for the run that separates two effects).
    fn shape(&self) -> Shape;
    /// For a lag of value `value`, how it acts in form `e` and its delay at low frequency;
    /// `None` for anything else.
    fn lag(&self, e: &Effect, value: f64) -> Option<Lag>;
    /// The `propid drive` run that shows it more clearly than data where it came close.
    fn revealing_run(&self) -> SeparatingRun;
    /// Whether the held-out simulation of the velocity can see it (a torque ripple far above
    /// the sample rate moves the load as its mean over a step does: about nothing).
    fn simulation_sees(&self) -> bool;
    /// Whether its nonlinear parameter is tuned by the simulated velocity as well as the
    /// equation (`tune`): a lag of what drives the rotor (the torque's, a second-order stage).
    /// Not a term of the equation, nor a lag of the acceleration's estimate (it leaves the
    /// velocity, which the simulation is scored on, untouched), nor a force sensor's lag (the
    /// equation's coefficient of the force's slope).
    fn tuned_by_simulation(&self) -> bool;
    /// What it changes in the seed's parameters.
    fn base_term(&self, e: &Effect, v: Estimate) -> BaseTerm;
    /// Its regression column on a designed pattern (for `propid plan`'s separations); `None`
    /// when a plan does not consider it.
    fn design_column(&self, d: &Design) -> Option<Vec<f64>>;
}

/// Declares the effects: one line each, `Variant => module::CANDIDATE` (a unit struct, or a const
/// of a shared type such as [`torque_term::TorqueTerm`]). Generates the module
/// declarations, [`EffectKind`] and its one exhaustive dispatch.
macro_rules! registry {
    ($( $(#[$doc:meta])* $kind:ident => $module:ident :: $ty:ident, )*) => {
        $( mod $module; )*

        /// The effects propid knows how to look for (see each variant's file under
        /// `diagnose/candidate/`). Serialised as its name (`torque_lag`, …).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum EffectKind {
            $( $(#[$doc])* $kind, )*
        }

        impl EffectKind {
            /// Every effect, in the order the search tries them.
            pub const ALL: &'static [EffectKind] = &[$( EffectKind::$kind, )*];

            /// Its candidate (the one dispatch on the kind).
            pub(crate) fn candidate(self) -> &'static dyn Candidate {
                match self {
                    $( EffectKind::$kind => &$module::$ty, )*
                }
            }
        }
    };
}

/// The one-column torque terms' shared implementation (coulomb, offset, viscous).
mod torque_term;

registry! {
    /// Constant torque opposing rotation [N·m].
    CoulombFriction => coulomb::COULOMB_FRICTION,
    /// The reported force reads this much when no torque acts [N·m].
    ForceOffset => offset::FORCE_OFFSET,
    /// A torque braking the rotor while it slows, missing from the reported force [N·m].
    BrakingTorque => braking::BrakingTorque,
    /// Torque ∝ ω [N·m·s/rad] (the seed's c1).
    ViscousFriction => viscous::VISCOUS_FRICTION,
    /// Aerodynamic torque ∝ |ω|^p with p ≠ 2 [–].
    DragExponent => drag_exponent::DragExponent,
    /// The torque the load feels lags the reported force [s].
    TorqueLag => torque_lag::TorqueLag,
    /// The reported force lags the torque the load feels [s].
    ForceSensorLag => force_sensor_lag::ForceSensorLag,
    /// The reported acceleration lags the true one [s].
    AccelerationLag => acceleration_lag::AccelerationLag,
    /// The load feels the reported force through a second-order stage [Hz].
    SecondOrderLag => second_order_lag::SecondOrderLag,
    /// Torque periodic in rotor position [N·m].
    TorqueRipple => ripple::TorqueRipple,
    /// The device clock runs at 1 + ε host seconds per second [–].
    TimeBase => time_base::TimeBase,
    /// A torque periodic in time: the probe for structure no candidate explains [N·m].
    PeriodicDisturbance => periodic::PeriodicDisturbance,
}

impl EffectKind {
    /// Its name in reports.
    pub fn name(self) -> &'static str {
        self.candidate().name()
    }

    /// The unit of its value.
    pub fn unit(self) -> &'static str {
        self.candidate().unit()
    }

    /// Its regression column on a designed pattern, if a plan considers it.
    pub(crate) fn design_column(self, d: &Design) -> Option<Vec<f64>> {
        self.candidate().design_column(d)
    }

    /// The effects the search tries in the acceleration equation, in order.
    pub(crate) fn searched() -> impl Iterator<Item = EffectKind> {
        EffectKind::ALL
            .iter()
            .copied()
            .filter(|k| matches!(k.candidate().enters(), Enters::Equation))
    }
}

impl std::fmt::Display for EffectKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for EffectKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        EffectKind::ALL
            .iter()
            .copied()
            .find(|k| k.name() == s)
            .ok_or_else(|| format!("unknown effect `{s}`"))
    }
}

impl Serialize for EffectKind {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for EffectKind {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        name.parse().map_err(serde::de::Error::custom)
    }
}

/// Whether an effect's value measured outside a regression (from the rows, or from a
/// steady-state law) can be the effect: the candidate's own rule, with no fit to read.
pub(crate) fn admissible_measured(kind: EffectKind, v: Estimate) -> Result<(), Inadmissible> {
    let none = || f64::NAN;
    let fitted = Fitted {
        theta: &[],
        stderr: &[],
        column: 0,
        rms: f64::NAN,
        profile: &none,
    };
    kind.candidate()
        .admissible(&Effect::new(kind, v.value), v, &fitted)
}

/// The `propid drive` run that tells effects `a` and `b` apart, from their shapes.
pub(crate) fn separating_run(a: EffectKind, b: EffectKind) -> SeparatingRun {
    let (sa, sb) = (a.candidate().shape(), b.candidate().shape());
    let constant = |s: Shape| matches!(s, Shape::Constant { .. });
    let torque_shape = |s: Shape| constant(s) || s == Shape::SpeedLaw;
    if constant(sa) && constant(sb) && sa != sb {
        SeparatingRun {
            pattern: Pattern::Chirp,
            lo: Some(-0.5),
            hi: Some(0.9),
            why: "a pattern that reverses the rotor: friction changes sign with the rotation, a sensor offset does not",
        }
    } else if torque_shape(sa) && torque_shape(sb) {
        LOW_SPEED_STEPS
    } else if sa == Shape::Slowing || sb == Shape::Slowing {
        SeparatingRun {
            pattern: Pattern::Steps,
            lo: None,
            hi: None,
            why: "held speeds, then sudden slowing, where only braking acts",
        }
    } else if sa == Shape::Lag && sb == Shape::Lag {
        SeparatingRun {
            pattern: Pattern::Chirp,
            lo: None,
            hi: None,
            why: "a sweep of frequencies: a late torque delays the velocity too, a late sensor only its own signal, and the difference grows with frequency",
        }
    } else {
        SeparatingRun {
            pattern: Pattern::Chirp,
            lo: None,
            hi: None,
            why: "a sweep of frequencies, over which a lag's effect grows and a friction's or drag's does not",
        }
    }
}

/// Steps down to low speed: where a constant torque, one ∝ ω and one ∝ ω^p differ most.
pub(crate) const LOW_SPEED_STEPS: SeparatingRun = SeparatingRun {
    pattern: Pattern::Steps,
    lo: Some(0.02),
    hi: Some(0.9),
    why: "a pattern that reaches low speeds: there a constant torque, one ∝ ω and one ∝ ω^p differ most",
};

/// A chirp: what reveals a lag.
pub(crate) const CHIRP_FOR_A_LAG: SeparatingRun = SeparatingRun {
    pattern: Pattern::Chirp,
    lo: None,
    hi: None,
    why: "a sweep of frequencies: a lag's effect grows with frequency, and one sinusoid at 0.5 Hz hardly shows a few milliseconds",
};

/// The drag exponents tried first (also by the steady-state law).
pub(crate) fn drag_exponent_grid() -> Vec<f64> {
    drag_exponent::grid()
}

/// The shortest lag tried [s]: it stands for "no lag".
pub(crate) const SHORTEST_LAG: f64 = 2e-4;

/// The lags tried first: 0.2 ms … 100 ms (current loops and filters), within the half-second
/// warm-up, each 1.86 times the last (the golden-section refinement between a point's
/// neighbours then finds the minimum to 0.3 % of that bracket).
pub(crate) fn lag_grid() -> Vec<f64> {
    (0..=10).map(|k| SHORTEST_LAG * 1.865f64.powi(k)).collect()
}

impl EffectKind {
    /// The effect it refines (see [`Candidate::refines`]).
    pub(crate) fn refines(self) -> Option<EffectKind> {
        self.candidate().refines()
    }
}

/// A lag is admissible when positive, resolved (more than [`RESOLVED`] standard errors) and
/// longer than the shortest lag tried, which stands for none. The signals are continuous between
/// samples, so a lag shorter than a sample interval is measurable.
pub(crate) fn admissible_lag(v: Estimate) -> Result<(), Inadmissible> {
    if !v.value.is_finite() {
        Err(Inadmissible::NotFinite)
    } else if v.value <= 0.0 {
        Err(Inadmissible::WrongSign)
    } else if !(v.resolved_from(0.0, RESOLVED) && v.value > 1.01 * SHORTEST_LAG) {
        Err(Inadmissible::NotResolved {
            value: v.value,
            stderr: v.stderr,
        })
    } else {
        Ok(())
    }
}

/// A torque [N·m] is admissible when resolved from zero and of the sign the mechanism has
/// (`positive`: a friction or braking; otherwise any sign, an offset).
///
/// Why resolved: after an acceleration filter on the sine, a force offset of 7.5·10⁻⁵ N·m (2 %
/// of the sine's amplitude) gained 24 % on held-out acceleration and nothing in simulation.
pub(crate) fn admissible_torque(v: Estimate, positive: bool) -> Result<(), Inadmissible> {
    if !v.value.is_finite() {
        Err(Inadmissible::NotFinite)
    } else if !v.resolved_from(0.0, RESOLVED) {
        Err(Inadmissible::NotResolved {
            value: v.value,
            stderr: v.stderr,
        })
    } else if positive && v.value <= 0.0 {
        Err(Inadmissible::WrongSign)
    } else {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_parse_back() {
        for (i, a) in EffectKind::ALL.iter().enumerate() {
            assert_eq!(a.name().parse::<EffectKind>(), Ok(*a));
            for b in &EffectKind::ALL[i + 1..] {
                assert_ne!(a.name(), b.name());
            }
        }
        assert_eq!(
            serde_json::to_string(&EffectKind::TorqueLag).unwrap(),
            "\"torque_lag\""
        );
    }

    #[test]
    fn the_run_that_separates_two_effects_follows_their_shapes() {
        use EffectKind::*;
        let run = |a, b| separating_run(a, b);
        assert_eq!(run(CoulombFriction, ForceOffset).lo, Some(-0.5));
        assert_eq!(run(ForceOffset, CoulombFriction).lo, Some(-0.5));
        assert_eq!(run(CoulombFriction, ViscousFriction), LOW_SPEED_STEPS);
        assert_eq!(run(ViscousFriction, DragExponent), LOW_SPEED_STEPS);
        assert_eq!(run(BrakingTorque, CoulombFriction).pattern, Pattern::Steps);
        assert_eq!(run(TorqueLag, AccelerationLag).pattern, Pattern::Chirp);
        assert_eq!(run(TorqueLag, CoulombFriction).pattern, Pattern::Chirp);
    }
}
