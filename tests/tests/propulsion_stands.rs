//! Propulsion identification on simulated stands with thrust and electrical columns: every
//! identified constant within 2 % of the simulator's truth, on steps (plateaus) and on the seed's
//! sine (dynamic), on the formula-level stand and the mechanism-level one.

use propid_science::excitation::{Excitation, Pattern};
use propid_science::propulsion::{
    identify, Air, MethodChoice, Options, PlateauOptions, Propulsion, Quantity, Recording, TAU,
};
use propid_science::stand::{DrivetrainConfig, Stand, StandConfig};

const D: f64 = 0.1778;

fn formula_recording(
    pattern: Pattern,
    period: f64,
    duration: f64,
    dt: DrivetrainConfig,
    seed: u64,
) -> Recording {
    let config = StandConfig {
        inertia: 3.0e-5,
        c2: 5.9e-8,
        ..StandConfig::default()
    };
    let excitation = Excitation {
        lo: 0.1,
        hi: 0.9,
        period,
        duration,
        init_duration: 5.0,
        pattern,
    };
    let mut stand = Stand::new(config, seed).with_drivetrain(dt, seed);
    let mut rec = Recording::default();
    let (mut thrust, mut voltage, mut current, mut duty, mut torque) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    stand
        .run(&excitation, |row| {
            rec.time.push(row.sample.t);
            rec.speed.push(row.sample.velocity);
            rec.acceleration.push(row.sample.acceleration);
            torque.push(row.sample.force);
            thrust.push(row.stand.thrust);
            voltage.push(row.stand.voltage);
            current.push(row.stand.current);
            duty.push(row.stand.command);
            Ok::<(), ()>(())
        })
        .unwrap();
    rec.torque = Some(torque);
    rec.thrust = Some(thrust);
    rec.voltage = Some(voltage);
    rec.current = Some(current);
    rec.duty = Some(duty);
    rec
}

fn options() -> Options {
    Options {
        diameter: D,
        air: Air::isa(),
        chord: None,
        reference_speed: None,
        plateaus: PlateauOptions::default(),
        method: MethodChoice::Auto,
    }
}

/// Asserts `q` is identified and within `tol` (relative) of `truth`.
fn within(name: &str, q: &Quantity, truth: f64, tol: f64) {
    let v = q
        .identified()
        .unwrap_or_else(|| panic!("{name} not identified: {}", q.describe()));
    let e = (v - truth) / truth;
    assert!(
        e.abs() <= tol,
        "{name} = {} against the truth {truth:.6e}: {:+.2} %",
        q.describe(),
        100.0 * e
    );
    eprintln!(
        "{name:>24} = {:<40} truth {truth:.6e} ({:+.3} %)",
        q.describe(),
        100.0 * e
    );
}

/// C at the law's reference speed for a law k·ω^p (thrust: m = 4, torque: m = 5).
fn coefficient_truth(k: f64, p: f64, n_r: f64, m: i32) -> f64 {
    k * (TAU * n_r).powf(p) / (Air::isa().density * n_r * n_r * D.powi(m))
}

fn check_formula(p: &Propulsion, dt: &DrivetrainConfig, dynamic: bool) {
    let t = p.thrust.as_ref().unwrap();
    within(
        "C_T(n_r)",
        &t.at_reference,
        coefficient_truth(dt.thrust_k, dt.thrust_exponent, t.reference_speed, 4),
        0.02,
    );
    within("thrust exponent", &t.exponent, dt.thrust_exponent, 0.02);
    let q = p.torque.as_ref().unwrap();
    within(
        "C_Q(n_r)",
        &q.at_reference,
        coefficient_truth(5.9e-8, 2.0, q.reference_speed, 5),
        0.02,
    );
    within("torque exponent", &q.exponent, 2.0, 0.02);
    let m = p.motor.as_ref().unwrap();
    within("Kv [rpm/V]", &m.kv, dt.kv, 0.02);
    within("R [Ω]", &m.resistance, dt.resistance, 0.02);
    within("K_t [N·m/A]", &m.kt, dt.ke(), 0.02);
    within("I_0 [A]", &m.no_load_current, dt.no_load_current, 0.02);
    if dynamic {
        within(
            "thrust cell lag [s]",
            t.sensor_lag.as_ref().unwrap(),
            dt.thrust_lag,
            0.02,
        );
        within(
            "current filter [s]",
            m.current_filter.as_ref().unwrap(),
            dt.current_filter,
            0.02,
        );
    }
}

fn drivetrain() -> DrivetrainConfig {
    DrivetrainConfig {
        thrust_exponent: 2.1,
        thrust_k: 0.12 * 1.225 * D.powi(4) / TAU.powi(2) / 1000f64.powf(0.1),
        current_filter: 0.02,
        ..DrivetrainConfig::typical()
    }
}

#[test]
fn formula_stand_on_steps_every_constant_within_2_percent() {
    let dt = drivetrain();
    let rec = formula_recording(Pattern::Steps, 10.0, 90.0, dt, 3);
    let p = identify(&rec, &options()).unwrap();
    assert!(
        p.operating_points.len() >= 15,
        "{} plateaus",
        p.operating_points.len()
    );
    assert_eq!(
        p.thrust.as_ref().unwrap().method,
        propid_science::propulsion::Method::Plateaus
    );
    check_formula(&p, &dt, false);
}

#[test]
fn formula_stand_on_the_seed_sine_every_constant_within_2_percent() {
    let dt = drivetrain();
    let rec = formula_recording(Pattern::Sine, 2.0, 60.0, dt, 5);
    let p = identify(&rec, &options()).unwrap();
    assert!(p.operating_points.is_empty(), "a sine has no plateau");
    assert_eq!(
        p.thrust.as_ref().unwrap().method,
        propid_science::propulsion::Method::Dynamic
    );
    check_formula(&p, &dt, true);
}
