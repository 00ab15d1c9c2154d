//! How long 120 s of stand take to simulate (1 kHz feedback, 10 kHz control), clean and with every
//! mechanism on. `cargo bench -p propid-mechsim`.

use criterion::{criterion_group, criterion_main, Criterion};
use propid_mechsim::{
    pattern, simulate, Braking, CurrentLoop, Disturbance, MechConfig, Run, TorqueReport,
    VelocityEstimator,
};

fn everything_on() -> MechConfig {
    let mut c = MechConfig::default().with_typical_noise();
    c.rotor.drag.exponent = 2.1;
    c.rotor.drag.cq_slope = 0.1;
    c.rotor.bearing.coulomb = 2e-3;
    c.rotor.bearing.breakaway = 4e-3;
    c.rotor.bearing.viscous = 1e-6;
    c.rotor.cogging.amplitude = 2e-3;
    c.drive.current_loop = Some(CurrentLoop { bandwidth: 300.0 });
    c.drive.braking = Some(Braking {
        torque: 4e-3,
        on_threshold: 50.0,
        off_threshold: 20.0,
    });
    c.sensing.kinematics.counts_per_rev = Some(4096);
    c.sensing.kinematics.velocity = VelocityEstimator::Pll {
        natural_hz: 30.0,
        damping: std::f64::consts::FRAC_1_SQRT_2,
    };
    c.sensing.kinematics.acceleration_filter = 5e-3;
    c.sensing.torque = TorqueReport::LoadCell {
        natural_hz: 80.0,
        damping: 0.2,
        rate: 80.0,
        offset: 3e-3,
        noise: 1e-4,
    };
    c.disturbance = Disturbance::Periodic {
        amplitude: 2e-3,
        hz: 7.0,
    };
    c.link.clock.rate_error = 0.01;
    c.link.clock.stamp_jitter = 50e-6;
    c.link.drop_probability = 0.05;
    c.link.latency_jitter = 5e-4;
    c
}

fn bench(c: &mut Criterion) {
    let run = Run {
        init_setpoint: 0.9,
        init_duration: 0.0,
        duration: 120.0,
    };
    let mut g = c.benchmark_group("mechsim_120s_1kHz");
    g.sample_size(10);
    for (name, mut config) in [
        ("clean", MechConfig::default()),
        ("everything_on", everything_on()),
    ] {
        config.link.rate = 1000.0;
        g.bench_function(name, |b| {
            b.iter(|| simulate(config, &run, pattern::sine(0.1, 0.9, 2.0), 1).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
