//! The stop commands leave as several transfers even when the link is stopped when the stop
//! begins. A Cyphal receiver (PyCyphal, libcanard) discards a transfer whose transfer-ID equals
//! the last one it took from that source and subject within the transfer-ID timeout (2 s): a
//! single zero setpoint after a gap is lost 1 time in 32. Found against PyCyphal behind a stalled
//! bus (`host-cli/tests/pycyphal_congestion.rs`): the five repeats queued while the link refused
//! everything superseded each other and one zero setpoint left, which PyCyphal once discarded;
//! its last decoded setpoint stayed 0.9 while its readiness went to STANDBY.
//!
//! The repeats alone were not enough: transfers that never left (superseded in the queue, refused
//! by the link until stale, purged by the stop) used up transfer-IDs, so after a stall the first
//! stop commands carried arbitrary IDs, and PyCyphal still discarded one now and then. A
//! transfer now takes its ID as its first frame leaves (`propid_core::node::TxQueue`), and a
//! frame the link refused until stale gives its ID back (`Node::unsent`).

use std::ops::Range;
use std::time::Duration;

use propid_core::can::Frame;
use propid_core::time::Instant;
use propid_drive_host::stand::Played;
use propid_drive_proto::drive::{Drive, DriveConfig, DriveEvent, StopReport, STOP_REPEATS};
use propid_drive_proto::settings::Deadman;
use propid_drive_proto::{Machine, StopReason};
use propid_science::excitation::{Excitation, Pattern};

/// (subject, transfer-ID) of every transfer that left whole, in order.
fn transfers(frames: &[Frame]) -> Vec<(u32, u8)> {
    frames
        .iter()
        .filter(|f| f.data().last().is_some_and(|t| t & 0x40 != 0))
        .map(|f| (f.id() >> 8 & 0x1FFF, f.data().last().unwrap() & 0x1F))
        .collect()
}

/// A drive running the seed's sine on a virtual clock (1 ms steps), stopped by a signal at
/// `stop_at` ms, behind a link that takes every frame except from `stall.start` to `stall.end`
/// ms, when it refuses everything. Every frame the link took, and the stop report.
fn run_behind_a_stalled_link(stop_at: u64, stall: Range<u64>) -> (Vec<Frame>, StopReport) {
    let excitation = Excitation {
        lo: 0.1,
        hi: 0.9,
        period: 2.0,
        duration: 10.0,
        init_duration: 0.0,
        pattern: Pattern::Sine,
    };
    let cfg = DriveConfig {
        deadman: Deadman::new(5.0).unwrap(),
        ..DriveConfig::example(Played::try_from(excitation).unwrap())
    };
    let mut drive = Drive::new(cfg, Instant::ZERO);
    let ms = |n: u64| Instant::ZERO + Duration::from_millis(n);
    let mut sent = Vec::new();
    let mut t = 0;
    let mut report = None;
    while !drive.is_stopped() {
        let now = ms(t);
        if t == stop_at {
            drive.handle_fault(now, StopReason::Signal);
        }
        while let Some(f) = drive.poll_transmit(now) {
            if stall.contains(&t) {
                drive.handle_blocked(now, f);
                break;
            }
            sent.push(f);
        }
        while let Some(e) = drive.poll_event() {
            if let DriveEvent::Stopped(r) = e {
                report = Some(r);
            }
        }
        t += 1;
        assert!(t < 5000, "the stop sequence ended");
    }
    (sent, report.expect("a stop report"))
}

#[test]
fn stop_repeats_behind_a_stopped_link_leave_with_consecutive_transfer_ids() {
    // The link takes everything until the stop, then nothing for 300 ms, then all again.
    let stop_at = 100;
    let (sent, report) = run_behind_a_stalled_link(stop_at, stop_at..400);
    let after_stop: Vec<Frame> = sent
        .into_iter()
        .filter(|f| f.timestamp >= Instant::ZERO + Duration::from_millis(stop_at))
        .collect();
    let after_stop = transfers(&after_stop);
    let ids = |subject: u32| -> Vec<u8> {
        after_stop
            .iter()
            .filter(|(s, _)| *s == subject)
            .map(|(_, id)| *id)
            .collect()
    };
    for subject in [10, 24] {
        let ids = ids(subject);
        assert_eq!(
            ids.len(),
            STOP_REPEATS as usize,
            "subject {subject}: {ids:?}"
        );
        for w in ids.windows(2) {
            assert_eq!(w[1], (w[0] + 1) % 32, "subject {subject}: {ids:?}");
        }
    }
    assert_eq!(report.standby_sent, STOP_REPEATS, "{report:?}");
    assert_eq!(report.zero_setpoints_sent, STOP_REPEATS, "{report:?}");
}

/// A receiver deduplicates by transfer-ID, so what matters is the sequence it sees: the link
/// stops during the pattern, the stop begins while it is stopped, and it resumes. Every frame
/// the drive polled meanwhile was refused until stale; none of them may use up a transfer-ID,
/// or the stop's first commands would carry an arbitrary ID, equal to the last one the receiver
/// took one time in 32, and be discarded as a repeat (PyCyphal did so behind a stalled bus).
#[test]
fn transfer_ids_run_on_across_a_stalled_link_so_no_stop_command_looks_like_a_repeat() {
    // The link stops during the pattern; the stop begins while it is stopped; it resumes.
    let (sent, report) = run_behind_a_stalled_link(250, 100..400);
    // Frames went stale in the drive's hand and setpoints were superseded in the queue.
    assert!(
        report.tx.dropped > 10 && report.tx.superseded > 40,
        "{report:?}"
    );
    let whole = transfers(&sent);
    for subject in [10, 24] {
        let ids: Vec<u8> = whole
            .iter()
            .filter(|(s, _)| *s == subject)
            .map(|(_, id)| *id)
            .collect();
        assert!(ids.len() >= 20 + STOP_REPEATS as usize, "{ids:?}");
        // One after another; a step of two only where a transfer was cut short by the stall
        // (its first frames left, so its ID is used, and a receiver abandons it).
        let steps: Vec<u8> = ids.windows(2).map(|w| (w[1] + 32 - w[0]) % 32).collect();
        assert!(
            steps.iter().all(|s| *s == 1 || *s == 2)
                && steps.iter().filter(|s| **s == 2).count() <= 1,
            "subject {subject}: {ids:?}"
        );
    }
    // What a Cyphal receiver makes of it: the five STANDBY and zero setpoints, none discarded.
    let mut receiver = propid_core::node::Node::<4, 4, 64, 4>::new(
        propid_core::node::NodeConfig::new(
            propid_core::can::NodeId::from_const(42),
            "org.propid.test",
            propid_core::can::Mtu::Classic,
        ),
        Instant::ZERO,
    );
    for subject in [10, 24] {
        receiver
            .subscribe_message(propid_core::can::SubjectId::from_const(subject), 64)
            .unwrap();
    }
    let mut last = Vec::new();
    for f in &sent {
        if let Some(propid_core::node::Event::Message {
            subject_id,
            payload,
            ..
        }) = receiver.handle_frame(f.timestamp, f)
        {
            last.push((
                subject_id.get(),
                payload.iter().all(|b| *b == 0) || payload == [2],
            ));
        }
    }
    let stop_commands = last.iter().rev().take_while(|(_, stop)| *stop).count();
    assert_eq!(
        stop_commands,
        2 * STOP_REPEATS as usize,
        "{:?}",
        &last[last.len() - 12..]
    );
    // Nothing rejected but the heartbeats it does not subscribe to.
    let rx = receiver.stats().rx;
    assert_eq!(
        rx.rejected_total() - rx.rejected(propid_core::can::RxError::NotSubscribed),
        0,
        "{rx:?}"
    );
}
