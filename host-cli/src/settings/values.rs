//! How text becomes values, shared by the settings of every command: numbers as a `real64[N]`
//! register takes them, IDs (65535: unset), the frame size, bits.

use propid_core::can::{IdError, Mtu, NodeId, SubjectId};
use propid_drive_proto::registers::UNSET;
use propid_drive_proto::settings::{Range, RangeError, SetpointRange};

use super::Problem;

/// `N` numbers, space- (or comma-) separated: a `real64[N]` register's text.
pub fn numbers<const N: usize>(text: &str) -> Result<[f64; N], Problem> {
    const TYPES: [&str; 3] = ["real64[0]", "real64[1]", "real64[2]"];
    let bad = || Problem::Type {
        text: text.to_string(),
        ty: TYPES.get(N).copied().unwrap_or("real64 array"),
    };
    let v: Vec<f64> = text
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<f64>().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    v.try_into().map_err(|_| bad())
}

/// One number checked by `make` (a range type's `new`).
pub fn number<T>(text: &str, make: fn(f64) -> Result<T, RangeError>) -> Result<T, Problem> {
    let [x] = numbers::<1>(text)?;
    make(x).map_err(Problem::Range)
}

/// A number of seconds in `range` (settings whose range is theirs alone, not a machine's type).
pub fn seconds_in(text: &str, range: Range) -> Result<f64, Problem> {
    let [x] = numbers::<1>(text)?;
    if range.contains(x) {
        Ok(x)
    } else {
        Err(Problem::Range(RangeError { range, got: x }))
    }
}

/// The seed's setpoint range, two numbers.
pub fn setpoint_range(text: &str) -> Result<SetpointRange, Problem> {
    let [lo, hi] = numbers::<2>(text)?;
    SetpointRange::new(lo, hi).map_err(Problem::SetpointRange)
}

/// A node-ID; 65535 (the register's "unset") is `None`.
pub fn node_id(text: &str) -> Result<Option<NodeId>, Problem> {
    unset_or(text, |t| t.parse::<NodeId>())
}

/// A subject-ID; 65535 (the register's "unset") is `None`.
pub fn subject_id(text: &str) -> Result<Option<SubjectId>, Problem> {
    unset_or(text, |t| t.parse::<SubjectId>())
}

fn unset_or<T>(text: &str, parse: fn(&str) -> Result<T, IdError>) -> Result<Option<T>, Problem> {
    if text.trim() == UNSET.to_string() {
        return Ok(None);
    }
    parse(text).map(Some).map_err(Problem::Id)
}

/// The frame size: 8 or 64.
pub fn mtu(text: &str) -> Result<Mtu, Problem> {
    text.trim()
        .parse()
        .ok()
        .and_then(Mtu::from_bytes)
        .ok_or_else(|| Problem::Mtu(text.to_string()))
}

/// `true`/`false` (or 1/0, as a `bit` register).
pub fn bit(text: &str) -> Result<bool, Problem> {
    match propid_drive_proto::registers::normalize_bool(text) {
        "1" => Ok(true),
        "0" => Ok(false),
        _ => Err(Problem::Type {
            text: text.to_string(),
            ty: "bit (true or false)",
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_from_text() {
        assert_eq!(numbers::<2>("0.2, 0.8"), Ok([0.2, 0.8]));
        assert!(numbers::<2>("0.2").is_err());
        assert_eq!(node_id("65535"), Ok(None));
        assert_eq!(
            node_id("200").unwrap_err().to_string(),
            "node-ID 200 is out of range: it must be from 0 to 127"
        );
        assert_eq!(mtu("64"), Ok(Mtu::Fd));
        assert!(mtu("16").is_err());
        assert_eq!(bit("False"), Ok(false));
    }
}
