//! Two Sans-IO nodes through a simulated link with a virtual clock (quinn-proto style): heartbeat
//! cadence, GetInfo round trip, multi-frame publish/subscribe, Classic and FD, and a lossy link.

use core::time::Duration;

use propid_core::can::{Frame, Mtu, NodeId, Priority, ServiceId, SubjectId};
use propid_core::dsdl::{
    DataType, DoF3rdTs, GetInfoResponse, Heartbeat, Vector31, GET_INFO_SERVICE_ID,
};
use propid_core::node::{Event, Node, NodeConfig};
use propid_core::time::Instant;

type TestNode = Node<6, 8, 512, 64>;

const HEARTBEAT: SubjectId = SubjectId::from_const(Heartbeat::FIXED_SUBJECT_ID);
const SETPOINT: SubjectId = SubjectId::from_const(24);
const FEEDBACK: SubjectId = SubjectId::from_const(110);
const GET_INFO: ServiceId = ServiceId::from_const(GET_INFO_SERVICE_ID);

#[derive(Default)]
struct Seen {
    heartbeats: Vec<(u8, u32)>,
    setpoints: Vec<Vector31>,
    feedback: Vec<DoF3rdTs>,
    info: Vec<GetInfoResponse>,
}

fn record(seen: &mut Seen, event: Event<'_>) {
    match event {
        Event::Message {
            subject_id: HEARTBEAT,
            source,
            payload,
            ..
        } => seen.heartbeats.push((
            source.unwrap().get(),
            Heartbeat::deserialize(payload).unwrap().uptime,
        )),
        Event::Message {
            subject_id: SETPOINT,
            payload,
            ..
        } => seen.setpoints.push(Vector31::deserialize(payload).unwrap()),
        Event::Message {
            subject_id: FEEDBACK,
            payload,
            ..
        } => seen.feedback.push(DoF3rdTs::deserialize(payload).unwrap()),
        Event::Response {
            service_id: GET_INFO,
            payload,
            ..
        } => seen
            .info
            .push(GetInfoResponse::deserialize(payload).unwrap()),
        other => panic!("unexpected {other:?}"),
    }
}

/// Runs both nodes for `seconds` of virtual time in 1 ms steps; `lose(k)` drops the k-th frame.
fn run(mtu: Mtu, seconds: u64, lose: impl Fn(u64) -> bool) -> (Seen, Seen, TestNode, TestNode) {
    let t0 = Instant::from_millis(1000);
    let mut driver = TestNode::new(
        NodeConfig::new(NodeId::from_const(10), "org.propid.driver", mtu),
        t0,
    );
    let mut drive = TestNode::new(
        NodeConfig::new(NodeId::from_const(42), "org.propid.sim_drive", mtu),
        t0,
    );
    for n in [&mut driver, &mut drive] {
        n.subscribe_message(HEARTBEAT, 12).unwrap();
    }
    drive.subscribe_message(SETPOINT, 62).unwrap();
    driver.subscribe_message(FEEDBACK, 23).unwrap();
    let (mut a_seen, mut b_seen) = (Seen::default(), Seen::default());
    let mut k = 0u64;
    driver
        .request(
            t0,
            GET_INFO,
            NodeId::from_const(42),
            &[],
            448,
            Duration::from_secs(1),
        )
        .unwrap();
    for ms in 0..seconds * 1000 {
        let now = t0 + Duration::from_millis(ms);
        if ms % 5 == 0 {
            let sp = Vector31::splat((ms as f32 / 1000.0).sin());
            driver
                .publish_message(
                    now,
                    SETPOINT,
                    Priority::HIGH,
                    &sp,
                    Duration::from_millis(50),
                )
                .unwrap();
        }
        if ms % 10 == 0 {
            let mut fb = DoF3rdTs::default();
            fb.timestamp.microsecond = ms * 1000;
            fb.value.kinematics.base.velocity = ms as f32;
            drive
                .publish_message(
                    now,
                    FEEDBACK,
                    Priority::HIGH,
                    &fb,
                    Duration::from_millis(50),
                )
                .unwrap();
        }
        let mut a_to_b: Vec<Frame> = Vec::new();
        while let Some(f) = driver.poll_transmit(now) {
            a_to_b.push(f);
        }
        let mut b_to_a: Vec<Frame> = Vec::new();
        while let Some(f) = drive.poll_transmit(now) {
            b_to_a.push(f);
        }
        for f in a_to_b {
            k += 1;
            if !lose(k) {
                if let Some(e) = drive.handle_frame(now, &f) {
                    record(&mut b_seen, e);
                }
            }
        }
        for f in b_to_a {
            k += 1;
            if !lose(k) {
                if let Some(e) = driver.handle_frame(now, &f) {
                    record(&mut a_seen, e);
                }
            }
        }
        // The node says when to come back; with nothing queued it is the next heartbeat.
        let next = driver.poll_timeout().unwrap();
        assert!(
            next > now && next <= now + Duration::from_secs(1),
            "{next:?} at {now:?}"
        );
    }
    (a_seen, b_seen, driver, drive)
}

#[test]
fn heartbeats_get_info_and_pub_sub_over_classic_and_fd() {
    for mtu in [Mtu::Classic, Mtu::Fd] {
        let (a, b, driver, drive) = run(mtu, 10, |_| false);
        // One heartbeat per second each, uptime counting up.
        assert_eq!(a.heartbeats.len(), 10, "{mtu:?}");
        assert_eq!(b.heartbeats.len(), 10);
        assert!(a.heartbeats.iter().all(|(src, _)| *src == 42));
        let uptimes: Vec<u32> = a.heartbeats.iter().map(|h| h.1).collect();
        assert_eq!(uptimes, (0..10).collect::<Vec<u32>>());
        // GetInfo round trip.
        assert_eq!(a.info.len(), 1);
        assert_eq!(&a.info[0].name[..], b"org.propid.sim_drive");
        assert_eq!(drive.stats().get_info_answered, 1);
        // Every multi-frame setpoint (62 bytes: 10 frames on Classic) and every feedback arrived.
        assert_eq!(b.setpoints.len(), 2000);
        assert_eq!(a.feedback.len(), 1000);
        assert_eq!(a.feedback[999].value.kinematics.base.velocity, 9990.0);
        assert_eq!(driver.stats().tx.expired, 0);
    }
}

#[test]
fn a_lossy_link_loses_transfers_but_never_delivers_garbage() {
    // Drop every 13th frame: multi-frame setpoints that lose a frame must not arrive at all.
    let (a, b, _, drive) = run(Mtu::Classic, 5, |k| k % 13 == 0);
    assert!(
        b.setpoints.len() < 1000 && b.setpoints.len() > 100,
        "{}",
        b.setpoints.len()
    );
    for sp in &b.setpoints {
        // Every element of a delivered setpoint is the same value: no mixing of transfers.
        assert!(sp.value.iter().all(|v| *v == sp.value[0]));
    }
    assert!(!a.feedback.is_empty());
    assert!(drive.stats().rx.rejected_total() > 0);
}
