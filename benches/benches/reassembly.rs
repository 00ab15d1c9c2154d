//! Cyphal/CAN reassembly of a realistic mixed stream, propid against canadensis, same frames,
//! same criterion group (so the ratio comes from one run): one second of a drive's bus —
//! DoF3rdTs feedback from one node at 1 kHz (4 Classic frames each), Heartbeats from 20 nodes,
//! and the 62-byte Vector31 setpoint at 200 Hz (10 frames each).

use std::collections::VecDeque;
use std::time::Duration;

use canadensis_can::driver::ReceiveDriver;
use canadensis_core::subscription::Subscription as CdSubscription;
use canadensis_core::time::{Clock, MicrosecondDuration32, Microseconds32};
use canadensis_core::transport::Receiver as _;
use canadensis_core::{nb, SubjectId as CdSubjectId};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use propid_core::can::{
    Frame, FrameSplitter, Mtu, NodeId, Port, Priority, Reassembler, SubjectId, Subscription,
    TransferHeader, TransferKind,
};
use propid_core::dsdl::{DataType, DoF3rdTs, Heartbeat, Vector31};
use propid_core::time::Instant;

fn stream() -> Vec<Frame> {
    let mut frames = Vec::new();
    let mut push = |subject: u16, source: u8, tid: u8, payload: &[u8], us: u64| {
        let h = TransferHeader {
            priority: Priority::HIGH,
            kind: TransferKind::Message {
                subject_id: SubjectId::from_const(subject),
            },
            source: Some(NodeId::from_const(source)),
            transfer_id: tid % 32,
        };
        frames.extend(
            FrameSplitter::new(&h, payload, Mtu::Classic, Instant::from_micros(us)).unwrap(),
        );
    };
    let mut buf = [0u8; 64];
    for ms in 0..1000u64 {
        let mut fb = DoF3rdTs::default();
        fb.value.kinematics.base.velocity = ms as f32;
        let n = fb.serialize(&mut buf);
        push(110, 42, ms as u8, &buf[..n], ms * 1000);
        if ms % 5 == 0 {
            let n = Vector31::splat(0.5).serialize(&mut buf);
            push(24, 10, (ms / 5) as u8, &buf[..n], ms * 1000 + 100);
        }
        if ms % 50 == 0 {
            let node = (ms / 50) as u8 + 60;
            let n = Heartbeat {
                uptime: 7,
                ..Default::default()
            }
            .serialize(&mut buf);
            push(7509, node, 0, &buf[..n], ms * 1000 + 200);
        }
    }
    frames
}

fn propid_count(frames: &[Frame]) -> usize {
    let mut rx: Reassembler<3, 32, 64> = Reassembler::new(Some(NodeId::from_const(1)));
    for (port, extent) in [(110, 23), (24, 62), (7509, 12)] {
        rx.subscribe(Subscription {
            port: Port::Subject(SubjectId::from_const(port)),
            extent,
            transfer_id_timeout: Duration::from_secs(2),
        })
        .unwrap();
    }
    frames
        .iter()
        .filter(|f| matches!(rx.accept(f), Ok(Some(_))))
        .count()
}

struct FrameClock(u32);
impl Clock for FrameClock {
    fn now(&mut self) -> Microseconds32 {
        Microseconds32::from_ticks(self.0)
    }
}

struct QueueDriver(VecDeque<canadensis_can::Frame>);
impl ReceiveDriver<FrameClock> for QueueDriver {
    type Error = ();
    fn receive(&mut self, _clock: &mut FrameClock) -> nb::Result<canadensis_can::Frame, ()> {
        self.0.pop_front().ok_or(nb::Error::WouldBlock)
    }
    fn apply_filters<S: IntoIterator<Item = CdSubscription>>(
        &mut self,
        _: Option<canadensis_can::CanNodeId>,
        _: S,
    ) {
    }
    fn apply_accept_all(&mut self) {}
}

fn canadensis_frames(frames: &[Frame]) -> Vec<canadensis_can::Frame> {
    frames
        .iter()
        .map(|f| {
            canadensis_can::Frame::new(
                Microseconds32::from_ticks(f.timestamp.as_micros() as u32),
                canadensis_can::CanId::try_from(f.id()).unwrap(),
                f.data(),
            )
        })
        .collect()
}

fn canadensis_count(frames: &[canadensis_can::Frame]) -> usize {
    let mut driver = QueueDriver(frames.iter().cloned().collect());
    let mut clock = FrameClock(0);
    let mut rx = canadensis_can::CanReceiver::<FrameClock, QueueDriver>::new(
        canadensis_can::CanNodeId::try_from(1u8).unwrap(),
    );
    let timeout = MicrosecondDuration32::from_ticks(2_000_000);
    for (port, extent) in [(110u16, 23usize), (24, 62), (7509, 12)] {
        rx.subscribe_message(
            CdSubjectId::try_from(port).unwrap(),
            extent,
            timeout,
            &mut driver,
        )
        .unwrap();
    }
    let mut n = 0;
    while let Ok(Some(_)) = rx.receive(&mut clock, &mut driver) {
        n += 1;
    }
    n
}

fn reassembly(c: &mut Criterion) {
    let frames = stream();
    let cd = canadensis_frames(&frames);
    // Both deliver every transfer of the stream.
    let (a, b) = (propid_count(&frames), canadensis_count(&cd));
    assert_eq!(a, 1000 + 200 + 20);
    assert_eq!(a, b, "propid {a}, canadensis {b}");
    println!(
        "static RAM per reassembly session: {} bytes at extent 64, {} bytes at extent 512; this stream: {} frames, {a} transfers",
        Reassembler::<1, 1, 64>::session_size(),
        Reassembler::<1, 1, 512>::session_size(),
        frames.len()
    );
    let mut g = c.benchmark_group("reassembly/mixed stream (1 s of a drive's bus)");
    g.throughput(Throughput::Elements(frames.len() as u64));
    g.bench_function("propid Reassembler", |bch| {
        bch.iter(|| propid_count(std::hint::black_box(&frames)))
    });
    g.bench_function("canadensis CanReceiver", |bch| {
        bch.iter(|| canadensis_count(std::hint::black_box(&cd)))
    });
    g.finish();
}

criterion_group!(benches, reassembly);
criterion_main!(benches);
