//! What to plot: thrust and torque over speed with the fitted laws, the coefficients over speed
//! with the band table, and the efficiency map (iso-efficiency lines over speed and torque from
//! the loss model, the measured points on it).

use crate::figure::{Figure, Panel, Series, Style};

use super::law::{Coefficient, Kind};
use super::{Propulsion, Recording, TAU};

fn law_lines(c: &Coefficient, p: &Propulsion, coefficient: bool) -> Vec<Series> {
    let Some(law) = c.law else {
        return Vec::new();
    };
    let (lo, hi) = (law.speed_range[0] * 0.9, law.speed_range[1] * 1.05);
    let ns: Vec<f64> = (0..=120)
        .map(|k| lo + (hi - lo) * k as f64 / 120.0)
        .collect();
    let scale = |n: f64| {
        if coefficient {
            c.kind.scale(p.air.density, n, p.diameter)
        } else {
            1.0
        }
    };
    let mut out = vec![Series {
        name: format!("power law, p = {:.3}", law.exponent),
        x: ns.iter().map(|n| n * 60.0).collect(),
        y: ns.iter().map(|&n| law.value(n) / scale(n)).collect(),
        style: Style::Line,
    }];
    if let Some(cq) = c.quadratic.value() {
        out.push(Series {
            name: format!("quadratic law, {} = {cq:.4}", c.kind.symbol()),
            x: ns.iter().map(|n| n * 60.0).collect(),
            y: ns
                .iter()
                .map(|&n| cq * c.kind.scale(p.air.density, n, p.diameter) / scale(n))
                .collect(),
            style: Style::Line,
        });
    }
    out
}

fn measured(p: &Propulsion, rec: Option<&Recording>, kind: Kind, coefficient: bool) -> Vec<Series> {
    let mut out = Vec::new();
    let pts: Vec<(f64, f64)> = p
        .operating_points
        .iter()
        .filter_map(|o| {
            let v = match (kind, coefficient) {
                (Kind::Thrust, false) => o.thrust,
                (Kind::Torque, false) => o.torque,
                (Kind::Thrust, true) => o.c_t,
                (Kind::Torque, true) => o.c_q,
            }?;
            Some((o.rpm, v))
        })
        .collect();
    if !pts.is_empty() {
        out.push(Series {
            name: "steady plateaus".into(),
            x: pts.iter().map(|p| p.0).collect(),
            y: pts.iter().map(|p| p.1).collect(),
            style: Style::Points,
        });
    }
    // A dynamic run: its samples (at most 3000 of them).
    let c = match kind {
        Kind::Thrust => p.thrust.as_ref(),
        Kind::Torque => p.torque.as_ref(),
    };
    if let (Some(rec), Some(c)) = (rec, c) {
        if c.method == super::Method::Dynamic && !coefficient {
            if let Some(v) = match kind {
                Kind::Thrust => rec.thrust.as_ref(),
                Kind::Torque => rec.torque.as_ref(),
            } {
                let step = (rec.time.len() / 3000).max(1);
                let (x, y): (Vec<f64>, Vec<f64>) = (0..rec.time.len())
                    .step_by(step)
                    .filter(|&k| v[k].is_finite() && rec.speed[k].is_finite())
                    .map(|k| (rec.speed[k].abs() / TAU * 60.0, v[k]))
                    .unzip();
                out.push(Series {
                    name: "samples (through the cell's lag)".into(),
                    x,
                    y,
                    style: Style::Points,
                });
            }
        }
    }
    if coefficient {
        if let Some(c) = c {
            let bands: Vec<(f64, f64)> = c
                .bands
                .iter()
                .filter_map(|b| Some((b.speed * 60.0, b.coefficient.value()?)))
                .collect();
            out.push(Series {
                name: "speed bands".into(),
                x: bands.iter().map(|b| b.0).collect(),
                y: bands.iter().map(|b| b.1).collect(),
                style: Style::Points,
            });
        }
    }
    out
}

/// Iso-efficiency points of the loss model over speed and torque.
fn efficiency_map(p: &Propulsion) -> Option<Panel> {
    let losses = p.motor.as_ref()?.losses.as_ref()?;
    let top_rpm = p
        .operating_points
        .iter()
        .map(|o| o.rpm)
        .fold(0.0, f64::max)
        .max(
            p.torque
                .as_ref()
                .and_then(|c| c.law)
                .map_or(0.0, |l| l.speed_range[1] * 60.0),
        );
    let top_q = p
        .operating_points
        .iter()
        .filter_map(|o| o.torque)
        .fold(0.0, f64::max)
        .max(
            p.torque
                .as_ref()
                .and_then(|c| c.law)
                .map_or(0.0, |l| l.value(l.speed_range[1])),
        );
    if !(top_rpm > 0.0 && top_q > 0.0) {
        return None;
    }
    let mut series = Vec::new();
    for level in [0.5, 0.6, 0.7, 0.75, 0.8, 0.85, 0.9] {
        let (mut x, mut y) = (Vec::new(), Vec::new());
        for i in 1..=80 {
            let rpm = 1.2 * top_rpm * i as f64 / 80.0;
            let w = rpm * TAU / 60.0;
            let qs: Vec<f64> = (0..=400).map(|k| 1.5 * top_q * k as f64 / 400.0).collect();
            for pair in qs.windows(2) {
                let (Some(a), Some(b)) =
                    (losses.efficiency(w, pair[0]), losses.efficiency(w, pair[1]))
                else {
                    continue;
                };
                if (a - level) * (b - level) < 0.0 {
                    let f = (level - a) / (b - a);
                    x.push(rpm);
                    y.push(pair[0] + f * (pair[1] - pair[0]));
                }
            }
        }
        if !x.is_empty() {
            series.push(Series {
                name: format!("η = {:.0} %", 100.0 * level),
                x,
                y,
                style: Style::Points,
            });
        }
    }
    let measured: Vec<(f64, f64)> = p
        .operating_points
        .iter()
        .filter_map(|o| Some((o.rpm, o.torque?)))
        .collect();
    series.push(Series {
        name: "measured plateaus".into(),
        x: measured.iter().map(|m| m.0).collect(),
        y: measured.iter().map(|m| m.1).collect(),
        style: Style::Points,
    });
    Some(Panel {
        title: format!(
            "Efficiency map (shaft power / electrical power; {})",
            losses.source
        ),
        y_label: "torque [N·m]".into(),
        series,
    })
}

/// The figure of an identification.
pub fn figure(p: &Propulsion, rec: Option<&Recording>) -> Figure {
    let mut panels = Vec::new();
    for (c, kind, what, unit) in [
        (p.thrust.as_ref(), Kind::Thrust, "Thrust", "thrust [N]"),
        (p.torque.as_ref(), Kind::Torque, "Torque", "torque [N·m]"),
    ] {
        let Some(c) = c else { continue };
        let mut series = measured(p, rec, kind, false);
        series.extend(law_lines(c, p, false));
        panels.push(Panel {
            title: format!("{what} over speed"),
            y_label: unit.into(),
            series,
        });
        let mut series = measured(p, rec, kind, true);
        series.extend(law_lines(c, p, true));
        panels.push(Panel {
            title: format!(
                "{} over speed (ρ = {:.4} kg/m³, D = {} m)",
                kind.symbol(),
                p.air.density,
                p.diameter
            ),
            y_label: kind.symbol().into(),
            series,
        });
    }
    if let Some(panel) = efficiency_map(p) {
        panels.push(panel);
    }
    Figure {
        title: "Propeller and motor".into(),
        x_label: "speed [rpm]".into(),
        panels,
    }
}
