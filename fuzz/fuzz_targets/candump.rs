//! Fuzz the candump parser and `replay`: any bytes, as a log, must never panic; every row
//! written is counted; every line is accounted for (used, skipped by kind, or malformed).
#![no_main]

use libfuzzer_sys::fuzz_target;
use propid_io::candump::{parse_candump_line, replay, ReplayOptions};

fuzz_target!(|bytes: &[u8]| {
    // Each line alone through the parser…
    for line in String::from_utf8_lossy(bytes).lines() {
        let _ = parse_candump_line(line);
    }
    // …and the whole log through replay, with and without a source node.
    for source_node in [None, Some(10)] {
        let options = ReplayOptions {
            feedback_id: 100,
            source_node,
        };
        let mut out = Vec::new();
        let s =
            replay(bytes, "fuzz.log", &options, &mut out).expect("only I/O errors stop a replay");
        let newlines = bytes.iter().filter(|&&b| b == b'\n').count();
        let lines = (newlines + usize::from(bytes.last().is_some_and(|&b| b != b'\n'))) as u64;
        assert_eq!(s.lines, lines);
        assert!(s.malformed + s.error_frames + s.remote_frames + s.base_frames <= s.lines);
        let written = out.iter().filter(|&&b| b == b'\n').count() as u64;
        assert_eq!(written, s.rows + 1, "header + one line per row");
        assert!(s.malformed_first.len() as u64 <= s.malformed);
    }
});
