//! Every frame sequence of PyCyphal's golden CAN vectors (`tests/data/can_frames.json`), both
//! ways: transmit must produce exactly the recorded frames, and the recorded frames must
//! reassemble into what PyCyphal's receiver delivered.

use core::time::Duration;

use propid_core::can::{
    FrameSplitter, Mtu, NodeId, Priority, Reassembler, ServiceId, SubjectId, Subscription,
    TransferHeader, TransferKind,
};
use propid_core::time::Instant;
use serde_json::Value;

fn header_of(case: &Value) -> TransferHeader {
    let kind = if let Some(subject) = case.get("subject_id").and_then(Value::as_u64) {
        TransferKind::Message {
            subject_id: SubjectId::try_from(subject).unwrap(),
        }
    } else {
        let service_id = ServiceId::try_from(case["service_id"].as_u64().unwrap()).unwrap();
        let destination = NodeId::try_from(case["destination_node_id"].as_u64().unwrap()).unwrap();
        if case["request"].as_bool().unwrap() {
            TransferKind::Request {
                service_id,
                destination,
            }
        } else {
            TransferKind::Response {
                service_id,
                destination,
            }
        }
    };
    TransferHeader {
        priority: Priority::new(case["priority"].as_u64().unwrap() as u8).unwrap(),
        kind,
        source: case["source_node_id"]
            .as_u64()
            .map(|n| NodeId::try_from(n).unwrap()),
        transfer_id: (case["transfer_id"].as_u64().unwrap() % 32) as u8,
    }
}

#[test]
fn every_frame_vector_passes_both_ways() {
    let doc: Value = serde_json::from_str(include_str!("data/can_frames.json")).unwrap();
    let cases = doc["cases"].as_array().unwrap();
    let (mut tx_ok, mut rx_ok, mut frames_checked) = (0usize, 0usize, 0usize);
    let mut failures = Vec::new();
    for case in cases {
        let name = case["description"].as_str().unwrap();
        let mtu = Mtu::from_bytes(case["mtu"].as_u64().unwrap() as usize).unwrap();
        let header = header_of(case);
        let payload = hex::decode(case["payload_hex"].as_str().unwrap()).unwrap();
        let want: Vec<(u32, Vec<u8>)> = case["frames"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| {
                (
                    u32::from_str_radix(f["can_id_hex"].as_str().unwrap(), 16).unwrap(),
                    hex::decode(f["data_hex"].as_str().unwrap()).unwrap(),
                )
            })
            .collect();
        frames_checked += want.len();

        // Transmit.
        let got: Vec<(u32, Vec<u8>)> = FrameSplitter::new(&header, &payload, mtu, Instant::ZERO)
            .unwrap()
            .map(|f| (f.id(), f.data().to_vec()))
            .collect();
        if got == want {
            tx_ok += 1;
        } else {
            failures.push(format!(
                "{name}: transmit gave {got:02x?}, want {want:02x?}"
            ));
        }

        // Receive.
        let local = match header.kind {
            TransferKind::Message { .. } => None,
            TransferKind::Request { destination, .. }
            | TransferKind::Response { destination, .. } => Some(destination),
        };
        let mut rx: Reassembler<1, 1, 512> = Reassembler::new(local);
        rx.subscribe(Subscription {
            port: header.kind.port(),
            extent: 512,
            transfer_id_timeout: Duration::from_secs(2),
        })
        .unwrap();
        let expected = hex::decode(case["pycyphal_rx_payload_hex"].as_str().unwrap()).unwrap();
        let mut delivered = Vec::new();
        for (i, (id, data)) in want.iter().enumerate() {
            let frame =
                propid_core::can::Frame::new(Instant::from_micros(i as u64), *id, data).unwrap();
            match rx.accept(&frame) {
                Ok(Some(t)) => {
                    let mut h = t.header;
                    if h.source.is_none() {
                        // Anonymous: the pseudo node-ID is not part of the header.
                        h.source = None;
                    }
                    assert_eq!(h, header, "{name}: header");
                    assert_eq!(
                        t.timestamp,
                        Instant::from_micros(0),
                        "{name}: first-frame time"
                    );
                    delivered.push(t.payload.to_vec());
                }
                Ok(None) => {}
                Err(e) => failures.push(format!("{name}: frame {i} rejected: {e:?}")),
            }
        }
        if delivered == vec![expected] {
            rx_ok += 1;
        } else {
            failures.push(format!("{name}: receive delivered {delivered:02x?}"));
        }
    }
    let report = format!(
        "can vectors: transmit {tx_ok} of {n}, receive {rx_ok} of {n} cases passed ({frames_checked} frames)\n",
        n = cases.len()
    );
    std::io::Write::write_all(&mut std::io::stderr(), report.as_bytes()).unwrap();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert_eq!((tx_ok, rx_ok), (cases.len(), cases.len()));
    assert_eq!(cases.len(), 66, "the vector file has 66 cases");
}
