//! Every file the station and the emulator read because a user named it (recordings, arenas,
//! Map and Plan objects, light maps, parameter and key files) comes in here, by one rule, as
//! every file they write leaves through [`crate::output_file`].
//!
//! Layer: file I/O only. The rule: a file is read only if it is a regular file, and only up to
//! its kind's size limit ([`InputKind`]), which the error states. A device (`/dev/zero` never
//! ends, `/dev/urandom` neither), a socket or a directory is refused; a FIFO or pipe is refused
//! too unless the kind takes one (a key from `--key-file <(pass show robot)`), and then it is
//! read up to the limit and no further. The file is opened without blocking (a FIFO with no
//! writer would hang the open) and judged by what was opened (`fstat`), not by its name, so a
//! name swapped for a FIFO between a check and the open gains nothing. A regular file past the
//! limit is refused from its length before a byte is read; one that grows while it is read is
//! cut off at the limit plus one byte and refused. A header may be read from any file that
//! passes the rule ([`read_head`]), to decide what it is before the limit applies.
//! What can fail: [`InputError`], each naming the path.

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

/// What a kind of input file may be.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InputKind {
    /// The kind, plural, for the errors ("recordings", "arena files").
    pub what: &'static str,
    /// Most bytes read.
    pub max_bytes: u64,
    /// A FIFO or pipe is read (up to `max_bytes`) instead of refused.
    pub pipes: bool,
}

/// Why an input file was not read.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{} is {kind}, not a regular file; {what} are read only from {from}", path.display())]
    NotRegular {
        path: PathBuf,
        kind: &'static str,
        what: &'static str,
        /// "regular files", or "regular files or pipes".
        from: &'static str,
    },
    #[error("{} is {len} bytes; {what} are limited to {max} bytes", path.display())]
    TooLong {
        path: PathBuf,
        len: u64,
        what: &'static str,
        max: u64,
    },
    #[error(
        "{} gave more than {max} bytes; {what} are limited to {max} bytes",
        path.display()
    )]
    PipeTooLong {
        path: PathBuf,
        what: &'static str,
        max: u64,
    },
}

impl InputError {
    /// The file does not exist (callers add hints of their own).
    pub fn is_not_found(&self) -> bool {
        matches!(self, InputError::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound)
    }

    /// The file.
    pub fn path(&self) -> &Path {
        match self {
            InputError::Io { path, .. }
            | InputError::NotRegular { path, .. }
            | InputError::TooLong { path, .. }
            | InputError::PipeTooLong { path, .. } => path,
        }
    }

    /// What is wrong, without the path (for errors that name the file their own way).
    pub fn reason(&self) -> String {
        match self {
            InputError::Io { source, .. } => format!("cannot read: {source}"),
            InputError::NotRegular {
                kind, what, from, ..
            } => format!("{kind}, not a regular file; {what} are read only from {from}"),
            InputError::TooLong { len, what, max, .. } => {
                format!("{len} bytes; {what} are limited to {max} bytes")
            }
            InputError::PipeTooLong { what, max, .. } => {
                format!("more than {max} bytes; {what} are limited to {max} bytes")
            }
        }
    }
}

/// The whole of `path`, by the rule above.
pub fn read(path: &Path, kind: &InputKind) -> Result<Vec<u8>, InputError> {
    InputFile::open(path, kind)?.read_all()
}

/// The first `n` bytes of `path` at most (a header, read to decide what the file is and
/// whether to read the rest), by the same rule; the size limit applies when the rest is read
/// with [`read`].
pub fn read_head(path: &Path, kind: &InputKind, n: u64) -> Result<Vec<u8>, InputError> {
    InputFile::open(path, kind)?.read_up_to(n.min(kind.max_bytes))
}

/// An input file opened by the rule above, not read yet (a caller may judge the opened file
/// first: a key file's mode).
pub struct InputFile {
    path: PathBuf,
    kind: InputKind,
    file: File,
    meta: std::fs::Metadata,
}

impl InputFile {
    /// Opens `path` without blocking and checks what it is (the opened file, `fstat`).
    pub fn open(path: &Path, kind: &InputKind) -> Result<InputFile, InputError> {
        let io = |source| InputError::Io {
            path: path.to_path_buf(),
            source,
        };
        let file = open_nonblocking(path).map_err(io)?;
        let meta = file.metadata().map_err(io)?;
        let t = meta.file_type();
        let taken = t.is_file() || (kind.pipes && is_fifo(t));
        if !taken {
            return Err(InputError::NotRegular {
                path: path.to_path_buf(),
                kind: if t.is_dir() {
                    "a directory"
                } else {
                    crate::output_file::kind(t)
                },
                what: kind.what,
                from: if kind.pipes {
                    "regular files or pipes"
                } else {
                    "regular files"
                },
            });
        }
        if !t.is_file() {
            // Blocking again: a pipe's writer may not have written yet.
            blocking(&file).map_err(io)?;
        }
        Ok(InputFile {
            path: path.to_path_buf(),
            kind: *kind,
            file,
            meta,
        })
    }

    /// The opened file's metadata.
    pub fn metadata(&self) -> &std::fs::Metadata {
        &self.meta
    }

    /// Everything, up to the kind's limit: a regular file past it is refused from its length,
    /// before a byte is read; one that grows past it while it is read, or a pipe, is cut off
    /// at the limit and refused.
    pub fn read_all(self) -> Result<Vec<u8>, InputError> {
        let (max, what, regular) = (self.kind.max_bytes, self.kind.what, self.meta.is_file());
        let path = self.path.clone();
        if regular && self.meta.len() > max {
            return Err(InputError::TooLong {
                path,
                len: self.meta.len(),
                what,
                max,
            });
        }
        let bytes = self.read_up_to(max.saturating_add(1))?;
        if bytes.len() as u64 <= max {
            return Ok(bytes);
        }
        Err(if regular {
            InputError::TooLong {
                path,
                len: bytes.len() as u64,
                what,
                max,
            }
        } else {
            InputError::PipeTooLong { path, what, max }
        })
    }

    fn read_up_to(self, n: u64) -> Result<Vec<u8>, InputError> {
        let mut out = Vec::new();
        self.file
            .take(n)
            .read_to_end(&mut out)
            .map_err(|source| InputError::Io {
                path: self.path,
                source,
            })?;
        Ok(out)
    }
}

#[cfg(unix)]
fn open_nonblocking(path: &Path) -> std::io::Result<File> {
    use std::os::unix::fs::OpenOptionsExt as _;
    std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(nix::fcntl::OFlag::O_NONBLOCK.bits())
        .open(path)
}

#[cfg(not(unix))]
fn open_nonblocking(path: &Path) -> std::io::Result<File> {
    File::open(path)
}

#[cfg(unix)]
fn blocking(file: &File) -> std::io::Result<()> {
    use nix::fcntl::{fcntl, FcntlArg, OFlag};
    fcntl(file, FcntlArg::F_SETFL(OFlag::empty()))
        .map(|_| ())
        .map_err(std::io::Error::from)
}

#[cfg(not(unix))]
fn blocking(_: &File) -> std::io::Result<()> {
    Ok(())
}

#[cfg(unix)]
fn is_fifo(t: std::fs::FileType) -> bool {
    use std::os::unix::fs::FileTypeExt as _;
    t.is_fifo()
}

#[cfg(not(unix))]
fn is_fifo(_: std::fs::FileType) -> bool {
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: InputKind = InputKind {
        what: "test files",
        max_bytes: 8,
        pipes: false,
    };

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("input-file-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).expect("dir");
        d
    }

    #[test]
    fn a_device_is_refused_without_reading_it() {
        // /dev/zero never ends: read, it would fill the memory.
        let e = read(Path::new("/dev/zero"), &SMALL).expect_err("refused");
        assert_eq!(
            e.to_string(),
            "/dev/zero is a character device, not a regular file; test files are read only \
             from regular files"
        );
        let e = read(Path::new("/"), &SMALL).expect_err("refused");
        assert!(e.to_string().contains("is a directory"), "{e}");
    }

    #[test]
    fn a_regular_file_is_read_up_to_its_limit_and_refused_past_it() {
        let d = dir("limit");
        let ok = d.join("ok");
        std::fs::write(&ok, b"12345678").expect("writes");
        assert_eq!(read(&ok, &SMALL).expect("reads"), b"12345678");
        assert_eq!(read_head(&ok, &SMALL, 3).expect("reads"), b"123");
        let long = d.join("long");
        std::fs::write(&long, b"123456789").expect("writes");
        let e = read(&long, &SMALL).expect_err("refused");
        assert!(
            e.to_string()
                .ends_with("long is 9 bytes; test files are limited to 8 bytes"),
            "{e}"
        );
        assert!(!read(&d.join("missing"), &SMALL)
            .expect_err("missing")
            .to_string()
            .is_empty());
        assert!(read(&d.join("missing"), &SMALL)
            .expect_err("missing")
            .is_not_found());
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn a_fifo_without_a_writer_neither_blocks_nor_is_read_unless_the_kind_takes_pipes() {
        let d = dir("fifo");
        let fifo = d.join("fifo");
        nix::unistd::mkfifo(&fifo, nix::sys::stat::Mode::S_IRWXU).expect("mkfifo");
        let e = read(&fifo, &SMALL).expect_err("refused");
        assert!(e.to_string().contains("is a FIFO (named pipe)"), "{e}");
        // A pipe the kind takes: read to its end (no writer: at once), bounded.
        let pipes = InputKind {
            pipes: true,
            ..SMALL
        };
        assert_eq!(read(&fifo, &pipes).expect("reads"), b"");
        let _ = std::fs::remove_dir_all(&d);
    }
}
