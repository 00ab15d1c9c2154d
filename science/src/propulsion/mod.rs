//! # Propulsion: thrust, torque, power and efficiency, and the drivetrain they size
//!
//! The seed identifies J and c2 "for sizing the drivetrain": the torque and speed a propeller
//! needs for a lift, then the motor, controller, DC link and battery that deliver them. This
//! module does that part, from what a test stand records beside the speed — thrust and torque
//! load cells, the bus voltage and current, the ESC's duty — and answers the propulsion
//! engineer's questions: C_T and C_Q and how they change with speed, thrust per watt, the figure
//! of merit, the motor's Kv, resistance and no-load current, its efficiency map, and (in
//! [`size`]) what it takes to make a given thrust.
//!
//! ```text
//!  Recording (t, ω, dω/dt, thrust?, torque?, V?, I?, duty?)        SI units, NaN = no sample
//!      │
//!      ├─► plateau::find ─► steady plateaus (means ± independent-sample errors), load-cell zeros
//!      │        │
//!      │        ├─► law::coefficient_from_points ─► C_T, C_Q: power law about n_r (exponent p),
//!      │        │                                   quadratic law, table per speed band (Re, Mach)
//!      │        └─► motor::from_plateaus ─► Kv, R (back-EMF), K_t, I_0, losses, efficiency
//!      │
//!      └─► (no plateaus) dynamic::fit ─► the same laws through the load cell's lag;
//!                        motor::from_dynamic ─► back-EMF through the ESC's current filter
//!                                      │
//!                                      ▼
//!                       Propulsion (every value a Quantity: identified ± s.e., not identified,
//!                       or cannot judge) ─► size::size (targets → operating points) ─► figure
//! ```
//! Conventions: T = C_T·ρ·n²·D⁴ and Q = C_Q·ρ·n²·D⁵ with n in **rev/s** (ω = 2π·n); the seed's
//! c2 (Q = c2·ω²) is C_Q = c2·(2π)²/(ρ·D⁵). Air: [`air::Air`] (ISA sea level, 1.225 kg/m³, unless
//! a density or temperature and pressure are given). A coefficient scales as 1/ρ: with the density
//! not measured, it carries that assumption (said in every result), not an invented error. Every
//! equation is derived, with its source, in docs/PROPULSION.md.

pub mod air;
pub mod dynamic;
pub mod figure;
pub mod law;
pub mod motor;
pub mod plateau;
pub mod quantity;
pub mod read;
pub mod size;
pub mod text;
pub mod units;

use serde::{Deserialize, Serialize};

pub use air::Air;
pub use law::{Coefficient, Kind, PowerLaw};
pub use motor::{Losses, Motor};
pub use plateau::{Channel, PlateauOptions, Steady};
pub use quantity::Quantity;

/// 2π.
pub const TAU: f64 = std::f64::consts::TAU;

/// What a stand recorded, one entry per row, in SI units. A channel the stand did not log is
/// `None`; NaN marks a row where a logged channel has no sample (slow load cells).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Recording {
    /// Time [s], increasing.
    pub time: Vec<f64>,
    /// Mechanical speed ω [rad/s].
    pub speed: Vec<f64>,
    /// dω/dt [rad/s²] (NaN where unknown).
    pub acceleration: Vec<f64>,
    /// Shaft torque [N·m] (a load cell's, or the drive's estimate).
    pub torque: Option<Vec<f64>>,
    /// Thrust [N], positive along the thrust axis.
    pub thrust: Option<Vec<f64>>,
    /// DC bus voltage [V].
    pub voltage: Option<Vec<f64>>,
    /// DC bus current [A].
    pub current: Option<Vec<f64>>,
    /// Duty (ratio 0–1).
    pub duty: Option<Vec<f64>>,
}

impl Recording {
    /// Time and speed only.
    pub fn new(time: Vec<f64>, speed: Vec<f64>) -> Recording {
        let n = time.len();
        Recording {
            time,
            speed,
            acceleration: vec![f64::NAN; n],
            ..Recording::default()
        }
    }

    /// A channel's values.
    pub fn channel(&self, c: Channel) -> Option<&[f64]> {
        match c {
            Channel::Thrust => self.thrust.as_deref(),
            Channel::Torque => self.torque.as_deref(),
            Channel::Voltage => self.voltage.as_deref(),
            Channel::Current => self.current.as_deref(),
            Channel::Duty => self.duty.as_deref(),
        }
    }

    /// Checks lengths and time order; the error names the channel or the row.
    pub fn check(&self) -> Result<(), String> {
        let n = self.time.len();
        let lens = [
            ("speed", Some(self.speed.len())),
            ("acceleration", Some(self.acceleration.len())),
            ("torque", self.torque.as_ref().map(Vec::len)),
            ("thrust", self.thrust.as_ref().map(Vec::len)),
            ("voltage", self.voltage.as_ref().map(Vec::len)),
            ("current", self.current.as_ref().map(Vec::len)),
            ("duty", self.duty.as_ref().map(Vec::len)),
        ];
        for (name, len) in lens {
            if let Some(len) = len {
                if len != n {
                    return Err(format!("{name} has {len} values for {n} times"));
                }
            }
        }
        if let Some(k) = self
            .time
            .windows(2)
            .position(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
        {
            return Err(format!(
                "time does not increase at row {} ({} then {})",
                k + 2,
                self.time[k],
                self.time[k + 1]
            ));
        }
        if n < 3 {
            return Err(format!("{n} rows; at least 3 are needed"));
        }
        Ok(())
    }
}

/// How a coefficient (or the motor) was measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Means over steady plateaus.
    Plateaus,
    /// Row by row through the sensor's lag (a dynamic run).
    Dynamic,
}

/// Which method to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum MethodChoice {
    /// Plateaus where there are at least three at different speeds, else dynamic.
    #[default]
    Auto,
    /// Plateaus only.
    Plateaus,
    /// Dynamic only.
    Dynamic,
}

/// What the identification is asked to do (checked by [`Options::check`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Propeller diameter D [m].
    pub diameter: f64,
    /// The air.
    pub air: Air,
    /// Blade chord at 75 % radius [m], for the blade Reynolds number.
    pub chord: Option<f64>,
    /// Reference speed for the power laws [rev/s] (default: the log-mean plateau speed).
    pub reference_speed: Option<f64>,
    /// Plateau detection.
    pub plateaus: PlateauOptions,
    /// Method.
    pub method: MethodChoice,
}

impl Options {
    /// What `propid propulsion --diameter D` asks by default: plateaus where there are three,
    /// else the dynamic fit; no chord; the log-mean plateau speed as the reference.
    pub fn at(diameter: f64, air: Air) -> Options {
        Options {
            diameter,
            air,
            chord: None,
            reference_speed: None,
            plateaus: PlateauOptions::default(),
            method: MethodChoice::Auto,
        }
    }

    /// Checks the geometry.
    pub fn check(&self) -> Result<(), String> {
        if !(self.diameter > 0.0 && self.diameter.is_finite()) {
            return Err(format!(
                "the propeller diameter must be a positive length (got {} m)",
                self.diameter
            ));
        }
        if let Some(c) = self.chord {
            if !(c > 0.0 && c < self.diameter) {
                return Err(format!(
                    "the chord ({c} m) must be positive and shorter than the diameter ({} m)",
                    self.diameter
                ));
            }
        }
        if let Some(n) = self.reference_speed {
            if !(n > 0.0 && n.is_finite()) {
                return Err(format!(
                    "the reference speed must be positive (got {n} rev/s)"
                ));
            }
        }
        Ok(())
    }
}

/// One steady plateau, as a propulsion engineer reads it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OperatingPoint {
    /// Plateau start and end [s].
    pub time: [f64; 2],
    /// Speed [rpm].
    pub rpm: f64,
    /// Thrust [N].
    pub thrust: Option<f64>,
    /// Shaft torque [N·m].
    pub torque: Option<f64>,
    /// C_T.
    pub c_t: Option<f64>,
    /// C_Q.
    pub c_q: Option<f64>,
    /// Mechanical power ω·Q [W].
    pub mechanical_power: Option<f64>,
    /// Figure of merit √(2/π)·C_T^1.5/C_P.
    pub figure_of_merit: Option<f64>,
    /// Thrust per mechanical watt [N/W].
    pub thrust_per_mechanical_watt: Option<f64>,
    /// Bus voltage [V].
    pub voltage: Option<f64>,
    /// Bus current [A].
    pub current: Option<f64>,
    /// Duty.
    pub duty: Option<f64>,
    /// Electrical power V·I [W].
    pub electrical_power: Option<f64>,
    /// Motor and ESC efficiency ω·Q/(V·I).
    pub efficiency: Option<f64>,
    /// Thrust per electrical watt [N/W].
    pub thrust_per_electrical_watt: Option<f64>,
}

/// Propeller performance at the reference speed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Performance {
    /// Speed [rev/s].
    pub speed: f64,
    /// C_T there.
    pub c_t: Quantity,
    /// C_Q there.
    pub c_q: Quantity,
    /// C_P = 2π·C_Q.
    pub c_p: Quantity,
    /// Figure of merit √(2/π)·C_T^1.5/C_P.
    pub figure_of_merit: Quantity,
    /// Thrust per mechanical watt C_T/(C_P·n·D) [N/W].
    pub thrust_per_watt: Quantity,
    /// C_T/C_Q = T·D/Q: needs neither the density nor the speed.
    pub thrust_torque_ratio: Quantity,
}

/// The result of the identification.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Propulsion {
    /// Propeller diameter [m].
    pub diameter: f64,
    /// The air used.
    pub air: Air,
    /// Blade chord at 75 % radius [m].
    pub chord: Option<f64>,
    /// Rows in the recording.
    pub rows: usize,
    /// The steady plateaus.
    pub operating_points: Vec<OperatingPoint>,
    /// C_T.
    pub thrust: Option<Coefficient>,
    /// C_Q.
    pub torque: Option<Coefficient>,
    /// Performance at the reference speed.
    pub performance: Option<Performance>,
    /// The motor.
    pub motor: Option<Motor>,
    /// Why there is no motor section.
    pub motor_absent: Option<String>,
    /// Warnings: implausible values and their likely cause, extrapolation, drift.
    pub warnings: Vec<String>,
}

impl Propulsion {
    /// The seed's c2 [N·m·s²/rad²] equivalent to the torque law at the reference speed:
    /// c2 = C_Q·ρ·D⁵/(2π)².
    pub fn c2(&self) -> Option<Quantity> {
        let c = self.torque.as_ref()?;
        let f = self.air.density * self.diameter.powi(5) / (TAU * TAU);
        Some(c.at_reference.scaled(f, "N·m·s²/rad²"))
    }
}

/// Physical range of static coefficients: (C_T, C_Q).
pub const PLAUSIBLE_C_T: [f64; 2] = [0.02, 0.35];
/// Physical range of C_Q.
pub const PLAUSIBLE_C_Q: [f64; 2] = [0.001, 0.05];

/// If `c` lies outside `range`, the sentence that says so with the mistakes that would explain it.
pub fn plausibility(kind: Kind, c: f64, diameter: f64) -> Option<String> {
    let range = match kind {
        Kind::Thrust => PLAUSIBLE_C_T,
        Kind::Torque => PLAUSIBLE_C_Q,
    };
    if c >= range[0] && c <= range[1] {
        return None;
    }
    let m = kind.diameter_power();
    let mut causes: Vec<String> = Vec::new();
    let fits = |f: f64| {
        let x = c * f;
        x >= range[0] && x <= range[1]
    };
    if kind == Kind::Thrust {
        for (factor, what) in [
            (1e-3 * units::G0, "the thrust was in gram-force but read as newtons (divide by 101.97; the importers convert `Thrust (gf)`)"),
            (units::G0, "the thrust was in kilogram-force but read as newtons (multiply by 9.807)"),
            (units::G0 * 0.453_592_37, "the thrust was in pound-force but read as newtons (multiply by 4.448)"),
        ] {
            if fits(factor) {
                causes.push(what.into());
            }
        }
    }
    if fits(39.37f64.powi(m)) || fits(1e3f64.powi(m)) {
        causes.push(format!(
            "the diameter ({diameter} m) was given in inches or millimetres as metres (write `7in` or `178mm`)"
        ));
    }
    if fits((60.0 / TAU).powi(2)) {
        causes.push("the speed is in rpm but read as rad/s (9.55 times too fast)".into());
    }
    if fits((TAU / 60.0).powi(2)) {
        causes.push("the speed is in rad/s but read as rpm (9.55 times too slow)".into());
    }
    let pairs: Vec<i32> = (2..=21)
        .filter(|p: &i32| fits(f64::from(*p * *p)))
        .collect();
    if let (Some(lo), Some(hi)) = (pairs.first(), pairs.last()) {
        causes.push(format!(
            "the speed is electrical, not mechanical: an electrical rpm is the mechanical times the motor's pole pairs ({lo}–{hi} pole pairs would put {} in range; a common 14-pole outrunner has 7, which gives {:.4}); give `--pole-pairs`",
            kind.symbol(),
            c * 49.0
        ));
    }
    Some(format!(
        "{} = {c:.4e} is outside what propellers have ({}–{}, static): {}",
        kind.symbol(),
        range[0],
        range[1],
        if causes.is_empty() {
            "check the units of the speed, the thrust or torque and the diameter".to_string()
        } else {
            format!("likely {}", causes.join("; or "))
        }
    ))
}

/// Identifies what the recording's columns allow.
pub fn identify(rec: &Recording, options: &Options) -> Result<Propulsion, String> {
    options.check()?;
    rec.check()?;
    if rec.thrust.is_none() && rec.torque.is_none() {
        return Err(
            "no thrust and no torque column: a propeller's coefficients need at least one".into(),
        );
    }
    let steady = plateau::find(rec, &options.plateaus);
    let mut warnings = Vec::new();
    let thrust = rec
        .thrust
        .as_ref()
        .map(|_| coefficient(Kind::Thrust, rec, &steady, options, &mut warnings));
    let torque = rec
        .torque
        .as_ref()
        .map(|_| coefficient(Kind::Torque, rec, &steady, options, &mut warnings));
    let air = options.air;
    let d = options.diameter;
    let operating_points = steady
        .plateaus
        .iter()
        .map(|p| operating_point(p, &air, d))
        .collect();
    let performance = match (&thrust, &torque) {
        (Some(t), Some(q)) => performance(t, q, &air, d),
        _ => None,
    };
    let use_plateaus = |enough: bool| match options.method {
        MethodChoice::Plateaus => true,
        MethodChoice::Dynamic => false,
        MethodChoice::Auto => enough,
    };
    let (motor, motor_absent) = if rec.voltage.is_none() && rec.current.is_none() {
        (
            None,
            Some("no `voltage` or `current` column: no motor constants or efficiency".to_string()),
        )
    } else {
        let enough = steady
            .plateaus
            .iter()
            .filter(|p| p.voltage.is_some() && p.current.is_some())
            .count()
            >= 3;
        // The torque against the current needs the torque's zero: where it was fitted with the
        // law (no rest to measure it at), it is taken off here too.
        let fitted_zero = torque.as_ref().and_then(|c| c.fitted_zero.as_ref());
        let torque_zero = fitted_zero.and_then(Quantity::value).unwrap_or(0.0);
        let zero_stderr = fitted_zero.and_then(Quantity::stderr).unwrap_or(0.0);
        let m = if use_plateaus(enough) {
            let mut plateaus = steady.plateaus.clone();
            for p in &mut plateaus {
                if let Some(q) = &mut p.torque {
                    q.value -= torque_zero;
                }
            }
            motor::from_plateaus(rec, &plateaus)
        } else {
            let mut corrected = rec.clone();
            if let Some(q) = &mut corrected.torque {
                q.iter_mut().for_each(|x| *x -= torque_zero);
            }
            // A torque cell with a lag of its own reads the shaft torque late, while the current
            // has only the ESC's filter: the torque is then rebuilt from the cell's fitted law
            // and inertia, A·(ω/ω_r)^p + J·dω/dt, without the cell's lag.
            if let Some(model) = torque.as_ref().and_then(|c| shaft_torque_model(c, rec)) {
                corrected.torque = Some(model);
            }
            motor::from_dynamic(&corrected)
        };
        match m {
            Ok(mut m) => {
                // I_m = (Q − Q₀)/K_t + I_0: only I_0 − Q₀/K_t is measured, so without the
                // torque's zero Q₀ measured at rest (it was fitted with the law, whose shape alone
                // separates the two) I_0 and the friction torque are not identified.
                if fitted_zero.is_some() {
                    let why = "the torque cell's zero was not measured at rest (no rows at rest before and after the run), and I_m = (Q − Q₀)/K_t + I_0 gives only I_0 − Q₀/K_t: record a few seconds at rest before and after";
                    let total = |q: &Quantity, scale: f64| match (q.value(), q.stderr()) {
                        (Some(v), Some(se)) => Quantity::judge_relative(
                            v,
                            (se * se + (zero_stderr * scale).powi(2)).sqrt(),
                            q.unit(),
                            f64::INFINITY,
                        )
                        .not_identified(why),
                        _ => q.clone(),
                    };
                    let kt = m.kt.value().unwrap_or(f64::NAN);
                    m.no_load_current = total(&m.no_load_current, 1.0 / kt);
                    if let Some(l) = &mut m.losses {
                        l.friction_torque = total(&l.friction_torque, 1.0);
                    }
                }
                (Some(m), None)
            }
            Err(why) => (None, Some(why)),
        }
    };
    Ok(Propulsion {
        diameter: d,
        air,
        chord: options.chord,
        rows: rec.time.len(),
        operating_points,
        thrust,
        torque,
        performance,
        motor,
        motor_absent,
        warnings,
    })
}

use plateau::Zero;

fn coefficient(
    kind: Kind,
    rec: &Recording,
    steady: &Steady,
    options: &Options,
    warnings: &mut Vec<String>,
) -> Coefficient {
    let channel = match kind {
        Kind::Thrust => Channel::Thrust,
        Kind::Torque => Channel::Torque,
    };
    let zero = match kind {
        Kind::Thrust => steady.thrust_zero,
        Kind::Torque => steady.torque_zero,
    }
    .unwrap_or(Zero::Unknown);
    let points: Vec<law::Point> = steady
        .plateaus
        .iter()
        .filter_map(|p| {
            let m = p.get(channel)?;
            Some(law::Point {
                n: law::rev_per_s(p.speed.value.abs()),
                value: m.value,
                stderr: m.stderr,
            })
        })
        .collect();
    let distinct = {
        let lo = points.iter().map(|p| p.n).fold(f64::INFINITY, f64::min);
        let hi = points.iter().map(|p| p.n).fold(0.0, f64::max);
        points.len() >= 3 && hi > 1.2 * lo
    };
    let use_plateaus = match options.method {
        MethodChoice::Plateaus => true,
        MethodChoice::Dynamic => false,
        MethodChoice::Auto => distinct,
    };
    let unit = kind.unit();
    let mut c = if use_plateaus {
        law::coefficient_from_points(
            kind,
            &points,
            match zero {
                Zero::Unknown => law::ZeroTreatment::Fitted,
                z => law::ZeroTreatment::Subtracted { stderr: z.stderr() },
            },
            zero.describe(unit),
            &options.air,
            options.diameter,
            options.chord,
            options.reference_speed,
        )
    } else {
        match dynamic_coefficient(kind, rec, options) {
            Some(c) => c,
            None => {
                let samples = rec
                    .channel(channel)
                    .map_or(0, |v| dynamic::updates(v).len());
                let why = format!(
                    "{} steady plateau(s) at different speeds (the speed must hold within {:.0} % for {:.1} s; three are needed) and {samples} {} readings, too few for a dynamic fit (50 needed): run held steps of a few seconds, or a faster-sampled load cell",
                    points.len(),
                    100.0 * options.plateaus.tolerance,
                    options.plateaus.settle + options.plateaus.min_duration,
                    kind.symbol().replace("C_T", "thrust").replace("C_Q", "torque"),
                );
                let cj = || Quantity::cannot_judge("1", why.clone());
                Coefficient {
                    kind,
                    method: Method::Plateaus,
                    points: points.len(),
                    at_reference: cj(),
                    reference_speed: options.reference_speed.unwrap_or(f64::NAN),
                    exponent: cj(),
                    quadratic: cj(),
                    law: None,
                    speed_dependent: false,
                    bands: Vec::new(),
                    zero: zero.describe(unit),
                    fitted_zero: None,
                    inertia: None,
                    sensor_lag: None,
                }
            }
        }
    };
    // Plausibility: a coefficient no propeller has is most likely a unit mistake.
    for q in [&mut c.at_reference, &mut c.quadratic] {
        if let Some(v) = q.value() {
            if let Some(why) = plausibility(kind, v, options.diameter) {
                *q = q.clone().not_identified(why.clone());
                if !warnings.contains(&why) {
                    warnings.push(why);
                }
            }
        }
    }
    for b in &c.bands {
        if !b.law_agrees {
            warnings.push(format!(
                "{}: the power law misses the band {:.0}–{:.0} rpm by more than three standard errors",
                kind.symbol(),
                b.from * 60.0,
                b.to * 60.0
            ));
        }
    }
    c
}

/// The shaft torque rebuilt from a torque cell's dynamic fit, when the cell has a lag of its own.
fn shaft_torque_model(c: &Coefficient, rec: &Recording) -> Option<Vec<f64>> {
    if c.method != Method::Dynamic || c.sensor_lag.as_ref()?.identified().is_none() {
        return None;
    }
    let law = c.law?;
    let j = c.inertia.as_ref()?.value()?;
    let (a, _) = dynamic::derivative(&rec.time, &rec.speed, 5);
    Some(
        rec.speed
            .iter()
            .zip(&a)
            .map(|(w, a)| law.value(w.abs() / TAU) + j * a)
            .collect(),
    )
}

fn dynamic_coefficient(kind: Kind, rec: &Recording, options: &Options) -> Option<Coefficient> {
    let (cell, accel) = match kind {
        Kind::Thrust => (rec.thrust.as_deref()?, None),
        Kind::Torque => (rec.torque.as_deref()?, Some(())),
    };
    // The reference: given, else the log-mean speed of the fitted rows.
    let top = rec
        .speed
        .iter()
        .map(|w| w.abs())
        .filter(|w| w.is_finite())
        .fold(0.0, f64::max);
    let used: Vec<f64> = rec
        .speed
        .iter()
        .filter(|w| w.is_finite() && w.abs() > 0.05 * top)
        .map(|w| w.abs())
        .collect();
    if used.is_empty() {
        return None;
    }
    let omega_r = options
        .reference_speed
        .map(|n| n * TAU)
        .unwrap_or_else(|| (used.iter().map(|w| w.ln()).sum::<f64>() / used.len() as f64).exp());
    // The torque cell carries J·dω/dt: dω/dt as the local slope of the speed over ±5 rows (its
    // noise is far below a differentiated acceleration column's, and it has no lag of its own).
    let derived = accel.map(|_| dynamic::derivative(&rec.time, &rec.speed, 5));
    let accel = derived.as_ref().map(|(a, noise)| (a.as_slice(), *noise));
    let free = dynamic::fit(&rec.time, &rec.speed, accel, cell, omega_r, None)?;
    let quad = dynamic::fit(&rec.time, &rec.speed, accel, cell, omega_r, Some(2.0))?;
    let n_r = omega_r / TAU;
    let air = options.air;
    let d = options.diameter;
    let scale = kind.scale(air.density, n_r, d);
    let exponent = Quantity::judge(free.exponent, free.exponent_stderr, "1");
    let speed_dependent = match (exponent.identified(), exponent.stderr()) {
        (Some(p), Some(s)) => (p - 2.0).abs() > 3.0 * s,
        _ => false,
    };
    let lo = used.iter().copied().fold(f64::INFINITY, f64::min) / TAU;
    let hi = top / TAU;
    let law = PowerLaw {
        reference_speed: n_r,
        at_reference: free.amplitude,
        exponent: free.exponent,
        covariance: [
            [free.amplitude_stderr.powi(2), 0.0],
            [0.0, free.exponent_stderr.powi(2)],
        ],
        speed_range: [lo, hi],
    };
    // The band table: the law's amplitude refitted per band of speed (at the fitted lag).
    let mut bands = Vec::new();
    let width = law::band_width_rpm((hi - lo) * 60.0) / 60.0;
    let mut from = (lo / width).floor() * width;
    while from <= hi {
        let to = from + width;
        let rows: Vec<&(usize, f64, f64)> = free
            .rows
            .iter()
            .filter(|(k, _, _)| {
                let n = rec.speed[*k].abs() / TAU;
                n >= from && n < to
            })
            .collect();
        if rows.len() >= 20 {
            let (mut sxy, mut sxx, mut sn) = (0.0, 0.0, 0.0);
            for (k, y, x) in &rows {
                sxy += x * y;
                sxx += x * x;
                sn += rec.speed[*k].abs() / TAU;
            }
            let s = sxy / sxx;
            let rss: f64 = rows.iter().map(|(_, y, x)| (y - s * x).powi(2)).sum();
            let se = (rss / (rows.len() as f64 - 1.0) / sxx).sqrt();
            let n = sn / rows.len() as f64;
            // The band's amplitude times the law's coefficient at the band's speed.
            let c_law = law.value(n) / kind.scale(air.density, n, d) / free.amplitude;
            bands.push(law::Band {
                from,
                to,
                plateaus: rows.len(),
                speed: n,
                coefficient: Quantity::judge(s * c_law, se * c_law, "1"),
                reynolds: air.reynolds_rotational(n, d),
                reynolds_075: options.chord.map(|c| air.reynolds_075(n, d, c)),
                tip_mach: air.tip_mach(n, d),
                law_agrees: (s - free.amplitude).abs() <= 3.0 * se,
            });
        }
        from = to;
    }
    Some(Coefficient {
        kind,
        method: Method::Dynamic,
        points: free.samples,
        at_reference: Quantity::judge(free.amplitude / scale, free.amplitude_stderr / scale, "1"),
        reference_speed: n_r,
        exponent,
        quadratic: Quantity::judge(quad.amplitude / scale, quad.amplitude_stderr / scale, "1"),
        law: Some(law),
        speed_dependent,
        bands,
        inertia: free.inertia.map(|(j, s)| Quantity::judge(j, s, "kg·m²")),
        fitted_zero: Some(Quantity::judge_relative(
            free.offset,
            free.offset_stderr,
            kind.unit(),
            f64::INFINITY,
        )),
        zero: format!(
            "zero {:+.4} ± {:.4} {} fitted with the law{}",
            free.offset,
            free.offset_stderr,
            kind.unit(),
            free.inertia.map_or(String::new(), |(j, s)| format!(
                "; inertia seen by the cell J = {j:.4e} ± {s:.1e} kg·m²"
            ))
        ),
        sensor_lag: Some(if free.lag > 0.0 {
            Quantity::judge_relative(free.lag, free.lag_stderr, "s", 0.5)
        } else {
            Quantity::cannot_judge(
                "s",
                "no lag resolved: τ = 0 fits best (the cell follows within a row interval)",
            )
        }),
    })
}

fn operating_point(p: &plateau::Plateau, air: &Air, d: f64) -> OperatingPoint {
    let omega = p.speed.value.abs();
    let n = omega / TAU;
    let thrust = p.thrust.map(|m| m.value);
    let torque = p.torque.map(|m| m.value);
    let c_t = thrust.map(|t| t / Kind::Thrust.scale(air.density, n, d));
    let c_q = torque.map(|q| q / Kind::Torque.scale(air.density, n, d));
    let mechanical_power = torque.map(|q| omega * q);
    let electrical_power = p.electrical_power.map(|m| m.value);
    OperatingPoint {
        time: [p.start, p.end],
        rpm: n * 60.0,
        thrust,
        torque,
        c_t,
        c_q,
        mechanical_power,
        figure_of_merit: match (c_t, c_q) {
            (Some(t), Some(q)) if t > 0.0 && q > 0.0 => Some(figure_of_merit(t, q)),
            _ => None,
        },
        thrust_per_mechanical_watt: match (thrust, mechanical_power) {
            (Some(t), Some(pm)) if pm > 0.0 => Some(t / pm),
            _ => None,
        },
        voltage: p.voltage.map(|m| m.value),
        current: p.current.map(|m| m.value),
        duty: p.duty.map(|m| m.value),
        electrical_power,
        efficiency: match (mechanical_power, electrical_power) {
            (Some(m), Some(e)) if e > 0.0 => Some(m / e),
            _ => None,
        },
        thrust_per_electrical_watt: match (thrust, electrical_power) {
            (Some(t), Some(e)) if e > 0.0 => Some(t / e),
            _ => None,
        },
    }
}

/// FM = √(2/π)·C_T^1.5/C_P with C_P = 2π·C_Q (the ideal induced power T^1.5/√(2ρA) over the
/// shaft power, A = πD²/4).
pub fn figure_of_merit(c_t: f64, c_q: f64) -> f64 {
    (2.0 / std::f64::consts::PI).sqrt() * c_t.powf(1.5) / (TAU * c_q)
}

fn performance(t: &Coefficient, q: &Coefficient, air: &Air, d: f64) -> Option<Performance> {
    let n = t.reference_speed;
    let tl = t.law?;
    let ql = q.law?;
    let st = Kind::Thrust.scale(air.density, n, d);
    let sq = Kind::Torque.scale(air.density, n, d);
    let (ct, ct_s) = (tl.value(n) / st, tl.value_stderr(n) / st);
    let (cq, cq_s) = (ql.value(n) / sq, ql.value_stderr(n) / sq);
    if !(ct > 0.0 && cq > 0.0) {
        return None;
    }
    let (rt, rq) = (ct_s / ct, cq_s / cq);
    let fm = figure_of_merit(ct, cq);
    let tpw = ct / (TAU * cq * n * d);
    let inherit = |x: Quantity| {
        if t.at_reference.identified().is_none() || q.at_reference.identified().is_none() {
            x.not_identified("C_T or C_Q is not identified")
        } else {
            x
        }
    };
    Some(Performance {
        speed: n,
        c_t: inherit(Quantity::judge(ct, ct_s, "1")),
        c_q: inherit(Quantity::judge(cq, cq_s, "1")),
        c_p: inherit(Quantity::judge(TAU * cq, TAU * cq_s, "1")),
        figure_of_merit: inherit(Quantity::judge(
            fm,
            fm * ((1.5 * rt).powi(2) + rq * rq).sqrt(),
            "1",
        )),
        thrust_per_watt: inherit(Quantity::judge(
            tpw,
            tpw * (rt * rt + rq * rq).sqrt(),
            "N/W",
        )),
        thrust_torque_ratio: inherit(Quantity::judge(
            ct / cq,
            ct / cq * (rt * rt + rq * rq).sqrt(),
            "1",
        )),
    })
}
