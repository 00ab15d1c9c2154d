//! The SLCAN codec, Sans-IO.
//!
//! Lines end in `\r`. From the adapter: `T` + 8 hex ID + length digit + data + optional 4 hex
//! millisecond timestamp (extended data frame), `t` (standard ID, 3 hex), `R`/`r` (remote frames),
//! `z`/`Z` (transmit acknowledged: the Babel answers each `t`/`T` with one), an empty line (command
//! accepted), BELL `\x07` (command refused), `F` + 2 hex status flags, `V`/`N` + version or serial
//! number. Anything else is garbage: it is skipped and counted, never a panic.
//!
//! Bit rates: `S0`..`S8` = 10k, 20k, 50k, 100k, 125k, 250k, 500k, 800k (the Babel; python-can
//! calls S7 750k), 1M. Classic CAN only: SLCAN has no CAN FD frames.

/// Status flags reported by `F` (Lawicel's layout: bit 0 receive FIFO full, 1 transmit FIFO
/// full, 2 error warning, 3 data overrun, 5 error-passive, 6 arbitration lost, 7 bus error).
/// Lawicel has no separate bus-off bit; propid reads bit 7 as bus-off, the state in which an
/// adapter's controller keeps reporting bus errors and transmits nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StatusFlags(pub u8);

impl StatusFlags {
    /// The receive queue overflowed (receive FIFO full or data overrun): frames were lost.
    pub fn overrun(self) -> bool {
        self.0 & 0x08 != 0 || self.0 & 0x01 != 0
    }
    /// The adapter's transmit queue is full.
    pub fn transmit_full(self) -> bool {
        self.0 & 0x02 != 0
    }
    /// An error counter passed the warning level.
    pub fn error_warning(self) -> bool {
        self.0 & 0x04 != 0
    }
    /// The controller is error-passive.
    pub fn error_passive(self) -> bool {
        self.0 & 0x20 != 0
    }
    /// The controller is bus-off (bit 7, see the type's documentation).
    pub fn bus_off(self) -> bool {
        self.0 & 0x80 != 0
    }
    /// The worst state the flags report.
    pub fn bus_state(self) -> propid_transport::BusState {
        use propid_transport::BusState;
        if self.bus_off() {
            BusState::BusOff
        } else if self.error_passive() {
            BusState::Passive
        } else if self.error_warning() {
            BusState::Warning
        } else {
            BusState::Active
        }
    }
}

/// What the adapter said.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Event {
    /// A received frame.
    Frame {
        /// 29-bit (extended) or 11-bit (standard) ID.
        id: u32,
        /// Whether the ID is extended.
        extended: bool,
        /// Data bytes (empty for remote frames).
        data: Vec<u8>,
        /// A remote frame.
        remote: bool,
        /// The adapter's millisecond timestamp (0..60000), when timestamps are on.
        adapter_ms: Option<u16>,
    },
    /// A transmitted frame was acknowledged (`z`/`Z`).
    TransmitAck,
    /// A command was accepted (an empty line).
    Ack,
    /// A command was refused (BELL).
    Nack,
    /// Status flags (`F`).
    Status(StatusFlags),
    /// Version or serial number (`V`, `N`).
    Info(String),
    /// A line that is none of the above (skipped).
    Garbage(String),
}

/// Turns the byte stream into events.
#[derive(Default)]
pub struct Decoder {
    line: Vec<u8>,
    garbage: u64,
}

/// Longest line kept; longer input is garbage (a binary stream without `\r`).
const MAX_LINE: usize = 64;

impl Decoder {
    /// A decoder with an empty buffer.
    pub fn new() -> Self {
        Self::default()
    }

    /// Lines skipped as garbage so far.
    pub fn garbage_count(&self) -> u64 {
        self.garbage
    }

    /// Feeds bytes; complete lines become events appended to `out`.
    pub fn push(&mut self, bytes: &[u8], out: &mut Vec<Event>) {
        for &b in bytes {
            match b {
                b'\r' | b'\n' => {
                    if b == b'\n' && self.line.is_empty() {
                        continue;
                    }
                    let line = std::mem::take(&mut self.line);
                    let event = parse_line(&line);
                    if matches!(event, Event::Garbage(_)) {
                        self.garbage += 1;
                    }
                    out.push(event);
                }
                0x07 => {
                    self.line.clear();
                    out.push(Event::Nack);
                }
                _ => {
                    if self.line.len() >= MAX_LINE {
                        self.garbage += 1;
                        out.push(Event::Garbage(
                            String::from_utf8_lossy(&self.line).into_owned(),
                        ));
                        self.line.clear();
                    }
                    self.line.push(b);
                }
            }
        }
    }
}

fn hex(bytes: &[u8]) -> Option<u32> {
    if bytes.is_empty() || bytes.len() > 8 {
        return None;
    }
    let s = std::str::from_utf8(bytes).ok()?;
    u32::from_str_radix(s, 16).ok()
}

fn parse_line(line: &[u8]) -> Event {
    let garbage = || Event::Garbage(String::from_utf8_lossy(line).into_owned());
    let Some((&kind, rest)) = line.split_first() else {
        return Event::Ack;
    };
    match kind {
        b'T' | b't' | b'R' | b'r' => {
            let extended = kind == b'T' || kind == b'R';
            let remote = kind == b'R' || kind == b'r';
            let id_len = if extended { 8 } else { 3 };
            if rest.len() < id_len + 1 {
                return garbage();
            }
            let Some(id) = hex(&rest[..id_len]) else {
                return garbage();
            };
            if (extended && id > 0x1FFF_FFFF) || (!extended && id > 0x7FF) {
                return garbage();
            }
            let dlc = rest[id_len];
            if !dlc.is_ascii_digit() || dlc > b'8' {
                return garbage();
            }
            let n = usize::from(dlc - b'0');
            let body = &rest[id_len + 1..];
            let data_chars = if remote { 0 } else { 2 * n };
            let adapter_ms = match body.len().checked_sub(data_chars) {
                Some(0) => None,
                Some(4) => match hex(&body[data_chars..]) {
                    Some(ms) => Some(ms as u16),
                    None => return garbage(),
                },
                _ => return garbage(),
            };
            let mut data = Vec::with_capacity(n);
            for k in 0..data_chars / 2 {
                match hex(&body[2 * k..2 * k + 2]) {
                    Some(b) => data.push(b as u8),
                    None => return garbage(),
                }
            }
            Event::Frame {
                id,
                extended,
                data,
                remote,
                adapter_ms,
            }
        }
        b'z' | b'Z' if rest.is_empty() => Event::TransmitAck,
        b'F' if rest.len() == 2 => match hex(rest) {
            Some(f) => Event::Status(StatusFlags(f as u8)),
            None => garbage(),
        },
        b'V' | b'N' | b'v' => Event::Info(String::from_utf8_lossy(line).into_owned()),
        _ => garbage(),
    }
}

/// The line that transmits an extended-ID data frame (Classic CAN: at most 8 bytes).
pub fn encode_frame(id: u32, data: &[u8]) -> Option<String> {
    if data.len() > 8 || id > 0x1FFF_FFFF {
        return None;
    }
    let mut s = format!("T{id:08X}{}", data.len());
    for b in data {
        s.push_str(&format!("{b:02X}"));
    }
    s.push('\r');
    Some(s)
}

/// The command that sets `bitrate` (bit/s): `S0`..`S8` for the standard rates (both 750k and
/// 800k map to `S7`, which the Babel runs at 800k), or `None` if there is no S-code for it.
pub fn bitrate_command(bitrate: u32) -> Option<&'static str> {
    Some(match bitrate {
        10_000 => "S0\r",
        20_000 => "S1\r",
        50_000 => "S2\r",
        100_000 => "S3\r",
        125_000 => "S4\r",
        250_000 => "S5\r",
        500_000 => "S6\r",
        750_000 | 800_000 => "S7\r",
        1_000_000 => "S8\r",
        _ => return None,
    })
}

/// The Lawicel raw bit-rate command `sXXYY`: the SJA1000-style bus timing registers BTR0 and BTR1,
/// for rates the `S` codes do not cover.
pub fn raw_bitrate_command(btr0: u8, btr1: u8) -> String {
    format!("s{btr0:02X}{btr1:02X}\r")
}

/// The command that opens the channel: `O` (normal) or `L` (listen only: the adapter neither
/// acknowledges nor transmits, for sniffing a running stand).
pub fn open_command(listen_only: bool) -> &'static str {
    if listen_only {
        "L\r"
    } else {
        "O\r"
    }
}

/// Turns the adapter's millisecond timestamps, which wrap every 60 s, into a monotonic count of
/// milliseconds, trusting that frames come more often than once a minute. [`AdapterClock`] also
/// uses the host clock and is what the transport uses.
#[derive(Default)]
pub struct TimestampUnwrapper {
    last: Option<u16>,
    base_ms: u64,
}

impl TimestampUnwrapper {
    /// Milliseconds since the first timestamp seen (monotonic as long as frames come more often
    /// than once a minute).
    pub fn unwrap(&mut self, ms: u16) -> u64 {
        if let Some(last) = self.last {
            if ms < last {
                self.base_ms += 60_000;
            }
        }
        self.last = Some(ms);
        self.base_ms + u64::from(ms)
    }
}

/// The adapter's timestamp period: `Z1` timestamps count milliseconds modulo 60 000.
const WRAP_MS: u64 = 60_000;
/// A disagreement between the two clocks larger than this re-anchors the mapping at once (an
/// adapter reset, a suspended host) and is counted.
const RESYNC_US: u64 = 1_000_000;
/// The offset is re-estimated once per this much host time.
const WINDOW_US: u64 = 1_000_000;
/// The offset moves towards its estimate by at most this fraction of the adapter time that
/// passes (1000 ppm): crystal drift (±100 ppm) is followed, and mapped time never runs backwards.
const SLEW_DIVISOR: i128 = 1000;

/// Maps the adapter's wrapping millisecond timestamps onto the host clock, Sans-IO.
///
/// - Wraps: the number of 60 s periods between two frames is the one that best matches the
///   host time that passed, so a gap of more than a minute between frames loses no period.
/// - Offset (host minus adapter time): anchored at the first frame, so the adapter's intervals
///   are kept exactly (the point of hardware timestamps); every second it is re-estimated as the
///   smallest arrival latency seen, and moved there slowly (at most 1000 ppm of elapsed time),
///   so a drifting adapter crystal is followed without a jump and mapped times stay monotonic.
/// - A disagreement of more than a second re-anchors at once and is counted ([`Self::resyncs`]).
#[derive(Default)]
pub struct AdapterClock {
    /// (last raw timestamp, its unwrapped value in ms, host arrival in µs)
    last: Option<(u16, u64, u64)>,
    /// Host µs minus adapter µs, as applied.
    offset_us: i128,
    /// Where the offset is heading.
    target_us: i128,
    window_start_us: u64,
    /// The smallest (arrival − mapped time) in the current window.
    window_min_us: Option<i128>,
    resyncs: u64,
}

impl AdapterClock {
    /// A clock that has seen no timestamp.
    pub fn new() -> Self {
        Self::default()
    }

    /// Times the mapping was re-anchored.
    pub fn resyncs(&self) -> u64 {
        self.resyncs
    }

    /// The host time (µs, same epoch as `host_now_us`) at which the adapter stamped a frame
    /// with `ms`, the frame having arrived at `host_now_us`.
    pub fn map(&mut self, ms: u16, host_now_us: u64) -> u64 {
        let ms_in = u64::from(ms) % WRAP_MS;
        let Some((last_raw, last_ms, last_host)) = self.last else {
            self.anchor(ms, ms_in, host_now_us);
            return host_now_us;
        };
        let d0 = (ms_in + WRAP_MS - u64::from(last_raw) % WRAP_MS) % WRAP_MS;
        let host_ms = host_now_us.saturating_sub(last_host) / 1000;
        // Whole periods that best explain the host time that passed.
        let k = (host_ms.saturating_sub(d0) + WRAP_MS / 2) / WRAP_MS;
        let adapter_ms = last_ms + d0 + k * WRAP_MS;
        let adapter_us = i128::from(adapter_ms) * 1000;
        let latency = i128::from(host_now_us) - adapter_us - self.offset_us;
        if latency.unsigned_abs() > u128::from(RESYNC_US) {
            self.resyncs += 1;
            self.anchor(ms, adapter_ms, host_now_us);
            return host_now_us;
        }
        self.window_min_us = Some(self.window_min_us.map_or(latency, |m| m.min(latency)));
        if host_now_us.saturating_sub(self.window_start_us) >= WINDOW_US {
            self.target_us = self.offset_us + self.window_min_us.take().unwrap_or(0);
            self.window_start_us = host_now_us;
        }
        let step = i128::from(adapter_ms - last_ms) * 1000 / SLEW_DIVISOR;
        self.offset_us += (self.target_us - self.offset_us).clamp(-step, step);
        self.last = Some((ms, adapter_ms, host_now_us));
        (adapter_us + self.offset_us).max(0) as u64
    }

    fn anchor(&mut self, ms: u16, adapter_ms: u64, host_now_us: u64) {
        self.offset_us = i128::from(host_now_us) - i128::from(adapter_ms) * 1000;
        self.target_us = self.offset_us;
        self.window_start_us = host_now_us;
        self.window_min_us = None;
        self.last = Some((ms, adapter_ms, host_now_us));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(bytes: &[u8]) -> (Vec<Event>, u64) {
        let mut d = Decoder::new();
        let mut out = Vec::new();
        d.push(bytes, &mut out);
        (out, d.garbage_count())
    }

    #[test]
    fn frames_and_replies() {
        let (ev, garbage) =
            decode(b"T1060642A203E0\rT1060642A203E0EA60\rz\r\r\x07F88\rt1232AABB\rV1013\r");
        assert_eq!(garbage, 0);
        assert_eq!(
            ev[0],
            Event::Frame {
                id: 0x1060_642A,
                extended: true,
                data: vec![3, 0xE0],
                remote: false,
                adapter_ms: None
            }
        );
        assert!(matches!(
            &ev[1],
            Event::Frame {
                adapter_ms: Some(60000),
                ..
            }
        ));
        assert_eq!(ev[2], Event::TransmitAck);
        assert_eq!(ev[3], Event::Ack);
        assert_eq!(ev[4], Event::Nack);
        let Event::Status(f) = ev[5] else { panic!() };
        assert!(f.bus_off() && f.overrun());
        assert!(matches!(
            &ev[6],
            Event::Frame {
                id: 0x123,
                extended: false,
                ..
            }
        ));
        assert!(matches!(&ev[7], Event::Info(_)));
        assert_eq!(
            encode_frame(0x1060_642A, &[3, 0xE0]).unwrap(),
            "T1060642A203E0\r"
        );
        assert!(encode_frame(1, &[0; 9]).is_none());
    }

    #[test]
    fn garbage_is_counted_not_fatal() {
        let (ev, garbage) = decode(b"T1060642A9\rTXYZ\rhello\r\x00\x01\x02\r");
        assert_eq!(garbage, 4);
        assert!(ev.iter().all(|e| matches!(e, Event::Garbage(_))));
        // A long binary stream without line ends.
        let noise: Vec<u8> = (0..1000u32)
            .map(|i| (i * 37 % 251) as u8 + 1)
            .filter(|b| *b != 13 && *b != 7 && *b != 10)
            .collect();
        let (_, garbage) = decode(&noise);
        assert!(garbage > 10);
    }

    #[test]
    fn bitrates_and_timestamps() {
        assert_eq!(bitrate_command(800_000), Some("S7\r"));
        assert_eq!(bitrate_command(750_000), Some("S7\r"));
        assert_eq!(bitrate_command(1_000_000), Some("S8\r"));
        assert_eq!(bitrate_command(333_333), None);
        assert_eq!(raw_bitrate_command(0x00, 0x14), "s0014\r");
        assert_eq!(open_command(true), "L\r");
        assert_eq!(open_command(false), "O\r");
        let mut u = TimestampUnwrapper::default();
        assert_eq!(u.unwrap(59_990), 59_990);
        assert_eq!(u.unwrap(10), 60_010);
        assert_eq!(u.unwrap(20), 60_020);
    }

    #[test]
    fn status_flags_name_the_bus_state() {
        use propid_transport::BusState;
        assert_eq!(StatusFlags(0x00).bus_state(), BusState::Active);
        assert_eq!(StatusFlags(0x04).bus_state(), BusState::Warning);
        assert_eq!(StatusFlags(0x24).bus_state(), BusState::Passive);
        assert_eq!(StatusFlags(0xA4).bus_state(), BusState::BusOff);
        assert!(StatusFlags(0x01).overrun() && StatusFlags(0x08).overrun());
        assert!(!StatusFlags(0x02).overrun() && StatusFlags(0x02).transmit_full());
    }

    #[test]
    fn adapter_clock_across_wraps_gaps_and_resets() {
        let mut c = AdapterClock::new();
        let s = 1_000_000u64; // host µs per second
                              // A burst that arrives in one read: the adapter's intervals are kept, across the wrap.
        let t0 = c.map(59_990, 100 * s);
        assert_eq!(t0, 100 * s);
        assert_eq!(c.map(10, 100 * s), t0 + 20_000);
        assert_eq!(c.map(20, 100 * s), t0 + 30_000);
        // 130 s of silence: two more wraps; the raw value alone would say 10 s.
        let got = c.map(10_020, 230 * s + 30_000);
        // The burst showed the first frame arrived ≥ 30 ms late; the gap lets the offset take
        // that in (1000 ppm of 130 s allows it all): stamped 30 ms before arrival.
        assert_eq!(got, 230 * s);
        assert_eq!(c.resyncs(), 0);
    }

    #[test]
    fn adapter_clock_follows_a_drifting_crystal_monotonically() {
        for ppm in [-100i64, 100] {
            let mut c = AdapterClock::new();
            let mut host = 5_000_000u64;
            let mut ms = 0u64;
            let mut last_t = c.map(0, host + 300);
            let mut worst = 0i64;
            for _ in 0..3000 {
                ms += 100;
                host = (host as i64 + 100_000 + ppm / 10) as u64; // 100 ms ± drift
                let t = c.map((ms % 60_000) as u16, host + 300);
                assert!(
                    t > last_t,
                    "mapped time ran backwards: {last_t} then {t}, host {host}"
                );
                last_t = t;
                // Against the anchor: the first frame's arrival, 300 µs after its host time (a
                // latency the mapping cannot know and keeps).
                worst = worst.max((host as i64 + 300 - t as i64).abs());
            }
            // Without following, the error would reach 3000 × 10 µs = 30 ms; docs/TRANSPORTS.md:
            // "a ±100 ppm crystal over 300 s stays within 200 µs of its anchor" (180 at +100 ppm).
            assert!(worst <= 200, "{ppm} ppm: {worst} µs");
            assert_eq!(c.resyncs(), 0);
        }
    }

    #[test]
    fn adapter_clock_re_anchors_after_a_reset() {
        let mut c = AdapterClock::new();
        c.map(30_000, 10_000_000);
        c.map(30_100, 10_100_000);
        // The adapter restarts its clock 5 ms later: re-anchored at arrival, and counted.
        assert_eq!(c.map(0, 10_105_000), 10_105_000);
        assert_eq!(c.resyncs(), 1);
        assert_eq!(c.map(10, 10_115_000), 10_115_000);
    }

    proptest::proptest! {
        #[test]
        fn never_panics_on_any_bytes(bytes: Vec<u8>) {
            let mut d = Decoder::new();
            let mut out = Vec::new();
            d.push(&bytes, &mut out);
        }
    }
}
