//! `propid replay` throughput on a large candump log: 250,000 DoF3rdTs transfers (1,000,000
//! Classic CAN frames) written as `candump -L` lines, replayed through the library call the CLI
//! uses, timed whole (parsing, reassembly, decoding, TSV writing). `-- --test`: 25,000 frames.

use std::io::Write;
use std::time::Instant as Clock;

use propid_core::can::{FrameSplitter, Mtu, Priority, TransferHeader, TransferKind};
use propid_core::dsdl::{DataType, DoF3rdTs};
use propid_core::time::Instant;

fn main() {
    let smoke = std::env::args().any(|a| a == "--test");
    let transfers: u64 = if smoke { 6_250 } else { 250_000 };
    let dir = std::env::temp_dir().join(format!("propid-replay-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("bus.log");
    {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&log).unwrap());
        let mut buf = [0u8; 23];
        for k in 0..transfers {
            let mut fb = DoF3rdTs::default();
            fb.timestamp.microsecond = k * 2000;
            fb.value.kinematics.base.velocity = k as f32;
            let n = fb.serialize(&mut buf);
            let h = TransferHeader {
                priority: Priority::HIGH,
                kind: TransferKind::Message { subject_id: 110 },
                source: Some(42),
                transfer_id: (k % 32) as u8,
            };
            for f in FrameSplitter::new(&h, &buf[..n], Mtu::Classic, Instant::ZERO).unwrap() {
                let us = 1_700_000_000_000_000 + k * 2000;
                write!(
                    w,
                    "({}.{:06}) can0 {:08X}#",
                    us / 1_000_000,
                    us % 1_000_000,
                    f.id()
                )
                .unwrap();
                for b in f.data() {
                    write!(w, "{b:02X}").unwrap();
                }
                writeln!(w).unwrap();
            }
        }
    }
    let frames = transfers * 4;
    let bytes = std::fs::metadata(&log).unwrap().len();
    let t0 = Clock::now();
    let input = std::io::BufReader::new(std::fs::File::open(&log).unwrap());
    let rows = propid_io::candump::replay(input, "bus.log", 110, std::io::sink()).unwrap();
    let secs = t0.elapsed().as_secs_f64();
    assert_eq!(rows, transfers);
    println!(
        "replay: {frames} frames ({:.1} MB of candump log) → {rows} TSV rows in {secs:.3} s: {:.2} M frames/s",
        bytes as f64 / 1e6,
        frames as f64 / secs / 1e6
    );
    let _ = std::fs::remove_dir_all(&dir);
}
