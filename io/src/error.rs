//! Bad input, typed: where it is ([`Place`]: file, line, column) and what is wrong with it
//! ([`ErrorKind`]), rendered once by `Display` as `FILE: line N, column `C`: WHAT`.
//!
//! Code matches on the kind, never on a message's wording; the message is for a person, and
//! says what to do where there is something to do. A value check that has no better kind (a
//! flag out of range, a fitted value that is not physical) is [`ErrorKind::Invalid`] with its
//! message, built by [`InputError::invalid`].

use std::fmt;
use std::path::Path;

/// Where in the input a problem is. Each part is optional: a flag's value has no file, a
/// header problem has no column, a file-wide problem has no line.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Place {
    /// The file's name as the user gave it, or `<stdin>`.
    pub file: Option<String>,
    /// 1-based line number.
    pub line: Option<u64>,
    /// The column's name as the file spells it.
    pub column: Option<String>,
}

/// A compressed format recognised by its first bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compression {
    /// gzip (RFC 1952), `1f 8b`: read transparently by [`crate::input::open`].
    Gzip,
    /// Zstandard, `28 b5 2f fd`: refused, with the command that decompresses it.
    Zstd,
    /// xz, `fd 37 7a 58 5a 00`: refused likewise.
    Xz,
    /// bzip2, `42 5a 68`: refused likewise.
    Bzip2,
    /// A zip archive, `50 4b 03 04`: refused likewise.
    Zip,
}

impl Compression {
    /// The format of a stream that starts with `head`, if it is one of these.
    pub fn sniff(head: &[u8]) -> Option<Compression> {
        const MAGIC: [(&[u8], Compression); 5] = [
            (&[0x1f, 0x8b], Compression::Gzip),
            (&[0x28, 0xb5, 0x2f, 0xfd], Compression::Zstd),
            (&[0xfd, 0x37, 0x7a, 0x58, 0x5a, 0x00], Compression::Xz),
            (b"BZh", Compression::Bzip2),
            (&[0x50, 0x4b, 0x03, 0x04], Compression::Zip),
        ];
        MAGIC
            .iter()
            .find(|(magic, _)| head.starts_with(magic))
            .map(|(_, c)| *c)
    }

    /// The format's name.
    pub fn name(self) -> &'static str {
        match self {
            Compression::Gzip => "gzip",
            Compression::Zstd => "zstd",
            Compression::Xz => "xz",
            Compression::Bzip2 => "bzip2",
            Compression::Zip => "zip",
        }
    }

    /// The command that writes the stream's content to standard output.
    fn unpack(self) -> &'static str {
        match self {
            Compression::Gzip => "gzip -dc",
            Compression::Zstd => "zstd -dc",
            Compression::Xz => "xz -dc",
            Compression::Bzip2 => "bzip2 -dc",
            Compression::Zip => "unzip -p",
        }
    }
}

/// The importers (`propid import …`), for errors that name the one to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Importer {
    /// RCbenchmark / Tyto Robotics CSV exports.
    Rcbench,
    /// AutoQuad ESC32 telemetry CSV.
    Autoquad,
}

impl Importer {
    /// What such a file is.
    pub fn what(self) -> &'static str {
        match self {
            Importer::Rcbench => "an RCbenchmark/Tyto CSV export",
            Importer::Autoquad => "an AutoQuad ESC32 telemetry CSV",
        }
    }

    /// The command that converts it.
    pub fn command(self) -> &'static str {
        match self {
            Importer::Rcbench => "propid import rcbench FILE -o run.tsv",
            Importer::Autoquad => "propid import autoquad FILE --kv KV -o run.tsv",
        }
    }
}

/// What is wrong.
#[derive(Clone, Debug, PartialEq)]
pub enum ErrorKind {
    /// A field is not a number.
    NotANumber {
        /// The field's text (at most 40 characters of it).
        text: String,
    },
    /// The header lacks a column the reader needs.
    MissingColumn {
        /// The column wanted (`a` or `b` when several spellings are accepted).
        wanted: String,
        /// The header's columns, comma-separated (shortened when long).
        columns: String,
    },
    /// A row ends before a column it must have.
    ShortRow {
        /// Fields in the row.
        found: usize,
        /// 1-based index of the column.
        needed: usize,
    },
    /// The input is empty: no header line.
    Empty,
    /// A header but no data rows.
    NoRows,
    /// The time does not increase from the previous row.
    TimeNotIncreasing {
        /// The previous row's time [s].
        previous: f64,
        /// This row's time [s].
        time: f64,
    },
    /// A line longer than the bound (its text is never echoed).
    LineTooLong {
        /// The bound [bytes].
        limit: usize,
    },
    /// A compressed stream where text was expected.
    Compressed(Compression),
    /// Bytes that are not text (a NUL byte, or not UTF-8 where text is required).
    NotText,
    /// The operating system refused (opening, reading, mapping, writing); its words, once.
    Os {
        /// What was being done: `cannot open`, `cannot read`, ….
        action: &'static str,
        /// The system's message, without the `(os error N)` suffix.
        message: String,
    },
    /// A directory where a file was expected.
    IsADirectory,
    /// The file is a stand's own export, which an importer converts.
    ForeignFormat(Importer),
    /// An output path that names an input: writing it would destroy what is being read.
    OutputIsInput {
        /// The output path as given.
        output: String,
    },
    /// The data cannot support a verdict (exit status 3, distinct from bad input).
    CannotJudge(String),
    /// Any other check of a value, in words (the message names its place itself).
    Invalid(String),
}

/// An error caused by bad input (a file's content, a value given by the user): where and what.
/// `Display` renders it once: `run.tsv: line 7, column `velocity`: `abc` is not a number`.
#[derive(Clone, Debug, PartialEq)]
pub struct InputError {
    /// Where.
    pub place: Place,
    /// What.
    pub kind: ErrorKind,
}

impl std::error::Error for InputError {}

impl InputError {
    /// An error of `kind` with no place yet (add one with [`InputError::in_file`] and the
    /// others).
    pub fn new(kind: ErrorKind) -> InputError {
        InputError {
            place: Place::default(),
            kind,
        }
    }

    /// A value check in words ([`ErrorKind::Invalid`]); the message names its place itself.
    pub fn invalid(message: String) -> InputError {
        InputError::new(ErrorKind::Invalid(message))
    }

    /// The data cannot support a verdict ([`ErrorKind::CannotJudge`]).
    pub fn cannot_judge(message: String) -> InputError {
        InputError::new(ErrorKind::CannotJudge(message))
    }

    /// The operating system's refusal to `action` (`cannot open`, …) the file `file`. A
    /// directory is [`ErrorKind::IsADirectory`].
    pub fn os(file: impl Into<String>, action: &'static str, error: &std::io::Error) -> InputError {
        // A reader of propid's own (the line limit) reports bad input through `io::Error`.
        if let Some(inner) = error.get_ref().and_then(|e| e.downcast_ref::<InputError>()) {
            return inner.clone().in_file(file);
        }
        let kind = if error.kind() == std::io::ErrorKind::IsADirectory {
            ErrorKind::IsADirectory
        } else {
            ErrorKind::Os {
                action,
                message: os_message(error),
            }
        };
        InputError::new(kind).in_file(file)
    }

    /// The same error in `file`.
    pub fn in_file(mut self, file: impl Into<String>) -> InputError {
        self.place.file = Some(file.into());
        self
    }

    /// The same error at 1-based `line`.
    pub fn at_line(mut self, line: u64) -> InputError {
        self.place.line = Some(line);
        self
    }

    /// The same error in `column`.
    pub fn in_column(mut self, column: impl Into<String>) -> InputError {
        self.place.column = Some(column.into());
        self
    }

    /// True for [`ErrorKind::CannotJudge`].
    pub fn is_cannot_judge(&self) -> bool {
        matches!(self.kind, ErrorKind::CannotJudge(_))
    }
}

/// The display name of a path: `<stdin>` for `-`.
pub fn display_name(path: &Path) -> String {
    if path == Path::new("-") {
        "<stdin>".into()
    } else {
        path.display().to_string()
    }
}

/// The system's message without Rust's ` (os error N)` suffix (the words are the point; the
/// number only repeats them).
pub(crate) fn os_message(error: &std::io::Error) -> String {
    let text = error.to_string();
    match text.find(" (os error ") {
        Some(i) => text[..i].to_string(),
        None => text,
    }
}

impl fmt::Display for ErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ErrorKind::NotANumber { text } => write!(f, "`{text}` is not a number"),
            ErrorKind::MissingColumn { wanted, columns } => {
                write!(f, "no column `{wanted}` (the header has: {columns})")
            }
            ErrorKind::ShortRow { found, needed } => write!(
                f,
                "missing (the row has {found} fields, the column is field {needed})"
            ),
            ErrorKind::Empty => f.write_str("empty input (no header line)"),
            ErrorKind::NoRows => f.write_str("no data rows after the header"),
            ErrorKind::TimeNotIncreasing { previous, time } => write!(
                f,
                "time does not increase ({time} s after {previous} s)"
            ),
            ErrorKind::LineTooLong { limit } => write!(
                f,
                "the line is longer than {} KiB without a line end: not a line of a log (is it the right file?)",
                limit >> 10
            ),
            ErrorKind::Compressed(c) => write!(
                f,
                "{} compressed; propid reads gzip itself, other formats must be decompressed first: `{} FILE > run.tsv`",
                c.name(),
                c.unpack()
            ),
            ErrorKind::NotText => f.write_str(
                "not text (binary bytes: a NUL byte or bytes that are not UTF-8); propid reads TSV and CSV logs",
            ),
            ErrorKind::Os { action, message } => write!(f, "{action}: {message}"),
            ErrorKind::IsADirectory => f.write_str("is a directory, not a file"),
            ErrorKind::ForeignFormat(importer) => write!(
                f,
                "this is {}, not propid's TSV: convert it first with `{}`{}",
                importer.what(),
                importer.command(),
                match importer {
                    Importer::Autoquad => " (KV: the motor's rpm per volt)",
                    Importer::Rcbench => "",
                }
            ),
            ErrorKind::OutputIsInput { output } => write!(
                f,
                "the output `{output}` is this input file: writing it would destroy what is being read; choose another output path"
            ),
            ErrorKind::CannotJudge(message) => write!(f, "cannot judge: {message}"),
            ErrorKind::Invalid(message) => f.write_str(message),
        }
    }
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = &self.place;
        if let Some(file) = &p.file {
            write!(f, "{file}: ")?;
        }
        match (p.line, &p.column) {
            (Some(line), Some(column)) => write!(f, "line {line}, column `{column}`: ")?,
            (Some(line), None) => write!(f, "line {line}: ")?,
            (None, Some(column)) => write!(f, "column `{column}`: ")?,
            (None, None) => {}
        }
        write!(f, "{}", self.kind)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rendered_once_with_the_place() {
        let e = InputError::new(ErrorKind::NotANumber { text: "abc".into() })
            .in_file("run.tsv")
            .at_line(7)
            .in_column("velocity");
        assert_eq!(
            e.to_string(),
            "run.tsv: line 7, column `velocity`: `abc` is not a number"
        );
        let os = std::io::Error::from_raw_os_error(13);
        let e = InputError::os("secret.tsv", "cannot open", &os);
        assert_eq!(e.to_string(), "secret.tsv: cannot open: Permission denied");
        let dir = std::io::Error::from(std::io::ErrorKind::IsADirectory);
        let e = InputError::os("logs", "cannot read", &dir);
        assert_eq!(e.kind, ErrorKind::IsADirectory);
        assert_eq!(e.to_string(), "logs: is a directory, not a file");
        assert_eq!(
            InputError::invalid("kv must be positive".into()).to_string(),
            "kv must be positive"
        );
        assert!(InputError::cannot_judge("x".into()).is_cannot_judge());
        assert_eq!(
            Compression::sniff(&[0x1f, 0x8b, 8, 0]),
            Some(Compression::Gzip)
        );
        assert_eq!(Compression::sniff(b"ts_local\tt"), None);
    }
}
