//! Fuzz the SLCAN decoder: any byte stream, cut into any pieces, must decode without panicking;
//! every decoded frame has a valid ID and length; the events do not depend on how the stream was
//! cut; garbage is counted once per garbage event; and every extended data frame survives
//! encode → decode unchanged.
#![no_main]

use libfuzzer_sys::fuzz_target;
use propid_slcan::{encode_frame, Decoder, Event};

fn decode_in_pieces(bytes: &[u8], cut: usize) -> (Vec<Event>, u64) {
    let mut d = Decoder::new();
    let mut out = Vec::new();
    let cut = cut.min(bytes.len());
    d.push(&bytes[..cut], &mut out);
    d.push(&bytes[cut..], &mut out);
    (out, d.garbage_count())
}

fuzz_target!(|input: &[u8]| {
    let Some((&cut, bytes)) = input.split_first() else {
        return;
    };
    let (events, garbage) = decode_in_pieces(bytes, usize::from(cut));
    // Streaming: one push or two give the same events.
    let (whole, whole_garbage) = decode_in_pieces(bytes, bytes.len());
    assert_eq!(events, whole, "events depend on where the stream was cut");
    assert_eq!(garbage, whole_garbage);
    let garbage_events = events.iter().filter(|e| matches!(e, Event::Garbage(_))).count();
    assert_eq!(garbage, garbage_events as u64);
    for event in &events {
        let Event::Frame { id, extended, data, remote, adapter_ms } = event else {
            continue;
        };
        assert!(*id <= if *extended { 0x1FFF_FFFF } else { 0x7FF }, "ID {id:#X}");
        assert!(data.len() <= 8, "{} data bytes", data.len());
        assert!(!*remote || data.is_empty(), "a remote frame with data");
        if let Some(ms) = adapter_ms {
            assert!(*ms <= 0xFFFF);
        }
        if *extended && !*remote {
            let line = encode_frame(*id, data).expect("a decoded frame must encode");
            let mut d = Decoder::new();
            let mut again = Vec::new();
            d.push(line.as_bytes(), &mut again);
            assert_eq!(
                again,
                [Event::Frame {
                    id: *id,
                    extended: true,
                    data: data.clone(),
                    remote: false,
                    adapter_ms: None
                }]
            );
        }
    }
});
