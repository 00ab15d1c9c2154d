//! Opening what a command reads: a file or standard input (`-`), read in bounded memory.
//!
//! ```text
//!  path ─► directory? ─► File::open ─► first bytes: gzip? ─► gzip decoder ─┐
//!  "-"  ─► standard input ───────────►   zstd/xz/bzip2/zip/NUL? refused   ─┴─► LineLimit ─► BufRead
//! ```
//! - Every OS error is reported once, with the path: `run.tsv: cannot open: Permission denied`.
//! - gzip is recognised by its magic bytes, not by the file's name, and read transparently (flate2,
//!   a pure-Rust inflater already in the build). Other compressions and binary files are refused
//!   in plain words, with the command that decompresses them.
//! - No line may be longer than [`MAX_LINE`]: a file without line ends (a 2 GiB dump, `/dev/zero`)
//!   is an error naming the line after at most that many bytes, never read whole.

use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use crate::error::{display_name, Compression, ErrorKind, InputError};
pub use crate::tsv::MAX_LINE;

/// An opened input: decompressed, its lines bounded, named for messages.
pub struct Input {
    name: String,
    compression: Option<Compression>,
    reader: BufReader<LineLimit<Box<dyn Read + Send>>>,
}

/// Opens `path` for reading (`-`: standard input). See the module's notes for what is refused.
pub fn open(path: &Path) -> Result<Input, InputError> {
    let name = display_name(path);
    let raw: Box<dyn Read + Send> = if path == Path::new("-") {
        Box::new(std::io::stdin())
    } else {
        // A directory opens on some systems and fails on the first read: say what it is first.
        if std::fs::metadata(path).is_ok_and(|m| m.is_dir()) {
            return Err(InputError::new(ErrorKind::IsADirectory).in_file(name));
        }
        Box::new(File::open(path).map_err(|e| InputError::os(name.clone(), "cannot open", &e))?)
    };
    from_reader(raw, name)
}

/// A file that can be memory-mapped: the path itself when it is a plain file
/// ([`is_plain_file`]), else a temporary copy of what [`open`] reads from it (standard input, a
/// pipe, a gzip file), deleted when this is dropped.
pub struct Mappable {
    given: String,
    spool: Option<tempfile::NamedTempFile>,
    path: std::path::PathBuf,
}

impl Mappable {
    /// Prepares `path` (`-`: standard input).
    pub fn new(path: &Path) -> Result<Mappable, InputError> {
        let spool = if is_plain_file(path)? {
            None
        } else {
            Some(open(path)?.spool()?)
        };
        Ok(Mappable {
            given: display_name(path),
            path: spool
                .as_ref()
                .map_or_else(|| path.to_owned(), |s| s.path().to_owned()),
            spool,
        })
    }

    /// The path to map.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The input's name as the user gave it (`<stdin>` for `-`).
    pub fn name(&self) -> &str {
        &self.given
    }

    /// `e` naming the input as the user gave it rather than a spool file.
    pub fn rename(&self, mut e: InputError) -> InputError {
        if self.spool.is_some() && e.place.file.is_some() {
            e.place.file = Some(self.given.clone());
        }
        e
    }
}

/// True if `path` is a regular file that starts as text, not compressed (what can be
/// memory-mapped and read as it is); false for standard input (`-`), a pipe or a compressed
/// file, which go through [`open`]. The OS's refusal to open it is an error naming the path.
pub fn is_plain_file(path: &Path) -> Result<bool, InputError> {
    if path == Path::new("-") {
        return Ok(false);
    }
    let name = display_name(path);
    let meta =
        std::fs::metadata(path).map_err(|e| InputError::os(name.clone(), "cannot open", &e))?;
    if meta.is_dir() {
        return Err(InputError::new(ErrorKind::IsADirectory).in_file(name));
    }
    if !meta.is_file() {
        return Ok(false);
    }
    let mut head = [0u8; 8];
    let mut file = File::open(path).map_err(|e| InputError::os(name.clone(), "cannot open", &e))?;
    let mut n = 0;
    while n < head.len() {
        match file.read(&mut head[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(InputError::os(name, "cannot read", &e)),
        }
    }
    Ok(Compression::sniff(&head[..n]).is_none())
}

/// [`open`] for a reader already open (named `name` in messages).
pub fn from_reader(raw: Box<dyn Read + Send>, name: String) -> Result<Input, InputError> {
    let mut raw = BufReader::with_capacity(64 << 10, raw);
    let head = raw
        .fill_buf()
        .map_err(|e| InputError::os(name.clone(), "cannot read", &e))?;
    let compression = Compression::sniff(head);
    let decoded: Box<dyn Read + Send> = match compression {
        None if head.contains(&0) => return Err(InputError::new(ErrorKind::NotText).in_file(name)),
        None => Box::new(raw),
        Some(Compression::Gzip) => Box::new(flate2::read::MultiGzDecoder::new(raw)),
        Some(other) => return Err(InputError::new(ErrorKind::Compressed(other)).in_file(name)),
    };
    Ok(Input {
        name,
        compression,
        reader: BufReader::with_capacity(64 << 10, LineLimit::new(decoded)),
    })
}

impl Input {
    /// The name for messages (`<stdin>` for `-`).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The compression read through, if any.
    pub fn compression(&self) -> Option<Compression> {
        self.compression
    }

    /// Copies the whole (decompressed) input into a new temporary file, for readers that need
    /// a regular file (the fit maps it). Lines stay bounded, so the copy of an endless stream
    /// stops with an error.
    pub fn spool(mut self) -> Result<tempfile::NamedTempFile, InputError> {
        let mut tmp = tempfile::NamedTempFile::new()
            .map_err(|e| InputError::os("a temporary file", "cannot create", &e))?;
        std::io::copy(&mut self.reader, tmp.as_file_mut()).map_err(|e| {
            self.read_error(&e)
                .unwrap_or_else(|| InputError::os("a temporary file", "cannot write", &e))
        })?;
        Ok(tmp)
    }

    /// The error a failed read of this input means, if the input failed (not the writer).
    fn read_error(&self, e: &std::io::Error) -> Option<InputError> {
        let limit = self.reader.get_ref();
        limit.failed.then(|| error_of(&self.name, e, limit.line))
    }
}

/// An I/O error met while reading `name` at about `line`, as an input error: the line limit's
/// own error, or the system's.
pub fn error_of(name: &str, e: &std::io::Error, line: u64) -> InputError {
    let error = InputError::os(name, "cannot read", e);
    if error.place.line.is_some() {
        error
    } else {
        error.at_line(line)
    }
}

impl Read for Input {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        self.reader.read(buf)
    }
}

impl BufRead for Input {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        self.reader.fill_buf()
    }

    fn consume(&mut self, amount: usize) {
        self.reader.consume(amount)
    }
}

/// A reader that fails (with an [`InputError`] of kind [`ErrorKind::LineTooLong`] inside the
/// `io::Error`, see [`error_of`]) once a line grows past [`MAX_LINE`] bytes, so that no reader
/// above it buffers an unbounded line. Counts lines for the message.
pub struct LineLimit<R> {
    inner: R,
    /// Bytes since the last `\n`.
    run: usize,
    /// 1-based number of the line being read.
    line: u64,
    /// The inner reader failed (or the limit was hit): errors after this are the input's.
    failed: bool,
}

impl<R> LineLimit<R> {
    /// Wraps `inner`.
    pub fn new(inner: R) -> LineLimit<R> {
        LineLimit {
            inner,
            run: 0,
            line: 1,
            failed: false,
        }
    }

    /// The 1-based number of the line being read.
    pub fn line(&self) -> u64 {
        self.line
    }
}

impl<R: Read> Read for LineLimit<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf).inspect_err(|_| self.failed = true)?;
        for chunk in buf[..n].split_inclusive(|b| *b == b'\n') {
            if chunk.last() == Some(&b'\n') {
                self.line += 1;
                self.run = 0;
            } else {
                self.run += chunk.len();
            }
        }
        // `\r\n` line ends and a little slack: the same bound as the TSV reader's.
        if self.run > MAX_LINE + 2 {
            self.failed = true;
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                InputError::new(ErrorKind::LineTooLong { limit: MAX_LINE }).at_line(self.line),
            ));
        }
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn gzip_is_read_through_and_other_compressions_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("run.tsv.gz");
        let text = "t\tforce\tvelocity\tacceleration\n1\t2\t3\t4\n";
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        gz.write_all(text.as_bytes()).unwrap();
        std::fs::write(&p, gz.finish().unwrap()).unwrap();
        let mut input = open(&p).unwrap();
        assert_eq!(input.compression(), Some(Compression::Gzip));
        let mut back = String::new();
        input.read_to_string(&mut back).unwrap();
        assert_eq!(back, text);
        std::fs::write(&p, [0x28, 0xb5, 0x2f, 0xfd, 0, 0]).unwrap();
        let e = open(&p).err().unwrap();
        assert_eq!(e.kind, ErrorKind::Compressed(Compression::Zstd));
        assert!(e.to_string().contains("zstd -dc FILE > run.tsv"), "{e}");
        // A directory, a missing file: named once, with the path.
        let e = open(dir.path()).err().unwrap();
        assert_eq!(e.kind, ErrorKind::IsADirectory);
        let missing = dir.path().join("nope.tsv");
        let e = open(&missing).err().unwrap().to_string();
        assert_eq!(
            e,
            format!(
                "{}: cannot open: No such file or directory",
                missing.display()
            )
        );
    }

    #[test]
    fn an_endless_line_stops_at_the_bound_with_its_number() {
        let head: &'static [u8] = b"a,b\n1,2\n";
        let endless = std::io::Read::chain(head, std::io::repeat(b'9'));
        let mut input = from_reader(Box::new(endless), "x.csv".into()).unwrap();
        let mut sink = Vec::new();
        let e = std::io::copy(&mut input, &mut sink).err().unwrap();
        let e = error_of("x.csv", &e, 0);
        assert_eq!(e.kind, ErrorKind::LineTooLong { limit: MAX_LINE });
        assert_eq!(
            e.to_string().split(':').take(2).collect::<Vec<_>>(),
            ["x.csv", " line 3"]
        );
        assert!(sink.len() < 2 * MAX_LINE + 1024);
        // The spool of an endless stream stops too.
        let endless = std::io::Read::chain(head, std::io::repeat(b'9'));
        let input = from_reader(Box::new(endless), "<stdin>".into()).unwrap();
        let e = input.spool().err().unwrap();
        assert_eq!(e.kind, ErrorKind::LineTooLong { limit: MAX_LINE });
        // NUL bytes (/dev/zero) are not text.
        let e = from_reader(Box::new(std::io::repeat(0)), "<stdin>".into())
            .err()
            .unwrap();
        assert_eq!(e.kind, ErrorKind::NotText);
    }
}
