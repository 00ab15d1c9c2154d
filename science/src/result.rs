//! The one Result every command that fits ends with (`fit`, `diagnose`, `report`, `demo`).
//!
//! J, c2 (c1 when it was free), the named effects, C_Q with the diameter and density it
//! was computed with, and C_T where the file has a thrust column — each with its statistical standard error **and** the spread across the
//! models the data could not rule out (the diagnosis's ambiguous alternatives) — the rows used
//! and dropped, the warnings, and the caveat no data can lift: a torque-constant error scales J
//! and c2 invisibly. [`Outcome`] is serialised by serde for JSON and rendered to YAML from the
//! same value ([`Outcome::to_yaml`]), so both carry the same keys, and every number loads as a
//! number in PyYAML. A value the data do not identify carries no standard error (never a 0, never
//! NaN) and is listed under `not_identified`.

use serde::Serialize;

use crate::diagnose::{Report, Verdict};
use crate::fit::{yaml_float, FitReport};

/// A float as [`yaml_float`] writes it, with the shortest mantissa that reads back to the same
/// f64 (the YAML's numbers equal the JSON's, bit for bit).
fn exact_float(v: f64) -> String {
    let digits = format!("{v:e}").split_once('e').map_or(0, |(m, _)| {
        m.trim_start_matches('-').len().saturating_sub(2)
    });
    yaml_float(v, digits)
}

/// Which model the Result's values are from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Model {
    /// The seed's model J·dω/dt = F − c1·ω − c2·ω|ω| (`propid fit`).
    Seed,
    /// The seed's model with the effects the diagnosis named (`propid diagnose`).
    Extended,
}

/// A value with its unit and uncertainties.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Value {
    /// The estimate.
    pub value: f64,
    /// Its unit.
    pub unit: &'static str,
    /// Statistical standard error (absent when the data do not identify the value).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stderr: Option<f64>,
    /// The largest difference to the value of the models the data could not rule out (absent
    /// when no model comparison was made: `propid fit`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model_spread: Option<f64>,
}

impl Value {
    fn new(value: f64, unit: &'static str, stderr: f64, model_spread: Option<f64>) -> Value {
        let identified = stderr > 0.0
            && stderr.is_finite()
            && stderr <= crate::plausibility::MAX_RELATIVE_STDERR * value.abs();
        Value {
            value,
            unit,
            stderr: identified.then_some(stderr),
            model_spread,
        }
    }

    fn scaled(&self, k: f64, unit: &'static str) -> Value {
        Value {
            value: self.value * k,
            unit,
            stderr: self.stderr.map(|s| s * k.abs()),
            model_spread: self.model_spread.map(|s| s * k.abs()),
        }
    }
}

/// A named effect of the extended model.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Effect {
    /// Its name (`torque_lag`, …).
    pub name: String,
    /// Its parameter.
    #[serde(flatten)]
    pub value: Value,
    /// What it means, in a sentence.
    pub explanation: String,
}

/// The propeller's geometry and air a coefficient was computed with.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Air {
    /// Diameter [m].
    pub diameter_m: f64,
    /// Air density [kg/m³].
    pub density_kg_m3: f64,
}

/// The thrust coefficient from the file's `thrust` column (the same identification as
/// `propid propulsion`'s).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Thrust {
    /// C_T = T/(ρ·n²·D⁵) (n in rev/s) at `speed_rpm`.
    pub c_t: Value,
    /// The speed C_T is quoted at [rpm] (the log-mean of the speeds measured).
    pub speed_rpm: f64,
    /// The exponent p of T ∝ n^p (2 where C_T does not change with speed).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub exponent: Option<Value>,
    /// How it was measured: means over steady plateaus, or row by row through the load cell's
    /// lag.
    pub method: crate::propulsion::Method,
}

/// Plausible torque coefficients C_Q = Q/(ρ n² D⁵) of propellers and fans (n in rev/s): a
/// value outside is a unit mistake far more often than a propeller.
pub const C_Q_RANGE: std::ops::RangeInclusive<f64> = 1e-4..=0.1;

/// The caveat every Result carries.
pub const TORQUE_CONSTANT_CAVEAT: &str = "J and c2 are in the torque column's units: a torque-constant (K_t) error r scales both by r and leaves no trace in the data; only a known inertia or a load cell checks it";

/// The Result.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Outcome {
    /// Which model the values are from.
    pub model: Model,
    /// The inertia J.
    pub inertia: Value,
    /// The quadratic drag coefficient c2 (for a drag law k·|ω|^p, its quadratic equivalent at
    /// the RMS speed).
    pub c2: Value,
    /// The viscous coefficient c1, when it was free.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub c1: Option<Value>,
    /// The effects named (empty for the seed's model).
    pub effects: Vec<Effect>,
    /// The torque coefficient C_Q = 4π²·c2/(ρ·D⁵), when a diameter was given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub c_q: Option<Value>,
    /// C_T, when the file has a thrust column and a diameter was given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub thrust: Option<Thrust>,
    /// The diameter and density C_Q and C_T used.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub air: Option<Air>,
    /// Whether the seed's model explains the data (absent when not tested: `propid fit`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed_model_holds: Option<bool>,
    /// Whether the diagnosis finds something the model lacks on which these values depend (a
    /// candidate both held-out errors, or the simulated velocity with J or c2 moving, would take
    /// but the rules do not name: `simulation_only`), or a model asked about does better
    /// (`--compare`): the values are then the model's best fit, not established. Absent when
    /// false.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub incomplete: bool,
    /// Parameters the data do not identify (their values are not measurements).
    pub not_identified: Vec<String>,
    /// Rows used.
    pub rows_used: u64,
    /// Rows dropped (incomplete, cut, or outside the seed's window).
    pub rows_dropped: u64,
    /// What to know before using the values.
    pub warnings: Vec<String>,
    /// [`TORQUE_CONSTANT_CAVEAT`].
    pub caveat: &'static str,
}

const J_UNIT: &str = "kg·m²";
const C2_UNIT: &str = "N·m·s²/rad²";

impl Outcome {
    /// The Result of the seed's fit.
    pub fn from_fit(fit: &FitReport, c1_free: bool, air: Option<Air>) -> Outcome {
        // A parameter the fit lists as not identified (on its bound: the error of the fit
        // without bounds is no precision of a bound) carries no statistical error here.
        let value = |name: &str, v: f64, unit: &'static str, stderr: f64| {
            let mut x = Value::new(v, unit, stderr, None);
            if fit.not_identified.contains(&name) {
                x.stderr = None;
            }
            x
        };
        let mut out = Outcome {
            model: Model::Seed,
            inertia: value("mass", fit.mass, J_UNIT, fit.mass_stderr),
            c2: value("c2", fit.c2, C2_UNIT, fit.c2_stderr),
            c1: c1_free.then(|| value("c1", fit.c1, "N·m·s/rad", fit.c1_stderr)),
            effects: Vec::new(),
            c_q: None,
            thrust: None,
            air: None,
            seed_model_holds: None,
            incomplete: false,
            // The Result calls the inertia J, as diagnose's does (the seed's YAML: mass).
            not_identified: fit
                .not_identified
                .iter()
                .map(|&s| if s == "mass" { "J" } else { s }.to_string())
                .collect(),
            rows_used: fit.samples,
            rows_dropped: fit.rows.saturating_sub(fit.samples),
            warnings: fit.warnings.clone(),
            caveat: TORQUE_CONSTANT_CAVEAT,
        };
        out.warnings.push(
            "the seed's model only: `propid diagnose` tests whether it explains the data and gives the spread across the models the data cannot rule out".into(),
        );
        out.finish(air);
        out
    }

    /// The Result of a diagnosis (`None` when it could not judge). `rows_dropped` counts the
    /// rows the reader dropped before the diagnosis saw them.
    pub fn from_diagnosis(r: &Report, rows_dropped: u64, air: Option<Air>) -> Option<Outcome> {
        if matches!(r.verdict, Verdict::CannotJudge { .. }) {
            return None;
        }
        let ext = &r.extended;
        // The spread across the models the data could not rule out: each ambiguity's
        // alternative, against the extended model.
        let spread = |f: &dyn Fn(&crate::diagnose::BaseModel) -> f64| {
            r.ambiguities
                .iter()
                .map(|a| (f(&a.alternative) - f(ext)).abs())
                .filter(|d| d.is_finite())
                .fold(0.0, f64::max)
        };
        let effects = r
            .effects
            .iter()
            .map(|e| {
                // An alternative without the effect reads it as zero (a twin in its place, or
                // a term and a lag).
                let alternatives = r
                    .ambiguities
                    .iter()
                    .map(|a| {
                        a.alternative_effects
                            .iter()
                            .find(|v| v.effect == e.effect)
                            .map_or(e.value.abs(), |v| (v.value - e.value).abs())
                    })
                    .filter(|d| d.is_finite())
                    .fold(0.0, f64::max);
                Effect {
                    name: e.effect.name().to_string(),
                    value: Value::new(e.value, e.unit, e.stderr, Some(alternatives)),
                    explanation: e.explanation.clone(),
                }
            })
            .collect();
        let mut out = Outcome {
            model: Model::Extended,
            inertia: Value::new(
                ext.inertia,
                J_UNIT,
                ext.inertia_stderr,
                Some(spread(&|m| m.inertia)),
            ),
            c2: Value::new(ext.c2, C2_UNIT, ext.c2_stderr, Some(spread(&|m| m.c2))),
            c1: None,
            effects,
            c_q: None,
            thrust: None,
            air: None,
            seed_model_holds: Some(r.verdict == Verdict::NothingWrong),
            incomplete: r.simulation_only.is_some() || r.asked_does_better(),
            not_identified: r
                .unidentified
                .iter()
                .map(|u| u.parameter.symbol().to_string())
                .collect(),
            rows_used: r.samples as u64,
            rows_dropped,
            warnings: r.notes.clone(),
            caveat: TORQUE_CONSTANT_CAVEAT,
        };
        if let Some(l) = &r.left_out {
            out.warnings
                .push(crate::diagnose::left_out_sentence(l, &r.extended));
        }
        if let Some(o) = &r.simulation_only {
            out.warnings
                .push(crate::diagnose::simulation_only_sentence(o, &r.extended));
        }
        if !r.ambiguities.is_empty() {
            out.warnings.push(format!(
                "the data cannot rule out {} other model(s): model_spread is how far their values lie from these",
                r.ambiguities.len()
            ));
        }
        out.finish(air);
        Some(out)
    }

    /// Adds C_T from the recording's `thrust` column (a recording without one changes nothing),
    /// by the identification `propid propulsion` makes (steady plateaus where there are three,
    /// else row by row through the load cell's lag). Without a diameter, or where C_T cannot be
    /// judged, a warning says so; a C_T the data do not pin down is listed as not identified; one
    /// outside what propellers have warns with the unit mistakes that would explain it.
    pub fn add_thrust(&mut self, rec: &crate::propulsion::Recording) {
        use crate::propulsion::{self as p, Quantity};
        if rec.thrust.is_none() {
            return;
        }
        let Some(air) = self.air else {
            self.warnings.push(
                "the file has a `thrust` column: give --diameter (7in, 0.1778m) for its C_T".into(),
            );
            return;
        };
        let identified = p::Air::with_density(air.density_kg_m3, None)
            .and_then(|a| p::identify(rec, &p::Options::at(air.diameter_m, a)));
        let coefficient = match identified {
            Ok(r) => r.thrust,
            Err(why) => {
                self.warnings.push(format!("no C_T: {why}"));
                return;
            }
        };
        let Some(c) = coefficient else { return };
        let value = |q: &Quantity| match q {
            Quantity::Identified { value, stderr, .. } => Some(Value {
                value: *value,
                unit: "1",
                stderr: Some(*stderr),
                model_spread: None,
            }),
            Quantity::NotIdentified { value, .. } => Some(Value {
                value: *value,
                unit: "1",
                stderr: None,
                model_spread: None,
            }),
            Quantity::CannotJudge { .. } => None,
        };
        let Some(c_t) = value(&c.at_reference) else {
            if let Quantity::CannotJudge { reason, .. } = &c.at_reference {
                self.warnings.push(format!("no C_T: {reason}"));
            }
            return;
        };
        if let Quantity::NotIdentified { reason, .. } = &c.at_reference {
            self.not_identified.push("C_T".into());
            self.warnings
                .push(format!("C_T is not identified: {reason}"));
        }
        if let Some(w) = p::plausibility(p::Kind::Thrust, c_t.value, air.diameter_m) {
            self.warnings.push(w);
        }
        self.thrust = Some(Thrust {
            c_t,
            speed_rpm: c.reference_speed * 60.0,
            exponent: value(&c.exponent).map(|e| Value { unit: "1", ..e }),
            method: c.method,
        });
    }

    /// C_Q and its range check; every parameter without a standard error listed.
    fn finish(&mut self, air: Option<Air>) {
        for (name, v) in [("J", &self.inertia), ("c2", &self.c2)] {
            if v.stderr.is_none() && !self.not_identified.iter().any(|n| n == name) {
                self.not_identified.push(name.to_string());
            }
        }
        let Some(air) = air else { return };
        let k = 4.0 * std::f64::consts::PI.powi(2) / (air.density_kg_m3 * air.diameter_m.powi(5));
        let c_q = self.c2.scaled(k, "1");
        self.warnings.extend(c_q_warning(c_q.value, air.diameter_m));
        self.c_q = Some(c_q);
        self.air = Some(air);
    }

    /// The Result as text for a person.
    pub fn to_text(&self) -> String {
        let v = |name: &str, x: &Value| {
            if !x.value.is_finite() {
                // JSON and YAML carry it as null.
                return format!("   {name:<4} = – [{}] (these data give no value)\n", x.unit);
            }
            let mut s = format!("   {name:<4} = {:.4e}", x.value);
            if x.unit != "1" {
                s += &format!(" {}", x.unit);
            }
            match x.stderr {
                Some(se) => s += &format!(" ± {se:.2e} (statistical)"),
                None => s += " (not identified by these data)",
            }
            match x.model_spread {
                Some(m) if m > 0.0 => s += &format!(" ± {m:.2e} (models the data cannot rule out)"),
                Some(_) => s += ", no other model fits as well",
                None => {}
            }
            s + "\n"
        };
        let mut s = match self.model {
            Model::Seed => "Result (the seed's model)".to_string(),
            Model::Extended if self.effects.is_empty() => {
                "Result (the seed's model, tested)".into()
            }
            Model::Extended => format!(
                "Result (the seed's model with {})",
                self.effects
                    .iter()
                    .map(|e| e.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        s += &format!(
            ": {} of {} rows used\n",
            self.rows_used,
            self.rows_used + self.rows_dropped
        );
        s += &v("J", &self.inertia);
        s += &v("c2", &self.c2);
        if let Some(c1) = &self.c1 {
            s += &v("c1", c1);
        }
        for e in &self.effects {
            s += &v(&e.name, &e.value);
        }
        if let (Some(c_q), Some(air)) = (&self.c_q, &self.air) {
            s += &v("C_Q", c_q);
            s += &format!(
                "        (Q = C_Q·ρ·n²·D⁵, n in rev/s) with D = {:.4} m ({:.2} in), ρ = {:.4} kg/m³\n",
                air.diameter_m,
                air.diameter_m / 0.0254,
                air.density_kg_m3
            );
            if let Some(w) = c_q_warning(c_q.value, air.diameter_m) {
                s += &format!("        Warning: {w}\n");
            }
        }
        if let Some(t) = &self.thrust {
            s += &v("C_T", &t.c_t);
            s += &format!(
                "        (T = C_T·ρ·n²·D⁴) at {:.0} rpm, from {}{}\n",
                t.speed_rpm,
                match t.method {
                    crate::propulsion::Method::Plateaus => "steady plateaus",
                    crate::propulsion::Method::Dynamic => "every load-cell reading through its lag",
                },
                match &t.exponent {
                    Some(p) => format!("; thrust ∝ n^{:.2}", p.value),
                    None => String::new(),
                }
            );
        }
        match self.seed_model_holds {
            _ if self.incomplete => {
                s += "   The model does not explain these data: these values are its best fit, not established (the diagnosis below says what it lacks).\n"
            }
            Some(true) => s += "   The seed's model explains these data.\n",
            Some(false) if !self.effects.is_empty() => {
                s += "   The seed's model is wrong on these data: use these extended values, not `propid fit`'s.\n"
            }
            _ => {}
        }
        if !self.not_identified.is_empty() {
            s += &format!(
                "   Not identified (values are not measurements): {}\n",
                self.not_identified.join(", ")
            );
        }
        s += &format!("   Caveat: {}.\n", self.caveat);
        s
    }

    /// The Result as YAML with the JSON's keys; every number loads as a number in YAML 1.1
    /// readers (PyYAML) and 1.2 readers alike.
    pub fn to_yaml(&self) -> String {
        let value = serde_json::to_value(self).unwrap_or(serde_json::Value::Null);
        let mut out = String::new();
        yaml(&value, 0, &mut out);
        out
    }
}

/// Block-style YAML of a JSON value at `indent`: maps and lists on their own lines, floats by
/// [`yaml_float`], strings JSON-quoted (a JSON string is a YAML double-quoted scalar).
fn yaml(v: &serde_json::Value, indent: usize, out: &mut String) {
    use serde_json::Value as J;
    let pad = " ".repeat(indent);
    let scalar = |v: &J| -> String {
        match v {
            J::Number(n) if n.is_f64() => exact_float(n.as_f64().unwrap_or(f64::NAN)),
            J::Number(n) => n.to_string(),
            J::String(s) => serde_json::to_string(s).unwrap_or_default(),
            J::Bool(b) => b.to_string(),
            J::Null => "null".into(),
            J::Array(a) if a.is_empty() => "[]".into(),
            J::Object(o) if o.is_empty() => "{}".into(),
            _ => String::new(),
        }
    };
    let nested = |v: &J| {
        matches!(v, J::Array(a) if !a.is_empty()) || matches!(v, J::Object(o) if !o.is_empty())
    };
    match v {
        J::Object(map) => {
            for (k, x) in map {
                if nested(x) {
                    out.push_str(&format!("{pad}{k}:\n"));
                    yaml(x, indent + 2, out);
                } else {
                    out.push_str(&format!("{pad}{k}: {}\n", scalar(x)));
                }
            }
        }
        J::Array(items) => {
            for x in items {
                if nested(x) {
                    let mut inner = String::new();
                    yaml(x, indent + 2, &mut inner);
                    // "- " takes the place of the first line's indentation.
                    let inner = inner.replacen(&format!("{pad}  "), &format!("{pad}- "), 1);
                    out.push_str(&inner);
                } else {
                    out.push_str(&format!("{pad}- {}\n", scalar(x)));
                }
            }
        }
        x => out.push_str(&format!("{pad}{}\n", scalar(x))),
    }
}

impl Outcome {
    /// One line: J, c2 and C_Q with its diameter (the demo's closing line).
    pub fn headline(&self) -> String {
        let mut s = format!(
            "J = {:.4e} kg·m², c2 = {:.4e} N·m·s²/rad² ({})",
            self.inertia.value,
            self.c2.value,
            match self.model {
                Model::Seed => "the seed's model".to_string(),
                Model::Extended if self.effects.is_empty() => "the seed's model, tested".into(),
                Model::Extended => format!(
                    "with {}",
                    self.effects
                        .iter()
                        .map(|e| format!("{} = {:.4e} {}", e.name, e.value.value, e.value.unit))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            }
        );
        if let (Some(c_q), Some(air)) = (&self.c_q, &self.air) {
            s += &format!(
                ", C_Q = {:.4e} at D = {:.4} m ({:.2} in), ρ = {:.4} kg/m³",
                c_q.value,
                air.diameter_m,
                air.diameter_m / 0.0254,
                air.density_kg_m3
            );
        }
        s
    }
}

/// The warning a C_Q outside what propellers have earns (None inside it), with the unit mistake
/// that would explain it: a diameter in inches read as metres makes C_Q about 10⁸ times too small;
/// one given too small (7mm for 7in) makes it too large by the factor's fifth power.
fn c_q_warning(c_q: f64, diameter_m: f64) -> Option<String> {
    if C_Q_RANGE.contains(&c_q) {
        return None;
    }
    let d = format!("{diameter_m:.6}");
    let d = d.trim_end_matches('0').trim_end_matches('.');
    let why = if c_q < *C_Q_RANGE.start() {
        format!(
            "a diameter in inches read as metres makes C_Q about 10⁸ times too small: --diameter {d}in if inches were meant"
        )
    } else {
        "a diameter given too small by a factor f makes C_Q f⁵ times too large; 7mm for 7in is f = 25.4".to_string()
    };
    Some(format!(
        "C_Q = {c_q:.3e} is outside {:e}–{:e}, where propellers lie: is the diameter {d} m right? ({why})",
        C_Q_RANGE.start(),
        C_Q_RANGE.end(),
    ))
}
