//! The node's transmit queue under a congested link, on a virtual clock: a link that takes fewer
//! frames per millisecond than the node offers, as an SLCAN adapter behind a busy bus does.
//! Everything here is deterministic, so the counts are exact.

use core::time::Duration;

use propid_core::can::{Frame, Mtu, NodeId, Priority, SubjectId, TxError};
use propid_core::dsdl::{DataType, Heartbeat, Readiness, Vector31};
use propid_core::node::{Event, Health, Mode, Node, NodeConfig};
use propid_core::time::Instant;

/// 16 ports: transfer-ID counters for the 12 bulk subjects of the load test.
type TestNode = Node<16, 8, 512, 32>;

const SETPOINT: SubjectId = SubjectId::from_const(24);
const READINESS: SubjectId = SubjectId::from_const(23);
const HEARTBEAT: SubjectId = SubjectId::from_const(Heartbeat::FIXED_SUBJECT_ID);

fn ms(t: u64) -> Instant {
    Instant::from_millis(t)
}

fn pair() -> (TestNode, TestNode) {
    let driver = TestNode::new(
        NodeConfig::new(NodeId::from_const(10), "org.propid.driver", Mtu::Classic),
        ms(0),
    );
    let mut drive = TestNode::new(
        NodeConfig::new(NodeId::from_const(42), "org.propid.drive", Mtu::Classic),
        ms(0),
    );
    drive
        .subscribe_message(HEARTBEAT, Heartbeat::EXTENT_BYTES)
        .unwrap();
    drive
        .subscribe_message(SETPOINT, Vector31::EXTENT_BYTES)
        .unwrap();
    drive
        .subscribe_message(READINESS, Readiness::EXTENT_BYTES)
        .unwrap();
    (driver, drive)
}

/// What the drive saw, in order of arrival.
#[derive(Debug, PartialEq)]
enum Seen {
    Heartbeat(Heartbeat),
    Setpoint(f32),
    Readiness(u8),
}

/// Moves up to `budget` frames from `from` to `to` at `now`; returns what `to` made of them.
fn carry(from: &mut TestNode, to: &mut TestNode, now: Instant, budget: usize) -> Vec<Seen> {
    let frames = send(from, now, budget);
    deliver(to, now, &frames)
}

/// Up to `budget` frames `from` sends at `now`.
fn send(from: &mut TestNode, now: Instant, budget: usize) -> Vec<Frame> {
    let mut frames: Vec<Frame> = Vec::new();
    while frames.len() < budget {
        match from.poll_transmit(now) {
            Some(f) => frames.push(f),
            None => break,
        }
    }
    frames
}

/// What `to` makes of `frames` at `now`.
fn deliver(to: &mut TestNode, now: Instant, frames: &[Frame]) -> Vec<Seen> {
    let mut seen = Vec::new();
    for f in frames {
        if let Some(Event::Message {
            subject_id,
            payload,
            ..
        }) = to.handle_frame(now, f)
        {
            seen.push(match subject_id {
                HEARTBEAT => Seen::Heartbeat(Heartbeat::deserialize(payload).unwrap()),
                SETPOINT => {
                    let v = Vector31::deserialize(payload).unwrap();
                    // Every element the same: no frame of another transfer mixed in.
                    assert!(v.value.iter().all(|x| *x == v.value[0]), "{v:?}");
                    Seen::Setpoint(v.value[0])
                }
                READINESS => Seen::Readiness(Readiness::deserialize(payload).unwrap().value),
                other => panic!("subject {other}"),
            });
        }
    }
    seen
}

fn publish_setpoint(node: &mut TestNode, now: Instant, value: f32) -> Result<(), TxError> {
    node.publish_message(
        now,
        SETPOINT,
        Priority::HIGH,
        &Vector31::splat(value),
        Duration::from_millis(50),
    )
}

#[test]
fn a_congested_link_gets_the_newest_setpoint_whole_and_the_stop_first() {
    // The seed's 5 ms setpoint period; a 62-byte Vector31 is 10 Classic frames; the link takes
    // one frame per millisecond, half of what is offered.
    let (mut driver, mut drive) = pair();
    let mut seen = Vec::new();
    for t in 0..1000u64 {
        if t % 5 == 0 {
            publish_setpoint(&mut driver, ms(t), (t / 5) as f32).unwrap();
        }
        seen.extend(carry(&mut driver, &mut drive, ms(t), 1));
        assert_eq!(driver.poll_timeout(), Some(ms(t)), "frames wait at {t} ms");
    }
    // Setpoint k is published at 5k ms. The one in progress finishes (10 ms); of the two
    // published meanwhile the newer supersedes the older: 0, 2, 4, … 198 arrive, each whole.
    let expected: Vec<Seen> = (0..100).map(|k| Seen::Setpoint(2.0 * k as f32)).collect();
    assert_eq!(seen, expected);
    let tx = driver.stats().tx;
    assert_eq!(tx.sent, 1000);
    assert_eq!(tx.superseded, 99);
    assert_eq!((tx.expired, tx.refused, tx.displaced), (0, 0, 0));
    assert_eq!(drive.stats().rx.rejected_total(), 0);
    // Waiting: setpoint 199 (10 frames) and the first heartbeat, starved by the higher priority.
    assert_eq!(driver.pending_frames(SETPOINT), 10);
    assert_eq!(driver.transmit_queue_len(), 11);

    // The stop sequence: purge, then STANDBY and a zero setpoint are the first frames out.
    let now = ms(1000);
    assert_eq!(driver.purge_transmit(), 11);
    assert!(driver.is_transmit_queue_empty());
    driver
        .publish_message(
            now,
            READINESS,
            Priority::HIGH,
            &Readiness {
                value: Readiness::STANDBY,
            },
            Duration::from_millis(50),
        )
        .unwrap();
    publish_setpoint(&mut driver, now, 0.0).unwrap();
    let stop = carry(&mut driver, &mut drive, now, usize::MAX);
    assert_eq!(
        stop,
        vec![
            Seen::Readiness(Readiness::STANDBY),
            Seen::Setpoint(0.0),
            // The heartbeat due at 1 s is NOMINAL: it follows the HIGH stop commands.
            Seen::Heartbeat(Heartbeat {
                uptime: 1,
                health: Heartbeat::HEALTH_NOMINAL,
                mode: Heartbeat::MODE_OPERATIONAL,
                vendor_specific_status_code: 0,
            }),
        ]
    );
    assert_eq!(driver.stats().tx.purged, 11);
    assert_eq!(driver.poll_timeout(), Some(ms(2000)));
}

#[test]
fn heartbeats_still_go_out_under_load_and_report_the_status() {
    // HIGH setpoints (2 frames/ms) plus LOW bulk transfers (4 frames/ms, rotating over 12
    // subjects so that more wait than the 32-frame queue holds) through a link of 3 frames/ms: the
    // queue is full of LOW frames, yet the NOMINAL heartbeat displaces them and leaves on time.
    let (mut driver, mut drive) = pair();
    let mut heartbeats = Vec::new();
    let mut setpoints = 0;
    let mut bulk_refused = 0;
    for t in 0..10_000u64 {
        if t == 4500 {
            driver.set_status(Health::Caution, Mode::Maintenance, 7);
            assert_eq!(driver.status(), (Health::Caution, Mode::Maintenance, 7));
        }
        if t % 5 == 0 {
            publish_setpoint(&mut driver, ms(t), 1.0).unwrap();
        }
        let bulk = driver.publish(
            ms(t),
            SubjectId::try_from(300 + t % 12).unwrap(),
            Priority::LOW,
            &[0x55; 22],
            Duration::from_millis(500),
        );
        if bulk == Err(TxError::QueueFull) {
            bulk_refused += 1;
        }
        for s in carry(&mut driver, &mut drive, ms(t), 3) {
            match s {
                Seen::Heartbeat(h) => heartbeats.push((t, h)),
                Seen::Setpoint(_) => setpoints += 1,
                Seen::Readiness(_) => unreachable!(),
            }
        }
    }
    // Every setpoint arrived, and one heartbeat a second. Ahead of it go at most the rest of a
    // started LOW transfer (3 frames) and the setpoint of the same millisecond (10): its 14th
    // frame leaves at most 4 ms late.
    assert_eq!(setpoints, 2000);
    assert_eq!(heartbeats.len(), 10);
    for (k, (t, h)) in heartbeats.iter().enumerate() {
        assert!(
            *t >= 1000 * k as u64 && *t <= 1000 * k as u64 + 4,
            "heartbeat {k} at {t} ms"
        );
        assert_eq!(h.uptime, k as u32);
        let expected = if k < 5 {
            (Heartbeat::HEALTH_NOMINAL, Heartbeat::MODE_OPERATIONAL, 0)
        } else {
            (Heartbeat::HEALTH_CAUTION, Heartbeat::MODE_MAINTENANCE, 7)
        };
        assert_eq!((h.health, h.mode, h.vendor_specific_status_code), expected);
    }
    let tx = driver.stats().tx;
    // The link was busy every millisecond.
    assert_eq!(tx.sent, 30_000);
    assert_eq!(driver.stats().heartbeats, 10);
    // The overload is counted, not hidden: refusals of bulk and displacements for the rest.
    assert_eq!(tx.refused, bulk_refused);
    assert!(tx.refused > 0 && tx.displaced > 0, "{tx:?}");
    assert_eq!(tx.expired, 0);
}

#[test]
fn a_frame_past_its_deadline_is_dropped_counted_and_never_sent() {
    let (mut driver, _) = pair();
    // The first heartbeat leaves at once; then the link stalls for longer than the setpoint's
    // 50 ms deadline.
    assert!(driver.poll_transmit(ms(0)).is_some());
    assert_eq!(driver.poll_timeout(), Some(ms(1000)));
    publish_setpoint(&mut driver, ms(1), 3.0).unwrap();
    assert_eq!(driver.poll_timeout(), Some(ms(1)));
    // At the deadline itself a frame still leaves; after it the other nine are dropped.
    assert!(driver.poll_transmit(ms(51)).is_some());
    assert_eq!(driver.poll_transmit(ms(52)), None);
    let tx = driver.stats().tx;
    assert_eq!((tx.sent, tx.expired), (2, 9));
    assert_eq!(driver.poll_timeout(), Some(ms(1000)));
}

#[test]
fn a_full_queue_is_a_counted_refusal() {
    let (mut driver, _) = pair();
    // 32 frames of room: three 10-frame setpoints on three subjects fit, a fourth does not.
    for subject in 0..3 {
        driver
            .publish_message(
                ms(0),
                SubjectId::try_from(100 + subject).unwrap(),
                Priority::HIGH,
                &Vector31::splat(1.0),
                Duration::from_secs(1),
            )
            .unwrap();
    }
    assert_eq!(
        driver.publish_message(
            ms(0),
            SubjectId::from_const(103),
            Priority::HIGH,
            &Vector31::splat(1.0),
            Duration::from_secs(1)
        ),
        Err(TxError::QueueFull)
    );
    assert_eq!(driver.stats().tx.refused, 1);
    assert_eq!(driver.transmit_queue_len(), 30);
    // The heartbeat (NOMINAL, 1 frame) still finds room.
    let first = driver.poll_transmit(ms(0)).unwrap();
    assert_eq!((first.id() >> 8) & 0x1FFF, 100);
    assert_eq!(driver.stats().heartbeats, 1);
    assert_eq!(driver.transmit_queue_len(), 30);
}

/// The transfer-ID in a frame's tail byte.
fn transfer_id(f: &Frame) -> u8 {
    f.data().last().unwrap() & 0x1F
}

#[test]
fn transfers_that_never_left_take_no_transfer_id() {
    let (mut driver, mut drive) = pair();
    publish_setpoint(&mut driver, ms(0), 1.0).unwrap();
    let first = send(&mut driver, ms(0), usize::MAX);
    assert!(deliver(&mut drive, ms(0), &first).contains(&Seen::Setpoint(1.0)));
    let setpoint_ids = |frames: &[Frame]| -> Vec<u8> {
        frames
            .iter()
            .filter(|f| (f.id() >> 8) & 0x1FFF == u32::from(SETPOINT.get()))
            .map(transfer_id)
            .collect()
    };
    assert_eq!(setpoint_ids(&first), [0; 10]);

    // 32 setpoints while the link takes nothing: each supersedes the one before. Numbered as
    // published, the last would carry 32 mod 32 = 0, the ID of the one that crossed, and the
    // receiver would discard it as a repeat (as PyCyphal did after a stalled bus).
    for k in 0..32u64 {
        publish_setpoint(&mut driver, ms(1 + k), 2.0 + k as f32).unwrap();
    }
    assert_eq!(driver.stats().tx.superseded, 31);
    let next = send(&mut driver, ms(33), usize::MAX);
    assert_eq!(setpoint_ids(&next), [1; 10]);
    assert_eq!(deliver(&mut drive, ms(33), &next), [Seen::Setpoint(33.0)]);

    // A transfer cut short by a stop: 3 of its 10 frames leave, the rest is purged. The zero
    // setpoint after it is next in number; the receiver abandons the cut one and takes it.
    publish_setpoint(&mut driver, ms(40), 5.0).unwrap();
    let cut = send(&mut driver, ms(40), 3);
    assert_eq!(setpoint_ids(&cut), [2; 3]);
    assert_eq!(deliver(&mut drive, ms(40), &cut), []);
    assert_eq!(driver.purge_transmit(), 7);
    publish_setpoint(&mut driver, ms(41), 0.0).unwrap();
    let stop = send(&mut driver, ms(41), usize::MAX);
    assert_eq!(setpoint_ids(&stop), [3; 10]);
    assert_eq!(deliver(&mut drive, ms(41), &stop), [Seen::Setpoint(0.0)]);
    assert_eq!(drive.stats().rx.rejected_total(), 0);
}
