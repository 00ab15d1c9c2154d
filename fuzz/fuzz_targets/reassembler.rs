//! Fuzz the reassembler: arbitrary frame sequences must never panic, and every delivered
//! transfer must respect the subscription's extent and carry a header that matches its frames.
#![no_main]

use core::time::Duration;

use libfuzzer_sys::fuzz_target;
use propid_core::can::{CanId, Frame, NodeId, Port, Reassembler, ServiceId, SubjectId, Subscription};
use propid_core::time::Instant;

fuzz_target!(|bytes: &[u8]| {
    let mut rx: Reassembler<3, 4, 64> = Reassembler::new(Some(NodeId::from_const(42)));
    for (port, extent) in [
        (Port::Subject(SubjectId::from_const(100)), 23),
        (Port::Subject(SubjectId::from_const(7509)), 12),
        (Port::Request(ServiceId::from_const(430)), 0),
    ] {
        rx.subscribe(Subscription { port, extent, transfer_id_timeout: Duration::from_millis(50) })
            .unwrap();
    }
    // Each record: 4 bytes ID, 1 byte length, 2 bytes time step (µs), then the data.
    let mut rest = bytes;
    let mut now = 0u64;
    while rest.len() >= 7 {
        let id = u32::from_le_bytes([rest[0], rest[1], rest[2], rest[3]]) & 0x1FFF_FFFF;
        let len = usize::from(rest[4]) % 65;
        now += u64::from(u16::from_le_bytes([rest[5], rest[6]]));
        rest = &rest[7..];
        let len = len.min(rest.len());
        let (data, tail) = rest.split_at(len);
        rest = tail;
        let frame = Frame::new(Instant::from_micros(now), id, data).unwrap();
        if let Ok(Some(t)) = rx.accept(&frame) {
            assert!(t.payload.len() <= 23);
            let parsed = CanId::parse(id).expect("delivered from a valid Cyphal ID");
            assert_eq!(t.header.kind.port(), parsed.kind.port());
        }
    }
});
