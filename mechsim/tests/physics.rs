//! Physical sanity of the mechanism-level stand: steady state, energy, the clean stand's data obey
//! the seed's equation, seeds reproduce, rates and timestamps are what was asked for.

use propid_mechsim::{
    pattern, simulate, write_tsv, Braking, ConfigError, Disturbance, Field, MechConfig, Record,
    Run, TorqueReport, TSV_HEADER,
};

fn run(duration: f64) -> Run {
    Run {
        init_setpoint: 0.9,
        init_duration: 2.0,
        duration,
    }
}

#[test]
fn steady_state_speed_is_where_torque_equals_drag_and_friction() {
    let mut c = MechConfig::default();
    c.rotor.drag.exponent = 2.3;
    c.rotor.drag.k = 2.0e-9;
    c.rotor.bearing.coulomb = 3e-3;
    c.rotor.bearing.viscous = 2e-6;
    let sp = 0.6;
    let recs = simulate(
        c,
        &Run {
            init_setpoint: sp,
            init_duration: 0.0,
            duration: 8.0,
        },
        pattern::constant(sp),
        1,
    )
    .unwrap();
    let w = recs.last().unwrap().truth.velocity;
    // Solve sp·Tmax = k w^p + Fc + b w by bisection.
    let g = |w: f64| sp * 0.1 - 2.0e-9 * w.powf(2.3) - 3e-3 - 2e-6 * w;
    let (mut lo, mut hi) = (1.0, 1e5);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if g(mid) > 0.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    assert!(
        (w / lo - 1.0).abs() < 1e-4,
        "steady speed {w} vs analytic {lo}"
    );
}

#[test]
fn energy_is_conserved() {
    let mut c = MechConfig::default();
    c.rotor.bearing.coulomb = 2e-3;
    c.rotor.bearing.breakaway = 5e-3;
    c.rotor.bearing.viscous = 1e-6;
    c.rotor.cogging.amplitude = 3e-3;
    c.rotor.drag.cq_slope = 0.2;
    c.drive.braking = Some(Braking {
        torque: 5e-3,
        on_threshold: 50.0,
        off_threshold: 20.0,
    });
    c.drive.current_loop = Some(propid_mechsim::CurrentLoop { bandwidth: 300.0 });
    c.disturbance = Disturbance::Periodic {
        amplitude: 4e-3,
        hz: 7.3,
    };
    let recs = simulate(c, &run(10.0), pattern::sine(0.1, 0.9, 2.0), 3).unwrap();
    let j = c.rotor.inertia;
    let mut worst: f64 = 0.0;
    for r in &recs {
        let e = r.truth.energy;
        let kinetic = 0.5 * j * r.truth.velocity.powi(2);
        worst = worst.max((kinetic - (e.drive - e.loss + e.external)).abs() / e.drive);
    }
    assert!(
        worst < 1e-7,
        "energy balance off by {worst:e} of the work done"
    );
}

/// The clean stand's reported data obey J·a = F − k·ω|ω| exactly, and with noise the residual is
/// the noise the configuration asked for.
#[test]
fn clean_run_obeys_the_seed_equation_within_the_noise() {
    let c = MechConfig::default();
    let recs = simulate(c, &run(20.0), pattern::sine(0.1, 0.9, 2.0), 5).unwrap();
    let (j, k) = (c.rotor.inertia, c.rotor.drag.k);
    let residual = |r: &Record| j * r.acceleration - (r.force - k * r.velocity * r.velocity.abs());
    let worst = recs.iter().map(|r| residual(r).abs()).fold(0.0, f64::max);
    assert!(worst < 1e-12, "clean residual {worst:e} N·m");

    let noisy = c.with_typical_noise();
    let recs = simulate(noisy, &run(20.0), pattern::sine(0.1, 0.9, 2.0), 5).unwrap();
    let n = recs.len() as f64;
    let rms = (recs.iter().map(|r| residual(r).powi(2)).sum::<f64>() / n).sqrt();
    let s = noisy.sensing.noise;
    // Var = σF² + (J σa)² + E[(2kω σv)²] (+ k²σv⁴·2, negligible).
    let mean_w2 = recs.iter().map(|r| r.truth.velocity.powi(2)).sum::<f64>() / n;
    let expected = (s.force.powi(2)
        + (j * s.acceleration).powi(2)
        + 4.0 * k * k * mean_w2 * s.velocity.powi(2))
    .sqrt();
    assert!(
        (rms / expected - 1.0).abs() < 0.05,
        "residual RMS {rms:e} vs noise {expected:e}"
    );
}

#[test]
fn same_seed_same_records_other_seed_other_noise() {
    let mut c = MechConfig::default().with_typical_noise();
    c.link.drop_probability = 0.05;
    c.link.clock.stamp_jitter = 100e-6;
    c.link.latency_jitter = 300e-6;
    let p = pattern::chirp(0.1, 0.9, 2.0, 5.0);
    let a = simulate(c, &run(5.0), &p, 42).unwrap();
    let b = simulate(c, &run(5.0), &p, 42).unwrap();
    let d = simulate(c, &run(5.0), &p, 43).unwrap();
    assert_eq!(a, b);
    assert_ne!(a.len(), 0);
    assert!(a.len() != d.len() || a.iter().zip(&d).any(|(x, y)| x.force != y.force));
}

#[test]
fn rates_from_100_to_1000_hz_give_one_message_per_period() {
    for rate in [100.0, 250.0, 500.0, 1000.0] {
        let mut c = MechConfig::default();
        c.link.rate = rate;
        let recs = simulate(c, &run(4.0), pattern::sine(0.1, 0.9, 2.0), 1).unwrap();
        assert_eq!(recs.len(), (4.0 * rate) as usize + 1, "rate {rate}");
        let h = 1.0 / c.drive.control_rate;
        for w in recs.windows(2) {
            let dt = w[1].t - w[0].t;
            assert!(
                (dt - 1.0 / rate).abs() <= h + 1e-9,
                "rate {rate}: interval {dt}"
            );
            assert!(w[1].ts_local > w[0].ts_local);
        }
    }
}

#[test]
fn dropped_messages_and_clock_rate_error() {
    let mut c = MechConfig::default();
    c.link.rate = 1000.0;
    c.link.drop_probability = 0.1;
    c.link.clock.rate_error = 0.01;
    let recs = simulate(c, &run(10.0), pattern::sine(0.1, 0.9, 2.0), 9).unwrap();
    // Messages are scheduled on the device clock: 1 % more of them in 10 s of true time.
    let scheduled = 10.0 * 1.01 * 1000.0;
    let share = recs.len() as f64 / scheduled;
    assert!((share - 0.9).abs() < 0.01, "delivered share {share}");
    // Device time runs 1 % fast against the host's receive time.
    let (a, b) = (recs.first().unwrap(), recs.last().unwrap());
    let ratio = (b.t - a.t) / (b.ts_local - a.ts_local);
    assert!((ratio - 1.01).abs() < 1e-6, "clock ratio {ratio}");
}

#[test]
fn tsv_matches_propids_header_and_number_format() {
    let c = MechConfig::default();
    let recs = simulate(c, &run(0.01), pattern::constant(0.5), 1).unwrap();
    let mut out = Vec::new();
    write_tsv(&mut out, &recs, true).unwrap();
    let text = String::from_utf8(out).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        format!("{}\tsetpoint", TSV_HEADER.join("\t"))
    );
    let first: Vec<&str> = lines.next().unwrap().split('\t').collect();
    assert_eq!(first.len(), 7);
    assert_eq!(first[0], format!("{}", recs[0].ts_local));
    assert_eq!(first[6], "0.5");
    let mut out = Vec::new();
    write_tsv(&mut out, &recs, false).unwrap();
    assert!(String::from_utf8(out)
        .unwrap()
        .starts_with("ts_local\tt\tforce\tvelocity\tacceleration\tposition\n"));
}

#[test]
fn bad_configuration_names_the_field() {
    let mut c = MechConfig::default();
    c.link.rate = 0.0;
    let e = simulate(c, &run(1.0), pattern::constant(0.5), 1).unwrap_err();
    assert!(matches!(
        e,
        ConfigError::OutOfRange {
            field: Field::LinkRate,
            ..
        }
    ));
    assert!(e.to_string().starts_with("link.rate must be"), "{e}");
    let mut c = MechConfig::default();
    c.sensing.torque = TorqueReport::LoadCell {
        natural_hz: f64::NAN,
        damping: 0.3,
        rate: 80.0,
        offset: 0.0,
        noise: 0.0,
    };
    assert!(c.validate().unwrap_err().to_string().contains("natural_hz"));
    let bad_run = Run {
        init_setpoint: 0.5,
        init_duration: 0.0,
        duration: -1.0,
    };
    let e = simulate(MechConfig::default(), &bad_run, pattern::constant(0.5), 1).unwrap_err();
    assert!(e.to_string().contains("run.duration"));
}
