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

/// Status flags reported by `F`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StatusFlags(pub u8);

impl StatusFlags {
    /// The receive queue overflowed: frames were lost.
    pub fn overrun(self) -> bool {
        self.0 & 0x08 != 0 || self.0 & 0x02 != 0
    }
    /// The controller is error-passive.
    pub fn error_passive(self) -> bool {
        self.0 & 0x20 != 0
    }
    /// The controller is bus-off.
    pub fn bus_off(self) -> bool {
        self.0 & 0x80 != 0
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
/// microseconds.
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

    proptest::proptest! {
        #[test]
        fn never_panics_on_any_bytes(bytes: Vec<u8>) {
            let mut d = Decoder::new();
            let mut out = Vec::new();
            d.push(&bytes, &mut out);
        }
    }
}
