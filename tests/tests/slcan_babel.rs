//! The SLCAN transport against a peer that behaves like a Zubax Babel, over a real
//! pseudo-terminal pair: set-up commands answered, transmissions acknowledged with `z`, received
//! frames carrying millisecond timestamps that wrap at 60 s, status flags, garbage on the line,
//! and the adapter vanishing.

#![cfg(unix)] // pseudo-terminals (serialport::TTYPort) exist on Unix only

use std::io::{Read, Write};
use std::time::Duration;

use propid_core::can::Frame;
use propid_core::time::Instant;
use propid_slcan::SlcanTransport;
use propid_transport::{CanTransport, TransportError};
use serialport::{SerialPort, TTYPort};

/// Plays the adapter: answers commands, acks frames, then sends frames across a timestamp wrap.
fn babel(mut port: TTYPort) -> Vec<String> {
    port.set_timeout(Duration::from_millis(500)).unwrap();
    let mut seen = Vec::new();
    let mut line = Vec::new();
    let mut buf = [0u8; 256];
    // Commands C, S8, Z1, O, then two frames.
    while seen.len() < 6 {
        let n = port.read(&mut buf).expect("host writes");
        for &b in &buf[..n] {
            if b == b'\r' {
                let text = String::from_utf8(std::mem::take(&mut line)).unwrap();
                let reply: &[u8] = if text.starts_with('T') { b"z\r" } else { b"\r" };
                port.write_all(reply).unwrap();
                seen.push(text);
            } else {
                line.push(b);
            }
        }
    }
    // Frames from the bus, with timestamps that wrap (59.990 s → 0.010 s), a status report and
    // garbage in between.
    port.write_all(
        b"T1060642A203E0EA56\rF08\r\x01\x02garbage\rT1060642A203E1000A\rT1060642A203E20014\r",
    )
    .unwrap();
    std::thread::sleep(Duration::from_millis(300));
    seen
}

#[test]
fn talks_to_a_babel_like_peer() {
    let (host_end, adapter_end) = TTYPort::pair().expect("pty pair");
    let peer = std::thread::spawn(move || babel(adapter_end));
    let mut t = SlcanTransport::from_port(Box::new(host_end), "pty");
    t.configure(1_000_000).unwrap();
    let f = Frame::new(Instant::ZERO, 0x1060_642A, &[0x03, 0xE0]).unwrap();
    t.send(&f).unwrap();
    t.send(&f).unwrap();
    let mut got = Vec::new();
    while got.len() < 3 {
        match t.receive(Duration::from_secs(2)).unwrap() {
            Some(f) => got.push(f),
            None => panic!("timed out after {} frames", got.len()),
        }
    }
    let seen = peer.join().unwrap();
    assert_eq!(&seen[..4], ["C", "S8", "Z1", "O"]);
    assert_eq!(seen[4], "T1060642A203E0");
    assert_eq!(got[0].data(), &[0x03, 0xE0]);
    assert_eq!(got[2].data(), &[0x03, 0xE2]);
    // Adapter time 59.990 s → 60.010 s → 60.020 s: monotonic across the wrap, 20 ms then 10 ms.
    let dt1 = got[1].timestamp.as_micros() - got[0].timestamp.as_micros();
    let dt2 = got[2].timestamp.as_micros() - got[1].timestamp.as_micros();
    assert_eq!((dt1, dt2), (20_000, 10_000));
    assert_eq!(t.status_events, 1);
    assert_eq!(t.garbage_count(), 1);
    // CAN FD is refused with a clear error.
    let fd = Frame::new(Instant::ZERO, 1, &[0; 12]).unwrap();
    assert!(t
        .send(&fd)
        .unwrap_err()
        .to_string()
        .contains("Classic CAN only"));
    // The adapter is gone: a clear error, not a hang or a panic.
    let err = loop {
        match t.receive(Duration::from_millis(200)) {
            Ok(_) => continue,
            Err(e) => break e,
        }
    };
    assert!(matches!(err, TransportError::Closed(_)), "{err}");
}

#[test]
fn a_missing_port_is_a_clear_error() {
    let err = SlcanTransport::open("/dev/does-not-exist", 115_200, 1_000_000)
        .err()
        .unwrap();
    assert!(err.to_string().contains("/dev/does-not-exist"), "{err}");
    let (a, _b) = TTYPort::pair().unwrap();
    let mut t = SlcanTransport::from_port(Box::new(a), "pty");
    assert!(t
        .configure(333_333)
        .unwrap_err()
        .to_string()
        .contains("no SLCAN bit-rate code"));
}
