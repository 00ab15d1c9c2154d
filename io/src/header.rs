//! A stand's own export recognised by its header line, and header names compared loosely: what
//! both the TSV reader (to tell a user who gave it a stand's CSV which importer reads it) and the
//! importers (to find their columns) need, so neither depends on the other for it.

use crate::error::Importer;

/// The importer for a file whose first line is `header`, when it is a stand's own export (what a
/// TSV reader tells a user who gave it one).
pub(crate) fn recognise(header: &str) -> Option<Importer> {
    let names: Vec<String> = header.split(',').map(loose).collect();
    if names.len() < 3 {
        return None;
    }
    let has = |n: &str| names.iter().any(|h| *h == loose(n));
    let starts = |n: &str| names.iter().any(|h| h.starts_with(&loose(n)));
    if has("Timestamp") && has("Amps") && has("RPM") && has("Duty") {
        Some(Importer::Autoquad)
    } else if (starts("Time (") || has("Time")) && (starts("Torque (") || starts("Thrust (")) {
        Some(Importer::Rcbench)
    } else {
        None
    }
}

/// A header name compared loosely: no byte-order mark, lower case, `µ`/`μ` as `u`, and no
/// spaces, `·`, `-` or `.` (so `Torque (N·m)`, `Torque (N-m)` and `torque (Nm)` are one name).
pub(crate) fn loose(name: &str) -> String {
    name.trim_start_matches('\u{feff}')
        .to_lowercase()
        .replace(['µ', 'μ'], "u")
        .chars()
        .filter(|c| !matches!(c, ' ' | '·' | '-' | '.' | '\u{22c5}'))
        .collect()
}
