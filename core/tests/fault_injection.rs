//! Fault injection: a million random transfers through a channel that drops, duplicates,
//! reorders across sources and corrupts frames. No corrupted transfer may be accepted.
//!
//! What "corrupts" means here: a single-frame Cyphal transfer has no integrity check of its own,
//! and neither has the tail byte (one flipped end-of-transfer bit turns the first frame of a
//! multi-frame transfer into a complete single-frame transfer); the CAN controller's frame CRC
//! is what protects those, so no Cyphal receiver can detect their corruption. The channel
//! therefore corrupts what the transfer CRC is responsible for: payload bytes of multi-frame
//! transfers (bit flips, and bytes lost from a frame with its tail byte kept) and the CAN ID
//! bits of their frames (misrouting frames into other sessions). Drops, duplicates and
//! reordering across sources apply to every frame.
//!
//! A CRC-16 lets a corrupted transfer through with probability about 2⁻¹⁶, so the corruption
//! and loss rates are chosen to keep the expected number of such collisions well below one (the
//! test prints it). Losing two consecutive frames keeps the toggle sequence intact and leaves
//! the CRC as the only check: with 1 % of frames dropped, about 60,000 CRC failures let three
//! transfers through (measured while choosing these rates), which is the CRC's limit, not the
//! reassembler's.

use core::time::Duration;
use std::collections::HashMap;

use propid_core::can::{
    Frame, FrameSplitter, Mtu, NodeId, Port, Priority, Reassembler, RxError, SubjectId,
    Subscription, TransferHeader, TransferKind,
};
use propid_core::time::Instant;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

const TRANSFERS: usize = 1_000_000;
const SOURCES: [u8; 5] = [3, 17, 42, 99, 125];
const SUBJECTS: [u16; 3] = [100, 1234, 7509];

struct Sent {
    payload: Vec<u8>,
    delivered: bool,
}

#[test]
fn a_million_transfers_through_a_hostile_channel() {
    let mut rng = StdRng::seed_from_u64(0x5EED_CAFE);
    let mut rx: Reassembler<3, 64, 128> = Reassembler::new(None);
    for s in SUBJECTS {
        rx.subscribe(Subscription {
            port: Port::Subject(SubjectId::from_const(s)),
            extent: 128,
            transfer_id_timeout: Duration::from_secs(2),
        })
        .unwrap();
    }
    let mut next_tid: HashMap<(u8, u16), u8> = HashMap::new();
    let (mut sent_total, mut delivered_ok, mut corrupted_accepted, mut duplicates_accepted) =
        (0usize, 0usize, 0usize, 0usize);
    let (mut frames_total, mut faults) = (0usize, [0usize; 4]);
    let mut now_us = 0u64;
    while sent_total < TRANSFERS {
        now_us += 1000;
        let mtu = if rng.random_bool(0.5) {
            Mtu::Classic
        } else {
            Mtu::Fd
        };
        // One round: up to 6 transfers from distinct (source, subject) pairs, in flight together.
        let mut round: HashMap<(u8, u16), Sent> = HashMap::new();
        let mut queues: Vec<Vec<Frame>> = Vec::new();
        for _ in 0..6 {
            let key = (
                SOURCES[rng.random_range(0..SOURCES.len())],
                SUBJECTS[rng.random_range(0..SUBJECTS.len())],
            );
            if round.contains_key(&key) {
                continue;
            }
            let tid = next_tid.entry(key).or_insert(0);
            let len = if rng.random_bool(0.5) {
                rng.random_range(0..=7)
            } else {
                rng.random_range(8..=120)
            };
            let payload: Vec<u8> = (0..len).map(|_| rng.random()).collect();
            let header = TransferHeader {
                priority: Priority::NOMINAL,
                kind: TransferKind::Message {
                    subject_id: SubjectId::from_const(key.1),
                },
                source: Some(NodeId::from_const(key.0)),
                transfer_id: *tid,
            };
            *tid = (*tid + 1) % 32;
            let ts = Instant::from_micros(now_us);
            let frames: Vec<Frame> = FrameSplitter::new(&header, &payload, mtu, ts)
                .unwrap()
                .collect();
            let multi = frames.len() > 1;
            let mut faulty = Vec::with_capacity(frames.len() + 2);
            for f in frames {
                let r: f64 = rng.random();
                if r < 0.001 {
                    faults[0] += 1; // dropped
                    continue;
                }
                if r < 0.006 {
                    faults[1] += 1; // duplicated
                    faulty.push(f.clone());
                }
                if multi && (0.006..0.0075).contains(&r) {
                    faults[2] += 1; // corrupted
                    faulty.push(corrupt(&f, &mut rng));
                    continue;
                }
                faulty.push(f);
            }
            queues.push(faulty);
            round.insert(
                key,
                Sent {
                    payload,
                    delivered: false,
                },
            );
            sent_total += 1;
        }
        // Reorder across sources: interleave the per-transfer queues at random, keeping each
        // transfer's own frame order (CAN preserves order per identifier).
        faults[3] += 1;
        while queues.iter().any(|q| !q.is_empty()) {
            let live: Vec<usize> = (0..queues.len())
                .filter(|&i| !queues[i].is_empty())
                .collect();
            let q = live[rng.random_range(0..live.len())];
            let frame = queues[q].remove(0);
            frames_total += 1;
            if let Ok(Some(t)) = rx.accept(&frame) {
                let TransferKind::Message { subject_id } = t.header.kind else {
                    unreachable!("only subjects are subscribed")
                };
                let key = (t.header.source.unwrap().get(), subject_id.get());
                match round.get_mut(&key) {
                    Some(sent) if is_sent_payload(&sent.payload, t.payload) => {
                        if sent.delivered {
                            duplicates_accepted += 1;
                        } else {
                            sent.delivered = true;
                            delivered_ok += 1;
                        }
                    }
                    _ => corrupted_accepted += 1,
                }
            }
        }
    }
    let stats = rx.stats();
    let report = format!(
        "fault injection: {sent_total} transfers sent as {frames_total} frames \
         ({} dropped, {} duplicated, {} corrupted, {} interleaved rounds)\n\
         fault injection: {delivered_ok} delivered intact ({:.2} %), {corrupted_accepted} corrupted accepted, \
         {duplicates_accepted} duplicates accepted\n\
         fault injection: expected CRC-16 collisions for the CRC failures seen: {:.3}\n\
         fault injection: rejected: bad CRC {}, bad toggle {}, missing start {}, wrong transfer-ID {}, \
         duplicate transfer {}, not Cyphal {}, not subscribed {}, out of sessions {}\n",
        faults[0],
        faults[1],
        faults[2],
        faults[3],
        100.0 * delivered_ok as f64 / sent_total as f64,
        stats.rejected(RxError::BadCrc) as f64 / 65536.0,
        stats.rejected(RxError::BadCrc),
        stats.rejected(RxError::BadToggle),
        stats.rejected(RxError::MissingStart),
        stats.rejected(RxError::WrongTransferId),
        stats.rejected(RxError::DuplicateTransfer),
        stats.rejected(RxError::NotCyphal),
        stats.rejected(RxError::NotSubscribed),
        stats.rejected(RxError::OutOfSessions),
    );
    std::io::Write::write_all(&mut std::io::stderr(), report.as_bytes()).unwrap();
    assert!(sent_total >= TRANSFERS);
    assert_eq!(corrupted_accepted, 0, "{report}");
    assert_eq!(duplicates_accepted, 0, "{report}");
    // The channel loses a few percent of transfers; the rest must arrive.
    assert!(delivered_ok as f64 > 0.9 * sent_total as f64, "{report}");
    assert!(
        stats.rejected(RxError::BadCrc) > 0,
        "corruption must have been exercised"
    );
}

/// The payload as sent, or (CAN FD) followed by the zero padding of the last frame, which a
/// receiver cannot tell from data.
fn is_sent_payload(sent: &[u8], got: &[u8]) -> bool {
    got.len() >= sent.len()
        && got.len() - sent.len() < 64
        && got[..sent.len()] == *sent
        && got[sent.len()..].iter().all(|&b| b == 0)
}

/// A bit flip in a payload byte or in the ID, or payload bytes lost (the tail byte kept).
fn corrupt(f: &Frame, rng: &mut StdRng) -> Frame {
    let (&tail, body) = f.data().split_last().unwrap();
    let mut body = body.to_vec();
    let mut id = f.id();
    match rng.random_range(0..3) {
        0 if !body.is_empty() => {
            let i = rng.random_range(0..body.len());
            body[i] ^= 1 << rng.random_range(0..8);
        }
        1 => id ^= 1 << rng.random_range(0..29),
        _ => {
            let keep = rng.random_range(0..body.len().max(1));
            body.truncate(keep);
        }
    }
    body.push(tail);
    Frame::new(f.timestamp, id, &body).unwrap()
}
