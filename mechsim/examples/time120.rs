//! One 120 s run at 1 kHz feedback, for timing with `/usr/bin/time` (CPU time is what the
//! crate documentation states; criterion's wall time suffers on a loaded machine).
//! `cargo run --release -p propid-mechsim --example time120 [everything]`

use propid_mechsim::{pattern, simulate, MechConfig, Run};

fn main() {
    let mut c = MechConfig::default();
    if std::env::args().nth(1).as_deref() == Some("everything") {
        c.rotor.drag.exponent = 2.1;
        c.rotor.bearing.coulomb = 2e-3;
        c.rotor.bearing.breakaway = 4e-3;
        c.rotor.cogging.amplitude = 2e-3;
        c.drive.current_loop = Some(propid_mechsim::CurrentLoop { bandwidth: 300.0 });
        c.sensing.kinematics.counts_per_rev = Some(4096);
        c.sensing.kinematics.velocity = propid_mechsim::VelocityEstimator::Pll {
            natural_hz: 30.0,
            damping: 0.7,
        };
        c.sensing.kinematics.acceleration_filter = 5e-3;
        c.disturbance = propid_mechsim::Disturbance::Periodic {
            amplitude: 2e-3,
            hz: 7.0,
        };
        c = c.with_typical_noise();
    }
    c.link.rate = 1000.0;
    let run = Run {
        init_setpoint: 0.9,
        init_duration: 0.0,
        duration: 120.0,
    };
    let recs = simulate(c, &run, pattern::sine(0.1, 0.9, 2.0), 1).expect("valid configuration");
    std::process::exit(if recs.len() == 120_001 { 0 } else { 1 });
}
