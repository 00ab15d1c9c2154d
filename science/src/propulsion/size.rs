//! Sizing: what a propeller needs for a thrust, a torque or a speed, and what that asks of the
//! motor, the controller's DC link and the battery.
//!
//! ```text
//!  propeller (identified laws, scaled to the sizing air: X ∝ ρ)
//!    thrust T  →  n = n_r·(T/A_T)^(1/p_T)          torque Q = A_Q·(n/n_r)^(p_Q)
//!    mechanical power P = 2π·n·Q;  FM = √(2/π)·C_T^1.5/C_P;  thrust per watt T/P
//!  motor (Kv, R, I_0; K_e = K_t = 60/(2π·Kv) in SI)
//!    I_m = Q/K_t + I_0     V_m = K_e·ω + R·I_m     P_e = V_m·I_m     η = P/P_e
//!  or the loss model alone:  P_e = ω(Q+Q_f) + r(Q+Q_f)²
//!  controller on a DC link V:  d = V_m/V (≤ the duty limit),  I_dc = P_e/V = d·I_m,
//!    DC-link capacitor ripple I_rms = I_m·√(d(1−d))   (a buck converter's input, per motor)
//!  vehicle of N rotors:  thrust N·T, battery current N·I_dc, power N·P_e;
//!    battery of C A·h, usable fraction u:  endurance u·C/(N·I_dc), C-rate N·I_dc/C
//!  which motor (the reverse question): the largest K_e that still reaches ω with d ≤ d_max:
//!    K_e²·ω − K_e·(d_max·V − R·I_0) + R·Q = 0  ⇒  Kv_min = 60/(2π·K_e,max),  I_m = Q/K_e + I_0
//! ```
//! Each propeller figure carries its ± from the laws' covariance (first-order propagation);
//! the electrical figures are computed at the central values (the motor constants come from a
//! datasheet or the identification with their own ±, shown beside).

use serde::{Deserialize, Serialize};

use super::law::PowerLaw;
use super::motor::{ke_from_kv, Losses};
use super::{figure_of_merit, Kind, TAU};

/// What a rotor must deliver.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", content = "value", rename_all = "snake_case")]
pub enum Target {
    /// Thrust per rotor [N].
    Thrust(f64),
    /// Shaft torque [N·m].
    Torque(f64),
    /// Speed [rad/s].
    Speed(f64),
}

/// The propeller as sizing uses it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Propeller {
    /// Diameter [m].
    pub diameter: f64,
    /// Density the laws were identified at [kg/m³].
    pub density: f64,
    /// Thrust law (N).
    pub thrust: Option<PowerLaw>,
    /// Torque law (N·m).
    pub torque: Option<PowerLaw>,
}

/// Motor constants (a datasheet's or identified).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MotorConstants {
    /// Kv [rpm/V].
    pub kv: f64,
    /// Resistance [Ω].
    pub resistance: f64,
    /// No-load current [A].
    pub no_load_current: f64,
}

/// The DC link.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Supply {
    /// Voltage [V].
    pub voltage: f64,
    /// Highest duty the controller may use (control headroom).
    pub max_duty: f64,
}

/// The battery.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Battery {
    /// Capacity [A·h].
    pub capacity: f64,
    /// Usable fraction of it.
    pub usable: f64,
}

/// The sizing question.
#[derive(Clone, Debug, PartialEq)]
pub struct Question {
    /// The propeller.
    pub propeller: Propeller,
    /// Air density for the sizing [kg/m³].
    pub density: f64,
    /// The motor, if known.
    pub motor: Option<MotorConstants>,
    /// The loss model, if known (used when the motor constants are not).
    pub losses: Option<Losses>,
    /// The DC link, if given.
    pub supply: Option<Supply>,
    /// Rotors on the vehicle.
    pub rotors: u32,
    /// The battery, if given.
    pub battery: Option<Battery>,
    /// The targets.
    pub targets: Vec<Target>,
}

/// A value with its standard error.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Value {
    /// The value.
    pub value: f64,
    /// One standard error (0 when exact: a target).
    pub stderr: f64,
}

/// The electrical side of an operating point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Electrical {
    /// What the figures come from: "motor constants" or "loss model".
    pub from: String,
    /// Motor current I_m [A] (motor constants only).
    pub motor_current: Option<f64>,
    /// Motor voltage V_m [V] (motor constants only).
    pub motor_voltage: Option<f64>,
    /// Electrical input power per rotor [W].
    pub power: f64,
    /// Motor (and ESC, for a loss model) efficiency.
    pub efficiency: f64,
    /// Thrust per electrical watt [N/W].
    pub thrust_per_watt: f64,
    /// Duty on the DC link (supply and motor constants given).
    pub duty: Option<f64>,
    /// DC-link current per rotor [A] (supply given).
    pub dc_current: Option<f64>,
    /// DC-link capacitor ripple current per rotor [A rms].
    pub ripple_current: Option<f64>,
    /// False when the duty this needs exceeds the duty limit.
    pub reachable: bool,
}

/// The vehicle's totals.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Totals {
    /// Rotors.
    pub rotors: u32,
    /// Total thrust [N].
    pub thrust: f64,
    /// Total mechanical power [W].
    pub mechanical_power: f64,
    /// Total electrical power [W].
    pub electrical_power: Option<f64>,
    /// Battery current [A].
    pub battery_current: Option<f64>,
    /// Battery C-rate [1/h].
    pub c_rate: Option<f64>,
    /// Endurance at this point [min].
    pub endurance_minutes: Option<f64>,
}

/// One target's answer.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OperatingPoint {
    /// The target.
    pub target: Target,
    /// Speed [rad/s].
    pub speed: Value,
    /// Speed [rpm].
    pub rpm: f64,
    /// Thrust per rotor [N] (when the thrust law is known).
    pub thrust: Option<Value>,
    /// Shaft torque [N·m].
    pub torque: Value,
    /// Mechanical power per rotor [W].
    pub mechanical_power: Value,
    /// Figure of merit.
    pub figure_of_merit: Option<f64>,
    /// Thrust per mechanical watt [N/W].
    pub thrust_per_watt: Option<f64>,
    /// True when the speed lies outside the speeds the laws were identified on.
    pub extrapolated: bool,
    /// The electrical side.
    pub electrical: Option<Electrical>,
    /// The vehicle.
    pub totals: Totals,
    /// What limits this point, in words.
    pub notes: Vec<String>,
}

/// The reverse question's answer for one target.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KvAdvice {
    /// The target.
    pub target: Target,
    /// The DC-link voltage [V].
    pub voltage: f64,
    /// The duty limit.
    pub max_duty: f64,
    /// Resistance assumed [Ω].
    pub resistance: f64,
    /// No-load current assumed [A].
    pub no_load_current: f64,
    /// The lowest Kv that reaches the speed [rpm/V] (`None`: no Kv does).
    pub kv_min: Option<f64>,
    /// Motor current at that Kv [A].
    pub motor_current: Option<f64>,
    /// DC-link current per rotor at that Kv [A].
    pub dc_current: Option<f64>,
    /// Why no Kv does, when none does.
    pub why_not: Option<String>,
}

/// The answers.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Answer {
    /// Density used [kg/m³].
    pub density: f64,
    /// One point per target.
    pub points: Vec<OperatingPoint>,
    /// Which Kv, per target (when a supply voltage is given).
    pub kv_advice: Vec<KvAdvice>,
}

/// Why a question cannot be answered.
pub fn check(q: &Question) -> Result<(), String> {
    if q.propeller.torque.is_none() {
        return Err("the propeller has no torque law (its identification had no torque column): speed, torque and power cannot be sized".into());
    }
    for t in &q.targets {
        match t {
            Target::Thrust(x) | Target::Torque(x) | Target::Speed(x)
                if !(*x > 0.0 && x.is_finite()) =>
            {
                return Err(format!("a target must be positive and finite (got {t:?})"));
            }
            Target::Thrust(_) if q.propeller.thrust.is_none() => {
                return Err("a thrust target needs the thrust law, and the propeller's identification had no thrust column".into());
            }
            _ => {}
        }
    }
    if q.rotors == 0 {
        return Err("the number of rotors must be at least 1".into());
    }
    if let Some(s) = q.supply {
        if !(s.voltage > 0.0 && s.voltage.is_finite()) {
            return Err(format!(
                "the supply voltage must be positive (got {} V)",
                s.voltage
            ));
        }
        if !(s.max_duty > 0.0 && s.max_duty <= 1.0) {
            return Err(format!(
                "the duty limit must be in (0, 1] (got {})",
                s.max_duty
            ));
        }
    }
    if let Some(m) = q.motor {
        if !(m.kv > 0.0 && m.resistance >= 0.0 && m.no_load_current >= 0.0) {
            return Err(format!(
                "motor constants must be Kv > 0, R ≥ 0, I_0 ≥ 0 (got {m:?})"
            ));
        }
    }
    if let Some(b) = q.battery {
        if !(b.capacity > 0.0 && b.usable > 0.0 && b.usable <= 1.0) {
            return Err(format!(
                "battery capacity must be > 0 and its usable fraction in (0, 1] (got {b:?})"
            ));
        }
    }
    Ok(())
}

/// Answers the question.
pub fn size(q: &Question) -> Result<Answer, String> {
    check(q)?;
    let points = q.targets.iter().map(|t| point(q, *t)).collect();
    let kv_advice = match q.supply {
        Some(s) => q.targets.iter().map(|t| kv_advice(q, *t, s)).collect(),
        None => Vec::new(),
    };
    Ok(Answer {
        density: q.density,
        points,
        kv_advice,
    })
}

/// The laws scaled to the sizing density.
fn scaled(law: &PowerLaw, ratio: f64) -> PowerLaw {
    let mut l = *law;
    l.at_reference *= ratio;
    l.covariance[0][0] *= ratio * ratio;
    l.covariance[0][1] *= ratio;
    l.covariance[1][0] *= ratio;
    l
}

/// Speed [rev/s] and its standard error for a target.
fn speed_for(q: &Question, target: Target) -> (f64, f64) {
    let ratio = q.density / q.propeller.density;
    let torque = scaled(&q.propeller.torque.expect("checked"), ratio);
    match target {
        Target::Thrust(t) => {
            let law = scaled(&q.propeller.thrust.expect("checked"), ratio);
            (law.speed_for(t), law.speed_stderr(t))
        }
        Target::Torque(x) => (torque.speed_for(x), torque.speed_stderr(x)),
        Target::Speed(w) => (w / TAU, 0.0),
    }
}

fn point(q: &Question, target: Target) -> OperatingPoint {
    let ratio = q.density / q.propeller.density;
    let tl = q.propeller.thrust.map(|l| scaled(&l, ratio));
    let ql = scaled(&q.propeller.torque.expect("checked"), ratio);
    let d = q.propeller.diameter;
    let (n, n_se) = speed_for(q, target);
    let omega = TAU * n;
    // X(n) with the law's own error and the speed's error propagated (X ∝ n^p).
    let with_speed = |law: &PowerLaw| {
        let x = law.value(n);
        let law_se = law.value_stderr(n);
        let speed_part = law.exponent * x / n * n_se;
        Value {
            value: x,
            stderr: if matches!(target, Target::Speed(_)) {
                law_se
            } else {
                (law_se * law_se + speed_part * speed_part).sqrt()
            },
        }
    };
    let thrust = match (target, tl) {
        (Target::Thrust(t), _) => Some(Value {
            value: t,
            stderr: 0.0,
        }),
        (_, Some(l)) => Some(with_speed(&l)),
        _ => None,
    };
    let torque = match target {
        Target::Torque(x) => Value {
            value: x,
            stderr: 0.0,
        },
        _ => with_speed(&ql),
    };
    let p = omega * torque.value;
    let p_se = p * ((n_se / n).powi(2) + (torque.stderr / torque.value).powi(2)).sqrt();
    let mechanical_power = Value {
        value: p,
        stderr: p_se,
    };
    let c_q = torque.value / Kind::Torque.scale(q.density, n, d);
    let figure =
        thrust.map(|t| figure_of_merit(t.value / Kind::Thrust.scale(q.density, n, d), c_q));
    let tpw = thrust.map(|t| t.value / p);
    let extrapolated = !ql.covers(n) || tl.is_some_and(|l| !l.covers(n));
    let mut notes = Vec::new();
    if extrapolated {
        notes.push(format!(
            "{:.0} rpm lies outside the speeds the propeller was measured at ({:.0}–{:.0} rpm): the laws are extrapolated",
            n * 60.0,
            ql.speed_range[0] * 60.0,
            ql.speed_range[1] * 60.0
        ));
    }
    let electrical = electrical(q, omega, torque.value, thrust.map(|t| t.value), &mut notes);
    let totals = {
        let k = f64::from(q.rotors);
        let e_total = electrical.as_ref().map(|e| k * e.power);
        let i_total = electrical
            .as_ref()
            .and_then(|e| e.dc_current)
            .map(|i| k * i);
        Totals {
            rotors: q.rotors,
            thrust: k * thrust.map_or(f64::NAN, |t| t.value),
            mechanical_power: k * p,
            electrical_power: e_total,
            battery_current: i_total,
            c_rate: match (i_total, q.battery) {
                (Some(i), Some(b)) => Some(i / b.capacity),
                _ => None,
            },
            endurance_minutes: match (i_total, q.battery) {
                (Some(i), Some(b)) => Some(60.0 * b.usable * b.capacity / i),
                _ => None,
            },
        }
    };
    OperatingPoint {
        target,
        speed: Value {
            value: omega,
            stderr: TAU * n_se,
        },
        rpm: n * 60.0,
        thrust,
        torque,
        mechanical_power,
        figure_of_merit: figure,
        thrust_per_watt: tpw,
        extrapolated,
        electrical,
        totals,
        notes,
    }
}

fn electrical(
    q: &Question,
    omega: f64,
    torque: f64,
    thrust: Option<f64>,
    notes: &mut Vec<String>,
) -> Option<Electrical> {
    let p_mech = omega * torque;
    if let Some(m) = q.motor {
        let ke = ke_from_kv(m.kv);
        let im = torque / ke + m.no_load_current;
        let vm = ke * omega + m.resistance * im;
        let pe = vm * im;
        let (duty, dc, ripple, reachable) = match q.supply {
            Some(s) => {
                let d = vm / s.voltage;
                let reachable = d <= s.max_duty;
                if !reachable {
                    notes.push(format!(
                        "the motor needs {vm:.2} V, more than {:.0} % of the {:.2} V supply: it cannot reach this point (a higher Kv or voltage would)",
                        100.0 * s.max_duty,
                        s.voltage
                    ));
                }
                let dc = pe / s.voltage;
                let dd = d.min(1.0);
                (
                    Some(d),
                    Some(dc),
                    Some(im * (dd * (1.0 - dd)).max(0.0).sqrt()),
                    reachable,
                )
            }
            None => (None, None, None, true),
        };
        return Some(Electrical {
            from: format!(
                "motor constants Kv = {:.0} rpm/V, R = {:.4} Ω, I_0 = {:.3} A",
                m.kv, m.resistance, m.no_load_current
            ),
            motor_current: Some(im),
            motor_voltage: Some(vm),
            power: pe,
            efficiency: p_mech / pe,
            thrust_per_watt: thrust.map_or(f64::NAN, |t| t / pe),
            duty,
            dc_current: dc,
            ripple_current: ripple,
            reachable,
        });
    }
    let l = q.losses.as_ref()?;
    let pe = l.input_power(omega, torque)?;
    Some(Electrical {
        from: format!("loss model ({})", l.source),
        motor_current: None,
        motor_voltage: None,
        power: pe,
        efficiency: p_mech / pe,
        thrust_per_watt: thrust.map_or(f64::NAN, |t| t / pe),
        duty: None,
        dc_current: q.supply.map(|s| pe / s.voltage),
        ripple_current: None,
        reachable: true,
    })
}

fn kv_advice(q: &Question, target: Target, s: Supply) -> KvAdvice {
    let ratio = q.density / q.propeller.density;
    let ql = scaled(&q.propeller.torque.expect("checked"), ratio);
    let (n, _) = speed_for(q, target);
    let omega = TAU * n;
    let torque = match target {
        Target::Torque(x) => x,
        _ => ql.value(n),
    };
    let r = q.motor.map_or(0.0, |m| m.resistance);
    let i0 = q.motor.map_or(0.0, |m| m.no_load_current);
    let v = s.max_duty * s.voltage - r * i0;
    let disc = v * v - 4.0 * omega * r * torque;
    let mut advice = KvAdvice {
        target,
        voltage: s.voltage,
        max_duty: s.max_duty,
        resistance: r,
        no_load_current: i0,
        kv_min: None,
        motor_current: None,
        dc_current: None,
        why_not: None,
    };
    if v <= 0.0 || disc < 0.0 {
        advice.why_not = Some(format!(
            "at {:.2} V and a duty of at most {:.0} %, a resistance of {r:.4} Ω leaves too little voltage for {:.0} rpm at {torque:.4} N·m, whatever the Kv",
            s.voltage,
            100.0 * s.max_duty,
            n * 60.0
        ));
        return advice;
    }
    let ke = (v + disc.sqrt()) / (2.0 * omega);
    let im = torque / ke + i0;
    let vm = ke * omega + r * im;
    advice.kv_min = Some(60.0 / (TAU * ke));
    advice.motor_current = Some(im);
    advice.dc_current = Some(vm * im / s.voltage);
    advice
}

#[cfg(test)]
mod tests {
    use super::*;

    fn propeller() -> Propeller {
        // C_T = 0.12, C_Q = 0.01 constant (p = 2), D = 0.2 m, ρ = 1.2, reference 100 rev/s.
        let (rho, d, n): (f64, f64, f64) = (1.2, 0.2, 100.0);
        let law = |c: f64, m: i32| PowerLaw {
            reference_speed: n,
            at_reference: c * rho * n * n * d.powi(m),
            exponent: 2.0,
            covariance: [[1e-8, 0.0], [0.0, 0.0]],
            speed_range: [50.0, 200.0],
        };
        Propeller {
            diameter: d,
            density: rho,
            thrust: Some(law(0.12, 4)),
            torque: Some(law(0.01, 5)),
        }
    }

    #[test]
    fn thrust_to_speed_to_thrust_round_trips() {
        let q = Question {
            propeller: propeller(),
            density: 1.2,
            motor: None,
            losses: None,
            supply: None,
            rotors: 4,
            battery: None,
            targets: vec![Target::Thrust(6.0)],
        };
        let a = size(&q).unwrap();
        let p = &a.points[0];
        let n = p.speed.value / TAU;
        let back = 0.12 * 1.2 * n * n * 0.2f64.powi(4);
        assert!((back / 6.0 - 1.0).abs() < 1e-12, "{back}");
        assert_eq!(p.totals.thrust, 24.0);
    }

    #[test]
    fn the_lowest_kv_uses_exactly_the_duty_limit() {
        let q = Question {
            propeller: propeller(),
            density: 1.2,
            motor: Some(MotorConstants {
                kv: 1000.0,
                resistance: 0.1,
                no_load_current: 0.5,
            }),
            losses: None,
            supply: Some(Supply {
                voltage: 14.8,
                max_duty: 0.8,
            }),
            rotors: 1,
            battery: None,
            targets: vec![Target::Speed(900.0)],
        };
        let a = size(&q).unwrap();
        let k = &a.kv_advice[0];
        let kv = k.kv_min.unwrap();
        // With that Kv the motor needs exactly 80 % of 14.8 V.
        let ke = ke_from_kv(kv);
        let torque = a.points[0].torque.value;
        let im = torque / ke + 0.5;
        assert!(((ke * 900.0 + 0.1 * im) / 14.8 - 0.8).abs() < 1e-12);
    }
}
