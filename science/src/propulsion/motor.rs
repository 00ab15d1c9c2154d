//! The motor's constants from the bus voltage, current and duty, and its losses.
//!
//! ```text
//!  motor voltage  V_m = d·V_bus        motor current  I_m = I_bus/d     (an ESC without losses:
//!                                                                       V_bus·I_bus = V_m·I_m)
//!  back-EMF       V_m = K_e·ω + R·I_m                  at steady speed (L·dI/dt = 0)
//!  torque         K_t·(I_m − I_0) = Q                  Q the shaft torque, I_0 the no-load current
//!  Kv [rpm/V] = 60/(2π·K_e);  in SI K_t = K_e [N·m/A = V·s/rad]
//!  power balance  V_bus·I_bus = ω·(Q + Q_f) + r·(Q + Q_f)²,   Q_f = K_t·I_0,  r = R/K_t²
//!  efficiency     η(ω, Q) = ω·Q / (V_bus·I_bus)
//! ```
//! Where the duty is logged, K_e and R come from the back-EMF equation on steady plateaus
//! (least squares through the origin in ω and I_m), and K_t and I_0 from the shaft torque (only
//! where the torque is measured independently of the current: an ESC log whose torque was
//! computed from its current fits it exactly, and that is said). Without a duty, the power
//! balance still gives the friction torque Q_f and r = R/K_t² (but not K_e: the bus voltage is
//! not the motor's), and with them the efficiency map. On dynamic runs the back-EMF equation is
//! fitted row by row with the ESC's current filter (a first-order lag τ on the reported bus
//! current, as the AutoQuad ESC32's `adcAvgAmps` running average is) found by golden section:
//! multiplied by the duty, the equations are linear in the bus current the ESC filters,
//!
//! ```text
//!  L_τ[d²·V_bus] = K_e·L_τ[d·ω] + R·I_reported        I_reported = L_τ[d·Q]/K_t + I_0·L_τ[d]
//! ```

use propid_core::estimate::NormalEquations;
use serde::{Deserialize, Serialize};

use super::dynamic::{lag, updates};
use super::law::golden_min;
use super::plateau::Plateau;
use super::quantity::Quantity;
use super::{Recording, TAU};

/// Duties below this are not used (I_bus/d is then dominated by the current's noise).
pub const MIN_DUTY: f64 = 0.05;

/// Longest current filter a dynamic fit considers [s].
pub const MAX_CURRENT_FILTER: f64 = 0.2;

/// rpm/V from K_e [V·s/rad].
pub fn kv_from_ke(ke: f64) -> f64 {
    60.0 / (TAU * ke)
}

/// K_e [V·s/rad] from Kv [rpm/V].
pub fn ke_from_kv(kv: f64) -> f64 {
    60.0 / (TAU * kv)
}

/// The loss model: friction torque and copper-loss coefficient.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Losses {
    /// Q_f = K_t·I_0: the torque the motor spends on its own friction and iron losses [N·m].
    pub friction_torque: Quantity,
    /// r = R/K_t²: copper loss per squared torque [W/(N·m)²].
    pub copper: Quantity,
    /// How it was found.
    pub source: String,
    /// Plateaus (or rows) behind it.
    pub points: usize,
}

impl Losses {
    /// Electrical input power at speed ω [rad/s] and shaft torque Q [N·m]: ω(Q+Q_f) + r(Q+Q_f)².
    pub fn input_power(&self, omega: f64, torque: f64) -> Option<f64> {
        let qf = self.friction_torque.value()?;
        let r = self.copper.value()?;
        let q = torque + qf;
        Some(omega * q + r * q * q)
    }

    /// η = ω·Q / input power.
    pub fn efficiency(&self, omega: f64, torque: f64) -> Option<f64> {
        Some(omega * torque / self.input_power(omega, torque)?)
    }
}

/// The motor as the data give it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Motor {
    /// Kv from the back-EMF [rpm/V].
    pub kv: Quantity,
    /// Resistance seen by the motor current (windings, wiring and the ESC's switches) [Ω].
    pub resistance: Quantity,
    /// K_t from the shaft torque against the motor current [N·m/A].
    pub kt: Quantity,
    /// No-load current I_0 [A].
    pub no_load_current: Quantity,
    /// The reported current's filter (dynamic runs) [s].
    pub current_filter: Option<Quantity>,
    /// RMS residual of the back-EMF equation [V].
    pub back_emf_rms: Option<f64>,
    /// Points behind the back-EMF fit.
    pub back_emf_points: usize,
    /// The loss model (power balance, or from K_t, I_0, R).
    pub losses: Option<Losses>,
    /// How it was measured.
    pub method: super::Method,
}

/// Why nothing is checked against a torque computed from the current.
const COMPUTED_TORQUE: &str = "the torque column is proportional to the motor current (it was computed from it, as an ESC log's Kt·I/duty is): K_t, the no-load current and the losses cannot be checked against it";

fn no_duty() -> String {
    "no duty column: the back-EMF equation needs the motor's voltage d·V_bus (an ESC log's duty, \
     or `command` when it is the duty)"
        .into()
}

/// Back-EMF on plateaus: (K_e, R) with their standard errors and the residual RMS.
fn back_emf_plateaus(plateaus: &[Plateau]) -> Result<(Quantity, Quantity, f64, usize), String> {
    let pts: Vec<(f64, f64, f64)> = plateaus
        .iter()
        .filter_map(|p| {
            let (v, i, d) = (p.voltage?, p.current?, p.duty?);
            (d.value > MIN_DUTY).then_some((p.speed.value, d.value * v.value, i.value / d.value))
        })
        .collect();
    if pts.len() < 3 {
        return Err(format!(
            "{} steady plateau(s) with voltage, current and a duty above {MIN_DUTY}; the back-EMF fit needs 3",
            pts.len()
        ));
    }
    let mut eq = NormalEquations::<f64, 2>::new();
    for (w, vm, im) in &pts {
        eq.update(&[*w, *im], *vm);
    }
    let s = eq.solve().map_err(|_| {
        "speed and motor current do not vary independently across the plateaus".to_string()
    })?;
    Ok((
        Quantity::judge(s.theta[0], s.stderr[0], "V·s/rad"),
        Quantity::judge(s.theta[1], s.stderr[1], "Ω"),
        s.rms,
        pts.len(),
    ))
}

/// K_t and I_0 from plateaus: I_m = Q/K_t + I_0.
fn torque_current_plateaus(plateaus: &[Plateau]) -> TorqueCurrent {
    let pts: Vec<(f64, f64)> = plateaus
        .iter()
        .filter_map(|p| {
            let (q, i, d) = (p.torque?, p.current?, p.duty?);
            (d.value > MIN_DUTY).then_some((q.value, i.value / d.value))
        })
        .collect();
    torque_current(&pts, "steady plateau")
}

/// K_t, I_0, and whether the torque was computed from the current (then nothing electrical can
/// be checked against it).
type TorqueCurrent = (Quantity, Quantity, bool);

fn torque_current(pts: &[(f64, f64)], what: &str) -> TorqueCurrent {
    let cj = |r: String| {
        (
            Quantity::cannot_judge("N·m/A", r.clone()),
            Quantity::cannot_judge("A", r),
            false,
        )
    };
    if pts.len() < 3 {
        return cj(format!(
            "{} {what}(s) with torque, current and duty; K_t needs 3",
            pts.len()
        ));
    }
    let mut eq = NormalEquations::<f64, 2>::new();
    for (q, im) in pts {
        eq.update(&[*q, 1.0], *im);
    }
    let Ok(s) = eq.solve() else {
        return cj("the torque does not vary".into());
    };
    let mean_i = pts.iter().map(|p| p.1.abs()).sum::<f64>() / pts.len() as f64;
    if s.rms < 1e-6 * mean_i {
        let (kt, i0, _) = cj(COMPUTED_TORQUE.into());
        return (kt, i0, true);
    }
    let slope = s.theta[0];
    (
        Quantity::judge(1.0 / slope, s.stderr[0] / (slope * slope), "N·m/A"),
        Quantity::judge_relative(s.theta[1], s.stderr[1], "A", 0.5),
        false,
    )
}

/// The power balance on plateaus: (Q_f, r).
fn power_balance(plateaus: &[Plateau]) -> Option<Losses> {
    let pts: Vec<(f64, f64, f64)> = plateaus
        .iter()
        .filter_map(|p| {
            Some((
                p.speed.value.abs(),
                p.torque?.value,
                p.electrical_power?.value,
            ))
        })
        .filter(|(_, q, p)| *q > 0.0 && *p > 0.0)
        .collect();
    if pts.len() < 4 {
        return None;
    }
    let q_max = pts.iter().map(|p| p.1).fold(0.0, f64::max);
    let r_at = |qf: f64| {
        let (mut num, mut den) = (0.0, 0.0);
        for (w, q, p) in &pts {
            let s = (q + qf).powi(2);
            num += (p - w * (q + qf)) * s;
            den += s * s;
        }
        num / den
    };
    let rss = |qf: f64| {
        let r = r_at(qf);
        pts.iter()
            .map(|(w, q, p)| (p - w * (q + qf) - r * (q + qf).powi(2)).powi(2))
            .sum::<f64>()
    };
    let qf = golden_min(-0.5 * q_max, q_max, rss, 80);
    let r = r_at(qf);
    let sigma2 = rss(qf) / (pts.len() as f64 - 2.0);
    let mut m = [[0.0; 2]; 2];
    for (w, q, _) in &pts {
        let j = [w + 2.0 * r * (q + qf), (q + qf).powi(2)];
        for a in 0..2 {
            for b in 0..2 {
                m[a][b] += j[a] * j[b];
            }
        }
    }
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let (se_qf, se_r) = if det > 0.0 {
        (
            (sigma2 * m[1][1] / det).sqrt(),
            (sigma2 * m[0][0] / det).sqrt(),
        )
    } else {
        (f64::NAN, f64::NAN)
    };
    Some(Losses {
        friction_torque: Quantity::judge_relative(qf, se_qf, "N·m", 0.5),
        copper: Quantity::judge(r, se_r, "W/(N·m)²"),
        source: "power balance V·I = ω(Q+Q_f) + r(Q+Q_f)² on steady plateaus (ESC losses included)"
            .into(),
        points: pts.len(),
    })
}

/// The losses from K_t, I_0 and R: Q_f = K_t·I_0, r = R/K_t².
fn losses_from_constants(
    kt: &Quantity,
    i0: &Quantity,
    r: &Quantity,
    points: usize,
) -> Option<Losses> {
    let (kt_v, kt_s) = (kt.value()?, kt.stderr()?);
    let (i0_v, i0_s) = (i0.value()?, i0.stderr()?);
    let (r_v, r_s) = (r.value()?, r.stderr()?);
    let qf = kt_v * i0_v;
    let qf_s = ((kt_s * i0_v).powi(2) + (kt_v * i0_s).powi(2)).sqrt();
    let c = r_v / (kt_v * kt_v);
    let c_s = c * ((r_s / r_v).powi(2) + (2.0 * kt_s / kt_v).powi(2)).sqrt();
    Some(Losses {
        friction_torque: Quantity::judge_relative(qf, qf_s, "N·m", 0.5),
        copper: Quantity::judge(c, c_s, "W/(N·m)²"),
        source: "from K_t, I_0 and R (Q_f = K_t·I_0, r = R/K_t²)".into(),
        points,
    })
}

/// The motor from steady plateaus. `Err` says why nothing can be said (no current or voltage).
pub fn from_plateaus(rec: &Recording, plateaus: &[Plateau]) -> Result<Motor, String> {
    missing_columns(rec)?;
    let (kv, resistance, rms, points) = match (rec.duty.is_some(), back_emf_plateaus(plateaus)) {
        (false, _) => (
            Quantity::cannot_judge("rpm/V", no_duty()),
            Quantity::cannot_judge("Ω", no_duty()),
            None,
            0,
        ),
        (true, Ok((ke, r, rms, n))) => (kv_quantity(&ke), r, Some(rms), n),
        (true, Err(why)) => (
            Quantity::cannot_judge("rpm/V", why.clone()),
            Quantity::cannot_judge("Ω", why),
            None,
            0,
        ),
    };
    let (kt, no_load_current, computed) = if rec.torque.is_none() {
        let why = "no torque column: K_t needs the shaft torque".to_string();
        (
            Quantity::cannot_judge("N·m/A", why.clone()),
            Quantity::cannot_judge("A", why),
            false,
        )
    } else if rec.duty.is_none() {
        (
            Quantity::cannot_judge("N·m/A", no_duty()),
            Quantity::cannot_judge("A", no_duty()),
            false,
        )
    } else {
        torque_current_plateaus(plateaus)
    };
    let losses = if computed {
        None
    } else {
        power_balance(plateaus)
            .or_else(|| losses_from_constants(&kt, &no_load_current, &resistance, points))
    };
    Ok(Motor {
        kv,
        resistance,
        kt,
        no_load_current,
        current_filter: None,
        back_emf_rms: rms,
        back_emf_points: points,
        losses,
        method: super::Method::Plateaus,
    })
}

fn missing_columns(rec: &Recording) -> Result<(), String> {
    match (rec.voltage.is_some(), rec.current.is_some()) {
        (true, true) => Ok(()),
        (false, true) => Err("no `voltage` column: the motor's constants and efficiency need the bus voltage beside the current".into()),
        (true, false) => Err("no `current` column: the motor's constants and efficiency need the bus current beside the voltage".into()),
        (false, false) => Err("no `voltage` or `current` column: the motor's constants need the bus voltage and current (and the duty for Kv)".into()),
    }
}

fn kv_quantity(ke: &Quantity) -> Quantity {
    match (ke.value(), ke.stderr()) {
        (Some(k), Some(s)) if k > 0.0 => {
            let kv = kv_from_ke(k);
            let q = Quantity::judge(kv, kv * s / k, "rpm/V");
            if matches!(ke, Quantity::NotIdentified { .. }) {
                q.not_identified("K_e is not identified")
            } else {
                q
            }
        }
        (Some(k), _) => Quantity::cannot_judge(
            "rpm/V",
            format!("the back-EMF constant came out {k:.3e} V·s/rad, not positive: is the speed's sign or the duty right?"),
        ),
        _ => Quantity::cannot_judge("rpm/V", "K_e could not be fitted"),
    }
}

/// The motor from a dynamic run: the back-EMF equation row by row through the current filter.
pub fn from_dynamic(rec: &Recording) -> Result<Motor, String> {
    missing_columns(rec)?;
    let (Some(v), Some(i)) = (&rec.voltage, &rec.current) else {
        unreachable!("checked above")
    };
    let Some(d) = &rec.duty else {
        let why = no_duty();
        return Ok(Motor {
            kv: Quantity::cannot_judge("rpm/V", why.clone()),
            resistance: Quantity::cannot_judge("Ω", why.clone()),
            kt: Quantity::cannot_judge("N·m/A", why.clone()),
            no_load_current: Quantity::cannot_judge("A", why),
            current_filter: None,
            back_emf_rms: None,
            back_emf_points: 0,
            losses: None,
            method: super::Method::Dynamic,
        });
    };
    let t = &rec.time;
    // The ESC filters the bus current it reports, I_bus = d·I_m. Multiplied by d, the back-EMF
    // equation is linear in it: d²·V_bus = K_e·(d·ω) + R·I_bus; through the filter L_τ,
    // L_τ[d²·V_bus] = K_e·L_τ[d·ω] + R·I_reported, with no division by a filtered current.
    let active: Vec<bool> = d.iter().map(|d| *d > MIN_DUTY).collect();
    let d2v: Vec<f64> = v.iter().zip(d).map(|(v, d)| d * d * v).collect();
    let dw: Vec<f64> = rec.speed.iter().zip(d).map(|(w, d)| d * w).collect();
    let rows: Vec<usize> = updates(i)
        .into_iter()
        // The filter's state before the record is unknown: its first 5·τ_max are not fitted.
        .filter(|&k| t[k] > t[0] + 5.0 * MAX_CURRENT_FILTER)
        .filter(|&k| active[k] && d2v[k].is_finite() && dw[k].is_finite())
        .collect();
    if rows.len() < 50 {
        return Err(format!(
            "{} rows with a new current reading and a duty above {MIN_DUTY}; a dynamic fit needs 50",
            rows.len()
        ));
    }
    let voltage_noise = super::plateau::noise_of(v);
    let speed_noise = super::plateau::noise_of(&rec.speed);
    let interval = super::dynamic::median_interval(t);
    let mean_d2: f64 = rows.iter().map(|&k| d[k].powi(2)).sum::<f64>() / rows.len() as f64;
    let mean_d4: f64 = rows.iter().map(|&k| d[k].powi(4)).sum::<f64>() / rows.len() as f64;
    let solve = |tau: f64| {
        let yl = lag(t, &d2v, tau);
        let xl = lag(t, &dw, tau);
        let mut eq = NormalEquations::<f64, 2>::new();
        for &k in &rows {
            eq.update(&[xl[k], i[k]], yl[k]);
        }
        eq.solve()
            .ok()
            .map(|s| (eq.residual_sum_of_squares(&s.theta), s))
    };
    // The lag smooths the voltage's noise (in d²·V_bus) and the speed's (in K_e·d·ω): that part
    // of the residual is put back before lags are compared.
    let rss = |tau: f64| {
        solve(tau).map_or(f64::INFINITY, |s| {
            let lost = 1.0 - super::dynamic::smoothing_gain(interval, tau);
            let noise =
                mean_d4 * voltage_noise.powi(2) + mean_d2 * (s.1.theta[0] * speed_noise).powi(2);
            s.0 + lost * rows.len() as f64 * noise
        })
    };
    let mut tau = golden_min(0.0, MAX_CURRENT_FILTER, rss, 40);
    if rss(0.0) <= rss(tau) {
        tau = 0.0;
    }
    let (rss0, s) = solve(tau).ok_or("speed and current do not vary independently")?;
    let sigma2 = rss0 / (rows.len() as f64 - 3.0);
    let h = (0.05 * tau).max(1e-4);
    let x = tau.max(h);
    let c = (rss(x + h) - 2.0 * rss(x) + rss(x - h)) / (h * h);
    let tau_se = if c > 0.0 {
        (2.0 * sigma2 / c).sqrt()
    } else {
        f64::NAN
    };
    let ke = Quantity::judge(s.theta[0], s.stderr[0], "V·s/rad");
    let resistance = Quantity::judge(s.theta[1], s.stderr[1], "Ω");
    // K_t, I_0: I_reported = (1/K_t)·L_τ[d·Q] + I_0·L_τ[d].
    let (kt, no_load_current) = match &rec.torque {
        Some(q) => {
            let dq: Vec<f64> = q.iter().zip(d).map(|(q, d)| q * d).collect();
            let dql = lag(t, &dq, tau);
            let dl = lag(t, d, tau);
            let mut eq = NormalEquations::<f64, 2>::new();
            for &k in &rows {
                if dql[k].is_finite() {
                    eq.update(&[dql[k], dl[k]], i[k]);
                }
            }
            match eq.solve() {
                Ok(s) if s.rms >= 1e-9 * s.theta[1].abs().max(1e-3) => (
                    Quantity::judge(
                        1.0 / s.theta[0],
                        s.stderr[0] / (s.theta[0] * s.theta[0]),
                        "N·m/A",
                    ),
                    Quantity::judge_relative(s.theta[1], s.stderr[1], "A", 0.5),
                ),
                Ok(_) => {
                    let why = "the torque column is proportional to the current (it was computed from it): K_t cannot be checked against it".to_string();
                    (
                        Quantity::cannot_judge("N·m/A", why.clone()),
                        Quantity::cannot_judge("A", why),
                    )
                }
                Err(_) => {
                    let why = "the torque and the duty do not vary independently".to_string();
                    (
                        Quantity::cannot_judge("N·m/A", why.clone()),
                        Quantity::cannot_judge("A", why),
                    )
                }
            }
        }
        None => {
            let why = "no torque column: K_t needs the shaft torque".to_string();
            (
                Quantity::cannot_judge("N·m/A", why.clone()),
                Quantity::cannot_judge("A", why),
            )
        }
    };
    let losses = losses_from_constants(&kt, &no_load_current, &resistance, rows.len());
    Ok(Motor {
        kv: kv_quantity(&ke),
        resistance,
        kt,
        no_load_current,
        current_filter: Some(Quantity::judge_relative(tau, tau_se, "s", 0.5)),
        back_emf_rms: Some(s.rms),
        back_emf_points: rows.len(),
        losses,
        method: super::Method::Dynamic,
    })
}
