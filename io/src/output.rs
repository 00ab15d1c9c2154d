//! Writing what a command produces without ever destroying what it reads.
//!
//! [`AtomicOutput`] refuses an output path that is one of the command's inputs (the same file,
//! however it is spelled: a link, `./run.tsv`), and otherwise writes into a temporary file in the
//! output's own directory, renamed over the output only by [`AtomicOutput::commit`], after the
//! work is done. A command that fails midway leaves the old output (if any) as it was and no
//! half-written file.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::error::{os_message, ErrorKind, InputError};

/// An output file being written (see the module's notes).
pub struct AtomicOutput {
    path: PathBuf,
    sink: Sink,
}

enum Sink {
    /// A temporary file, renamed over `target` on commit.
    Temporary {
        file: BufWriter<tempfile::NamedTempFile>,
        target: PathBuf,
    },
    /// Something that is not a regular file (`/dev/null`, `/dev/full`, a FIFO): written
    /// directly, since renaming over it would replace the device with a file.
    Direct(BufWriter<std::fs::File>),
}

impl AtomicOutput {
    /// Starts writing `path`, refusing it if it is one of `inputs` ([`ErrorKind::OutputIsInput`])
    /// or if its directory cannot take a new file (the OS's reason, with the path). An existing
    /// output that is not a regular file (a device, a FIFO) is written directly; a symbolic link
    /// is followed, so the file it names is replaced, not the link.
    pub fn create(path: &Path, inputs: &[&Path]) -> Result<AtomicOutput, InputError> {
        let name = path.display().to_string();
        if let Some(input) = inputs.iter().find(|input| same_file(path, input)) {
            return Err(InputError::new(ErrorKind::OutputIsInput { output: name })
                .in_file(input.display().to_string()));
        }
        let sink = match std::fs::metadata(path) {
            Ok(m) if m.is_dir() => {
                return Err(InputError::new(ErrorKind::IsADirectory).in_file(name));
            }
            Ok(m) if !m.is_file() => Sink::Direct(BufWriter::new(
                std::fs::OpenOptions::new()
                    .write(true)
                    .open(path)
                    .map_err(|e| InputError::os(name.clone(), "cannot open", &e))?,
            )),
            exists => {
                // The file a link names is the one to replace.
                let target = match exists {
                    Ok(_) => std::fs::canonicalize(path).unwrap_or_else(|_| path.to_owned()),
                    Err(_) => path.to_owned(),
                };
                let dir = match target.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d,
                    _ => Path::new("."),
                };
                let mut builder = tempfile::Builder::new();
                // A new output gets the mode any new file gets (0666 less the umask), not a
                // temporary file's 0600; a replaced one keeps its own.
                #[cfg(unix)]
                {
                    use std::os::unix::fs::PermissionsExt;
                    builder.permissions(match &exists {
                        Ok(m) => m.permissions(),
                        Err(_) => std::fs::Permissions::from_mode(0o666),
                    });
                }
                let file = builder
                    .prefix(&format!(
                        ".{}.",
                        target
                            .file_name()
                            .map_or("out".into(), |n| n.to_string_lossy())
                    ))
                    .suffix(".partial")
                    .tempfile_in(dir)
                    .map_err(|e| InputError::os(name.clone(), "cannot create", &e))?;
                Sink::Temporary {
                    file: BufWriter::new(file),
                    target,
                }
            }
        };
        Ok(AtomicOutput {
            path: path.to_owned(),
            sink,
        })
    }

    /// The path it will have.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flushes and renames the temporary file over the output: the output now holds everything
    /// written, whole (an existing file is replaced only here).
    pub fn commit(self) -> std::io::Result<()> {
        let name = self.path.display().to_string();
        let fail = |e| with_path(&name, "cannot write", e);
        match self.sink {
            Sink::Direct(mut file) => file.flush().map_err(fail),
            Sink::Temporary { file, target } => {
                let tmp = file.into_inner().map_err(|e| fail(e.into_error()))?;
                tmp.as_file().sync_all().map_err(fail)?;
                tmp.persist(&target).map_err(|e| fail(e.error))?;
                Ok(())
            }
        }
    }
}

impl Write for AtomicOutput {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match &mut self.sink {
            Sink::Temporary { file, .. } => file.write(buf),
            Sink::Direct(file) => file.write(buf),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        match &mut self.sink {
            Sink::Temporary { file, .. } => file.flush(),
            Sink::Direct(file) => file.flush(),
        }
    }
}

/// An I/O error that names the path once: `out.tsv: cannot write: No space left on device`.
fn with_path(name: &str, action: &str, e: std::io::Error) -> std::io::Error {
    std::io::Error::new(e.kind(), format!("{name}: {action}: {}", os_message(&e)))
}

/// True if `a` and `b` name the same existing file.
fn same_file(a: &Path, b: &Path) -> bool {
    if b == Path::new("-") {
        return false;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (std::fs::metadata(a), std::fs::metadata(b)) {
            (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
            (Ok(x), Ok(y)) => x == y,
            _ => false,
        }
    }
}

/// Opens `path` for writing through [`AtomicOutput`] unless it is `-` (standard output).
pub enum Output {
    /// Standard output.
    Stdout(std::io::StdoutLock<'static>),
    /// A file, committed by [`Output::finish`].
    File(AtomicOutput),
}

impl Output {
    /// `None` or `-` is standard output; anything else an [`AtomicOutput`] refused if it is one
    /// of `inputs`.
    pub fn create(path: Option<&Path>, inputs: &[&Path]) -> Result<Output, InputError> {
        match path {
            None => Ok(Output::Stdout(std::io::stdout().lock())),
            Some(p) if p == Path::new("-") => Ok(Output::Stdout(std::io::stdout().lock())),
            Some(p) => AtomicOutput::create(p, inputs).map(Output::File),
        }
    }

    /// The name for messages.
    pub fn name(&self) -> String {
        match self {
            Output::Stdout(_) => "standard output".into(),
            Output::File(f) => f.path().display().to_string(),
        }
    }

    /// Flushes standard output, or commits the file.
    pub fn finish(self) -> std::io::Result<()> {
        match self {
            Output::Stdout(mut s) => s.flush(),
            Output::File(f) => f.commit(),
        }
    }
}

impl Write for Output {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match self {
            Output::Stdout(s) => s.write(buf),
            Output::File(f) => f.write(buf),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        match self {
            Output::Stdout(s) => s.flush(),
            Output::File(f) => f.flush(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A new output has the mode `File::create` gives (0666 less the umask), not a temporary
    /// file's 0600; a replaced output keeps the mode it had.
    #[cfg(unix)]
    #[test]
    fn an_output_has_a_new_files_mode_or_keeps_its_own() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let plain = dir.path().join("plain");
        std::fs::File::create(&plain).unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        let out = dir.path().join("out.html");
        let mut w = AtomicOutput::create(&out, &[]).unwrap();
        w.write_all(b"page").unwrap();
        w.commit().unwrap();
        assert_eq!(mode(&out), mode(&plain));
        std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o640)).unwrap();
        let mut w = AtomicOutput::create(&out, &[]).unwrap();
        w.write_all(b"again").unwrap();
        w.commit().unwrap();
        assert_eq!(mode(&out), 0o640);
    }

    #[test]
    fn an_input_is_never_the_output_and_nothing_is_half_written() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("run.tsv");
        std::fs::write(&input, "keep me").unwrap();
        // The same file by another spelling.
        let other = dir.path().join(".").join("run.tsv");
        let e = AtomicOutput::create(&other, &[&input]).err().unwrap();
        assert!(matches!(e.kind, ErrorKind::OutputIsInput { .. }), "{e}");
        assert!(e.to_string().contains("choose another output path"), "{e}");
        assert_eq!(std::fs::read_to_string(&input).unwrap(), "keep me");
        // Written only on commit; dropped without it, nothing is left.
        let out = dir.path().join("out.html");
        let mut w = AtomicOutput::create(&out, &[&input]).unwrap();
        w.write_all(b"half").unwrap();
        drop(w);
        assert!(!out.exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        let mut w = AtomicOutput::create(&out, &[&input]).unwrap();
        w.write_all(b"whole").unwrap();
        w.commit().unwrap();
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "whole");
        // A device is written directly, never replaced by a file.
        let mut w = AtomicOutput::create(Path::new("/dev/null"), &[]).unwrap();
        w.write_all(b"gone").unwrap();
        w.commit().unwrap();
        assert!(!std::fs::metadata("/dev/null").unwrap().is_file());
        // A link: the file it names is replaced, the link stays a link.
        #[cfg(unix)]
        {
            let link = dir.path().join("link.html");
            std::os::unix::fs::symlink(&out, &link).unwrap();
            let mut w = AtomicOutput::create(&link, &[]).unwrap();
            w.write_all(b"through the link").unwrap();
            w.commit().unwrap();
            assert!(std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink());
            assert_eq!(std::fs::read_to_string(&out).unwrap(), "through the link");
        }
        // A directory that does not exist: named once.
        let e = AtomicOutput::create(&dir.path().join("no/such/out.tsv"), &[])
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.ends_with("no/such/out.tsv: cannot create: No such file or directory"),
            "{e}"
        );
    }
}
