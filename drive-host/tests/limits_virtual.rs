//! The limits that stop a runaway rotor, each in virtual time against the simulated Telega: the
//! soft start (no feedback, the rotor turning the wrong way, not turning, the torque reported
//! reversed), the maximum speed, and the speed watchdog (a reversed torque with no soft start, a
//! propeller that comes loose mid-run) — each stopping with STANDBY as the first frame after the
//! fault (checked by `run_pair_with` for every run) and its reason in the report. And the other
//! side: runs with a torque lag, on the seed's sine and a chirp, trip nothing.

mod common;

use common::*;
use propid_core::can::SubjectId;
use propid_core::sample::Sample;
use propid_drive_host::stand::{Played, StandPlant};
use propid_drive_proto::drive::DriveConfig;
use propid_drive_proto::limits::{LimitStop, Limits};
use propid_drive_proto::plant::{Plant, TorqueScaled};
use propid_drive_proto::settings::MaxSpeed;
use propid_drive_proto::sim_drive::{SimDrive, SimDriveConfig};
use propid_drive_proto::virtual_link::LinkModel;
use propid_drive_proto::StopReason;
use propid_science::excitation::{Excitation, Pattern};
use propid_science::stand::StandConfig;

fn seed(limits: Limits) -> DriveConfig {
    DriveConfig {
        limits,
        ..DriveConfig::example(Played::try_from(seed_excitation(2.0, 10.0)).unwrap())
    }
}

fn scaled(scale: f64) -> Box<dyn Plant> {
    Box::new(TorqueScaled::new(stand(), scale))
}

/// Runs `cfg` against `plant`; the limit that stopped it, when it stopped (s), and the run.
fn limit_stop(plant: Box<dyn Plant>, cfg: DriveConfig) -> (LimitStop, f64, Run) {
    let (run, sim, _) = run_pair_with(plant, cfg, LinkModel::ideal(), &mut |_, _, _| true);
    let report = run.report.clone().unwrap();
    let StopReason::Limit(limit) = report.reason.clone() else {
        panic!("not stopped by a limit: {:?}", report.reason)
    };
    assert!(report.reason.is_fault());
    let stop = stopping_at(&run);
    assert_standby_first(&run, stop);
    assert_eq!(
        sim.sim.summary().last_readiness,
        Some(propid_core::dsdl::Readiness::STANDBY)
    );
    assert_eq!(sim.sim.summary().last_setpoint, Some(0.0));
    (limit, stop, run)
}

#[test]
fn no_feedback_during_the_soft_start_stops_before_any_high_torque() {
    // The drive is there but publishes its feedback on another subject.
    let sim = SimDrive::new(
        SimDriveConfig {
            feedback_id: SubjectId::from_const(111),
            ..SimDriveConfig::example()
        },
        stand(),
        T0,
    );
    let (run, _, _) = run_against(
        sim,
        seed(Limits::DEFAULT),
        LinkModel::ideal(),
        &mut |_, _, _| true,
    );
    let report = run.report.clone().unwrap();
    assert_eq!(
        report.reason,
        StopReason::Limit(LimitStop::SoftStartNoFeedback {
            messages: 0,
            seconds: 1.0,
            subject: 110
        })
    );
    assert_eq!(stopping_at(&run), 1.0);
    let text = report.reason.to_string();
    assert!(
        text.starts_with("no feedback during the soft start: 0 messages on subject 110 in 1 s"),
        "{text}"
    );
    // Nothing above the soft start's setpoint was ever commanded.
    assert!(run.sim_inputs.iter().all(|(_, i)| match i {
        SimInput::Setpoint(v) => *v <= 0.1,
        SimInput::Readiness(_) => true,
    }));
}

#[test]
fn a_reversed_torque_is_caught_by_the_soft_start() {
    // The watchdog runs during the soft start: the rotor speeding up against the torque stops it
    // once 50 rad/s past the margin, long before the soft start's end, in the soft start's words.
    let (limit, stop, run) = limit_stop(scaled(-1.0), seed(Limits::DEFAULT));
    let LimitStop::SoftStartWrongWay { setpoint, from, to } = limit else {
        panic!("{limit:?}")
    };
    assert!(stop < 0.2, "stopped at {stop} s");
    assert_eq!(setpoint, 0.1);
    assert!(
        (-70.0..-50.0).contains(&to) && from.abs() < 5.0,
        "{from} → {to}"
    );
    assert!(limit_text(&run).starts_with(
        "the rotor accelerated the wrong way: the torque sign is reversed (at setpoint +0.1"
    ));
    // Without the watchdog, the soft start's verdict at its end says the same.
    let limits = Limits {
        watchdog: None,
        ..Limits::DEFAULT
    };
    let (limit, stop, _) = limit_stop(scaled(-1.0), seed(limits));
    let LimitStop::SoftStartWrongWay { to, .. } = limit else {
        panic!("{limit:?}")
    };
    assert_eq!(stop, 1.0);
    assert!(to < -300.0, "{to}");
}

#[test]
fn a_motor_without_torque_does_not_pass_the_soft_start() {
    let (limit, stop, _) = limit_stop(scaled(0.0), seed(Limits::DEFAULT));
    assert!(
        matches!(limit, LimitStop::SoftStartNoMotion { setpoint, .. } if setpoint == 0.1),
        "{limit:?}"
    );
    assert_eq!(stop, 1.0);
}

#[test]
fn a_torque_reported_reversed_does_not_pass_the_soft_start() {
    for (watchdog, latest) in [(Limits::DEFAULT.watchdog, 0.2), (None, 1.0)] {
        let limits = Limits {
            watchdog,
            ..Limits::DEFAULT
        };
        // The rotor turns the commanded way; the drive reports its torque with the other sign.
        let plant = Box::new(TorqueScaled::new(stand(), 1.0).reporting(-1.0));
        let (limit, stop, _) = limit_stop(plant, seed(limits));
        assert!(
            matches!(limit, LimitStop::SoftStartTorqueReversed { torque, .. } if torque < -0.005),
            "{limit:?}"
        );
        assert!(stop <= latest, "stopped at {stop} s");
    }
}

#[test]
fn without_a_soft_start_the_watchdog_catches_a_reversed_torque_within_milliseconds() {
    let limits = Limits {
        soft_start: None,
        ..Limits::DEFAULT
    };
    let (limit, stop, _) = limit_stop(scaled(-1.0), seed(limits));
    let LimitStop::Runaway {
        to, inertia_bound, ..
    } = limit
    else {
        panic!("{limit:?}")
    };
    // The torque pushed against the rotation: no inertia needed to tell.
    assert_eq!(inertia_bound, None);
    // At 0.09 N·m on 2e-5 kg·m² the rotor gains 4,500 rad/s²: 50 rad/s take about 11 ms.
    assert!(stop < 0.03, "stopped at {stop} s");
    assert!(to < 120.0, "{to}");
}

#[test]
fn the_maximum_speed_stops_the_init_phase() {
    // The default stand runs to about 2,450 rad/s at 0.9; 1,500 rad/s is passed during the init.
    let limits = Limits {
        max_speed: Some(MaxSpeed::new(1500.0).unwrap()),
        ..Limits::DEFAULT
    };
    let (limit, stop, run) = limit_stop(stand(), seed(limits));
    let LimitStop::MaxSpeed { speed, max } = limit else {
        panic!("{limit:?}")
    };
    assert_eq!(max, 1500.0);
    // Two consecutive samples above the limit: the second is at most one 2 ms step further.
    assert!((1500.0..1520.0).contains(&speed), "{speed}");
    assert!((1.0..3.0).contains(&stop), "{stop}");
    assert!(run.rows.is_empty(), "stopped before the pattern");
    assert!(limit_text(&run).contains("above the maximum of 1500 rad/s (14324 rpm)"));
}

/// A rotor whose propeller comes loose at `at` seconds: from then on 15 % of the inertia and
/// no drag (the motor alone), the same speed. Integrated in 50 µs steps; measured without noise.
struct LooseAt {
    at: f64,
    t: f64,
    velocity: f64,
    setpoint: f64,
}

impl LooseAt {
    const MAX_TORQUE: f64 = 0.1;
    const INERTIA: f64 = 2e-5;
    const C2: f64 = 1.5e-8;
}

impl LooseAt {
    /// The inertia, the drag and the torque now.
    fn now(&self) -> (f64, f64, f64) {
        let (j, c2) = if self.t >= self.at {
            (0.15 * Self::INERTIA, 0.0)
        } else {
            (Self::INERTIA, Self::C2)
        };
        (j, c2, self.setpoint * Self::MAX_TORQUE)
    }

    fn acceleration(&self) -> f64 {
        let (j, c2, torque) = self.now();
        (torque - c2 * self.velocity * self.velocity.abs()) / j
    }
}

impl Plant for LooseAt {
    fn set_setpoint(&mut self, setpoint: f64) {
        self.setpoint = setpoint;
    }
    fn time(&self) -> f64 {
        self.t
    }
    fn advance_to(&mut self, t: f64) {
        while self.t < t {
            let dt = (t - self.t).min(50e-6);
            self.velocity += dt * self.acceleration();
            self.t += dt;
        }
    }
    fn measure(&mut self) -> Sample {
        Sample {
            t: self.t,
            force: self.now().2,
            velocity: self.velocity,
            acceleration: self.acceleration(),
            position: 0.0,
        }
    }
}

#[test]
fn a_propeller_coming_loose_mid_pattern_is_a_runaway() {
    let plant = Box::new(LooseAt {
        at: 8.0,
        t: 0.0,
        velocity: 0.0,
        setpoint: 0.0,
    });
    let (limit, stop, run) = limit_stop(plant, seed(Limits::DEFAULT));
    let LimitStop::Runaway {
        excess,
        inertia_bound,
        ..
    } = limit
    else {
        panic!("{limit:?}")
    };
    // The running fit knew J by then: the bound is a third of it.
    let j = inertia_bound.expect("an inertia bound");
    assert!((j / (LooseAt::INERTIA / 3.0) - 1.0).abs() < 0.05, "{j}");
    assert!(excess > 50.0);
    assert!((8.0..8.05).contains(&stop), "stopped at {stop} s");
    assert!(run.rows.len() > 2000, "the pattern ran until then");
}

fn limit_text(run: &Run) -> String {
    run.report.as_ref().unwrap().reason.to_string()
}

/// The limits trip on no ordinary run: a 20 ms torque lag (the demo hides 12 ms) on the seed's
/// sine and on a chirp, with the ramp.
#[test]
fn ordinary_runs_with_a_torque_lag_trip_nothing() {
    for pattern in [Pattern::Sine, Pattern::Chirp] {
        let plant = StandPlant::boxed(
            StandConfig {
                torque_lag: 0.02,
                ..StandConfig::default()
            },
            9,
        )
        .unwrap();
        let cfg = DriveConfig {
            limits: Limits {
                ramp: Some(propid_drive_proto::settings::RampDuration::new(0.5).unwrap()),
                max_speed: Some(MaxSpeed::new(3000.0).unwrap()),
                ..Limits::DEFAULT
            },
            ..DriveConfig::example(
                Played::try_from(Excitation {
                    pattern,
                    ..seed_excitation(2.0, 30.0)
                })
                .unwrap(),
            )
        };
        let (run, _, _) = run_pair_with(plant, cfg, LinkModel::ideal(), &mut |_, _, _| true);
        let report = run.report.unwrap();
        assert_eq!(report.reason, StopReason::Completed, "{pattern}");
        assert_eq!(report.rows, 15_000, "{pattern}");
    }
}
