//! candump logs (`candump -L`): back into the TSV `propid drive` would have written.
//!
//! ```text
//!  "(1700000000.123456) can0 1060642A#03E0"  (candump -L; CAN FD: "ID##<flags><data>")
//!    ─► Frame (timestamp from the log) ─► Reassembler (feedback subject) ─► DoF3rdTs ─► TSV row
//! ```
//! Malformed lines are reported with their line number (exit 2); frames of other ports are
//! skipped, as a live subscriber would skip them.

use std::io::{BufRead, Write};
use std::time::Duration;

use propid_core::can::{Frame, Port, Reassembler, Subscription, TransferKind};
use propid_core::dsdl::{DataType, DoF3rdTs};
use propid_core::time::Instant;

use crate::tsv::{Row, Sample, TsvWriter};
use crate::InputError;

/// Parses one `candump -L` line into a frame. `Err` says what is wrong.
pub fn parse_candump_line(line: &str) -> Result<Option<Frame>, String> {
    let line = line.trim();
    if line.is_empty() || line.starts_with('#') {
        return Ok(None);
    }
    let mut parts = line.split_whitespace();
    let stamp = parts.next().ok_or("empty line")?;
    let stamp = stamp
        .strip_prefix('(')
        .and_then(|s| s.strip_suffix(')'))
        .ok_or_else(|| format!("`{stamp}` is not a (seconds.micros) timestamp"))?;
    let (secs, micros) = stamp
        .split_once('.')
        .ok_or_else(|| format!("timestamp `{stamp}` has no fraction"))?;
    let secs: u64 = secs
        .parse()
        .map_err(|_| format!("timestamp `{stamp}` is not a number"))?;
    let frac: u64 = micros
        .parse()
        .map_err(|_| format!("timestamp `{stamp}` is not a number"))?;
    let micros = frac * 10u64.pow(6u32.saturating_sub(micros.len() as u32));
    let _iface = parts.next().ok_or("no interface name")?;
    let body = parts.next().ok_or("no frame (ID#DATA)")?;
    let (id, data) = if let Some((id, rest)) = body.split_once("##") {
        // CAN FD: one flags digit, then the data.
        let data = rest
            .get(1..)
            .ok_or_else(|| format!("`{body}`: CAN FD frame without flags"))?;
        (id, data)
    } else {
        body.split_once('#')
            .ok_or_else(|| format!("`{body}` is not ID#DATA"))?
    };
    if id.len() != 8 {
        // Cyphal uses 29-bit IDs only; 11-bit frames are someone else's.
        return if id.len() == 3 {
            Ok(None)
        } else {
            Err(format!("`{id}` is not a CAN ID"))
        };
    }
    let id =
        u32::from_str_radix(id, 16).map_err(|_| format!("`{id}` is not a hexadecimal CAN ID"))?;
    if data.starts_with('R') {
        return Ok(None);
    }
    if data.len() % 2 != 0 || data.len() > 128 {
        return Err(format!("`{data}` is not whole bytes of data (at most 64)"));
    }
    let bytes = (0..data.len() / 2)
        .map(|k| u8::from_str_radix(&data[2 * k..2 * k + 2], 16))
        .collect::<Result<Vec<u8>, _>>()
        .map_err(|_| format!("`{data}` is not hexadecimal data"))?;
    let ts = Instant::from_micros(secs * 1_000_000 + micros);
    Frame::new(ts, id, &bytes)
        .map(Some)
        .ok_or_else(|| format!("ID {id:08X} has more than 29 bits"))
}

/// Why a replay stopped.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The log is malformed.
    #[error(transparent)]
    Input(#[from] InputError),
    /// Reading the log failed.
    #[error("line {line}: {source}")]
    Read {
        /// 1-based line number.
        line: u64,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// Writing the TSV failed.
    #[error("writing the TSV: {0}")]
    Write(#[from] std::io::Error),
}

/// Replays a log: returns the rows written.
pub fn replay(
    input: impl BufRead,
    name: &str,
    feedback_id: u16,
    out: impl Write,
) -> Result<u64, ReplayError> {
    let mut rx: Reassembler<1, 32, 64> = Reassembler::new(None);
    rx.subscribe(Subscription {
        port: Port::Subject(feedback_id),
        extent: DoF3rdTs::EXTENT_BYTES,
        transfer_id_timeout: Duration::from_secs(2),
    })
    .map_err(|_| {
        InputError(format!(
            "feedback subject {feedback_id} cannot be subscribed"
        ))
    })?;
    let mut writer = TsvWriter::new(out, false)?;
    let mut rows = 0;
    for (k, line) in input.lines().enumerate() {
        let line = line.map_err(|e| ReplayError::Read {
            line: k as u64 + 1,
            source: e,
        })?;
        let frame = parse_candump_line(&line)
            .map_err(|why| InputError(format!("{name}: line {}: {why}", k + 1)))?;
        let Some(frame) = frame else { continue };
        let Ok(Some(t)) = rx.accept(&frame) else {
            continue;
        };
        if !matches!(t.header.kind, TransferKind::Message { .. }) {
            continue;
        }
        let ts = t.timestamp.as_secs_f64();
        let fb = DoF3rdTs::deserialize(t.payload)
            .map_err(|e| InputError(format!("{name}: line {}: {e}", k + 1)))?;
        let kin = &fb.value.kinematics;
        writer.write(&Row {
            ts_local: ts,
            sample: Sample {
                t: fb.timestamp.microsecond as f64 * 1e-6,
                force: f64::from(fb.value.force),
                velocity: f64::from(kin.base.velocity),
                acceleration: f64::from(kin.acceleration),
                position: f64::from(kin.base.position),
            },
        })?;
        rows += 1;
    }
    writer.into_inner()?;
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_candump_lines() {
        let f = parse_candump_line("(1700000000.123456) can0 1060642A#03E0")
            .unwrap()
            .unwrap();
        assert_eq!((f.id(), f.data()), (0x1060_642A, &[3u8, 0xE0][..]));
        assert_eq!(f.timestamp.as_micros(), 1_700_000_000_123_456);
        let fd = parse_candump_line("(1.5) vcan0 0C64D22A##1")
            .unwrap()
            .unwrap();
        assert!(fd.data().is_empty());
        assert!(parse_candump_line("(1.0) can0 123#11").unwrap().is_none());
        assert!(parse_candump_line("").unwrap().is_none());
        for (bad, why) in [
            ("1.0 can0 1060642A#03", "timestamp"),
            ("(1.0) can0 1060642A03", "ID#DATA"),
            ("(1.0) can0 1060642A#0", "whole bytes"),
            ("(1.0) can0 1060642A#ZZ", "hexadecimal"),
            ("(1.0) can0", "no frame"),
        ] {
            let e = parse_candump_line(bad).unwrap_err();
            assert!(e.contains(why), "{bad}: {e}");
        }
    }
}
