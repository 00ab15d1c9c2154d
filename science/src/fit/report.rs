//! A fit's sums turned into what is printed: the report with its standard errors and its checks
//! of what the data identify ([`report_of`]), the seed's YAML ([`to_yaml`]) and the plot
//! ([`figure`]).

use propid_core::estimate::{LoadBounds, LoadEstimate, LoadEstimator, SolveError};
use propid_io::tsv::Sample;
use propid_io::InputError;

use super::{FitOptions, FitReport, Window};
use crate::figure::{Figure, Panel, Series, Style};
use crate::plausibility;

/// Condition numbers above this mean the regressors are linearly dependent to within rounding:
/// any printed estimate would be an artefact of the arithmetic.
const UNIDENTIFIABLE_CONDITION: f64 = 1e15;

/// The report of the fitted sums. `gate` is a stretch of the window's rows (as in the file) for
/// the plausibility checks; the rows and sums are read as `args.reading` says first.
pub(super) fn report_of(
    estimator: &LoadEstimator<f64>,
    args: &FitOptions,
    window: Window,
    name: &str,
    gate: &[Sample],
) -> Result<FitReport, InputError> {
    let estimator = &args.reading.apply_to_estimator(estimator);
    let gate: Vec<Sample> = gate
        .iter()
        .map(|s| {
            let mut s = *s;
            args.reading.apply(&mut s);
            s
        })
        .collect();
    let n = estimator.count() as u64;
    if n < 10 {
        return Err(InputError::cannot_judge(format!(
            "only {n} usable samples after trimming (rows {}–{} of {}); at least 10 are needed",
            window.first + 1,
            window.last + 1,
            window.rows
        ))
        .in_file(name));
    }
    // An infinite c1_max or c2_max means "unbounded": the bound rows are `c·θ₀ ≤ θ` and an
    // infinite coefficient makes them NaN, so a finite stand-in far beyond any physical drag is
    // used (θ₀ = 1/J ≤ 1/mass_min keeps every product finite).
    let unbounded = |c: f64| if c.is_infinite() { 1e150 } else { c };
    let bounds = LoadBounds {
        mass_min: args.mass_min,
        mass_max: args.mass_max,
        c1_max: unbounded(args.c1_max),
        c2_max: unbounded(args.c2_max),
    };
    let implausible = plausibility::check(&gate, estimator, &args.reading);
    if !implausible.is_empty() {
        let why: Vec<String> = implausible.iter().map(|w| w.to_string()).collect();
        return Err(InputError::cannot_judge(format!(
            "no fit is given for data rows {}–{}: {}",
            window.first + 1,
            window.last + 1,
            why.join("; ")
        ))
        .in_file(name));
    }
    let names = ["force", "velocity", "velocity·|velocity|"];
    let est: LoadEstimate<f64> = estimator.estimate(&bounds).map_err(|e| match e {
        SolveError::NoExcitation { regressor } => InputError::cannot_judge(format!(
            "`{}` is zero in every sample: the data cannot identify {}",
            names[regressor],
            ["the mass", "c1", "c2"][regressor]
        ))
        .in_file(name),
        SolveError::TooFewSamples => InputError::cannot_judge("too few samples".into()).in_file(name),
        SolveError::Singular => InputError::cannot_judge(
            "the regressors are linearly dependent: the excitation does not identify mass, c1 and c2".into(),
        )
        .in_file(name),
        SolveError::Infeasible => InputError::invalid(format!("{name}: the bounds admit no solution")),
    })?;
    if est.condition_number.is_nan() || est.condition_number >= UNIDENTIFIABLE_CONDITION {
        return Err(InputError::cannot_judge(format!(
            "the data cannot identify the mass, c1 and c2 (condition number \
             {:.3e}): force, velocity and velocity·|velocity| are linearly dependent in data rows {}–{} \
             (e.g. a constant velocity); record with a torque that varies the speed",
            est.condition_number,
            window.first + 1,
            window.last + 1
        ))
        .in_file(name));
    }
    let mut warnings = Vec::new();
    if let Some((line, column)) = window.breaker {
        warnings.push(format!(
            "{} complete rows dropped by the seed's trimming: line {line} has a non-finite \
             `{column}`, and the seed fits only the last run of complete rows (after it)",
            window.dropped_complete()
        ));
    }
    if est.condition_number > 1e8 {
        let rel = [
            est.mass_stderr / est.mass.abs(),
            est.c1_stderr / est.c1.abs().max(f64::MIN_POSITIVE),
            est.c2_stderr / est.c2.abs().max(f64::MIN_POSITIVE),
        ];
        let worst = (0..3)
            .max_by(|a, b| rel[*a].total_cmp(&rel[*b]))
            .unwrap_or(0);
        warnings.push(format!(
            "poor excitation (condition number {:.3e}): the data can hardly identify {}",
            est.condition_number,
            ["mass", "c1", "c2"][worst]
        ));
    }
    if est.at_bound[0] {
        warnings.push(format!(
            "the mass sits on its bound ({:e}): these data do not identify it (steady plateaus, or a force too slow for the dynamics: `propid diagnose` fits the steady-state drag law then)",
            est.mass
        ));
    }
    let at_bound = ["mass", "c1", "c2"]
        .iter()
        .zip(est.at_bound)
        .filter(|(_, b)| *b)
        .map(|(n, _)| *n)
        .collect();
    // A parameter on a bound has the standard error of the fit without bounds (the precision
    // the data give it), never the 0 of the active bound; c1 under `c1_max = 0` is not a free
    // parameter (the seed's model has none) and keeps its 0.
    let free = estimator.estimate_unbounded().ok();
    let mut stderr = [est.mass_stderr, est.c1_stderr, est.c2_stderr];
    let values = [est.mass, est.c1, est.c2];
    let bounds = [
        if est.mass <= args.mass_min * (1.0 + 1e-9) {
            args.mass_min
        } else {
            args.mass_max
        },
        if est.c1 == 0.0 { 0.0 } else { args.c1_max },
        if est.c2 == 0.0 { 0.0 } else { args.c2_max },
    ];
    let mut not_identified = Vec::new();
    // Errors in the regressor: a bias no standard error shows (plausibility::torque_noise_bias).
    let torque_bias = plausibility::torque_noise_bias(
        &gate.iter().map(|s| s.force).collect::<Vec<f64>>(),
        &gate.iter().map(|s| s.velocity).collect::<Vec<f64>>(),
    );
    warnings.extend(plausibility::torque_noise_warning("mass", torque_bias));
    for (k, name) in ["mass", "c1", "c2"].into_iter().enumerate() {
        if k == 1 && args.c1_max == 0.0 {
            continue;
        }
        if est.at_bound[k] {
            stderr[k] = free.map_or(f64::INFINITY, |f| {
                [f.mass_stderr, f.c1_stderr, f.c2_stderr][k]
            });
            if !(stderr[k] > 0.0 && stderr[k].is_finite()) {
                stderr[k] = f64::INFINITY;
            }
        }
        let bound = est.at_bound[k].then_some(bounds[k]);
        let noisy = (k == 0 && torque_bias > plausibility::MAX_RELATIVE_STDERR)
            .then_some(plausibility::NotIdentified::NoisyTorque { bias: torque_bias });
        if let Some(why) = plausibility::identified(values[k], stderr[k], bound).or(noisy) {
            if k != 0 || !est.at_bound[0] {
                warnings.push(why.describe(name, values[k]));
            }
            not_identified.push(name);
        }
    }
    let [mass_stderr, c1_stderr, c2_stderr] = stderr;
    let c_q = args
        .diameter
        .map(|d| 4.0 * std::f64::consts::PI.powi(2) * est.c2 / (args.density * d.powi(5)));
    Ok(FitReport {
        mass: est.mass,
        c1: est.c1,
        c2: est.c2,
        mass_stderr,
        c1_stderr,
        c2_stderr,
        rms: est.rms,
        samples: n,
        rows: window.rows,
        condition_number: est.condition_number,
        at_bound,
        not_identified,
        c_q,
        warnings,
    })
}

/// A float as YAML 1.1 reads it as a float (PyYAML's resolver): a mantissa with a point and a
/// signed exponent of at least two digits (`2.827626e+02`, never `2.827626e2`, which YAML 1.1
/// loads as a string), and `.inf`, `-.inf`, `.nan`.
pub fn yaml_float(v: f64, digits: usize) -> String {
    if v.is_nan() {
        return ".nan".into();
    }
    if v.is_infinite() {
        return if v > 0.0 { ".inf" } else { "-.inf" }.into();
    }
    let v = v + 0.0; // no "-0"
    let text = format!("{v:.digits$e}");
    let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
    let exponent: i32 = exponent.parse().unwrap_or(0);
    let mantissa = if mantissa.contains('.') {
        mantissa.to_string()
    } else {
        format!("{mantissa}.0")
    };
    let sign = if exponent < 0 { '-' } else { '+' };
    format!("{mantissa}e{sign}{:02}", exponent.unsigned_abs())
}

/// The report as the seed's YAML (same keys and unit comments), plus propid's extras. Every
/// number loads as a float in YAML 1.1 readers (PyYAML) and YAML 1.2 readers alike.
pub fn to_yaml(r: &FitReport) -> String {
    let f = yaml_float;
    let mut s = String::new();
    s += &format!("mass: {} # [kg] | [kg*m^2]\n", f(r.mass, 9));
    s += &format!("c1:   {} # [N*s/m] | [N*m*s/rad]\n", f(r.c1, 9));
    s += &format!("c2:   {} # [N*s^2/m^2] | [N*m*s^2/rad^2]\n", f(r.c2, 9));
    s += &format!("mass_stderr: {}\n", f(r.mass_stderr, 3));
    s += &format!("c1_stderr: {}\n", f(r.c1_stderr, 3));
    s += &format!("c2_stderr: {}\n", f(r.c2_stderr, 3));
    s += &format!(
        "rms: {} # acceleration residual [m/s^2] | [rad/s^2]\n",
        f(r.rms, 6)
    );
    s += &format!("samples: {}\n", r.samples);
    s += &format!("condition_number: {}\n", f(r.condition_number, 3));
    s += &format!("at_bound: [{}]\n", r.at_bound.join(", "));
    s += &format!("not_identified: [{}]\n", r.not_identified.join(", "));
    if let Some(cq) = r.c_q {
        s += &format!("c_q: {} # propeller torque coefficient\n", f(cq, 6));
    }
    s
}

/// The plot: measured vs predicted acceleration, and the force, over time.
pub fn figure(r: &FitReport, samples: &[Sample]) -> Figure {
    let t: Vec<f64> = samples.iter().map(|s| s.t).collect();
    let predicted = samples
        .iter()
        .map(|s| (s.force - r.c1 * s.velocity - r.c2 * s.velocity * s.velocity.abs()) / r.mass)
        .collect();
    Figure {
        title: {
            // A value the data do not identify is not quoted as one (a J on its bound of 1e3).
            let value = |name: &str, symbol: &str, v: f64, unit: &str| {
                if r.not_identified.contains(&name) {
                    format!("{symbol} not identified")
                } else {
                    format!("{symbol} = {v:.4e}{unit}")
                }
            };
            format!(
                "propid fit: {}, {}, {} (RMS {:.3e} rad/s²)",
                value("mass", "J", r.mass, " kg·m²"),
                value("c1", "c1", r.c1 + 0.0, ""),
                value("c2", "c2", r.c2, ""),
                r.rms
            )
        },
        x_label: "t [s]".into(),
        panels: vec![
            Panel {
                title: "acceleration: measured vs model".into(),
                y_label: "dω/dt [rad/s²]".into(),
                series: vec![
                    Series {
                        name: "measured".into(),
                        x: t.clone(),
                        y: samples.iter().map(|s| s.acceleration).collect(),
                        style: Style::Points,
                    },
                    Series {
                        name: "model (F − c1·ω − c2·ω|ω|)/J".into(),
                        x: t.clone(),
                        y: predicted,
                        style: Style::Line,
                    },
                ],
            },
            Panel {
                title: "force (torque)".into(),
                y_label: "Q [N·m]".into(),
                series: vec![Series {
                    name: "force".into(),
                    x: t,
                    y: samples.iter().map(|s| s.force).collect(),
                    style: Style::Line,
                }],
            },
        ],
    }
}
