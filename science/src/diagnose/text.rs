//! The diagnosis as text and as plots, rendered from the typed report.

use super::report::{BaseModel, SimulationOnly};
use super::select::Decision;
use super::structure::{Condition, LeftOut};
use super::EffectKind;
use super::{Report, Verdict};
use crate::figure::{Figure, Panel, Series, Style};
use crate::propulsion::quantity::with_unit;

/// A readable report.
pub fn to_text(r: &Report, source: &str) -> String {
    let mut s = String::new();
    if let Verdict::CannotJudge { reasons } = &r.verdict {
        s += &format!(
            "propid diagnose {source}: {} samples over {:.1} s\n\ncannot judge: {}\n",
            r.samples,
            r.duration_s,
            reasons
                .iter()
                .map(|w| w.to_string())
                .collect::<Vec<_>>()
                .join("; ")
        );
        for n in &r.notes {
            s += &format!("   Note: {n}\n");
        }
        return s;
    }
    let b = &r.base;
    s += &format!(
        "propid diagnose {source}: {} samples over {:.1} s at {:.0} Hz\n\n",
        r.samples, r.duration_s, r.rate_hz
    );
    // Steady-state data (a slow load cell on held plateaus): the drag law alone, no dynamics.
    let steady = r.steady_state.as_ref().filter(|_| !b.inertia.is_finite());
    if let Some(law) = steady {
        s += "1. Base model (the seed's) on steady-state data: F = c2·ω² + F₀ (no dynamics: J is not identified)\n";
        s += &format!(
            "   c2 = {:.4e} ± {:.1e} N·m·s²/rad², F₀ = {:.3e} N·m, from {} torque samples above 10 % of the top speed;\n   \
             torque residual {:.3e} N·m RMS.\n\n",
            b.c2, b.c2_stderr, law.offset, law.samples, r.simulation_rms.base
        );
    } else {
        s += "1. Base model (the seed's): J·dω/dt = F − c2·ω|ω|, c1 = 0\n";
        s += &format!(
            "   J  = {:.4e} ± {:.1e} kg·m²\n   c2 = {:.4e} ± {:.1e} N·m·s²/rad²\n",
            b.inertia, b.inertia_stderr, b.c2, b.c2_stderr
        );
        s += &format!(
            "   What the simulation gets wrong: simulated open-loop from the measured force, its velocity\n   \
             misses the measured one by {:.3} rad/s RMS on the held-out last 30 % of the data.\n\n",
            r.simulation_rms.base
        );
    }
    s += "2. Residual of the base model, correlation with:\n";
    for (name, c) in &r.residual_analysis.correlations {
        s += &format!("   {name:<26} {c:+.3}\n");
    }
    if r.residual_analysis.dominant_frequency_hz.is_finite() {
        s += &format!(
            "   dominant frequency {:.3} Hz ({:.0}× the median of the spectrum)\n\n",
            r.residual_analysis.dominant_frequency_hz, r.residual_analysis.peak_to_median
        );
    } else {
        s += "   (no residual in time: the steady-state data are fitted as a torque law)\n\n";
    }
    s += "3. Candidate effects, searched in rounds: each tried on the model of the rounds before, scored on\n   \
          held-out data (blocked 10-fold cross-validation: the acceleration equation's error and the open-loop\n   \
          simulated velocity's; equation and simulation: how much lower each pooled held-out error is, negative\n   \
          when higher; gain = mean over the folds of the drop in the sum of their logs ± its standard error, and\n   \
          in how many folds that sum drops: a gain can be consistent while one pooled error rises):\n";
    let mut round = usize::MAX;
    for c in &r.candidates {
        if c.round != round {
            round = c.round;
            s += &if round == 0 {
                "   measured from the rows before the fit:\n".to_string()
            } else {
                format!("   round {round}:\n")
            };
        }
        let dash = |x: f64, unit: &str| {
            if x.is_finite() {
                format!("{x:+7.2} %{unit}")
            } else {
                format!("{:>9}{unit}", "–")
            }
        };
        let value = if c.value.is_finite() {
            format!("{:.4e}{}", c.value, with_unit(c.effect.unit()))
        } else {
            "–".into()
        };
        let gain = if c.gain.mean.is_finite() {
            format!(
                "{:+.3} ± {:.3}, {}/{} folds",
                c.gain.mean,
                c.gain.stderr,
                c.gain.folds_better,
                super::FOLDS
            )
        } else {
            "–".into()
        };
        s += &format!(
            "     {:<20} equation {}  simulation {}  gain {gain:<28} value {value:<20} {}\n",
            c.effect.name(),
            dash(c.cv_gain_percent, ""),
            dash(c.simulation_gain_percent, ""),
            decision_words(c.effect, &c.decision)
        );
    }
    s += "\n4. Verdict\n";
    for u in &r.unidentified {
        s += &match u.torque_noise_bias {
            Some(bias) => format!(
                "   These data do not identify {0} ({0} = {1:.4e}): {2}.\n",
                u.parameter.symbol(),
                u.value,
                crate::plausibility::torque_noise_corrected_words(u.parameter.symbol(), bias)
            ),
            None if !u.value.is_finite() => format!(
                "   These data do not identify {}: they give no value of it; {}.\n",
                u.parameter.symbol(),
                u.parameter.advice()
            ),
            None => format!(
                "   These data do not identify {}: {} = {:.4e} ± {:.1e} (more than {:.0} % of it, or no finite error); {}.\n",
                u.parameter.symbol(),
                u.parameter.symbol(),
                u.value,
                u.stderr,
                super::MAX_RELATIVE_STDERR * 100.0,
                u.parameter.advice()
            ),
        };
    }
    let identified = r.unidentified.is_empty();
    if r.effects.is_empty()
        && r.ambiguities.is_empty()
        && r.unexplained.is_none()
        && r.concentration.is_none()
        && r.simulation_only.is_none()
        && !r.asked_does_better()
    {
        if r.near_misses.is_empty() && identified {
            s += "   Nothing is wrong: no candidate effect improves the held-out fit, and the residual has no\n   structure left. The seed's model explains this data.\n";
        } else if r.near_misses.is_empty() {
            s += "   No candidate effect improves the held-out fit, and the residual has no structure left.\n";
        } else {
            s += &format!(
                "   Nothing is named: no candidate reaches the held-out threshold ({:.2}), and the residual has no\n   \
                 structure left. Close to it (consistent across the folds, the simulation agreeing; evidence, not a verdict):\n",
                super::MIN_GAIN
            );
        }
    } else if !r.near_misses.is_empty() {
        s += "   Close to being named as well (consistent across the folds, the simulation agreeing; evidence, not a verdict):\n";
    }
    for m in &r.near_misses {
        let unit = with_unit(m.unit);
        s += &format!(
            "     {} = {:.4e}{unit}: held-out gain {:.2} %, simulated velocity {:+.1} %\n",
            m.effect, m.value, m.cv_gain_percent, m.simulation_gain_percent
        );
    }
    // The runs that would show them, each once, with the near misses it is for.
    let mut runs: Vec<(&str, Vec<&str>)> = Vec::new();
    for m in &r.near_misses {
        match runs.iter_mut().find(|(look, _)| *look == m.look_with) {
            Some((_, names)) => names.push(m.effect.name()),
            None => runs.push((&m.look_with, vec![m.effect.name()])),
        }
    }
    for (look, names) in runs {
        s += &format!("     To see {}: {look}.\n", names.join(", "));
    }
    for e in &r.effects {
        s += &format!(
            "   {}: {} = {:.4e} ± {:.1e} {}\n     {}\n     alone it improves the simulated velocity by {:.1} % on the held-out last 30 %\n",
            e.effect, e.effect, e.value, e.stderr, e.unit, e.explanation, e.gain_percent
        );
    }
    for a in &r.ambiguities {
        let beside = a.alongside.as_ref().map_or(String::new(), |l| {
            format!(" with {} = {:.4e} {}", l.effect, l.value, l.unit)
        });
        s += &format!(
            "   Ambiguous: {} = {:.4e} {} (in the model) or {} = {:.4e} {}{beside}: the held-out data cannot tell the two\n   \
             apart (gains {:.2} % and {:.2} % on the acceleration, and no significant difference in the simulation). ",
            a.between[0], a.values[0], a.units[0], a.between[1], a.values[1], a.units[1],
            a.cv_gain_percent[0], a.cv_gain_percent[1]
        );
        s += &match a.agreed {
            Some(x) => format!(
                "Either way J = {:.4e} kg·m² and c2 = {:.4e} N·m·s²/rad². ",
                x.inertia, x.c2
            ),
            None => format!(
                "With the first J = {:.4e}, c2 = {:.4e}; with the second J = {:.4e}, c2 = {:.4e}. ",
                r.extended.inertia, r.extended.c2, a.alternative.inertia, a.alternative.c2
            ),
        };
        s += &format!("To separate them: {}.\n", a.separate_with);
    }
    if !r.effects.is_empty() {
        let x = &r.extended;
        s += &format!(
            "   Extended model: J = {:.4e} ± {:.1e} kg·m², c1 = {:.3e}, c2 = {:.4e} ± {:.1e}\n",
            x.inertia, x.inertia_stderr, x.c1, x.c2, x.c2_stderr
        );
        if let (Some(k), Some(p)) = (x.k, x.p) {
            s += &format!(
                "   Drag law: {k:.4e}·|ω|^{p:.3} (c2 above is its quadratic equivalent at the RMS speed)\n"
            );
        }
    }
    if steady.is_some() {
        s += &format!(
            "   Torque residual RMS on the steady-state data: seed's law {:.3e} → extended {:.3e} N·m (gain {:.1} %)\n",
            r.simulation_rms.base, r.simulation_rms.extended, r.simulation_rms.gain_percent
        );
    } else {
        s += &format!(
            "   Simulated-velocity RMS error on held-out data: base {:.3} → extended {:.3} rad/s (gain {:.1} %)\n",
            r.simulation_rms.base, r.simulation_rms.extended, r.simulation_rms.gain_percent
        );
    }
    match &r.unexplained {
        Some(u) => s += &format!("   Unexplained: {}\n", u.description),
        None => s += "   Unexplained periodic structure: none left in the residual\n",
    }
    if let Some(c) = &r.concentration {
        let at = if c.condition == Condition::TimeWindow {
            format!("between t = {:.1} s and {:.1} s", c.from_s, c.to_s)
        } else {
            format!("while {}", c.condition.words())
        };
        s += &format!(
            "   Unexplained, concentrated {at}: {:.0} % of the remaining held-out error in {:.0} % of the samples \
             ({:.1}× the error of the rest of the record)\n",
            c.error_percent, c.samples_percent, c.ratio
        );
    }
    if let Some(l) = &r.left_out {
        s += &format!("   {}\n", left_out_sentence(l, &r.extended));
    }
    if let Some(o) = &r.simulation_only {
        s += &format!(
            "   Unexplained: {}\n",
            simulation_only_sentence(o, &r.extended)
        );
    }
    if r.asked_does_better() {
        s += "   Unexplained: the model asked about (5. below) does better on held-out data than the one named, which is\n   \
              then not the best these data support\n";
    }
    for n in &r.notes {
        s += &format!("   Note: {n}\n");
    }
    if let Some(c) = &r.compared {
        s += &c.text();
    }
    s
}

/// The plots: measured vs simulated velocity (base and extended) on the held-out data, and the
/// acceleration residuals.
pub fn figure(r: &Report) -> Figure {
    let tr = &r.traces;
    let names: Vec<&str> = r.effects.iter().map(|e| e.effect.name()).collect();
    let ext = if names.is_empty() {
        "extended (= base)".to_string()
    } else {
        format!("base + {}", names.join(" + "))
    };
    Figure {
        title: format!(
            "propid diagnose: simulated-velocity RMS {:.3} → {:.3} rad/s ({:+.1} %)",
            r.simulation_rms.base, r.simulation_rms.extended, -r.simulation_rms.gain_percent
        ),
        x_label: "t [s]".into(),
        panels: vec![
            Panel {
                title: "held-out data: measured velocity vs open-loop simulation".into(),
                y_label: "ω [rad/s]".into(),
                series: vec![
                    Series {
                        name: "base model".into(),
                        x: tr.t.clone(),
                        y: tr.base.clone(),
                        style: Style::Line,
                    },
                    Series {
                        name: ext.clone(),
                        x: tr.t.clone(),
                        y: tr.extended.clone(),
                        style: Style::Line,
                    },
                    Series {
                        name: "measured".into(),
                        x: tr.t.clone(),
                        y: tr.measured.clone(),
                        style: Style::Points,
                    },
                ],
            },
            Panel {
                title: "simulation error (simulated − measured)".into(),
                y_label: "Δω [rad/s]".into(),
                series: vec![
                    Series {
                        name: "base model".into(),
                        x: tr.t.clone(),
                        y: tr
                            .base
                            .iter()
                            .zip(&tr.measured)
                            .map(|(a, b)| a - b)
                            .collect(),
                        style: Style::Line,
                    },
                    Series {
                        name: ext,
                        x: tr.t.clone(),
                        y: tr
                            .extended
                            .iter()
                            .zip(&tr.measured)
                            .map(|(a, b)| a - b)
                            .collect(),
                        style: Style::Line,
                    },
                ],
            },
            Panel {
                title: "acceleration residual (all data)".into(),
                y_label: "[rad/s²]".into(),
                series: vec![
                    Series {
                        name: "base model".into(),
                        x: tr.t_all.clone(),
                        y: tr.residual_base.clone(),
                        style: Style::Points,
                    },
                    Series {
                        name: "extended model".into(),
                        x: tr.t_all.clone(),
                        y: tr.residual_extended.clone(),
                        style: Style::Points,
                    },
                ],
            },
        ],
    }
}

/// A decision in words.
fn decision_words(effect: EffectKind, d: &Decision) -> String {
    use super::candidate::Inadmissible;
    use super::select::Rejection;
    match d {
        // "No effect" of an exponent is the seed's own law: say so.
        Decision::Rejected {
            reason:
                Rejection::Inadmissible {
                    why: Inadmissible::NotResolved { value, stderr },
                },
        } if effect == EffectKind::DragExponent => format!(
            "p = {value:.4} ± {stderr:.1e}: the seed's quadratic law holds (p = 2 within {} standard errors)",
            super::RESOLVED
        ),
        Decision::Named => "← named".into(),
        Decision::Ambiguous { with } => format!("ambiguous with {with}"),
        Decision::NearMiss => "near miss".into(),
        Decision::Dropped => "dropped (the model no longer needs it)".into(),
        Decision::Rejected { reason } => reason.to_string(),
    }
}

/// What the simulated velocity shows and the equation does not confirm, in a sentence (the
/// report's text and the Result's warning).
pub fn simulation_only_sentence(o: &SimulationOnly, extended: &BaseModel) -> String {
    let unit = with_unit(o.unit);
    if let Some(se) = o.value_stderr {
        return format!(
            "the model does not explain these data: both held-out errors drop consistently with {0} = {2:.4e} ± {6:.1e}{unit} (the simulated velocity's by {1:.1} %, the acceleration equation's by {3:+.2} %), a value they do not resolve from zero: it stands in for something the model lacks, and J and c2 are not established (with it J reads {4:+.1} % and c2 {5:+.1} %)",
            o.effect,
            o.simulation_gain_percent,
            o.value,
            o.equation_gain_percent,
            100.0 * (o.inertia_with / extended.inertia - 1.0),
            100.0 * (o.c2_with / extended.c2 - 1.0),
            se
        );
    }
    format!(
        "the simulated velocity is not explained: its held-out error drops by {1:.1} % with {0} = {2:.4e}{unit} while the acceleration equation's moves by {3:+.2} %, too little to name it; J and c2 depend on what the model lacks (with it J reads {4:+.1} % and c2 {5:+.1} %)",
        o.effect,
        o.simulation_gain_percent,
        o.value,
        o.equation_gain_percent,
        100.0 * (o.inertia_with / extended.inertia - 1.0),
        100.0 * (o.c2_with / extended.c2 - 1.0)
    )
}

/// What leaving an event's samples out did, in a sentence (the report's text and the Result's
/// warning).
pub fn left_out_sentence(l: &LeftOut, extended: &BaseModel) -> String {
    format!(
        "J and c2 are fitted without t = {:.1}–{:.1} s ({} samples), where something the model does not hold acts; with those samples J reads {:+.1} % and c2 {:+.1} %",
        l.from_s,
        l.to_s,
        l.samples,
        100.0 * (l.inertia_with / extended.inertia - 1.0),
        100.0 * (l.c2_with / extended.c2 - 1.0)
    )
}
