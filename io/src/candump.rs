//! candump logs (`candump -L`): back into the TSV `propid drive` would have written.
//!
//! ```text
//!  "(1700000000.123456) can0 1060642A#03E0"  (candump -L; CAN FD: "ID##<flags><data>")
//!    ─► Frame (timestamp from the log) ─► Reassembler (feedback subject) ─► DoF3rdTs ─► TSV row
//! ```
//! Nothing in a log stops a replay but an I/O error: malformed lines, error and remote frames,
//! 11-bit frames and the reassembler's drops (CRC, toggle, transfer-ID) are skipped and counted
//! in a [`ReplaySummary`], the first malformed lines with their number. Frames of other ports
//! are skipped, as a live subscriber would skip them; the feedback of one source node only is
//! written (several nodes on one subject are never merged).

use std::io::{BufRead, Write};
use std::time::Duration;

use std::collections::{BTreeMap, BTreeSet};

use propid_core::can::{
    CanId, Frame, NodeId, Port, Reassembler, RxError, RxStats, SubjectId, Subscription,
    TransferKind,
};
use propid_core::dsdl::{DataType, DoF3rdTs};
use propid_core::time::Instant;

use crate::tsv::{Row, Sample, TsvWriter};
use crate::InputError;

/// What one `candump -L` line holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CandumpLine {
    /// Blank or a comment.
    Empty,
    /// A 29-bit data frame (Cyphal's kind).
    Frame(Frame),
    /// An error frame (the CAN_ERR_FLAG bit 0x20000000 set in the ID, as `candump -L` logs
    /// bus errors).
    Error,
    /// A remote-transmission request (`ID#R`).
    Remote,
    /// A data frame with an 11-bit ID: not Cyphal.
    Base,
}

/// The CAN_ERR_FLAG bit of a Linux `can_id`, which candump keeps in an error frame's ID.
const CAN_ERR_FLAG: u32 = 0x2000_0000;

/// Parses one `candump -L` line. `Err` says what is wrong (never panics, whatever the bytes).
pub fn parse_candump_line(line: &str) -> Result<CandumpLine, String> {
    let line = line.trim();
    if line.is_empty() || line.starts_with('#') {
        return Ok(CandumpLine::Empty);
    }
    let mut parts = line.split_whitespace();
    let stamp = parts.next().ok_or("empty line")?;
    let stamp = stamp
        .strip_prefix('(')
        .and_then(|s| s.strip_suffix(')'))
        .ok_or_else(|| format!("`{stamp}` is not a (seconds.micros) timestamp"))?;
    let micros = parse_timestamp(stamp)?;
    let _iface = parts.next().ok_or("no interface name")?;
    let body = parts.next().ok_or("no frame (ID#DATA)")?;
    let (id, data) = if let Some((id, rest)) = body.split_once("##") {
        // CAN FD: one flags digit, then the data.
        let mut chars = rest.chars();
        if !chars.next().is_some_and(|c| c.is_ascii_hexdigit()) {
            return Err(format!("`{body}`: CAN FD frame without a flags digit"));
        }
        (id, chars.as_str())
    } else {
        body.split_once('#')
            .ok_or_else(|| format!("`{body}` is not ID#DATA"))?
    };
    if !id.bytes().all(|b| b.is_ascii_hexdigit()) || id.is_empty() {
        return Err(format!("`{id}` is not a hexadecimal CAN ID"));
    }
    let remote = data.starts_with('R');
    if id.len() == 3 {
        // Cyphal uses 29-bit IDs only; 11-bit frames are someone else's.
        return Ok(if remote {
            CandumpLine::Remote
        } else {
            CandumpLine::Base
        });
    }
    if id.len() != 8 {
        return Err(format!(
            "`{id}` is not a CAN ID (3 or 8 hexadecimal digits)"
        ));
    }
    let id = u32::from_str_radix(id, 16).map_err(|_| format!("`{id}` is not a CAN ID"))?;
    if id & CAN_ERR_FLAG != 0 {
        return Ok(CandumpLine::Error);
    }
    if remote {
        return Ok(CandumpLine::Remote);
    }
    if !data.bytes().all(|b| b.is_ascii_hexdigit()) {
        return Err(format!("`{data}` is not hexadecimal data"));
    }
    if data.len() % 2 != 0 || data.len() > 128 {
        return Err(format!("`{data}` is not whole bytes of data (at most 64)"));
    }
    // All ASCII hex digits: every two-byte slice is on a char boundary and parses.
    let bytes: Vec<u8> = data
        .as_bytes()
        .chunks(2)
        .map(|pair| (hex_digit(pair[0]) << 4) | hex_digit(pair[1]))
        .collect();
    Frame::new(Instant::from_micros(micros), id, &bytes)
        .map(CandumpLine::Frame)
        .ok_or_else(|| {
            format!(
                "ID {id:08X} has more than 29 bits or {} bytes is not a CAN length",
                bytes.len()
            )
        })
}

fn hex_digit(b: u8) -> u8 {
    match b {
        b'0'..=b'9' => b - b'0',
        b'a'..=b'f' => b - b'a' + 10,
        _ => b - b'A' + 10,
    }
}

/// `seconds.fraction` → microseconds, refusing what does not fit in 64 bits.
fn parse_timestamp(stamp: &str) -> Result<u64, String> {
    let (secs, frac) = stamp
        .split_once('.')
        .ok_or_else(|| format!("timestamp `{stamp}` has no fraction"))?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if !digits(secs) || !digits(frac) {
        return Err(format!("timestamp `{stamp}` is not a number"));
    }
    let secs: u64 = secs
        .parse()
        .map_err(|_| format!("timestamp `{stamp}` is too large"))?;
    // Microseconds: the first six digits of the fraction, padded with zeros.
    let micros = frac
        .bytes()
        .chain(std::iter::repeat(b'0'))
        .take(6)
        .fold(0u64, |acc, b| acc * 10 + u64::from(b - b'0'));
    secs.checked_mul(1_000_000)
        .and_then(|us| us.checked_add(micros))
        .ok_or_else(|| format!("timestamp `{stamp}` is too large (more than 2^64 µs)"))
}

/// What to replay.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReplayOptions {
    /// The feedback subject-ID (0..=8191).
    pub feedback_id: u16,
    /// Only this source node's transfers (0..=127). `None`: the first node seen on the subject;
    /// transfers of any other node are counted in [`ReplaySummary::other_sources`], never merged.
    pub source_node: Option<u8>,
}

/// What a replay read, used and skipped.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ReplaySummary {
    /// Lines read.
    pub lines: u64,
    /// TSV rows written (feedback transfers decoded).
    pub rows: u64,
    /// The node whose transfers were written.
    pub source: Option<u8>,
    /// Lines that are not `candump -L` frames: how many, and the first few (line, why).
    pub malformed: u64,
    /// The first malformed lines (at most [`ReplaySummary::KEPT`]): 1-based line and reason.
    pub malformed_first: Vec<(u64, String)>,
    /// Error frames (bus errors logged by the adapter).
    pub error_frames: u64,
    /// Remote-transmission requests.
    pub remote_frames: u64,
    /// 11-bit data frames.
    pub base_frames: u64,
    /// Transfers on the subject that did not decode as DoF3rdTs.
    pub undecodable: u64,
    /// Frames on the feedback subject from other nodes than [`ReplaySummary::source`] (node, frames).
    pub other_sources: Vec<(Option<u8>, u64)>,
    /// The reassembler's counters for the feedback subject's frames (CRC, toggle, transfer-ID…).
    pub rx: RxStats,
    /// Every message subject seen, with its source nodes (`None`: anonymous) and frame count.
    pub subjects: Vec<(u16, Vec<Option<u8>>, u64)>,
    /// Frames of service transfers.
    pub service_frames: u64,
}

impl ReplaySummary {
    /// How many malformed lines are kept with their reason.
    pub const KEPT: usize = 5;

    /// Frames the reassembler dropped for `why`.
    pub fn dropped(&self, why: RxError) -> u64 {
        self.rx.rejected(why)
    }
}

/// Why a replay stopped.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The options are invalid, or reading the log failed (the rows before it are written and
    /// flushed): the error names the log and the line.
    #[error(transparent)]
    Input(#[from] InputError),
    /// Writing the TSV failed.
    #[error("writing the TSV")]
    Write(#[from] std::io::Error),
}

/// Replays a log: writes the feedback subject's transfers as TSV rows and counts everything it
/// skips. A bad line is counted (with its number) and skipped; only an I/O error stops the
/// replay, after the rows before it are flushed.
pub fn replay(
    mut input: impl BufRead,
    name: &str,
    options: &ReplayOptions,
    out: impl Write,
) -> Result<ReplaySummary, ReplayError> {
    let feedback_id = options.feedback_id;
    let Some(subject) = SubjectId::new(feedback_id) else {
        return Err(InputError::invalid(format!(
            "feedback subject-ID {feedback_id} is out of range (0 to 8191)"
        ))
        .into());
    };
    if let Some(n) = options.source_node.filter(|&n| n > 127) {
        return Err(
            InputError::invalid(format!("source node-ID {n} is out of range (0 to 127)")).into(),
        );
    }
    let mut rx: Reassembler<1, 32, 64> = Reassembler::new(None);
    rx.subscribe(Subscription {
        port: Port::Subject(subject),
        extent: DoF3rdTs::EXTENT_BYTES,
        transfer_id_timeout: Duration::from_secs(2),
    })
    .map_err(|_| {
        InputError::invalid(format!(
            "feedback subject {feedback_id} cannot be subscribed"
        ))
    })?;
    let mut summary = ReplaySummary {
        source: options.source_node,
        ..ReplaySummary::default()
    };
    let mut subjects: BTreeMap<u16, (BTreeSet<Option<u8>>, u64)> = BTreeMap::new();
    let mut others: BTreeMap<Option<u8>, u64> = BTreeMap::new();
    let mut locked: Option<Option<u8>> = options.source_node.map(Some);
    let mut writer = TsvWriter::new(out, false)?;
    let mut buf = Vec::new();
    let result = loop {
        buf.clear();
        match input.read_until(b'\n', &mut buf) {
            Ok(0) => break Ok(()),
            Ok(_) => {}
            Err(source) => {
                break Err(ReplayError::Input(crate::input::error_of(
                    name,
                    &source,
                    summary.lines + 1,
                )))
            }
        }
        summary.lines += 1;
        let line = String::from_utf8_lossy(&buf);
        let frame = match parse_candump_line(&line) {
            Ok(CandumpLine::Frame(f)) => f,
            Ok(CandumpLine::Empty) => continue,
            Ok(CandumpLine::Error) => {
                summary.error_frames += 1;
                continue;
            }
            Ok(CandumpLine::Remote) => {
                summary.remote_frames += 1;
                continue;
            }
            Ok(CandumpLine::Base) => {
                summary.base_frames += 1;
                continue;
            }
            Err(why) => {
                summary.malformed += 1;
                if summary.malformed_first.len() < ReplaySummary::KEPT {
                    summary.malformed_first.push((summary.lines, why));
                }
                continue;
            }
        };
        let Some(id) = CanId::parse(frame.id()) else {
            continue;
        };
        let source_of_frame = id.source.map(NodeId::get);
        match id.kind {
            TransferKind::Message { subject_id } => {
                let subject_id = subject_id.get();
                let e = subjects.entry(subject_id).or_default();
                e.0.insert(source_of_frame);
                e.1 += 1;
                if subject_id != feedback_id {
                    continue;
                }
            }
            _ => {
                summary.service_frames += 1;
                continue;
            }
        }
        // One node's feedback only: the first seen unless one was chosen.
        let source = *locked.get_or_insert(source_of_frame);
        if source_of_frame != source {
            *others.entry(source_of_frame).or_default() += 1;
            continue;
        }
        let Ok(Some(t)) = rx.accept(&frame) else {
            continue;
        };
        let ts = t.timestamp.as_secs_f64();
        let Ok(fb) = DoF3rdTs::deserialize(t.payload) else {
            summary.undecodable += 1;
            continue;
        };
        let kin = &fb.value.kinematics;
        if let Err(e) = writer.write(&Row::new(
            ts,
            Sample {
                t: fb.timestamp.microsecond as f64 * 1e-6,
                force: f64::from(fb.value.force),
                velocity: f64::from(kin.base.velocity),
                acceleration: f64::from(kin.acceleration),
                position: f64::from(kin.base.position),
            },
        )) {
            break Err(e.into());
        }
        summary.rows += 1;
    };
    // The rows written so far reach the file whatever stopped the loop.
    let flushed = writer.into_inner().map(drop);
    result?;
    flushed?;
    summary.source = locked.flatten();
    summary.rx = rx.stats();
    summary.other_sources = others.into_iter().collect();
    summary.subjects = subjects
        .into_iter()
        .map(|(s, (nodes, n))| (s, nodes.into_iter().collect(), n))
        .collect();
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_core::can::{FrameSplitter, Mtu, Priority, TransferHeader};
    use propid_core::dsdl::{DoF2ndKinematics, DoF3rdDynamics, DoF3rdKinematics, Timestamp};

    fn frame(line: &str) -> Frame {
        match parse_candump_line(line).unwrap() {
            CandumpLine::Frame(f) => f,
            other => panic!("{line}: {other:?}"),
        }
    }

    #[test]
    fn parses_candump_lines() {
        let f = frame("(1700000000.123456) can0 1060642A#03E0");
        assert_eq!((f.id(), f.data()), (0x1060_642A, &[3u8, 0xE0][..]));
        assert_eq!(f.timestamp.as_micros(), 1_700_000_000_123_456);
        assert!(frame("(1.5) vcan0 0C64D22A##1").data().is_empty());
        assert_eq!(
            frame("(1.5) vcan0 0C64D22A#").timestamp.as_micros(),
            1_500_000
        );
        assert_eq!(
            frame("(1.1234567) c 0C64D22A#aa").timestamp.as_micros(),
            1_123_456
        );
        assert_eq!(
            parse_candump_line("(1.0) can0 123#11"),
            Ok(CandumpLine::Base)
        );
        assert_eq!(parse_candump_line(""), Ok(CandumpLine::Empty));
        assert_eq!(
            parse_candump_line("(1.0) can0 20000080#0000000000000000"),
            Ok(CandumpLine::Error)
        );
        assert_eq!(
            parse_candump_line("(1.0) can0 1060642A#R"),
            Ok(CandumpLine::Remote)
        );
        assert_eq!(
            parse_candump_line("(1.0) can0 123#R"),
            Ok(CandumpLine::Remote)
        );
        for (bad, why) in [
            ("1.0 can0 1060642A#03", "timestamp"),
            ("(1.0) can0 1060642A03", "ID#DATA"),
            ("(1.0) can0 1060642A#0", "whole bytes"),
            ("(1.0) can0 1060642A#ZZ", "hexadecimal"),
            ("(1.0) can0", "no frame"),
            // Non-ASCII bytes in the data, the ID and the FD flags: errors, not panics.
            ("(1.5) can0 1060642A#€0", "hexadecimal data"),
            ("(1.5) can0 1060642A#0€", "hexadecimal data"),
            ("(1.5) can0 106€42A#00", "hexadecimal CAN ID"),
            ("(1.5) can0 1060642A##€0", "flags"),
            ("(1.5) can0 1060642A##", "flags"),
            ("(1.5) can0 1060642#00", "3 or 8"),
            ("(+1.5) can0 1060642A#00", "not a number"),
            ("(1.-5) can0 1060642A#00", "not a number"),
            // 99999999999999 s × 10⁶ overflows 64 bits.
            ("(99999999999999.5) can0 1060642A#00", "too large"),
            ("(99999999999999999999.5) can0 1060642A#00", "too large"),
        ] {
            let e = parse_candump_line(bad).unwrap_err();
            assert!(e.contains(why), "{bad}: {e}");
        }
        // The largest timestamp that fits still parses.
        assert_eq!(
            frame("(18446744073709.551615) can0 1060642A#E0")
                .timestamp
                .as_micros(),
            u64::MAX
        );
    }

    /// A candump log line for every frame of one DoF3rdTs transfer from `node`.
    fn transfer_lines(node: u8, subject: u16, tid: u8, t_us: u64, velocity: f32) -> Vec<String> {
        let msg = DoF3rdTs {
            timestamp: Timestamp { microsecond: t_us },
            value: DoF3rdDynamics {
                kinematics: DoF3rdKinematics {
                    base: DoF2ndKinematics {
                        position: 0.0,
                        velocity,
                    },
                    acceleration: 0.0,
                },
                force: 1.0,
            },
        };
        let mut buf = [0u8; 23];
        let n = msg.serialize(&mut buf);
        let header = TransferHeader {
            priority: Priority::NOMINAL,
            kind: TransferKind::Message {
                subject_id: SubjectId::new(subject).unwrap(),
            },
            source: Some(NodeId::new(node).unwrap()),
            transfer_id: tid,
        };
        FrameSplitter::new(&header, &buf[..n], Mtu::Classic, Instant::from_micros(t_us))
            .unwrap()
            .map(|f| {
                let data: String = f.data().iter().map(|b| format!("{b:02X}")).collect();
                format!(
                    "({}.{:06}) can0 {:08X}#{data}",
                    t_us / 1_000_000,
                    t_us % 1_000_000,
                    f.id()
                )
            })
            .collect()
    }

    fn run(log: &str, options: ReplayOptions) -> (ReplaySummary, String) {
        let mut out = Vec::new();
        let s = replay(log.as_bytes(), "t.log", &options, &mut out).unwrap();
        (s, String::from_utf8(out).unwrap())
    }

    const FB: ReplayOptions = ReplayOptions {
        feedback_id: 100,
        source_node: None,
    };

    #[test]
    fn bad_lines_error_and_remote_frames_are_counted_not_fatal() {
        let mut log = String::new();
        log += &transfer_lines(10, 100, 0, 1_000_000, 1.0).join("\n");
        log += "\n(1.1) can0 20000080#0000000000000000\n";
        log += "(1.2) can0 1060640A#R\n";
        log += "(1.3) can0 1060642A#€0\n";
        log += "(99999999999999.5) can0 1060640A#E0\n";
        log += "(1.4) can0 123#1122\n";
        log += "garbage\n";
        log += &transfer_lines(10, 100, 1, 2_000_000, 2.0).join("\n");
        log += "\n";
        let (s, tsv) = run(&log, FB);
        assert_eq!(s.rows, 2, "{s:?}");
        assert_eq!(tsv.lines().count(), 3, "{tsv}");
        assert_eq!((s.error_frames, s.remote_frames, s.base_frames), (1, 1, 1));
        assert_eq!(s.malformed, 3);
        let lines: Vec<u64> = s.malformed_first.iter().map(|m| m.0).collect();
        let first = transfer_lines(10, 100, 0, 1_000_000, 1.0).len() as u64;
        assert_eq!(lines, [first + 3, first + 4, first + 6]);
        assert_eq!(s.source, Some(10));
        // Raw invalid UTF-8 is a malformed line too.
        let mut bytes = b"(1.0) can0 1060640A#\xFF\xFE\n".to_vec();
        bytes.extend_from_slice(log.as_bytes());
        let s = replay(&bytes[..], "t.log", &FB, std::io::sink()).unwrap();
        assert_eq!((s.rows, s.malformed), (2, 4));
    }

    #[test]
    fn reassembler_drops_are_counted() {
        let good = transfer_lines(10, 100, 0, 1_000_000, 1.0);
        assert!(good.len() >= 3, "DoF3rdTs takes several classic frames");
        // A corrupted payload byte in the first frame: the CRC fails.
        let mut crc = good.clone();
        let hash = crc[0].find('#').unwrap();
        let flipped = if &crc[0][hash + 1..hash + 2] == "0" {
            "1"
        } else {
            "0"
        };
        crc[0].replace_range(hash + 1..hash + 2, flipped);
        // A repeated middle frame: a toggle error.
        let mut toggle = transfer_lines(10, 100, 1, 2_000_000, 1.0);
        toggle.insert(2, toggle[1].clone());
        let log = [crc, toggle, transfer_lines(10, 100, 2, 3_000_000, 3.0)]
            .concat()
            .join("\n");
        let (s, _) = run(&log, FB);
        assert_eq!(s.dropped(RxError::BadCrc), 1, "{s:?}");
        assert!(s.dropped(RxError::BadToggle) >= 1, "{s:?}");
        assert_eq!(s.rows, 2);
    }

    #[test]
    fn two_sources_are_never_merged() {
        let mut log = Vec::new();
        for k in 0..3u8 {
            log.extend(transfer_lines(
                10,
                100,
                k,
                1_000_000 + u64::from(k) * 1000,
                1.0,
            ));
            log.extend(transfer_lines(
                11,
                100,
                k,
                1_000_500 + u64::from(k) * 1000,
                9.0,
            ));
            log.extend(transfer_lines(12, 7509, k, 1_000_600, 0.0));
        }
        let log = log.join("\n");
        let (s, tsv) = run(&log, FB);
        assert_eq!((s.rows, s.source), (3, Some(10)));
        assert!(
            tsv.lines()
                .skip(1)
                .all(|l| l.split('\t').nth(3) == Some("1")),
            "{tsv}"
        );
        assert_eq!(s.other_sources.len(), 1);
        assert_eq!(s.other_sources[0].0, Some(11));
        let (s, tsv) = run(
            &log,
            ReplayOptions {
                source_node: Some(11),
                ..FB
            },
        );
        assert_eq!((s.rows, s.source), (3, Some(11)));
        assert!(
            tsv.lines()
                .skip(1)
                .all(|l| l.split('\t').nth(3) == Some("9")),
            "{tsv}"
        );
        assert_eq!(s.other_sources[0].0, Some(10));
        // Everything seen is listed.
        let subjects: Vec<(u16, Vec<Option<u8>>)> =
            s.subjects.iter().map(|(a, b, _)| (*a, b.clone())).collect();
        assert_eq!(
            subjects,
            [(100, vec![Some(10), Some(11)]), (7509, vec![Some(12)])]
        );
    }

    #[test]
    fn out_of_range_ids_are_refused() {
        for options in [
            ReplayOptions {
                feedback_id: 9000,
                source_node: None,
            },
            ReplayOptions {
                feedback_id: 100,
                source_node: Some(128),
            },
        ] {
            let e = replay(&b""[..], "t.log", &options, std::io::sink()).unwrap_err();
            assert!(e.to_string().contains("out of range"), "{e}");
        }
    }

    #[test]
    fn rows_before_a_read_error_are_flushed() {
        struct Failing<'a>(&'a [u8]);
        impl std::io::Read for Failing<'_> {
            fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
                if self.0.is_empty() {
                    return Err(std::io::Error::other("device vanished"));
                }
                let n = self.0.len().min(buf.len());
                buf[..n].copy_from_slice(&self.0[..n]);
                self.0 = &self.0[n..];
                Ok(n)
            }
        }
        let log = transfer_lines(10, 100, 0, 1_000_000, 1.0).join("\n") + "\n";
        let mut out = Vec::new();
        let e = replay(
            std::io::BufReader::new(Failing(log.as_bytes())),
            "t.log",
            &FB,
            &mut out,
        )
        .unwrap_err();
        assert!(e.to_string().contains("t.log: line"), "{e}");
        assert_eq!(String::from_utf8(out).unwrap().lines().count(), 2);
    }
}
