//! Every file the station writes (exports, Plan and Map objects, calibrations, recordings)
//! reaches its final name here, by one rule.
//!
//! Layer: file I/O only. The bytes go to a temporary file in the target's own directory (so
//! the rename is atomic), created with O_EXCL under an unpredictable name (the `tempfile`
//! crate): a symlink or file another user planted at a name we would use is never opened or
//! written through. The temporary file is flushed and synced, then renamed to the target: over
//! an existing regular file only with `force`, otherwise with no-clobber semantics, so a file
//! that appeared meanwhile is not overwritten either. A target that exists and is not a
//! regular file (a device such as /dev/null, a FIFO, a socket, a directory) is refused even
//! with `force`: the rename would replace the node itself, and as root `--out-object
//! /dev/null` would destroy /dev/null. The checks run twice: up front (`check`, before a
//! command reads its input or opens a port, so nothing is done for an output that cannot be
//! kept) and again just before the rename.
//! What can fail: `OutputError`, each naming the path. A failure, or dropping an
//! `OutputFile` uncommitted, removes the temporary file.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use tempfile::TempPath;

/// Why an output file was not written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{} is a directory; give a file name", path.display())]
    Directory { path: PathBuf },
    #[error(
        "{} is {kind}, not a regular file; it is never replaced (not even with --force): \
         give the name of a regular file",
        path.display()
    )]
    NotRegular { path: PathBuf, kind: &'static str },
    #[error("{} exists; pass --force to overwrite it", path.display())]
    Exists { path: PathBuf },
    #[error("the directory {} does not exist", dir.display())]
    NoDirectory { dir: PathBuf },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// The directory a target lives in ("." for a bare file name).
fn directory(out: &Path) -> &Path {
    match out.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// What a non-regular file is, for the error (here and in `input_file`).
pub(crate) fn kind(t: std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt as _;
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    let _ = t;
    "a special file"
}

/// Refuses a target that cannot be written by the rule above: its directory is missing, it is
/// a directory or another non-regular file (whatever `force` says), or it exists and `force`
/// is false. A symlink is judged by what it points to (a link to a device is refused; the
/// rename would replace the link, but the user meant the device).
pub fn check(out: &Path, force: bool) -> Result<(), OutputError> {
    let dir = directory(out);
    if !dir.is_dir() {
        return Err(OutputError::NoDirectory {
            dir: dir.to_path_buf(),
        });
    }
    let meta = match std::fs::metadata(out) {
        Ok(m) => m,
        // A dangling symlink still occupies the name.
        Err(_) if out.symlink_metadata().is_ok() => {
            return match force {
                true => Ok(()),
                false => Err(OutputError::Exists {
                    path: out.to_path_buf(),
                }),
            };
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(source) => {
            return Err(OutputError::Io {
                path: out.to_path_buf(),
                source,
            })
        }
    };
    let t = meta.file_type();
    if t.is_dir() {
        return Err(OutputError::Directory {
            path: out.to_path_buf(),
        });
    }
    if !t.is_file() {
        return Err(OutputError::NotRegular {
            path: out.to_path_buf(),
            kind: kind(t),
        });
    }
    if !force {
        return Err(OutputError::Exists {
            path: out.to_path_buf(),
        });
    }
    Ok(())
}

/// An output being written: a temporary file beside the target. `commit` gives it the
/// target's name; dropping it without `commit` removes it.
pub struct OutputFile {
    out: PathBuf,
    force: bool,
    file: BufWriter<File>,
    tmp: TempPath,
}

impl OutputFile {
    /// Checks `out` (see `check`) and creates the temporary file beside it.
    pub fn create(out: &Path, force: bool) -> Result<OutputFile, OutputError> {
        check(out, force)?;
        let name = out
            .file_name()
            .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
        let prefix = format!(".{name}.");
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        // tempfile's default mode is 0600; an output should get the usual mode (0666 less
        // the umask), as `File::create` gives, since the final file keeps the temporary's.
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt as _;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let dir = directory(out);
        let (file, tmp) = builder
            .tempfile_in(dir)
            .map_err(|source| OutputError::Io {
                path: dir.to_path_buf(),
                source,
            })?
            .into_parts();
        Ok(OutputFile {
            out: out.to_path_buf(),
            force,
            file: BufWriter::new(file),
            tmp,
        })
    }

    /// Where the bytes go until `commit`.
    pub fn writer(&mut self) -> &mut BufWriter<File> {
        &mut self.file
    }

    /// The temporary file's name (unpredictable).
    pub fn temp_path(&self) -> &Path {
        &self.tmp
    }

    /// The target.
    pub fn path(&self) -> &Path {
        &self.out
    }

    /// Flushes and syncs the temporary file, then renames it to the target.
    pub fn commit(self) -> Result<(), OutputError> {
        let OutputFile {
            out,
            force,
            mut file,
            tmp,
        } = self;
        let io = |source| OutputError::Io {
            path: tmp.to_path_buf(),
            source,
        };
        file.flush().map_err(io)?;
        file.get_ref().sync_all().map_err(io)?;
        drop(file);
        persist(tmp, &out, force, Keep::No)
    }
}

/// Writes `bytes` to `out` through an `OutputFile`: a reader sees the old file or the new
/// one, never a part.
pub fn write_atomically(out: &Path, bytes: &[u8], force: bool) -> Result<(), OutputError> {
    let mut f = OutputFile::create(out, force)?;
    f.writer()
        .write_all(bytes)
        .map_err(|source| OutputError::Io {
            path: f.temp_path().to_path_buf(),
            source,
        })?;
    f.commit()
}

/// Renames a finished file that the caller created itself with O_EXCL (a recording's
/// `FILE.partial`, whose fixed name is how a crash's leftovers are found) to `out` by the
/// same rule. On failure `finished` stays where it is.
pub fn publish(finished: &Path, out: &Path, force: bool) -> Result<(), OutputError> {
    let tmp = TempPath::try_from_path(finished).map_err(|source| OutputError::Io {
        path: finished.to_path_buf(),
        source,
    })?;
    persist(tmp, out, force, Keep::Yes)
}

/// Whether a file that could not take its final name stays (the caller's) or goes (ours).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Keep {
    Yes,
    No,
}

/// The rename: re-checks the target (it may have changed since the first check), then
/// replaces a regular file only with `force`.
fn persist(tmp: TempPath, out: &Path, force: bool, keep: Keep) -> Result<(), OutputError> {
    // A dropped TempPath deletes its file; `keep` turns that off.
    let give_back = |tmp: TempPath| {
        if keep == Keep::Yes {
            let _ = tmp.keep();
        }
    };
    if let Err(e) = check(out, force) {
        give_back(tmp);
        return Err(e);
    }
    let done = if force {
        tmp.persist(out)
    } else {
        tmp.persist_noclobber(out)
    };
    if let Err(e) = done {
        give_back(e.path);
        return Err(if e.error.kind() == std::io::ErrorKind::AlreadyExists {
            OutputError::Exists {
                path: out.to_path_buf(),
            }
        } else {
            OutputError::Io {
                path: out.to_path_buf(),
                source: e.error,
            }
        });
    }
    // Make the rename itself durable.
    if let Ok(d) = File::open(directory(out)) {
        let _ = d.sync_all();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("output-file-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).expect("dir");
        d
    }

    fn names(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .expect("lists")
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn dev_null_is_refused_with_or_without_force_and_never_touched() {
        // Only `check`: nothing here could write, so a regression cannot destroy /dev/null.
        for force in [false, true] {
            let e = check(Path::new("/dev/null"), force).expect_err("refused");
            assert!(matches!(e, OutputError::NotRegular { .. }), "{e}");
            assert_eq!(
                e.to_string(),
                "/dev/null is a character device, not a regular file; it is never replaced \
                 (not even with --force): give the name of a regular file"
            );
        }
        let e = check(Path::new("/"), true).expect_err("refused");
        assert!(matches!(e, OutputError::Directory { .. }), "{e}");
        let e = check(Path::new("/nonexistent-dir/x"), true).expect_err("refused");
        assert!(
            e.to_string().contains("/nonexistent-dir does not exist"),
            "{e}"
        );
    }

    #[test]
    fn a_write_replaces_a_file_only_when_forced_and_leaves_no_temporary_file() {
        let d = dir("write");
        let path = d.join("map.obj");
        write_atomically(&path, b"one", false).expect("writes");
        let e = write_atomically(&path, b"two", false).expect_err("kept");
        assert!(matches!(e, OutputError::Exists { .. }), "{e}");
        write_atomically(&path, b"two", true).expect("replaces");
        assert_eq!(std::fs::read(&path).expect("reads"), b"two");
        assert_eq!(names(&d), ["map.obj"]);
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn the_temporary_name_is_unpredictable_and_goes_away_uncommitted() {
        let d = dir("temp");
        let path = d.join("out.csv");
        let a = OutputFile::create(&path, false).expect("creates");
        let b = OutputFile::create(&path, false).expect("creates");
        assert_ne!(a.temp_path(), b.temp_path());
        assert_eq!(a.temp_path().parent(), Some(d.as_path()));
        let name = a.temp_path().file_name().expect("name").to_string_lossy();
        assert!(
            name.starts_with(".out.csv.") && name.ends_with(".tmp"),
            "{name}"
        );
        drop((a, b));
        assert!(names(&d).is_empty());
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn a_file_that_appears_before_the_commit_is_not_overwritten_without_force() {
        let d = dir("race");
        let path = d.join("out.csv");
        let mut f = OutputFile::create(&path, false).expect("creates");
        f.writer().write_all(b"new").expect("writes");
        std::fs::write(&path, b"theirs").expect("writes");
        let e = f.commit().expect_err("kept");
        assert!(matches!(e, OutputError::Exists { .. }), "{e}");
        assert_eq!(std::fs::read(&path).expect("reads"), b"theirs");
        assert_eq!(names(&d), ["out.csv"]);
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn a_published_file_that_cannot_take_its_name_stays() {
        let d = dir("publish");
        let partial = d.join("run.rec.partial");
        std::fs::write(&partial, b"rec").expect("writes");
        std::fs::create_dir(d.join("run.rec")).expect("dir");
        let e = publish(&partial, &d.join("run.rec"), true).expect_err("refused");
        assert!(matches!(e, OutputError::Directory { .. }), "{e}");
        assert_eq!(std::fs::read(&partial).expect("kept"), b"rec");
        std::fs::remove_dir(d.join("run.rec")).expect("removes");
        publish(&partial, &d.join("run.rec"), false).expect("renames");
        assert_eq!(names(&d), ["run.rec"]);
        let _ = std::fs::remove_dir_all(&d);
    }
}
