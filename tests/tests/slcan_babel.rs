//! The SLCAN transport against a peer that behaves like a Zubax Babel, over a real
//! pseudo-terminal pair: set-up commands answered, transmissions acknowledged with `z`, received
//! frames carrying millisecond timestamps that wrap at 60 s, status flags, garbage on the line,
//! and the adapter vanishing. Then the faults, each against a pty peer: a peer that stops reading
//! (congestion: sends are refused at once and counted, the wire never carries half a frame
//! followed by another, flush reports whether everything left), the adapter refusing a command
//! (BELL, named), status flags (error-warning, error-passive, bus-off), and the device
//! disappearing mid-run (the master side of the pty closes, as a USB unplug).
//!
//! No test here bounds how long a call takes on the wall clock (a loaded machine stretches any
//! such bound): that a refused send or a flush past its deadline returns promptly is measured by
//! benches/benches/slcan_congestion.rs. The tests check what calls return and what reaches the
//! wire.

#![cfg(unix)] // pseudo-terminals (serialport::TTYPort) exist on Unix only

use std::io::{Read, Write};
use std::time::Duration;

use propid_core::can::Frame;
use propid_core::time::Instant;
use propid_slcan::{Decoder, Event, SlcanTransport};
use propid_transport::{BusState, CanTransport, TransportError};
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
    let mut t = SlcanTransport::from_tty(host_end, "pty").unwrap();
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
    let h = t.health();
    assert_eq!((h.status_reports, h.overruns, h.garbage), (1, 1, 1));
    assert_eq!(h.bus_state, BusState::Active);
    assert_eq!((h.frames_sent, h.frames_received, h.refused), (2, 3, 0));
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
    assert!(err.to_string().contains("device disappeared"), "{err}");
}

#[test]
fn a_missing_port_is_a_clear_error() {
    let err = SlcanTransport::open("/dev/does-not-exist", 115_200, 1_000_000)
        .err()
        .unwrap();
    assert!(err.to_string().contains("/dev/does-not-exist"), "{err}");
    let (a, _b) = TTYPort::pair().unwrap();
    let mut t = SlcanTransport::from_tty(a, "pty").unwrap();
    assert!(t
        .configure(333_333)
        .unwrap_err()
        .to_string()
        .contains("no SLCAN bit-rate code"));
}

/// Reads every byte the peer end has until it is quiet for `quiet`.
fn drain(port: &mut TTYPort, quiet: Duration) -> Vec<u8> {
    port.set_timeout(quiet).unwrap();
    let mut all = Vec::new();
    let mut buf = [0u8; 4096];
    while let Ok(n) = port.read(&mut buf) {
        if n == 0 {
            break;
        }
        all.extend_from_slice(&buf[..n]);
    }
    all
}

#[test]
fn congestion_refuses_and_never_splits_a_frame() {
    // The host holds the slave end, as it would /dev/ttyACM0; the peer reads nothing for now.
    let (mut peer, host_end) = TTYPort::pair().expect("pty pair");
    let mut t = SlcanTransport::from_tty(host_end, "pty-congested").unwrap();
    t.set_status_interval(None);
    let frame = |k: u32| {
        let b = k.to_le_bytes();
        Frame::new(
            Instant::ZERO,
            0x1060_642A,
            &[b[0], b[1], b[2], b[3], 5, 6, 7],
        )
        .unwrap()
    };
    let mut accepted = 0u32;
    let mut refusals = 0;
    // Offer until the pty's buffer is full and a few more offers are refused: a refusal returns
    // (it does not wait for the peer; how fast: benches/benches/slcan_congestion.rs).
    while refusals < 5 {
        match t.send(&frame(accepted)) {
            Ok(()) => accepted += 1,
            Err(e) if e.is_would_block() => refusals += 1,
            Err(e) => panic!("{e}"),
        }
        assert!(accepted < 1_000_000, "the pty never filled");
    }
    let h = t.health();
    assert_eq!((h.frames_sent, h.would_block), (u64::from(accepted), 5));
    // A flush with the peer still asleep gives up at its deadline and says so, or had nothing
    // left (the last accepted line fitted whole).
    let flushed = t
        .flush(std::time::Instant::now() + Duration::from_millis(30))
        .unwrap();
    // The peer wakes up: everything accepted arrives, each line whole and in order.
    let reader = std::thread::spawn(move || {
        let bytes = drain(&mut peer, Duration::from_millis(300));
        (bytes, peer)
    });
    if !flushed {
        assert!(t
            .flush(std::time::Instant::now() + Duration::from_secs(2))
            .unwrap());
    }
    let (bytes, _peer) = reader.join().unwrap();
    let mut d = Decoder::new();
    let mut events = Vec::new();
    d.push(&bytes, &mut events);
    assert_eq!(
        d.garbage_count(),
        0,
        "a split or interleaved line reached the wire"
    );
    let got: Vec<u32> = events
        .iter()
        .map(|e| match e {
            Event::Frame { id, data, .. } => {
                assert_eq!(*id, 0x1060_642A);
                u32::from_le_bytes([data[0], data[1], data[2], data[3]])
            }
            other => panic!("unexpected {other:?}"),
        })
        .collect();
    assert_eq!(got, (0..accepted).collect::<Vec<_>>());
    assert!(bytes.ends_with(b"\r"));
    // Drained, the link takes frames again.
    t.send(&frame(accepted)).unwrap();
}

/// Plays an adapter that answers every line, with `reply` choosing the answer.
fn answering_peer(
    mut port: TTYPort,
    lines: usize,
    reply: impl Fn(&str) -> Vec<u8> + Send + 'static,
) -> std::thread::JoinHandle<Vec<String>> {
    std::thread::spawn(move || {
        port.set_timeout(Duration::from_millis(1000)).unwrap();
        let mut seen = Vec::new();
        let mut line = Vec::new();
        let mut buf = [0u8; 256];
        while seen.len() < lines {
            let Ok(n) = port.read(&mut buf) else { break };
            for &b in &buf[..n] {
                if b == b'\r' {
                    let text = String::from_utf8(std::mem::take(&mut line)).unwrap();
                    port.write_all(&reply(&text)).unwrap();
                    seen.push(text);
                } else {
                    line.push(b);
                }
            }
        }
        std::thread::sleep(Duration::from_millis(200));
        seen
    })
}

#[test]
fn a_refused_bit_rate_is_an_error_naming_the_command() {
    let (peer, host_end) = TTYPort::pair().expect("pty pair");
    let peer = answering_peer(peer, 4, |l| {
        if l == "S8" {
            b"\x07".to_vec()
        } else {
            b"\r".to_vec()
        }
    });
    let mut t = SlcanTransport::from_tty(host_end, "pty-refusing").unwrap();
    let err = t.configure(1_000_000).unwrap_err();
    assert!(
        matches!(&err, TransportError::Refused { command, .. } if command == "S8"),
        "{err}"
    );
    assert_eq!(
        err.to_string(),
        "slcan:pty-refusing: the adapter refused the command `S8`"
    );
    assert_eq!(t.health().refused, 1);
    peer.join().unwrap();
}

#[test]
fn a_refused_frame_is_counted_named_and_the_status_asked_for() {
    let (peer, host_end) = TTYPort::pair().expect("pty pair");
    // Set-up accepted; the first frame acknowledged, the second refused (the controller went
    // bus-off); `F` answered with error-passive, then bus-off.
    let refused_once = std::sync::atomic::AtomicBool::new(false);
    let polls = std::sync::atomic::AtomicU32::new(0);
    let peer = answering_peer(peer, 8, move |l| {
        use std::sync::atomic::Ordering::SeqCst;
        match l {
            "F" => match polls.fetch_add(1, SeqCst) {
                0 => b"F24\r".to_vec(),
                _ => b"F80\r".to_vec(),
            },
            l if l.starts_with('T') => {
                if refused_once.swap(true, SeqCst) {
                    b"\x07".to_vec()
                } else {
                    b"z\r".to_vec()
                }
            }
            _ => b"\r".to_vec(),
        }
    });
    let mut t = SlcanTransport::from_tty(host_end, "pty-busoff").unwrap();
    t.configure(1_000_000).unwrap();
    let f = Frame::new(Instant::ZERO, 0x1060_642A, &[0x03, 0xE0]).unwrap();
    t.send(&f).unwrap();
    t.send(&Frame::new(Instant::ZERO, 0x1060_642A, &[0x04, 0xE1]).unwrap())
        .unwrap();
    // The refusal arrives while receiving; it triggers a status poll at once.
    let until = std::time::Instant::now() + Duration::from_secs(2);
    while t.health().status_reports == 0 && std::time::Instant::now() < until {
        assert!(t.receive(Duration::from_millis(20)).unwrap().is_none());
    }
    let h = t.health();
    assert_eq!(h.refused, 1);
    assert_eq!(h.last_refused.as_deref(), Some("T1060642A204E1"));
    assert_eq!(
        (h.bus_state, h.status_flags),
        (BusState::Passive, Some(0x24))
    );
    // The periodic poll sees bus-off.
    t.set_status_interval(Some(Duration::from_millis(10)));
    let until = std::time::Instant::now() + Duration::from_secs(2);
    while t.health().status_reports < 2 && std::time::Instant::now() < until {
        assert!(t.receive(Duration::from_millis(20)).unwrap().is_none());
    }
    assert_eq!(t.health().bus_state, BusState::BusOff);
    let seen = peer.join().unwrap();
    assert_eq!(&seen[..4], ["C", "S8", "Z1", "O"]);
    assert_eq!(seen[6], "F");
}

#[test]
fn the_device_disappearing_mid_run_is_an_error_naming_the_port() {
    let (peer, host_end) = TTYPort::pair().expect("pty pair");
    let name = host_end.name().unwrap();
    let mut t = SlcanTransport::from_tty(host_end, &name).unwrap();
    t.set_status_interval(None);
    let f = Frame::new(Instant::ZERO, 0x1060_642A, &[0x03, 0xE0]).unwrap();
    t.send(&f).unwrap();
    // Unplugged: the master side closes, the host's end reports a hang-up / EIO.
    drop(peer);
    let t0 = std::time::Instant::now();
    let err = loop {
        let r = t
            .send(&f)
            .and_then(|()| t.receive(Duration::from_millis(20)).map(|_| ()));
        match r {
            Err(e) if !e.is_would_block() => break e,
            _ => assert!(t0.elapsed() < Duration::from_secs(2), "no error after 2 s"),
        }
    };
    let text = err.to_string();
    assert!(matches!(err, TransportError::Closed(_)), "{text}");
    assert!(
        text.contains("device disappeared") && text.contains(&name),
        "{text}"
    );
    // Every later call fails the same way, at once.
    for r in [
        t.send(&f),
        t.flush(std::time::Instant::now()).map(|_| ()),
        t.receive(Duration::from_secs(1)).map(|_| ()),
    ] {
        assert!(matches!(r, Err(TransportError::Closed(_))));
    }
}

#[test]
fn the_stop_sequence_reports_whether_it_got_through() {
    // The peer is asleep: the link fills, and a STANDBY offered with a bound says it did not
    // get through, within that bound.
    let (mut peer, host_end) = TTYPort::pair().expect("pty pair");
    let mut t = SlcanTransport::from_tty(host_end, "pty-stop").unwrap();
    t.set_status_interval(None);
    let setpoint = Frame::new(Instant::ZERO, 0x1060_642A, &[0; 8]).unwrap();
    // Full means refused for 20 ms on end (the pty moves bytes into the reader's buffer in the
    // background for a while after the first refusal).
    let mut refused_since = None;
    while refused_since.is_none_or(|s: std::time::Instant| s.elapsed() < Duration::from_millis(20))
    {
        match t.send(&setpoint) {
            Ok(()) => refused_since = None,
            Err(e) if e.is_would_block() => {
                refused_since.get_or_insert_with(std::time::Instant::now);
            }
            Err(e) => panic!("{e}"),
        }
    }
    let standby = Frame::new(Instant::ZERO, 0x1060_6B2A, &[2, 0xE0]).unwrap();
    let t0 = std::time::Instant::now();
    let bound = Duration::from_millis(50);
    assert!(!t.send_by(&standby, t0 + bound).unwrap());
    // It tried until its deadline (how soon after it gives up: the congestion benchmark).
    let took = t0.elapsed();
    assert!(took >= bound, "{took:?}");
    // The peer wakes up and drains: the same call now gets through, and the STANDBY is the
    // last line on the wire, whole.
    let reader = std::thread::spawn(move || drain(&mut peer, Duration::from_millis(300)));
    assert!(t
        .send_by(&standby, std::time::Instant::now() + Duration::from_secs(2))
        .unwrap());
    let bytes = reader.join().unwrap();
    assert!(
        bytes.ends_with(b"T10606B2A202E0\r"),
        "{:?}",
        &bytes[bytes.len().saturating_sub(40)..]
    );
    let mut d = Decoder::new();
    d.push(&bytes, &mut Vec::new());
    assert_eq!(d.garbage_count(), 0);
}
