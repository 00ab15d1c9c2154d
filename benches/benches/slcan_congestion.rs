//! How promptly the SLCAN transport answers on a congested link (a pseudo-terminal whose reader
//! sleeps): a refused send, and a `send_by` (send, flush, retry) that gives up at its bound.
//! These are the timing claims the tests do not make (tests/tests/slcan_babel.rs checks what the
//! calls return, not how long they take, which a loaded machine stretches).
//! `cargo bench -p propid-benches --bench slcan_congestion`; figures in docs/TRANSPORTS.md.
#![cfg_attr(not(unix), allow(unused))]

use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};

#[cfg(unix)]
fn congested() -> (propid_slcan::SlcanTransport, serialport::TTYPort) {
    use propid_transport::CanTransport;
    let (peer, host_end) = serialport::TTYPort::pair().expect("a pty pair");
    let mut t = propid_slcan::SlcanTransport::from_tty(host_end, "bench").unwrap();
    t.set_status_interval(None);
    let f = propid_core::can::Frame::new(propid_core::time::Instant::ZERO, 0x1060_642A, &[0; 8])
        .unwrap();
    // Full: refused for 20 ms on end (the kernel moves bytes on for a while after a refusal).
    let mut refused_since: Option<Instant> = None;
    while refused_since.is_none_or(|s| s.elapsed() < Duration::from_millis(20)) {
        match t.send(&f) {
            Ok(()) => refused_since = None,
            Err(_) => {
                refused_since.get_or_insert_with(Instant::now);
            }
        }
    }
    (t, peer)
}

#[cfg(unix)]
fn congestion(c: &mut Criterion) {
    use propid_transport::CanTransport;
    let (mut t, _peer) = congested();
    let f = propid_core::can::Frame::new(propid_core::time::Instant::ZERO, 0x1060_642A, &[1; 8])
        .unwrap();
    let mut g = c.benchmark_group("slcan_congested");
    g.bench_function("refused_send", |b| {
        b.iter(|| assert!(t.send(&f).unwrap_err().is_would_block()))
    });
    // A send_by with a 2 ms bound on a link that takes nothing: the time it takes is the bound
    // plus how late it gives up.
    g.bench_function("send_by_2ms_bound", |b| {
        b.iter_custom(|iters| {
            let t0 = Instant::now();
            for _ in 0..iters {
                assert!(!t
                    .send_by(&f, Instant::now() + Duration::from_millis(2))
                    .unwrap());
            }
            t0.elapsed()
        })
    });
    g.finish();
}

#[cfg(not(unix))]
fn congestion(_: &mut Criterion) {}

criterion_group!(benches, congestion);
criterion_main!(benches);
