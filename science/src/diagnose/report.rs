//! The diagnosis as a typed value: every field a program reads, serialised by serde; the text
//! and the plots are rendered from it (`text`).

use serde::Serialize;

use super::candidate::EffectKind;
use super::gate::CannotJudge;
use super::model::LagShape;
use super::search::CandidateScore;
use super::select::{Decision, Gain};
use super::structure::{Concentration, LeftOut};
use crate::excitation::Pattern;

/// A model's seed parameters.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BaseModel {
    /// Inertia J [kg·m²].
    pub inertia: f64,
    /// Viscous coefficient (0: the seed's default bound).
    pub c1: f64,
    /// Drag coefficient of the quadratic law c2·ω|ω| [N·m·s²/rad²], always: for a drag law
    /// k·|ω|^p (`drag_exponent` named) it is the c2 whose quadratic torque equals k·|ω|^p at the
    /// data's RMS speed, and `k` and `p` hold the law itself.
    pub c2: f64,
    /// Standard error of J.
    pub inertia_stderr: f64,
    /// Standard error of c2.
    pub c2_stderr: f64,
    /// k of a drag law k·|ω|^p [N·m·(s/rad)^p] (absent for the quadratic law).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub k: Option<f64>,
    /// p of a drag law k·|ω|^p (absent for the quadratic law).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub p: Option<f64>,
}

impl BaseModel {
    /// A model with every value NaN (data that could not be judged).
    pub(crate) fn unknown() -> BaseModel {
        BaseModel {
            inertia: f64::NAN,
            c1: f64::NAN,
            c2: f64::NAN,
            inertia_stderr: f64::NAN,
            c2_stderr: f64::NAN,
            k: None,
            p: None,
        }
    }

    /// A drag law k·|ω|^p as its quadratic-equivalent c2 at the RMS speed `w_rms`.
    pub(crate) fn power_law(mut self, k: f64, k_stderr: f64, p: f64, w_rms: f64) -> BaseModel {
        let scale = w_rms.powf(p - 2.0);
        self.c2 = k * scale;
        self.c2_stderr = k_stderr * scale;
        self.k = Some(k);
        self.p = Some(p);
        self
    }
}

/// A named effect with its estimated parameter.
#[derive(Clone, Debug, Serialize)]
pub struct NamedEffect {
    /// Which effect (serialised as its name, `torque_lag`, …).
    #[serde(rename = "name")]
    pub effect: EffectKind,
    /// Its parameter.
    pub value: f64,
    /// Unit of the parameter.
    pub unit: &'static str,
    /// Standard error of the parameter.
    pub stderr: f64,
    /// Held-out simulated-velocity gain of the base model plus this effect alone [%] (fitted on
    /// the first 70 %, simulated over the last 30 %).
    pub gain_percent: f64,
    /// Held-out acceleration-equation gain when it was named [%].
    pub cv_gain_percent: f64,
    /// The selection's criterion when it was named.
    pub gain: Gain,
    /// For a lag, how it acts.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lag_form: Option<LagShape>,
    /// For a lag, its delay at low frequency [s] (a first-order lag's time constant, a delay's
    /// length, a second-order stage's 2ζ/ω_n): what every lag's value compares by.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lag_delay_s: Option<f64>,
    /// A sentence on what it means.
    pub explanation: String,
}

/// Simulated-velocity error on the held-out data.
#[derive(Clone, Debug, Serialize)]
pub struct SimulationRms {
    /// Base model [rad/s].
    pub base: f64,
    /// Extended model [rad/s].
    pub extended: f64,
    /// 100·(1 − extended/base).
    pub gain_percent: f64,
}

/// Periodic structure in the residual that no candidate explains.
#[derive(Clone, Debug, Serialize)]
pub struct Unexplained {
    /// What it looks like.
    pub description: String,
    /// Dominant frequency [Hz].
    pub frequency_hz: f64,
}

/// What the simulated velocity still shows and the acceleration equation does not confirm: an
/// effect that would be named on the simulation alone (rules 1–3 pass, the gain reaches
/// [`super::MIN_GAIN`]) but that rule 4 keeps out, and with which J or c2 would not agree with
/// the extended model's. The model does not explain the velocity, and its J and c2 depend on
/// what it lacks: the verdict is then unexplained, never explained.
#[derive(Clone, Debug, Serialize)]
pub struct SimulationOnly {
    /// The effect the simulation would take.
    pub effect: EffectKind,
    /// Its value, in [`EffectKind::unit`].
    pub value: f64,
    /// Its unit.
    pub unit: &'static str,
    /// How much lower the pooled held-out simulated-velocity error is with it [%].
    pub simulation_gain_percent: f64,
    /// How much lower the pooled held-out acceleration error is with it [%].
    pub equation_gain_percent: f64,
    /// J with it [kg·m²].
    pub inertia_with: f64,
    /// c2 (or its quadratic equivalent) with it [N·m·s²/rad²].
    pub c2_with: f64,
    /// Where the equation does gain with it, consistently over the folds as the simulation does,
    /// but its value is not resolved from zero (3 standard errors): that standard error. The
    /// model then lacks something these data show, which the effect stands in for at a value
    /// they cannot fix.
    pub value_stderr: Option<f64>,
}

/// `propid drive`'s default setpoint range, the seed's (`--setpoint-rat-lo-hi`).
const DRIVE_RANGE: (f64, f64) = (0.1, 0.9);

/// A `propid drive` run that shows an effect, or tells two apart.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SeparatingRun {
    /// `--pattern`.
    pub pattern: Pattern,
    /// The setpoint range's low end, when the run needs its own (a negative one reverses the
    /// rotor).
    pub lo: Option<f64>,
    /// The setpoint range's high end, when the run needs its own.
    pub hi: Option<f64>,
    /// What the run shows that these data do not.
    pub why: &'static str,
}

impl SeparatingRun {
    /// The advice in words: the `propid drive` command, and what it shows.
    pub fn advice(&self) -> String {
        format!("`propid drive {}`: {}", self.flags(), self.why)
    }

    /// The `propid drive` flags. The range is drive's one `--setpoint-rat-lo-hi` flag, the end
    /// not given at drive's default (`DRIVE_RANGE`), written with `=` so that a negative low end
    /// is not read as a flag.
    pub fn flags(&self) -> String {
        let mut s = format!("--pattern {}", self.pattern);
        if self.lo.is_some() || self.hi.is_some() {
            let lo = self.lo.unwrap_or(DRIVE_RANGE.0);
            let hi = self.hi.unwrap_or(DRIVE_RANGE.1);
            s += &format!(" --setpoint-rat-lo-hi=\"{lo} {hi}\"");
        }
        s
    }
}

/// A candidate with consistent held-out evidence below the threshold: not named, not a
/// verdict, and where to look. Listed only when the last round of the search named nothing.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NearMiss {
    /// Which effect.
    #[serde(rename = "name")]
    pub effect: EffectKind,
    /// Its estimate.
    pub value: f64,
    /// Unit of the estimate.
    pub unit: &'static str,
    /// Held-out acceleration gain [%].
    pub cv_gain_percent: f64,
    /// Held-out simulated-velocity gain [%] (positive: the simulation agrees).
    pub simulation_gain_percent: f64,
    /// The `propid drive` run that would show it more clearly, and why, in words.
    pub look_with: String,
    /// The same run as data.
    pub revealing_run: SeparatingRun,
}

/// J and c2 that do not depend on which of two ambiguous effects is chosen.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Agreed {
    /// Inertia [kg·m²].
    pub inertia: f64,
    /// Drag coefficient (its quadratic equivalent) [N·m·s²/rad²].
    pub c2: f64,
}

/// An effect's value in a model.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct EffectValue {
    /// Which effect.
    #[serde(rename = "name")]
    pub effect: EffectKind,
    /// Its value.
    pub value: f64,
    /// Its unit.
    pub unit: &'static str,
}

/// Two effects these data cannot tell apart: the first is in the extended model, the second
/// would explain the held-out data as well.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Ambiguity {
    /// The two effects, the one in the model first.
    pub between: [EffectKind; 2],
    /// Their estimates (the second from the model with it in place of the first).
    pub values: [f64; 2],
    /// Units of the estimates.
    pub units: [&'static str; 2],
    /// The lag the alternative model holds beside the second effect, when the data cannot tell
    /// the first from the two together (a constant torque, or a viscous friction and a lag);
    /// `None` when the second alone stands in place of the first.
    pub alongside: Option<EffectValue>,
    /// Held-out acceleration gains when they were tried [%] (for an alternative with a lag
    /// beside it: each model's over the model without the first).
    pub cv_gain_percent: [f64; 2],
    /// The extended model with the second in place of the first (its J, c2, drag law).
    pub alternative: BaseModel,
    /// The values of every effect of that model.
    pub alternative_effects: Vec<EffectValue>,
    /// J and c2 where the two models agree on them (within two standard errors or 0.5 %).
    pub agreed: Option<Agreed>,
    /// The `propid drive` run that would separate them, and why, in words.
    pub separate_with: String,
    /// The same run as data (for a program that acts on the advice).
    pub separating_run: SeparatingRun,
}

/// A parameter of the seed's model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Parameter {
    /// The inertia J.
    Inertia,
    /// The drag coefficient c2.
    Drag,
}

impl Parameter {
    /// Its symbol in reports.
    pub fn symbol(self) -> &'static str {
        match self {
            Parameter::Inertia => "J",
            Parameter::Drag => "c2",
        }
    }

    /// The run that would identify it.
    pub fn advice(self) -> &'static str {
        match self {
            Parameter::Inertia => "a run with larger accelerations would (`propid plan` designs one; `propid drive --pattern chirp` or `--pattern square`)",
            Parameter::Drag => "a run over a wider range of speeds would (`propid drive --pattern steps --setpoint-rat-lo-hi=\"0.02 0.9\"`)",
        }
    }
}

/// A parameter these data do not identify.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Unidentified {
    /// Which.
    pub parameter: Parameter,
    /// Its estimate.
    pub value: f64,
    /// Its standard error (NaN or infinite when none can be computed).
    pub stderr: f64,
    /// For J: how much higher than the truth least squares reads it because of the torque's own
    /// noise (`plausibility::torque_noise_bias`), when that is what leaves it unidentified.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub torque_noise_bias: Option<f64>,
}

/// Relative standard error above which a parameter is not identified.
pub const MAX_RELATIVE_STDERR: f64 = 0.3;

impl Unidentified {
    /// The parameters of `m` that are not identified: not positive, a standard error that is not
    /// a positive finite number, or one above [`MAX_RELATIVE_STDERR`] of the value.
    pub(crate) fn of(m: &BaseModel) -> Vec<Unidentified> {
        [
            (Parameter::Inertia, m.inertia, m.inertia_stderr),
            (Parameter::Drag, m.c2, m.c2_stderr),
        ]
        .into_iter()
        .filter(|&(_, v, se)| {
            !(v > 0.0 && se > 0.0 && se.is_finite() && se <= MAX_RELATIVE_STDERR * v)
        })
        .map(|(parameter, value, stderr)| Unidentified {
            parameter,
            value,
            stderr,
            torque_noise_bias: None,
        })
        .collect()
    }
}

/// Correlations of the base model's acceleration residual with candidate explanatory signals.
#[derive(Clone, Debug, Serialize)]
pub struct ResidualAnalysis {
    /// (signal name, correlation coefficient).
    pub correlations: Vec<(&'static str, f64)>,
    /// Frequency of the largest periodogram peak of the residual [Hz].
    pub dominant_frequency_hz: f64,
    /// That peak's power over the median power.
    pub peak_to_median: f64,
}

/// What the diagnosis concludes. Code that acts on a diagnosis matches on this, never on the
/// wording of a note.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Verdict {
    /// No candidate improves the held-out fit, no structure is left and J and c2 are
    /// identified: the seed's model explains these data.
    NothingWrong,
    /// Effects were named and no structure is left.
    Explained,
    /// Structure is left that no candidate explains (with or without named effects).
    Unexplained,
    /// Effects were named, but the data cannot tell one of them from another (see
    /// [`Report::ambiguities`]).
    Ambiguous,
    /// J or c2 is not identified by these data (see [`Report::unidentified`]): whatever else
    /// the report says, the model does not explain them.
    NotIdentified,
    /// The data cannot support a verdict; nothing else in the report is a conclusion.
    CannotJudge {
        /// Why.
        reasons: Vec<CannotJudge>,
    },
}

impl Verdict {
    /// Why the data cannot support a verdict, in one line (`None` for any other verdict).
    pub fn cannot_judge_reasons(&self) -> Option<String> {
        match self {
            Verdict::CannotJudge { reasons } => Some(
                reasons
                    .iter()
                    .map(|w| w.to_string())
                    .collect::<Vec<_>>()
                    .join("; "),
            ),
            _ => None,
        }
    }
}

/// The diagnosis.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// The verdict.
    pub verdict: Verdict,
    /// Samples analysed.
    pub samples: usize,
    /// Duration [s].
    pub duration_s: f64,
    /// Median sample rate [Hz].
    pub rate_hz: f64,
    /// The seed's model fitted to all the data.
    pub base: BaseModel,
    /// The named effects.
    pub effects: Vec<NamedEffect>,
    /// The extended model (base plus the named effects) fitted to all the data.
    pub extended: BaseModel,
    /// Simulated-velocity RMS before and after, on the held-out last 30 %.
    pub simulation_rms: SimulationRms,
    /// Periodic structure left, if any.
    pub unexplained: Option<Unexplained>,
    /// The residual analysis of the base model.
    pub residual_analysis: ResidualAnalysis,
    /// Every candidate tried, every round, with the selection's decision.
    pub candidates: Vec<CandidateScore>,
    /// The drag law from steady-state data, when the recording cannot identify the inertia
    /// (then `base.inertia` is null and the simulation fields are null).
    pub steady_state: Option<DragLaw>,
    /// Where the remaining held-out error of the extended model concentrates, if it does.
    pub concentration: Option<Concentration>,
    /// Where that concentration is an event in time: the span the extended model (its J, c2 and
    /// effects) was fitted without, and J and c2 with it.
    pub left_out: Option<LeftOut>,
    /// What the simulated velocity still shows that the equation does not confirm, where J or
    /// c2 move with it.
    pub simulation_only: Option<SimulationOnly>,
    /// The model asked about (`Options::compare`), fitted and scored beside the one named (null
    /// where none was asked about).
    pub compared: Option<super::Compared>,
    /// Effects the data cannot tell from one that is named.
    pub ambiguities: Vec<Ambiguity>,
    /// Candidates that came close to being named, best first.
    pub near_misses: Vec<NearMiss>,
    /// Parameters of the extended model these data do not identify.
    pub unidentified: Vec<Unidentified>,
    /// Share of the samples near steady state (|a|/2 < 1 % of |ω|).
    pub steady_share: f64,
    /// Notes about the data (steady-state data, missing columns, …).
    pub notes: Vec<String>,
    /// Series for plots (not serialised).
    #[serde(skip)]
    pub traces: Traces,
}

/// Time series for the plots.
#[derive(Clone, Debug, Default)]
pub struct Traces {
    /// Time of the held-out part [s].
    pub t: Vec<f64>,
    /// Measured velocity.
    pub measured: Vec<f64>,
    /// Base model, simulated open-loop.
    pub base: Vec<f64>,
    /// Extended model, simulated open-loop.
    pub extended: Vec<f64>,
    /// Time of all samples.
    pub t_all: Vec<f64>,
    /// Acceleration residual of the base model.
    pub residual_base: Vec<f64>,
    /// Acceleration residual of the extended model.
    pub residual_extended: Vec<f64>,
}

impl Report {
    /// A report that concludes nothing, for data the gate rejects.
    pub(crate) fn cannot_judge(
        samples: usize,
        duration_s: f64,
        reasons: Vec<CannotJudge>,
    ) -> Report {
        Report {
            verdict: Verdict::CannotJudge { reasons },
            samples,
            duration_s,
            rate_hz: f64::NAN,
            base: BaseModel::unknown(),
            effects: Vec::new(),
            extended: BaseModel::unknown(),
            simulation_rms: SimulationRms {
                base: f64::NAN,
                extended: f64::NAN,
                gain_percent: f64::NAN,
            },
            unexplained: None,
            residual_analysis: ResidualAnalysis {
                correlations: Vec::new(),
                dominant_frequency_hz: f64::NAN,
                peak_to_median: f64::NAN,
            },
            candidates: Vec::new(),
            steady_state: None,
            steady_share: f64::NAN,
            ambiguities: Vec::new(),
            near_misses: Vec::new(),
            unidentified: Vec::new(),
            concentration: None,
            left_out: None,
            simulation_only: None,
            compared: None,
            notes: Vec::new(),
            traces: Traces::default(),
        }
    }

    /// Whether the model asked about (`--compare`) does better on held-out data than the one
    /// named: the model named is then not the best these data support, and the report never says
    /// it explains them.
    pub fn asked_does_better(&self) -> bool {
        self.compared
            .as_ref()
            .is_some_and(|c| c.preferred == super::Preference::Asked)
    }

    /// The verdict from what the report holds, in order of what matters most to a user.
    pub(crate) fn conclude(&mut self) {
        if matches!(self.verdict, Verdict::CannotJudge { .. }) {
            return;
        }
        self.verdict = if !self.unidentified.is_empty() {
            Verdict::NotIdentified
        } else if !self.ambiguities.is_empty() {
            Verdict::Ambiguous
        } else if self.unexplained.is_some()
            || self.concentration.is_some()
            || self.left_out.is_some()
            || self.simulation_only.is_some()
            || self.asked_does_better()
        {
            Verdict::Unexplained
        } else if self.effects.is_empty() {
            Verdict::NothingWrong
        } else {
            Verdict::Explained
        };
    }
}

/// The drag law fitted from steady-state data (`steady`), when the inertia cannot be identified.
#[derive(Clone, Debug, Serialize)]
pub struct DragLaw {
    /// Samples used (finite torque, speed above 10 % of the top).
    pub samples: usize,
    /// c2 of the seed's law F = c2·ω² + F₀ [N·m·s²/rad²].
    pub c2: f64,
    /// Its standard error.
    pub c2_stderr: f64,
    /// Offset F₀ of the seed's law [N·m].
    pub offset: f64,
    /// Exponent of the extended law.
    pub exponent: f64,
    /// Its standard error.
    pub exponent_stderr: f64,
    /// k of the extended law [N·m·(s/rad)^p].
    pub k: f64,
    /// Pooled held-out gain of the extended law over the seed's [%].
    pub cv_gain_percent: f64,
    /// The selection's criterion.
    pub gain: Gain,
    /// RMS torque residual of the seed's law [N·m].
    pub rms_seed: f64,
    /// RMS torque residual of the extended law [N·m].
    pub rms_extended: f64,
    /// What the selection decided about the exponent.
    pub decision: Decision,
}
