//! The drive against the simulated Telega in virtual time: the seed's whole sequence (5 s init
//! at hi with feedback ignored, the 200 s sine at a 5 ms setpoint period, STANDBY + zero), with
//! exact phases and row counts, and the same after the default soft start and a ramp;
//! congestion; and the faults of the live path.

mod common;

use std::time::Duration;

use common::*;
use propid_core::dsdl::{DataType, DoF3rdTs, Readiness};
use propid_core::sample::Sample;
use propid_core::time::Instant;
use propid_drive_host::stand::Played;
use propid_drive_proto::drive::{
    Drive, DriveConfig, DriveEvent, Phase, SNAPSHOT_SAMPLES, STOP_WINDOW,
};
use propid_drive_proto::limits::Limits;
use propid_drive_proto::settings::{Deadman, RelativeError};
use propid_drive_proto::sim_drive::SimDrive;
use propid_drive_proto::virtual_link::{LinkModel, VirtualLink};
use propid_drive_proto::{Machine, StopReason};
use propid_science::excitation::Excitation;
use propid_science::stand::StandConfig;

#[test]
fn the_seed_sequence_in_virtual_time() {
    let t = std::time::Instant::now();
    // The seed's sequence exactly: no soft start, no ramp, no watchdog.
    let cfg = DriveConfig {
        limits: Limits::OFF,
        ..DriveConfig::example(Played::try_from(seed_excitation(5.0, 200.0)).unwrap())
    };
    let (run, sim, link) = run_pair(cfg, LinkModel::ideal(), &mut |_, _, _| true);
    let wall = t.elapsed();
    let report = run.report.clone().unwrap();
    assert_eq!(report.reason, StopReason::Completed);
    // Phases exactly on time.
    assert_eq!(
        run.phases,
        vec![
            (5_000_000, "pattern"),
            (205_000_000, "stopping"),
            (205_020_000, "stopped")
        ],
        "wall time {wall:?}"
    );
    // One row per feedback published in [5 s, 205 s): every 2 ms, arriving 100 µs later.
    assert_eq!(run.rows.len(), 100_000);
    assert_eq!(report.rows, 100_000);
    assert_eq!(run.rows[0].sample.t, 5.0);
    assert_rows_are_published(&run);
    // Init at hi (float16 of 0.9), then the sine, then STANDBY + zero first and last.
    let sp: Vec<f32> = run
        .sim_inputs
        .iter()
        .filter_map(|(_, i)| match i {
            SimInput::Setpoint(v) => Some(*v),
            _ => None,
        })
        .collect();
    assert_eq!(
        sp.len(),
        41_000 + 5,
        "one setpoint per 5 ms, 5 stop repeats"
    );
    assert!((sp[0] - 0.9).abs() < 1e-3);
    assert_standby_first(&run, 205.0);
    assert_eq!(sim.sim.summary().last_readiness, Some(Readiness::STANDBY));
    assert_eq!(sim.sim.summary().last_setpoint, Some(0.0));
    assert_eq!(
        sim.sim.summary().readiness_changes,
        vec![Readiness::ENGAGED, Readiness::STANDBY]
    );
    assert_eq!(report.standby_sent, 5);
    assert_eq!(report.zero_setpoints_sent, 5);
    assert_eq!(report.tx.dropped, 0);
    assert_eq!(run.progress, 199);
    assert_eq!(link.refused(), (0, 0));
    // The fit on the rows recovers the simulated load.
    let truth = StandConfig::default();
    let est = report.estimate.unwrap();
    assert!((est.j / truth.inertia - 1.0).abs() < 0.02, "J {}", est.j);
    eprintln!("the seed sequence took {wall:?} of wall time");
}

/// The default limits with a ramp: 1 s at 0.1 (the soft start), 1 s ramping to 0.9, then the
/// seed's init and pattern, exactly on time, every row recorded and no limit tripped.
#[test]
fn the_soft_start_and_a_ramp_come_before_the_seeds_init() {
    let cfg = DriveConfig {
        limits: Limits {
            ramp: Some(propid_drive_proto::settings::RampDuration::new(1.0).unwrap()),
            ..Limits::DEFAULT
        },
        ..DriveConfig::example(Played::try_from(seed_excitation(5.0, 20.0)).unwrap())
    };
    let (run, _, _) = run_pair(cfg, LinkModel::ideal(), &mut |_, _, _| true);
    let report = run.report.clone().unwrap();
    assert_eq!(report.reason, StopReason::Completed);
    assert_eq!(
        run.phases,
        vec![
            (1_000_000, "soft start passed"),
            (7_000_000, "pattern"),
            (27_000_000, "stopping"),
            (27_020_000, "stopped")
        ]
    );
    assert_eq!(run.rows.len(), 10_000);
    assert_rows_are_published(&run);
    let sp: Vec<(f64, f32)> = run
        .sim_inputs
        .iter()
        .filter_map(|(t, i)| match i {
            SimInput::Setpoint(v) => Some((*t, *v)),
            _ => None,
        })
        .collect();
    // float16 on the wire: 0.1 → 0.0999756, 0.9 → 0.8999023.
    let window = |from: f64, to: f64| -> Vec<f32> {
        sp.iter()
            .filter(|(t, _)| (from..to).contains(t))
            .map(|x| x.1)
            .collect()
    };
    let soft = window(0.0, 1.0);
    assert_eq!(soft.len(), 200);
    assert!(soft.iter().all(|v| (v - 0.1).abs() < 1e-3), "{soft:?}");
    let ramp = window(1.0, 2.0);
    assert_eq!(ramp.len(), 200);
    assert!(ramp.windows(2).all(|w| w[1] >= w[0]), "{ramp:?}");
    assert!(ramp[0] < 0.11 && ramp[199] > 0.89, "{ramp:?}");
    let init = window(2.0, 7.0);
    assert_eq!(init.len(), 1000);
    assert!(init.iter().all(|v| (v - 0.9).abs() < 1e-3));
    assert_standby_first(&run, 27.0);
}

#[test]
fn the_same_run_twice_is_the_same() {
    let cfg = DriveConfig::example(Played::try_from(seed_excitation(1.0, 5.0)).unwrap());
    let (a, _, _) = run_pair(cfg.clone(), LinkModel::ideal(), &mut |_, _, _| true);
    let (b, _, _) = run_pair(cfg, LinkModel::ideal(), &mut |_, _, _| true);
    assert_eq!(a.rows, b.rows);
    assert_eq!(a.sim_inputs, b.sim_inputs);
    assert_eq!(a.report, b.report);
}

#[test]
fn congestion_drops_frames_but_the_run_completes_and_standby_arrives() {
    // 1 frame per ms and at most 4 frames in flight: the setpoints (11 frames per 5 ms) and the
    // feedback (4 frames per 2 ms) cannot all pass.
    let model = LinkModel {
        frame_time: Duration::from_millis(1),
        latency: Duration::from_micros(100),
        capacity: 4,
    };
    let cfg = DriveConfig {
        deadman: Deadman::new(2.0).unwrap(),
        ..DriveConfig::example(Played::try_from(seed_excitation(1.0, 10.0)).unwrap())
    };
    let (run, sim, link) = run_pair(cfg, model, &mut |_, _, _| true);
    let report = run.report.clone().unwrap();
    assert_eq!(report.reason, StopReason::Completed);
    assert!(link.refused().0 > 0, "the link was congested");
    assert!(report.tx.would_block > 0, "{:?}", report.tx);
    assert!(
        report.tx.dropped + report.tx.superseded > 0,
        "{:?}",
        report.tx
    );
    assert!(run.rows.len() > 1000, "{}", run.rows.len());
    // Every row is something the stand published, in order; some feedback was lost.
    let mut published = run.published.iter().map(|fb| {
        let mut buf = [0u8; DoF3rdTs::MAX_SIZE_BYTES];
        fb.serialize(&mut buf);
        Sample::from(&DoF3rdTs::deserialize(&buf).unwrap())
    });
    for row in &run.rows {
        assert!(published.any(|p| p == row.sample), "{row:?} was published");
    }
    assert_standby_first(&run, stopping_at(&run));
    assert_eq!(sim.sim.summary().last_readiness, Some(Readiness::STANDBY));
    assert_eq!(sim.sim.summary().last_setpoint, Some(0.0));
    assert!(report.stop_commands_sent(true));
}

#[test]
fn lost_feedback_stops_at_the_deadman() {
    let mut when = at(3.0);
    let (run, sim, _) = run_pair(
        DriveConfig::example(Played::try_from(seed_excitation(1.0, 10.0)).unwrap()),
        LinkModel::ideal(),
        &mut |link, _, _| {
            let go = when(link);
            link.mute_b |= go;
            go
        },
    );
    let report = run.report.clone().unwrap();
    assert_eq!(report.reason, StopReason::LostFeedback { deadman: 0.5 });
    let stop = stopping_at(&run);
    assert!((3.5..3.52).contains(&stop), "{stop}");
    assert_eq!(sim.sim.summary().last_readiness, Some(Readiness::STANDBY));
    assert_eq!(sim.sim.summary().last_setpoint, Some(0.0));
}

#[test]
fn a_drive_reboot_stops_the_run() {
    let mut when = at(3.5);
    let (run, _, _) = run_pair(
        DriveConfig::example(Played::try_from(seed_excitation(1.0, 10.0)).unwrap()),
        LinkModel::ideal(),
        &mut |link, _, sim| {
            let go = when(link);
            if go {
                // The drive comes back: a new node, uptime 0.
                *sim = Observed {
                    sim: SimDrive::new(sim_cfg(), stand(), link.now()),
                    rx: std::mem::replace(&mut sim.rx, propid_core::can::Reassembler::new(None)),
                    log: std::mem::take(&mut sim.log),
                };
            }
            go
        },
    );
    let report = run.report.clone().unwrap();
    assert_eq!(
        report.reason,
        StopReason::DriveRebooted {
            node_id: 42,
            before: 3,
            after: 0
        }
    );
    assert_standby_first(&run, stopping_at(&run));
    assert_eq!(report.rows as usize, run.rows.len());
}

#[test]
fn a_clock_jump_stops_the_run_with_standby_first() {
    for step in [-2.0f64, 5.0] {
        let cfg = DriveConfig::example(Played::try_from(seed_excitation(1.0, 10.0)).unwrap());
        let mut drive = Drive::new(cfg, T0);
        let mut sim = SimDrive::new(sim_cfg(), stand(), T0);
        let mut link = VirtualLink::new(LinkModel::ideal(), T0);
        let at = 3.0 + SOFT;
        while link.now() < Instant::from_micros((at * 1e6) as u64) {
            link.step(&mut drive, &mut sim);
        }
        while drive.poll_event().is_some() {}
        // The live view's snapshot: the last samples, the estimate, the commands, the counters.
        let snap = drive.snapshot();
        assert_eq!(snap.phase, Phase::Pattern);
        assert_eq!(snap.readiness, Readiness::ENGAGED);
        assert_eq!(snap.recent.len(), SNAPSHOT_SAMPLES);
        assert_eq!(snap.rows, drive.rows());
        assert!(snap.rows >= SNAPSHOT_SAMPLES as u64, "{}", snap.rows);
        assert!((snap.recent.last().unwrap().t - (at - 0.002)).abs() < 1e-9);
        let est = snap
            .estimate
            .expect("two seconds of the sine identify the load");
        assert!(est.j_stderr > 0.0 && est.j_stderr < 0.1 * est.j, "{est:?}");
        assert_eq!(snap.tx.dropped, 0);
        let jumped = Instant::from_micros(((at + step) * 1e6) as u64);
        let first = drive.poll_transmit(jumped).expect("a frame after the jump");
        assert_eq!(drive.phase(), Phase::Stopping);
        // STANDBY is the first frame after the fault.
        assert_eq!(first.id() >> 8 & 0x1FFF, 10);
        let mut buf = [0u8; 1];
        buf.copy_from_slice(&first.data()[..1]);
        assert_eq!(buf[0], Readiness::STANDBY);
        let events: Vec<DriveEvent> = std::iter::from_fn(|| drive.poll_event()).collect();
        match &events[0] {
            DriveEvent::Stopping(StopReason::ClockJump { step: s }) => {
                assert!((s - step).abs() < 0.01, "{s} vs {step}")
            }
            e => panic!("{e:?}"),
        }
        // The machine ends its stop sequence within its window, whatever the clock does.
        let mut now = jumped;
        loop {
            while drive.poll_transmit(now).is_some() {}
            match drive.poll_timeout() {
                Some(t) => now = t.max(now),
                None => break,
            }
        }
        assert!(drive.is_stopped());
        assert!(now.saturating_duration_since(jumped) <= STOP_WINDOW);
    }
}

#[test]
fn a_fault_from_the_loop_puts_standby_first_and_keeps_rows() {
    for reason in [
        StopReason::BusOff,
        StopReason::AdapterRefused("T1060180A8...".into()),
        StopReason::DeviceVanished("slcan:/dev/pts/9".into()),
        StopReason::Signal,
    ] {
        let mut when = at(2.5 + SOFT);
        let r = reason.clone();
        let (run, _, _) = run_pair(
            DriveConfig::example(Played::try_from(seed_excitation(1.0, 10.0)).unwrap()),
            LinkModel::ideal(),
            &mut |link, drive, _| {
                let go = when(link);
                if go {
                    drive.handle_fault(link.now(), r.clone());
                }
                go
            },
        );
        let report = run.report.clone().unwrap();
        assert_eq!(report.reason, reason);
        assert!(report.reason.is_fault());
        assert_eq!(report.rows as usize, run.rows.len());
        assert!(run.rows.len() > 700, "{}", run.rows.len());
        assert_standby_first(&run, stopping_at(&run));
    }
}

/// `--until-stderr`: the drive stops, with STANDBY first as always, once the running estimate is
/// as precise as asked — within 20 % of the time `propid plan` predicts for that precision.
#[test]
fn until_stderr_stops_when_precise_near_the_planned_time() {
    use propid_science::plan::{design, Constraints, Prior};
    let stand = StandConfig::default();
    let target = 1.5e-4;
    let plan = design(
        &Prior::new(stand.inertia, stand.c2, stand.max_torque),
        &Constraints {
            lo: 0.1,
            hi: 0.9,
            max_speed: None,
            max_duration: 200.0,
        },
        Some(target),
    )
    .unwrap();
    let predicted = plan.predicted.seconds;
    let cfg = DriveConfig {
        until_rel_stderr: Some(RelativeError::new(target).unwrap()),
        ..DriveConfig::example(
            Played::try_from(Excitation {
                duration: 200.0,
                init_duration: 1.0,
                ..plan.excitation
            })
            .unwrap(),
        )
    };
    let (run, _, _) = run_pair(cfg, LinkModel::ideal(), &mut |_, _, _| true);
    let report = run.report.clone().unwrap();
    let StopReason::Precise {
        elapsed,
        rel_j,
        rel_c2,
    } = report.reason
    else {
        panic!("{:?}", report.reason)
    };
    assert!(rel_j <= target && rel_c2 <= target);
    assert!(
        (elapsed / predicted - 1.0).abs() <= 0.2,
        "stopped after {elapsed:.1} s, predicted {predicted:.1} s"
    );
    assert_standby_first(&run, stopping_at(&run) - 1e-3);
}
