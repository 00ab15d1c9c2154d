//! The diagnosis of dynamic data, start to end: the base fit and what its simulation gets
//! wrong, the residual analysis, the search over models of several effects, and the extended
//! model's report (its effects, the ambiguities, near misses, structure left, parameters not
//! identified).

use propid_io::InputError;

use super::candidate::{separating_run, BaseTerm, EffectKind};
use super::compare::{run_between, Compared, EffectSet, NotAdmissible, Preference};
use super::engine::{fit, fit_every_row, fit_on_all, held_out_residuals, residuals, Fit};
use super::model::{Effect, Model};
use super::report::{
    Agreed, Ambiguity, BaseModel, EffectValue, NamedEffect, NearMiss, Parameter, Report,
    ResidualAnalysis, SimulationOnly, SimulationRms, Traces, Unexplained, Unidentified, Verdict,
};
use super::search::{estimate_of, fit_set, judged, search, Found, Scored, Tie};
use super::select::{self, Decision, Evidence};
use super::signals::{correlation, Signals};
use super::simulate::{rms_error, simulate, SimPlan};
use super::structure::{
    concentration, event_span, harmonic_correlations, periodogram, sinusoid_share, LeftOut,
};
use super::{Observer, Options, Stage, HOLDOUT, STEADY_SHARE};

/// Peak of the residual's spectrum over its median from which a periodic probe is tried.
const PEAK_TO_MEDIAN: f64 = 40.0;

/// A residual peak is at a frequency the force is driven at when one sinusoid there carries at
/// least this share of the force's variance: the probe and the force are then more one column
/// than two.
const DRIVEN_SHARE: f64 = 0.5;

/// The seed's parameters (and c1, the drag law) of `model` fitted as `fit`.
fn base_model_of(fit: &Fit, model: &Model, s: &Signals) -> BaseModel {
    let t0 = fit.theta[0];
    let inertia = 1.0 / t0;
    let c2 = fit.theta[1] / t0;
    let mut quadratic = BaseModel {
        inertia,
        c1: 0.0,
        c2,
        inertia_stderr: fit.stderr[0] * inertia * inertia,
        c2_stderr: ((fit.stderr[1] / t0).powi(2) + (c2 * fit.stderr[0] / t0).powi(2)).sqrt(),
        k: None,
        p: None,
    };
    let mut exponent = None;
    for (i, e) in model.effects.iter().enumerate() {
        match e.candidate().base_term(e, estimate_of(model, i, fit, s)) {
            BaseTerm::None => {}
            BaseTerm::C1(v) => quadratic.c1 = v.value,
            BaseTerm::Exponent(p) => exponent = Some(p),
        }
    }
    // With a drag exponent the second coefficient is k of k·|ω|^p, not c2.
    match exponent {
        Some(p) => {
            let (k, k_stderr) = (quadratic.c2, quadratic.c2_stderr);
            quadratic.power_law(k, k_stderr, p, super::rms(&s.velocity))
        }
        None => quadratic,
    }
}

/// Whether two fitted values agree: within two combined standard errors or 0.5 %.
fn agree(a: f64, sa: f64, b: f64, sb: f64) -> bool {
    (a - b).abs() <= (2.0 * (sa * sa + sb * sb).sqrt()).max(0.005 * a.abs().max(b.abs()))
}

/// The whole diagnosis of dynamic data.
pub(crate) fn run(
    s: &Signals,
    options: Options,
    progress: Observer<'_>,
) -> Result<Report, InputError> {
    let n = s.len();
    let base = Model::default();
    let unfit = || {
        InputError::invalid(
            "the base model cannot be fitted: the force or velocity does not vary enough to identify J and c2"
                .into(),
        )
    };
    let base_fit = fit_on_all(&base, s).ok_or_else(unfit)?;
    if base_fit.theta[0].is_nan() || base_fit.theta[0] <= 0.0 {
        return Err(InputError::invalid(
            "the fitted inertia is not positive: force and acceleration do not move together (check signs and units)".into(),
        ));
    }
    let mut notes = Vec::new();
    let duration = s.t[n - 1] - s.t[0];

    // Residual analysis of the base model.
    let r_base = residuals(&base, &base_fit, s);
    let sign_correlation = {
        let sgn: Vec<f64> = s.velocity.iter().map(|w| w.signum()).collect();
        correlation(&r_base, &sgn)
    };
    let mut correlations = vec![
        ("velocity", correlation(&r_base, &s.velocity)),
        ("sign(velocity)", sign_correlation),
        ("force rate", correlation(&r_base, &s.force_rate)),
        ("acceleration", correlation(&r_base, &s.acceleration)),
        ("time", correlation(&r_base, &s.t)),
    ];
    if let Some(pos) = &s.position {
        let best = harmonic_correlations::<24>(&r_base, pos)
            .iter()
            .map(|(cs, cc)| (cs * cs + cc * cc).sqrt())
            .fold(0.0, f64::max);
        correlations.push(("position (best harmonic)", best));
    } else {
        notes.push("no position column: torque_ripple cannot be tested".into());
    }
    let (dominant_frequency_hz, peak_to_median) = periodogram(s, &r_base);
    // Only the plot's thinned copy is kept (the full residual is a column of n).
    let trace_step = (n / 20000).max(1);
    let residual_base_trace: Vec<f64> = r_base.iter().step_by(trace_step).copied().collect();
    drop(r_base);
    let force_span = s.force.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - s.force.iter().cloned().fold(f64::INFINITY, f64::min);
    let steady = s
        .acceleration
        .iter()
        .zip(&s.velocity)
        .filter(|(a, w)| a.abs() * 0.5 < 0.01 * w.abs())
        .count() as f64
        / n as f64;
    if steady > STEADY_SHARE {
        notes.push(format!(
            "{:.0} % of the samples are near steady state: the data speak mostly about the drag law, little about the inertia",
            steady * 100.0
        ));
    }
    if force_span <= 0.0 {
        notes.push("the force is constant: the inertia is not identifiable".into());
    }
    if let Some(u) = &s.force_updates {
        notes.push(format!(
            "the force updates every {:.1} ms ({:.0} Hz) in rows at {:.0} Hz ({:.0} % of the rows repeat the previous value): a held sensor reading, taken at the row that first shows it and linear in between; a force-sensor lag is counted from there",
            u.interval * 1e3,
            1.0 / u.interval,
            s.rate,
            u.repeated * 100.0
        ));
    }

    // The headline: fitted on the first 70 %, simulated over the last 30 % open-loop.
    let split = ((1.0 - HOLDOUT) * n as f64) as usize;
    let (train, test) = (s.first..split, split..n);
    let sim_of = |m: &Model| -> Option<Vec<f64>> {
        let p = m.prepare(s);
        let f = fit(m, s, train.clone())?;
        Some(simulate(m, &p, &f.theta, s, test.clone()))
    };
    let measured = &s.velocity[test.clone()];
    let sim_base = sim_of(&base).ok_or_else(unfit)?;

    // The search.
    let plan = SimPlan::new(s);
    let found = search(s, &plan, options.max_effects, progress).ok_or_else(unfit)?;
    notes.extend(found.notes.iter().cloned());
    let compared = (!options.compare.is_empty())
        .then(|| compared(&found, options.compare, s, &plan))
        .flatten();
    if !options.compare.is_empty() && compared.is_none() {
        notes.push(format!(
            "the model asked about ({}) cannot be fitted on these data",
            options.compare
        ));
    }

    progress(Stage::Extended);
    let model = found.model.model.clone();
    let ext_fit = fit_on_all(&model, s).ok_or_else(unfit)?;
    let sim_ext = sim_of(&model).ok_or_else(unfit)?;
    let rms_base = rms_error(&sim_base, measured);
    let rms_ext = rms_error(&sim_ext, measured);
    let extended = base_model_of(&ext_fit, &model, s);
    let mut effects = Vec::new();
    for (i, e) in model.effects.iter().enumerate() {
        let v = estimate_of(&model, i, &ext_fit, s);
        let alone = base
            .with(*e)
            .and_then(|m| sim_of(&m))
            .map(|v| 100.0 * (1.0 - rms_error(&v, measured) / rms_base))
            .unwrap_or(f64::NAN);
        let (cv_gain, gain) = found
            .entered_with
            .iter()
            .find(|(k, _, _)| *k == e.kind)
            .map(|(_, c, g)| (*c, *g))
            .unwrap_or((f64::NAN, select::Gain::NONE));
        effects.push(NamedEffect {
            effect: e.kind,
            value: v.value,
            unit: e.kind.unit(),
            stderr: v.stderr,
            gain_percent: alone,
            cv_gain_percent: cv_gain,
            gain,
            lag_form: e.candidate().lag(e, v.value).map(|l| l.shape),
            lag_delay_s: e.candidate().lag(e, v.value).map(|l| l.delay),
            explanation: e.candidate().explanation(e, v.value),
        });
    }
    let ambiguities = found
        .ties
        .iter()
        .filter_map(|t| ambiguity(&found, &model, &ext_fit, &extended, t, s))
        .collect();
    let near_misses = near_misses(&found);

    // Structure left: periodic in time, or concentrated somewhere in the record.
    let r_ext = residuals(&model, &ext_fit, s);
    let (f_peak, ratio) = periodogram(s, &r_ext);
    // A peak where the force itself is one sinusoid (the seed's sine at its own frequency) is
    // the model's response to its input: a probe there is one column with the force, and its
    // amplitude trades against 1/J (on a clean independent stand it took 0.04 N·m, the force's
    // whole swing, and "gained" by undoing the torque noise's bias on J). The candidates that
    // act through the input (a lag, J itself) were tried; it is not reported as a disturbance.
    let driven = ratio > PEAK_TO_MEDIAN
        && sinusoid_share(&s.force[s.first..], s.rate, f_peak) >= DRIVEN_SHARE;
    if driven {
        notes.push(format!(
            "the residual peaks at {f_peak:.3} Hz, where the force itself is driven: that is the model's response to its own input (a sinusoid there cannot be told from J), not a disturbance"
        ));
    }
    let unexplained = (ratio > PEAK_TO_MEDIAN && !driven)
        .then(|| periodic(&found.model, s, &plan, f_peak, ratio, &correlations))
        .flatten();
    let held_out = held_out_residuals(&model, s);
    let concentration = held_out.as_ref().and_then(|r| concentration(s, r));
    // Where the concentration is an event in time: its span, which `super::diagnose_complete`
    // then leaves out of every fit and score in a second diagnosis (this one, when `s.excluded`
    // is set), and what its samples do to the model.
    let span = if s.excluded.is_empty() {
        held_out
            .as_ref()
            .zip(concentration.as_ref())
            .and_then(|(r, c)| event_span(s, r, c))
    } else {
        Some(s.excluded.clone())
    };
    let left_out = span.and_then(|w| {
        let with = base_model_of(&fit_every_row(&model, s)?, &model, s);
        Some(LeftOut {
            from_s: s.t[w.start],
            to_s: s.t[w.end - 1],
            samples: w.len(),
            rows: w,
            inertia_with: with.inertia,
            c2_with: with.c2,
        })
    });
    drop(held_out);
    let simulation_only = simulation_only(&found, &extended, s);
    let mut unidentified = Unidentified::of(&extended);
    // Errors in the regressor: the torque's noise would bias J beyond what its standard error
    // says. The fit takes that bias out (engine::without_force_noise); where it is large, the
    // correction is large too and rests on the noise being white: said, and above
    // MAX_RELATIVE_STDERR J is not taken as identified.
    let bias = crate::plausibility::torque_noise_bias(&s.force, &s.velocity);
    notes.extend(crate::plausibility::torque_noise_corrected_warning(
        "J", bias,
    ));
    if bias > crate::plausibility::MAX_RELATIVE_STDERR
        && !unidentified
            .iter()
            .any(|u| u.parameter == Parameter::Inertia)
    {
        unidentified.push(Unidentified {
            parameter: Parameter::Inertia,
            value: extended.inertia,
            stderr: extended.inertia_stderr,
            torque_noise_bias: Some(bias),
        });
    }

    let step = trace_step;
    let traces = Traces {
        t: s.t[test.clone()].to_vec(),
        measured: measured.to_vec(),
        base: sim_base,
        extended: sim_ext,
        t_all: s.t.iter().step_by(step).copied().collect(),
        residual_base: residual_base_trace,
        residual_extended: r_ext.iter().step_by(step).copied().collect(),
    };
    let mut report = Report {
        verdict: Verdict::NothingWrong,
        samples: n,
        duration_s: duration,
        rate_hz: s.rate,
        base: base_model_of(&base_fit, &base, s),
        effects,
        extended,
        simulation_rms: SimulationRms {
            base: rms_base,
            extended: rms_ext,
            gain_percent: 100.0 * (1.0 - rms_ext / rms_base),
        },
        unexplained,
        residual_analysis: ResidualAnalysis {
            correlations,
            dominant_frequency_hz,
            peak_to_median,
        },
        candidates: found.candidates,
        steady_state: None,
        steady_share: steady,
        ambiguities,
        near_misses,
        unidentified,
        concentration,
        left_out,
        simulation_only,
        compared,
        notes,
        traces,
    };
    report.conclude();
    Ok(report)
}

/// The best candidate of the search's last round that the simulated velocity alone would name
/// (`Found::unconfirmed`) and with which J or c2 do not agree with `extended`'s (the agreement an
/// ambiguity's J and c2 are given by): the model's J and c2 then depend on what it does not hold.
/// Or one that both held-out errors would name but whose value is not resolved: whether or not
/// J and c2 move with it, the model lacks something.
fn simulation_only(found: &Found, extended: &BaseModel, s: &Signals) -> Option<SimulationOnly> {
    found.unconfirmed.iter().find_map(|u| {
        let with = base_model_of(&fit_on_all(&u.model, s)?, &u.model, s);
        let moves = !agree(
            with.inertia,
            with.inertia_stderr,
            extended.inertia,
            extended.inertia_stderr,
        ) || !agree(with.c2, with.c2_stderr, extended.c2, extended.c2_stderr);
        // Where both errors gain with it, the model lacks something whether or not J and c2
        // move with the term standing in for it.
        (moves || u.unresolved).then(|| SimulationOnly {
            effect: u.effect.kind,
            value: u.estimate.value,
            unit: u.effect.kind.unit(),
            simulation_gain_percent: u.simulation_percent,
            equation_gain_percent: u.equation_percent,
            inertia_with: with.inertia,
            c2_with: with.c2,
            value_stderr: u.unresolved.then_some(u.estimate.stderr),
        })
    })
}

/// The model of `set` fitted and scored beside the one the search named (see `compare`).
fn compared(found: &Found, set: EffectSet, s: &Signals, plan: &SimPlan) -> Option<Compared> {
    let asked = fit_set(set, s, plan)?;
    let model = &asked.model;
    let fit = fit_on_all(model, s)?;
    let mut effects = Vec::new();
    let mut inadmissible = Vec::new();
    for (i, e) in model.effects.iter().enumerate() {
        let (estimate, admissible) = judged(model, i, &fit, s);
        effects.push(EffectValue {
            effect: e.kind,
            value: estimate.value,
            unit: e.kind.unit(),
        });
        if let Err(why) = admissible {
            inadmissible.push(NotAdmissible {
                effect: e.kind,
                why,
            });
        }
    }
    let (named, theirs) = (found.model.errors(), asked.errors());
    let same = found.model.model.effects.len() == model.effects.len()
        && model.effects.iter().all(|e| found.model.model.has(e.kind));
    let (equation, simulation) = select::Gain::parts(&named, &theirs);
    let preferred = if same {
        Preference::Same
    } else if select::separates(&named, &theirs) {
        Preference::Asked
    } else if select::separates(&theirs, &named) {
        Preference::Named
    } else {
        Preference::Neither
    };
    let only = |a: &Model, b: &Model| -> Vec<EffectKind> {
        a.effects
            .iter()
            .map(|e| e.kind)
            .filter(|k| !b.has(*k))
            .collect()
    };
    let separating_run = run_between(
        &only(&found.model.model, model),
        &only(model, &found.model.model),
    );
    Some(Compared {
        asked: set.iter().collect(),
        effects,
        inadmissible,
        model: base_model_of(&fit, model, s),
        gain: select::Gain::of(&named, &theirs),
        equation,
        simulation,
        preferred,
        separating_run,
    })
}

/// The ambiguity `tie` records between an effect of `model` (fitted as `fit`) and its
/// alternative (with the lag beside it, for rule 10's tie): the values, J and c2 with each, what
/// they agree on, and the run that separates them.
fn ambiguity(
    found: &Found,
    model: &Model,
    fit: &Fit,
    extended: &BaseModel,
    tie: &Tie,
    s: &Signals,
) -> Option<Ambiguity> {
    let (named, alternative) = (tie.named, tie.alternative);
    let i = model.effects.iter().position(|e| e.kind == named)?;
    let mut other = model.without(i);
    other.effects.insert(i, alternative);
    if let Some(lag) = tie.alongside {
        other = other.with(lag)?;
    }
    let other_fit = fit_on_all(&other, s)?;
    let other_base = base_model_of(&other_fit, &other, s);
    let gain_of = |k: EffectKind| {
        found
            .candidates
            .iter()
            .rev()
            .find(|c| c.effect == k)
            .map_or(f64::NAN, |c| c.cv_gain_percent)
    };
    let (a, b) = (extended, &other_base);
    let agreed = (agree(a.inertia, a.inertia_stderr, b.inertia, b.inertia_stderr)
        && agree(a.c2, a.c2_stderr, b.c2, b.c2_stderr))
    .then_some(Agreed {
        inertia: 0.5 * (a.inertia + b.inertia),
        c2: 0.5 * (a.c2 + b.c2),
    });
    let run = separating_run(named, tie.alongside.unwrap_or(alternative).kind);
    let value_of = |k: usize| EffectValue {
        effect: other.effects[k].kind,
        value: estimate_of(&other, k, &other_fit, s).value,
        unit: other.effects[k].kind.unit(),
    };
    let alternative_effects = (0..other.effects.len()).map(value_of).collect();
    Some(Ambiguity {
        between: [named, alternative.kind],
        values: [
            estimate_of(model, i, fit, s).value,
            estimate_of(&other, i, &other_fit, s).value,
        ],
        units: [named.unit(), alternative.kind.unit()],
        alongside: tie.alongside.map(|_| value_of(other.effects.len() - 1)),
        cv_gain_percent: tie
            .cv_gain_percent
            .unwrap_or([gain_of(named), gain_of(alternative.kind)]),
        alternative: other_base.clone(),
        alternative_effects,
        agreed,
        separate_with: run.advice(),
        separating_run: run,
    })
}

/// The near misses of the search's last round, when it named nothing, best first.
fn near_misses(found: &Found) -> Vec<NearMiss> {
    let last = found.candidates.iter().map(|c| c.round).max().unwrap_or(0);
    let round: Vec<_> = found
        .candidates
        .iter()
        .filter(|c| c.round == last)
        .collect();
    if round
        .iter()
        .any(|c| matches!(c.decision, Decision::Named | Decision::Dropped))
    {
        return Vec::new();
    }
    let mut out: Vec<NearMiss> = round
        .iter()
        .filter(|c| c.decision == Decision::NearMiss)
        .map(|c| {
            let run = c.effect.candidate().revealing_run();
            NearMiss {
                effect: c.effect,
                value: c.value,
                unit: c.effect.unit(),
                cv_gain_percent: c.cv_gain_percent,
                simulation_gain_percent: c.simulation_gain_percent,
                look_with: run.advice(),
                revealing_run: run,
            }
        })
        .collect();
    out.sort_by(|a, b| b.cv_gain_percent.total_cmp(&a.cv_gain_percent));
    out
}

/// A torque periodic in time at the residual's peak `f_peak`, added to the model and judged as a
/// candidate is: reported as unexplained when it passes.
fn periodic(
    current: &Scored,
    s: &Signals,
    plan: &SimPlan,
    f_peak: f64,
    ratio: f64,
    correlations: &[(&'static str, f64)],
) -> Option<Unexplained> {
    let probe = current
        .model
        .with(Effect::new(EffectKind::PeriodicDisturbance, f_peak))?;
    // Judged on the predictor, as the residual that raised it: the question is whether the
    // signals as measured hold a sinusoid the model does not predict. (On the parameters without
    // the force noise's bias, a probe at the second harmonic of the seed's sine traded against
    // the torque shapes it is collinear with there and was not resolved from zero, while its
    // held-out gain, scored on the predictor, was consistent.)
    let fit = fit_on_all(&probe, s)?;
    let fit = Fit {
        theta: fit.predictor.clone(),
        ..fit
    };
    let (estimate, admissible) = super::search::judged(&probe, probe.effects.len() - 1, &fit, s);
    let scored = Scored::of(probe, s, plan)?;
    let evidence = Evidence {
        effect: EffectKind::PeriodicDisturbance,
        parameters: EffectKind::PeriodicDisturbance.candidate().parameters(),
        estimate,
        admissible,
        errors: scored.errors(),
        simulation_sees: true,
        lag_in_samples: None,
    };
    if select::judge(&current.errors(), &evidence).is_some() {
        return None;
    }
    let gain = select::Gain::of(&current.errors(), &evidence.errors);
    let by_position = correlations
        .iter()
        .find(|c| c.0.starts_with("position"))
        .map_or(String::new(), |c| {
            format!(", correlation with rotor angle {:.2}", c.1)
        });
    Some(Unexplained {
        description: format!(
            "a torque of about {:.2e} N·m periodic in time at {f_peak:.3} Hz (peak {ratio:.0}× the median of the residual spectrum) \
             that no candidate effect explains: it is not tied to speed, force rate or acceleration{by_position}; \
             modelled as a sinusoid it gains {:.3} ± {:.3} on held-out data (the selection's criterion)",
            estimate.value, gain.mean, gain.stderr
        ),
        frequency_hz: f_peak,
    })
}
