//! Register files: the text form of a node's registers, one `name: value` (or `name = value`)
//! per line, `#` comments, values as environment variables write them (space-separated numbers,
//! or text). `propid drive --registers FILE` reads one before the environment and the flags, and
//! rewrites it when a register is written over the bus. (PyCyphal's own register files are
//! SQLite databases; they are not read.)

use std::fmt;

use propid_core::dsdl::Value;
use propid_core::node::parse_value;
use propid_drive_proto::registers::normalize_bool;
use propid_drive_proto::HostRegistry;

/// One `name: value` line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Entry {
    /// Its line number, from 1.
    pub line: usize,
    /// The register's name.
    pub name: String,
    /// The value as written.
    pub value: String,
}

/// A line that is not `name: value`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LineError {
    /// Its line number, from 1.
    pub line: usize,
    /// The line as written.
    pub text: String,
}

impl fmt::Display for LineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "expected `name: value`, got `{}`", self.text)
    }
}

/// The entries of a register file, and every line that is not one.
pub fn read_entries(contents: &str) -> (Vec<Entry>, Vec<LineError>) {
    let (mut entries, mut errors) = (Vec::new(), Vec::new());
    for (i, line) in contents.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        match line.split_once(':').or_else(|| line.split_once('=')) {
            Some((name, value)) => entries.push(Entry {
                line: i + 1,
                name: name.trim().to_string(),
                value: value.trim().to_string(),
            }),
            None => errors.push(LineError {
                line: i + 1,
                text: line.to_string(),
            }),
        }
    }
    (entries, errors)
}

/// The value `text` gives a register holding `current`, by PyCyphal's rules (`true`/`false`
/// for bits); `None` where PyCyphal refuses it.
pub fn parse_text(current: &Value, text: &str) -> Option<Value> {
    parse_value(current, normalize_bool(text))
}

/// A register file's text holding the mutable registers' values (what [`read_entries`] reads).
pub fn render_file(r: &HostRegistry) -> String {
    let mut out = String::from("# propid registers: name: value (see docs/REGISTERS.md)\n");
    for reg in r.iter().filter(|x| x.mutable) {
        let value = match &reg.value {
            v if v.is_numeric() => (0..v.len())
                .filter_map(|i| v.float_at(i))
                .map(|x| format!("{x}"))
                .collect::<Vec<_>>()
                .join(" "),
            v => v.as_str().unwrap_or("").to_string(),
        };
        out += &format!("{}: {value}\n", reg.name.as_str().unwrap_or("?"));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_drive_proto::registers::drive_defaults;

    #[test]
    fn lines_comments_and_both_separators() {
        let text = "# the seed's example\nuavcan.node.id: 10\n\nuavcan.pub.sp_rat.id = 24 # port\njust text\n";
        let (entries, errors) = read_entries(text);
        let got: Vec<(usize, &str, &str)> = entries
            .iter()
            .map(|e| (e.line, e.name.as_str(), e.value.as_str()))
            .collect();
        assert_eq!(
            got,
            [
                (2, "uavcan.node.id", "10"),
                (4, "uavcan.pub.sp_rat.id", "24")
            ]
        );
        assert_eq!(
            errors,
            [LineError {
                line: 5,
                text: "just text".into()
            }]
        );
        assert_eq!(
            errors[0].to_string(),
            "expected `name: value`, got `just text`"
        );
    }

    #[test]
    fn a_rendered_file_reads_back() {
        let mut r = drive_defaults(true);
        let period = parse_text(&r.get("period").unwrap().value, "2.5").unwrap();
        r.set("period", &period).unwrap();
        assert!(parse_text(&period, "fast").is_none());
        let (entries, errors) = read_entries(&render_file(&r));
        assert!(errors.is_empty());
        let period = entries.iter().find(|e| e.name == "period").unwrap();
        assert_eq!(period.value, "2.5");
        assert!(entries.iter().all(|e| !e.name.ends_with(".type")));
    }
}
