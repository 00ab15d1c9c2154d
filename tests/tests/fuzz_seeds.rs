//! The fuzz targets' seed corpora (fuzz/corpus/<target>/seed-*), generated here so that they are
//! valid by construction: multi-frame Cyphal transfers framed by the core's `FrameSplitter`,
//! candump logs of them, TSV files and stand CSVs. The test fails when a committed seed differs
//! from what this code generates; `PROPID_WRITE_FUZZ_SEEDS=1 cargo test -p propid-tests --test
//! fuzz_seeds` rewrites them.
//!
//! It also proves what the reassembler seeds are for: each one, decoded exactly as the fuzz
//! harness decodes its input, delivers at least one multi-frame transfer (the fuzzer alone
//! found none in 9.7 M executions: it cannot guess a transfer CRC).

use std::path::{Path, PathBuf};
use std::time::Duration;

use propid_core::can::{
    CanId, Frame, FrameSplitter, Mtu, NodeId, Port, Priority, Reassembler, ServiceId, SubjectId,
    Subscription, TransferHeader, TransferKind,
};
use propid_core::time::Instant;

fn corpus(target: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/corpus")
        .join(target)
}

/// Compares (or, with PROPID_WRITE_FUZZ_SEEDS=1, writes) one target's seeds.
fn check(target: &str, seeds: &[(String, Vec<u8>)]) {
    let dir = corpus(target);
    let write = std::env::var_os("PROPID_WRITE_FUZZ_SEEDS").is_some();
    if write {
        std::fs::create_dir_all(&dir).unwrap();
    }
    for (name, bytes) in seeds {
        let path = dir.join(name);
        if write {
            std::fs::write(&path, bytes).unwrap();
        } else {
            let committed = std::fs::read(&path)
                .unwrap_or_else(|e| panic!("{}: {e} (regenerate the seeds)", path.display()));
            assert!(
                &committed == bytes,
                "{} is stale (regenerate the seeds)",
                path.display()
            );
        }
    }
}

/// Frames of one transfer.
fn frames(
    kind: TransferKind,
    source: u8,
    tid: u8,
    payload: &[u8],
    mtu: Mtu,
    t_us: u64,
) -> Vec<Frame> {
    let header = TransferHeader {
        priority: Priority::NOMINAL,
        kind,
        source: Some(NodeId::new(source).unwrap()),
        transfer_id: tid,
    };
    FrameSplitter::new(&header, payload, mtu, Instant::from_micros(t_us))
        .unwrap()
        .collect()
}

fn payload(n: usize, seed: u8) -> Vec<u8> {
    (0..n)
        .map(|k| (k as u8).wrapping_mul(37).wrapping_add(seed))
        .collect()
}

/// The reassembler harness's record: 4 bytes ID (LE), 1 byte length, 2 bytes time step (µs),
/// the data.
fn record(out: &mut Vec<u8>, frame: &Frame, step_us: u16) {
    out.extend_from_slice(&frame.id().to_le_bytes());
    out.push(frame.data().len() as u8);
    out.extend_from_slice(&step_us.to_le_bytes());
    out.extend_from_slice(frame.data());
}

const SUBJECT: TransferKind = TransferKind::Message {
    subject_id: SubjectId::from_const(100),
};
const OTHER: TransferKind = TransferKind::Message {
    subject_id: SubjectId::from_const(7509),
};
const REQUEST: TransferKind = TransferKind::Request {
    service_id: ServiceId::from_const(430),
    destination: NodeId::from_const(42),
};

/// Seed transfers: (name, list of transfers as frame lists), interleaved frame by frame.
fn transfer_sets() -> Vec<(&'static str, Vec<Vec<Frame>>)> {
    vec![
        (
            "dof3rdts_classic",
            vec![frames(SUBJECT, 10, 0, &payload(23, 1), Mtu::Classic, 0)],
        ),
        (
            "dof3rdts_fd_long",
            vec![frames(SUBJECT, 10, 1, &payload(80, 2), Mtu::Fd, 0)],
        ),
        (
            "truncated_to_extent_12",
            vec![frames(OTHER, 11, 2, &payload(40, 3), Mtu::Classic, 0)],
        ),
        (
            "request_extent_0",
            vec![frames(REQUEST, 12, 3, &payload(20, 4), Mtu::Classic, 0)],
        ),
        (
            "two_sources_interleaved",
            vec![
                frames(SUBJECT, 10, 4, &payload(30, 5), Mtu::Classic, 0),
                frames(SUBJECT, 11, 4, &payload(30, 6), Mtu::Classic, 0),
            ],
        ),
        (
            "three_ports_interleaved",
            vec![
                frames(SUBJECT, 10, 5, &payload(23, 7), Mtu::Classic, 0),
                frames(OTHER, 13, 6, &payload(64, 8), Mtu::Fd, 0),
                frames(REQUEST, 14, 7, &payload(9, 9), Mtu::Classic, 0),
            ],
        ),
        (
            "back_to_back",
            (0..4u8)
                .map(|k| frames(SUBJECT, 10, k, &payload(23, k), Mtu::Classic, 0))
                .collect(),
        ),
    ]
}

/// Frame-by-frame interleaving of several transfers (back_to_back runs them one after another).
fn interleave(name: &str, set: &[Vec<Frame>]) -> Vec<Frame> {
    if name == "back_to_back" {
        return set.concat();
    }
    let longest = set.iter().map(Vec::len).max().unwrap_or(0);
    (0..longest)
        .flat_map(|k| set.iter().filter_map(move |t| t.get(k).cloned()))
        .collect()
}

fn reassembler_seeds() -> Vec<(String, Vec<u8>)> {
    transfer_sets()
        .iter()
        .map(|(name, set)| {
            let mut bytes = Vec::new();
            for f in interleave(name, set) {
                record(&mut bytes, &f, 100);
            }
            (format!("seed-{name}.bin"), bytes)
        })
        .collect()
}

/// The reassembler fuzz harness, without the fuzzer: (multi-frame transfers delivered).
fn harness(bytes: &[u8]) -> usize {
    const PORTS: [(Port, usize); 3] = [
        (Port::Subject(SubjectId::from_const(100)), 23),
        (Port::Subject(SubjectId::from_const(7509)), 12),
        (Port::Request(ServiceId::from_const(430)), 0),
    ];
    let mut rx: Reassembler<3, 4, 64> = Reassembler::new(Some(NodeId::from_const(42)));
    for (port, extent) in PORTS {
        rx.subscribe(Subscription {
            port,
            extent,
            transfer_id_timeout: Duration::from_millis(50),
        })
        .unwrap();
    }
    let (mut rest, mut now, mut multi) = (bytes, 0u64, 0);
    while rest.len() >= 7 {
        let id = u32::from_le_bytes([rest[0], rest[1], rest[2], rest[3]]) & 0x1FFF_FFFF;
        let len = usize::from(rest[4]) % 65;
        now += u64::from(u16::from_le_bytes([rest[5], rest[6]]));
        rest = &rest[7..];
        let len = len.min(rest.len());
        let (data, tail) = rest.split_at(len);
        rest = tail;
        let frame = Frame::new(Instant::from_micros(now), id, data).unwrap();
        let start = data.last().is_some_and(|t| t & 0x80 != 0);
        if let Ok(Some(t)) = rx.accept(&frame) {
            let extent = PORTS
                .iter()
                .find(|(p, _)| *p == t.header.kind.port())
                .unwrap()
                .1;
            assert!(t.payload.len() <= extent);
            assert_eq!(CanId::parse(id).unwrap().kind.port(), t.header.kind.port());
            // A multi-frame transfer ends with a frame whose start-of-transfer bit is clear.
            if !start {
                multi += 1;
            }
        }
    }
    multi
}

fn candump_line(f: &Frame, t_us: u64) -> String {
    let data: String = f.data().iter().map(|b| format!("{b:02X}")).collect();
    let sep = if f.data().len() > 8 { "##0" } else { "#" };
    format!(
        "({}.{:06}) can0 {:08X}{sep}{data}\n",
        t_us / 1_000_000,
        t_us % 1_000_000,
        f.id()
    )
}

fn candump_seeds() -> Vec<(String, Vec<u8>)> {
    let mut seeds = Vec::new();
    for (name, set) in transfer_sets() {
        let mut log = String::new();
        for (k, f) in interleave(name, &set).iter().enumerate() {
            log += &candump_line(f, 1_700_000_000_000_000 + 100 * k as u64);
        }
        seeds.push((format!("seed-{name}.log"), log.into_bytes()));
    }
    let mut mixed = String::from("# a comment\n\n");
    for (k, f) in frames(SUBJECT, 10, 0, &payload(23, 1), Mtu::Classic, 0)
        .iter()
        .enumerate()
    {
        mixed += &candump_line(f, 1_500_000 + k as u64);
        mixed += "(1.500100) can0 20000080#0000000000000000\n(1.500200) can0 1060640A#R\n(1.5003) can0 123#1122\n";
    }
    mixed += "(1.6) can0 1060642A#€0\n(99999999999999.5) can0 1060640A#E0\n(1.7) can0 1060640A#0\n";
    seeds.push(("seed-mixed_bad_lines.log".into(), mixed.into_bytes()));
    seeds
}

fn tsv_seeds() -> Vec<(String, Vec<u8>)> {
    vec![
        (
            "seed-drive.tsv".into(),
            b"ts_local\tt\tforce\tvelocity\tacceleration\tposition\n100.5\t0\t0.01\t10\t-1.5\t0.25\n100.51\t0.01\tnan\t10.1\t2e-3\tnan\n".to_vec(),
        ),
        (
            "seed-minimal.tsv".into(),
            b"t\tforce\tvelocity\tacceleration\n0\t1\t2\t3\n0.1\t1\t2\t3\n".to_vec(),
        ),
        (
            "seed-extra_columns_crlf.tsv".into(),
            b"t\tforce\tvelocity\tacceleration\tcommand\r\n0\t1\t2\t3\t1100\r\n1e-3\t-inf\t2\t3\t\r\n".to_vec(),
        ),
    ]
}

fn importer_seeds() -> Vec<(String, Vec<u8>)> {
    let rc = "\u{feff}Time (s),ESC signal (µs),Torque (N·m),Motor Electrical Speed (RPM),Motor Optical Speed (RPM),App message,\n\
              0,1000,0.001,0,0,,\n0,1000,,0,0,,\n0.01,1100,,0,0,,\n0.02,1100,-0.05,6000,0,,\n0.03,1100,,6100,0,,\n0.04,1100,-0.06,6100,0,,\n0.05,1500,,9000,0,,\n";
    let tyto = "Time (ms),ESC Signal (us),Torque (N-m),Motor Optical Speed (RPM)\n0,1000,0.002,0\n10,1000,0.002,0\n20,1200,0.05,3000\n30,1200,0.05,3000\n";
    let aq = "Timestamp,Amps,Batt. Volts,Motor Volts,RPM,Duty\n2019-11-05 17:14:08:947,0.004,15.78,0,0,0\n2019-11-05 17:14:08:957,1.2,15.7,3,3000,20\n2019-11-05 17:14:08:967,1.3,15.7,3,3100,20\n2019-11-05 23:59:59:999,1.3,15.7,3,3100,20\n";
    let mut seeds = Vec::new();
    for (name, which, text) in [
        ("rcbench.csv", 0u8, rc),
        ("rcbench_subtract.csv", 1, rc),
        ("tyto_ms.csv", 0, tyto),
        ("autoquad.csv", 2, aq),
    ] {
        let mut bytes = vec![which];
        bytes.extend_from_slice(text.as_bytes());
        seeds.push((format!("seed-{name}"), bytes));
    }
    seeds
}

#[test]
fn seed_corpora_are_current() {
    let reassembler = reassembler_seeds();
    for (name, bytes) in &reassembler {
        let delivered = harness(bytes);
        assert!(delivered >= 1, "{name}: no multi-frame transfer delivered");
    }
    check("reassembler", &reassembler);
    check("candump", &candump_seeds());
    check("tsv_reader", &tsv_seeds());
    check("importers", &importer_seeds());
}

#[test]
fn candump_seeds_replay_their_transfers() {
    for (name, bytes) in candump_seeds() {
        let options = propid_io::candump::ReplayOptions {
            feedback_id: 100,
            source_node: None,
        };
        let s = propid_io::candump::replay(&bytes[..], &name, &options, std::io::sink()).unwrap();
        let expected = match name.as_str() {
            "seed-truncated_to_extent_12.log" | "seed-request_extent_0.log" => 0,
            "seed-back_to_back.log" => 4,
            _ => 1,
        };
        assert_eq!(s.rows, expected, "{name}: {s:?}");
    }
}
