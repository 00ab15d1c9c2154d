//! A model the engineer asks about, scored beside the one the diagnosis names.
//!
//! The search names the model the held-out data prefer among those it reaches one step at a
//! time. An engineer often has a model in mind (the stand's datasheet says the load cell is
//! filtered; a colleague suspects braking): `propid diagnose --compare force_sensor_lag,drag_exponent`
//! fits that model as the search would fit it (each effect tuned on the others, the nonlinear
//! parameters re-tuned jointly, the effects added best first) and scores it on the same folds by
//! the same criterion ([`super::select`]): the answer is which of the two models the data prefer,
//! or that they cannot tell them apart, never a new verdict. Where the data prefer the model asked
//! about, the search did not reach a better model, and the report says so.

use serde::Serialize;

use crate::propulsion::quantity::with_unit;

use super::candidate::{separating_run, EffectKind, Enters, Inadmissible, Shape, Slot};
use super::report::{BaseModel, EffectValue, SeparatingRun};
use super::select::{Gain, NEAR_MISS_GAIN};

/// The effects of a model asked about: a set of the effects the search tries in the equation, at
/// most one lag (a model holds one), parsed from their names separated by commas.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EffectSet(u32);

impl EffectSet {
    /// No effect: the seed's model.
    pub const EMPTY: EffectSet = EffectSet(0);

    /// Its bit: the kind's place among the variants (a fieldless enum; at most 32 of them).
    fn bit(kind: EffectKind) -> u32 {
        const _: () = assert!(EffectKind::ALL.len() <= 32);
        1 << kind as u32
    }

    /// Whether it holds `kind`.
    pub fn contains(self, kind: EffectKind) -> bool {
        self.0 & Self::bit(kind) != 0
    }

    /// Whether it holds no effect.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// Its effects, in the order the search tries them.
    pub fn iter(self) -> impl Iterator<Item = EffectKind> {
        EffectKind::ALL
            .iter()
            .copied()
            .filter(move |k| self.contains(*k))
    }

    /// The set with `kind` added, or why a model asked about cannot hold it.
    pub fn with(self, kind: EffectKind) -> Result<EffectSet, String> {
        if self.contains(kind) {
            return Err(format!("`{kind}` is named twice"));
        }
        match kind.candidate().enters() {
            Enters::Equation => {}
            Enters::Rows(_) => {
                return Err(format!(
                    "`{kind}` is measured from the rows before any model is fitted, not compared (give effects of the acceleration equation: {})",
                    searched_names()
                ))
            }
            Enters::Probe => {
                return Err(format!(
                    "`{kind}` is the probe for structure no effect explains, not an effect a model holds (give effects of the acceleration equation: {})",
                    searched_names()
                ))
            }
        }
        if kind.candidate().slot() == Slot::Lag {
            if let Some(other) = self.iter().find(|k| k.candidate().slot() == Slot::Lag) {
                return Err(format!(
                    "`{other}` and `{kind}` are both lags, and a model holds one"
                ));
            }
        }
        Ok(EffectSet(self.0 | Self::bit(kind)))
    }
}

fn searched_names() -> String {
    EffectKind::searched()
        .map(EffectKind::name)
        .collect::<Vec<_>>()
        .join(", ")
}

impl std::str::FromStr for EffectSet {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let mut set = EffectSet::EMPTY;
        for name in text.split(',').map(str::trim) {
            if name.is_empty() {
                return Err(format!(
                    "`{text}` has an empty name: give effects separated by commas ({})",
                    searched_names()
                ));
            }
            let kind: EffectKind = name
                .parse()
                .map_err(|e| format!("{e}: the effects are {}", searched_names()))?;
            set = set.with(kind)?;
        }
        Ok(set)
    }
}

impl std::fmt::Display for EffectSet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<&str> = self.iter().map(EffectKind::name).collect();
        f.write_str(&names.join(","))
    }
}

/// Which of two models the held-out data prefer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Preference {
    /// It holds the effects of the model named (its values may differ where the search reached
    /// them by another path).
    Same,
    /// The model asked about: the data separate it from the one named, in its favour (the
    /// selection's rule 5); the search did not reach it.
    Asked,
    /// The model named: the data separate it from the one asked about, in its favour.
    Named,
    /// Neither: the data cannot tell the two apart.
    Neither,
}

/// An effect of the model asked about whose fitted value cannot be the effect.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct NotAdmissible {
    /// Which effect.
    pub effect: EffectKind,
    /// Why its value cannot be it (serialised beside the effect: `why` and its figures).
    #[serde(flatten)]
    pub why: Inadmissible,
}

/// The model asked about, fitted and scored beside the one named.
#[derive(Clone, Debug, Serialize)]
pub struct Compared {
    /// The effects asked for.
    pub asked: Vec<EffectKind>,
    /// Its effects with the values these data give them (as the search tunes and fits them).
    pub effects: Vec<EffectValue>,
    /// Those of its effects whose fitted value cannot be the effect (a negative lag, a friction
    /// that drives the rotor), with why.
    pub inadmissible: Vec<NotAdmissible>,
    /// J and c2 under it.
    pub model: BaseModel,
    /// Its held-out gain over the model named (the selection's criterion: positive where it
    /// does better).
    pub gain: Gain,
    /// The acceleration equation's part of that gain.
    pub equation: Gain,
    /// The simulated velocity's part.
    pub simulation: Option<Gain>,
    /// Which of the two the data prefer.
    pub preferred: Preference,
    /// The run that would separate the two models (by an effect one holds and the other does
    /// not); `None` where they hold the same effects.
    pub separating_run: Option<SeparatingRun>,
}

impl Compared {
    /// The report's lines on it.
    pub fn text(&self) -> String {
        let asked: Vec<&str> = self.asked.iter().map(|k| k.name()).collect();
        let asked = asked.join(",");
        let values: Vec<String> = self
            .effects
            .iter()
            .map(|e| format!("{} = {:.4e}{}", e.effect, e.value, with_unit(e.unit)))
            .collect();
        let mut s = format!(
            "\n5. The model asked about (--compare {asked}), fitted and scored as the search would:\n   {}\n   J = {:.4e} kg·m², c2 = {:.4e} N·m·s²/rad²\n",
            if values.is_empty() {
                "the seed's model alone".to_string()
            } else {
                values.join(", ")
            },
            self.model.inertia,
            self.model.c2
        );
        for n in &self.inadmissible {
            s += &format!("   {}: {}\n", n.effect, n.why);
        }
        if self.preferred == Preference::Same {
            s += "   It holds the effects of the model named.\n";
            return s;
        }
        let run = |what: &str| {
            self.separating_run
                .as_ref()
                .map_or(String::new(), |r| format!(" {what}: {}.", r.advice()))
        };
        s += &format!(
            "   Its held-out gain over the model named: {:+.3} ± {:.3} (equation {:+.3}, simulation {}), better in {}/{} folds: {}.{}\n",
            self.gain.mean,
            self.gain.stderr,
            self.equation.mean,
            self.simulation
                .map_or("–".to_string(), |g| format!("{:+.3}", g.mean)),
            self.gain.folds_better,
            super::FOLDS,
            match self.preferred {
                Preference::Asked if self.equation.mean < NEAR_MISS_GAIN => format!(
                    "the data prefer it by the simulated velocity, but the acceleration equation gains under the {:.1} % the \
                     selection asks of an effect it names (rule 4): the model named is not the best these data support, and \
                     this one is not confirmed",
                    NEAR_MISS_GAIN * 100.0
                ),
                Preference::Asked => "the data prefer it: the search did not reach this model, and the model named is not \
                                      the best these data support"
                    .to_string(),
                Preference::Named => "the data prefer the model named".to_string(),
                Preference::Neither | Preference::Same => "the data cannot tell the two apart".to_string(),
            },
            match self.preferred {
                Preference::Neither => run("To separate them"),
                Preference::Asked if self.equation.mean < NEAR_MISS_GAIN => run("To confirm it"),
                _ => String::new(),
            }
        );
        s
    }
}

/// The run that separates two models, from the effects only the first holds and those only
/// the second holds: of two such effects, a pair that is not two constant torques first (a
/// Coulomb friction against an offset is a twin the reversing run settles; an exponent beside the
/// offset is what the models differ by); where only one model holds more, the run that reveals
/// its first such effect; `None` where they hold the same effects.
pub(crate) fn run_between(
    first_only: &[EffectKind],
    second_only: &[EffectKind],
) -> Option<SeparatingRun> {
    let constant = |k: EffectKind| matches!(k.candidate().shape(), Shape::Constant { .. });
    first_only
        .iter()
        .flat_map(|&a| second_only.iter().map(move |&b| (a, b)))
        .min_by_key(|&(a, b)| constant(a) && constant(b))
        .map(|(a, b)| separating_run(a, b))
        .or_else(|| {
            first_only
                .iter()
                .chain(second_only)
                .next()
                .map(|k| k.candidate().revealing_run())
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_set_parses_from_names_separated_by_commas() {
        let set: EffectSet = "drag_exponent, force_sensor_lag".parse().unwrap();
        assert_eq!(
            set.iter().collect::<Vec<_>>(),
            [EffectKind::DragExponent, EffectKind::ForceSensorLag]
        );
        assert_eq!(set.to_string(), "drag_exponent,force_sensor_lag");
    }

    #[test]
    fn the_separating_run_is_for_what_the_models_differ_by() {
        use EffectKind::*;
        // A Coulomb friction against an offset and an exponent: the exponent's run (low speeds),
        // not the twins' reversing one.
        let run = run_between(&[CoulombFriction], &[ForceOffset, DragExponent]).unwrap();
        assert_eq!(
            run.flags(),
            "--pattern steps --setpoint-rat-lo-hi=\"0.02 0.9\""
        );
        assert_eq!(
            run_between(&[CoulombFriction], &[ForceOffset])
                .unwrap()
                .flags(),
            "--pattern chirp --setpoint-rat-lo-hi=\"-0.5 0.9\""
        );
        // One model holds more: the run that reveals it.
        assert_eq!(
            run_between(&[], &[TorqueLag]).map(|r| r.flags()),
            Some(TorqueLag.candidate().revealing_run().flags())
        );
        assert!(run_between(&[], &[]).is_none());
    }

    #[test]
    fn a_set_refuses_what_a_model_cannot_hold() {
        let err = |t: &str| t.parse::<EffectSet>().unwrap_err();
        assert!(err("viscous")
            .starts_with("unknown effect `viscous`: the effects are coulomb_friction"));
        assert_eq!(
            err("torque_lag,force_sensor_lag"),
            "`torque_lag` and `force_sensor_lag` are both lags, and a model holds one"
        );
        assert_eq!(
            err("force_offset,force_offset"),
            "`force_offset` is named twice"
        );
        assert!(err("time_base").starts_with("`time_base` is measured from the rows"));
        assert!(err("force_offset,").contains("has an empty name"));
    }
}
