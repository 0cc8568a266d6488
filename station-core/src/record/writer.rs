//! Writing a recording: `FILE.partial` while it runs, `FILE` once it ends cleanly.
//!
//! Layer: file I/O around `record::encode_record`; time comes from the caller (`t_us` per
//! record, `now` for the flush policy). Invariants: the final name is created only by the
//! rename in `finish`, after the end record is written and the file synced, so a reader never
//! sees a half-written file under it; the `.partial` file always starts with a complete, synced
//! header, is flushed at least every `FLUSH_EVERY` and synced every `SYNC_EVERY`, so a crash
//! loses at most the last second; record times never decrease (an earlier time is raised to the
//! last one written). What can fail: creating, writing, syncing or renaming the file
//! (`RecordError::Io`); an existing `FILE` (unless overwriting) or `FILE.partial` is refused
//! before anything is written.

use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

use tokio::time::Instant;

use super::{encode_header, encode_record, partial_path, Meta, RecordError, RecordKind, MAX_DATA};

/// Longest time buffered bytes wait before they are written to the file.
pub const FLUSH_EVERY: Duration = Duration::from_secs(1);
/// Longest time written bytes wait before they are synced to the disk.
pub const SYNC_EVERY: Duration = Duration::from_secs(5);
/// Buffer size; a full buffer is written at once.
const BUFFER: usize = 64 * 1024;

/// An open recording. Dropping it without `finish` leaves `FILE.partial` (flushed).
pub struct RecordWriter {
    file: Option<BufWriter<File>>,
    partial: PathBuf,
    path: PathBuf,
    /// Whether `finish` may replace an existing file at `path`.
    overwrite: bool,
    last_t: u64,
    records: u64,
    bytes: u64,
    scratch: Vec<u8>,
    last_flush: Instant,
    last_sync: Instant,
}

/// What a finished recording holds.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Written {
    pub path: PathBuf,
    pub records: u64,
    pub bytes: u64,
    pub duration_us: u64,
}

impl RecordWriter {
    /// Creates `path.partial` and writes the header. Refuses an existing `path` unless
    /// `overwrite`, a `path` that is not a regular file always (`output_file::check`), and an
    /// existing `path.partial` (an unfinished recording) always.
    pub fn create(path: &Path, meta: &Meta, overwrite: bool) -> Result<RecordWriter, RecordError> {
        crate::output_file::check(path, overwrite)?;
        let partial = partial_path(path);
        let io = |source| RecordError::Io {
            path: partial.clone(),
            source,
        };
        let file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&partial)
            .map_err(|source| {
                if source.kind() == std::io::ErrorKind::AlreadyExists {
                    RecordError::PartialExists {
                        path: partial.clone(),
                    }
                } else {
                    io(source)
                }
            })?;
        let header = encode_header(meta);
        let mut file = BufWriter::with_capacity(BUFFER, file);
        let now = Instant::now();
        let mut w = RecordWriter {
            bytes: header.len() as u64,
            file: None,
            partial: partial.clone(),
            path: path.to_path_buf(),
            overwrite,
            last_t: 0,
            records: 0,
            scratch: Vec::with_capacity(512),
            last_flush: now,
            last_sync: now,
        };
        let started = file
            .write_all(&header)
            .and_then(|()| file.flush())
            .and_then(|()| file.get_ref().sync_data());
        if let Err(source) = started {
            drop(file);
            let _ = std::fs::remove_file(&partial);
            return Err(io(source));
        }
        w.file = Some(file);
        Ok(w)
    }

    /// The final name.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The name being written.
    pub fn partial_path(&self) -> &Path {
        &self.partial
    }

    /// Records and bytes so far.
    pub fn records(&self) -> u64 {
        self.records
    }

    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    /// Time of the last record, µs.
    pub fn last_t_us(&self) -> u64 {
        self.last_t
    }

    /// Appends a record of link 0 (split into several if longer than the format allows).
    pub fn append(&mut self, t_us: u64, kind: RecordKind, data: &[u8]) -> Result<(), RecordError> {
        self.append_link(t_us, kind, 0, data)
    }

    /// Appends a record of link `link` (an index into the header's `links`).
    pub fn append_link(
        &mut self,
        t_us: u64,
        kind: RecordKind,
        link: u8,
        data: &[u8],
    ) -> Result<(), RecordError> {
        let t_us = t_us.max(self.last_t);
        self.last_t = t_us;
        let chunks: Vec<&[u8]> = if data.is_empty() {
            vec![data]
        } else {
            data.chunks(MAX_DATA).collect()
        };
        for chunk in chunks {
            self.scratch.clear();
            encode_record(&mut self.scratch, t_us, kind, link, chunk);
            let Some(file) = self.file.as_mut() else {
                return Ok(());
            };
            file.write_all(&self.scratch)
                .map_err(|source| RecordError::Io {
                    path: self.partial.clone(),
                    source,
                })?;
            self.records += 1;
            self.bytes += self.scratch.len() as u64;
        }
        Ok(())
    }

    /// Flushes and syncs when they are due; call about once a second or more often.
    pub fn tick(&mut self, now: Instant) -> Result<(), RecordError> {
        if now.saturating_duration_since(self.last_flush) >= FLUSH_EVERY {
            self.last_flush = now;
            self.flush(false)?;
        }
        if now.saturating_duration_since(self.last_sync) >= SYNC_EVERY {
            self.last_sync = now;
            self.flush(true)?;
        }
        Ok(())
    }

    fn flush(&mut self, sync: bool) -> Result<(), RecordError> {
        let Some(file) = self.file.as_mut() else {
            return Ok(());
        };
        let r = file.flush().and_then(|()| {
            if sync {
                file.get_ref().sync_data()
            } else {
                Ok(())
            }
        });
        r.map_err(|source| RecordError::Io {
            path: self.partial.clone(),
            source,
        })
    }

    /// Writes the end record, syncs, and renames `FILE.partial` to `FILE`.
    pub fn finish(mut self, t_us: u64, reason: &str) -> Result<Written, RecordError> {
        self.append(t_us, RecordKind::End, reason.as_bytes())?;
        self.flush(true)?;
        drop(self.file.take());
        // By the station's one rule (a special file is never replaced, an existing file only
        // when overwriting); on failure FILE.partial stays for a reader.
        crate::output_file::publish(&self.partial, &self.path, self.overwrite)?;
        Ok(Written {
            path: self.path.clone(),
            records: self.records,
            bytes: self.bytes,
            duration_us: self.last_t,
        })
    }
}

impl Drop for RecordWriter {
    fn drop(&mut self) {
        // Not finished: keep what there is in FILE.partial for a reader to salvage.
        if let Some(mut f) = self.file.take() {
            let _ = f.flush();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::Recording;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("rec-writer-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_finished_recording_appears_only_under_its_final_name() {
        let d = dir("finish");
        let path = d.join("run.rec");
        let mut w = RecordWriter::create(&path, &Meta::default(), false).unwrap();
        w.append(5, RecordKind::FromRobot, &[1, 2, 3]).unwrap();
        w.append(3, RecordKind::ToRobot, &[4]).unwrap();
        assert!(!path.exists());
        assert!(partial_path(&path).exists());
        let written = w.finish(9, "done").unwrap();
        assert_eq!(written.records, 3);
        assert!(!partial_path(&path).exists());
        let r = Recording::open(&path).unwrap();
        assert!(r.damage.is_none());
        assert_eq!(r.end.as_deref(), Some("done"));
        // The earlier time was raised so times never decrease.
        assert_eq!(r.records[1].t_us, 5);
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn an_unfinished_recording_stays_partial_and_reads_up_to_its_last_flush() {
        let d = dir("crash");
        let path = d.join("run.rec");
        {
            let mut w = RecordWriter::create(&path, &Meta::default(), false).unwrap();
            w.append(1, RecordKind::FromRobot, &[9; 10]).unwrap();
            w.tick(Instant::now() + FLUSH_EVERY).unwrap();
            // Dropped without finish: a crash that still ran destructors.
        }
        assert!(!path.exists());
        let r = Recording::open(&partial_path(&path)).unwrap();
        assert_eq!(r.records.len(), 1);
        assert!(r.end.is_none());
        let missing = Recording::open(&path).unwrap_err().to_string();
        assert!(missing.contains("unfinished recording"), "{missing}");
        let again = RecordWriter::create(&path, &Meta::default(), false);
        assert!(matches!(again, Err(RecordError::PartialExists { .. })));
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn an_existing_file_is_kept_unless_overwriting() {
        let d = dir("exists");
        let path = d.join("run.rec");
        std::fs::write(&path, b"precious").unwrap();
        assert!(matches!(
            RecordWriter::create(&path, &Meta::default(), false),
            Err(RecordError::Output(
                crate::output_file::OutputError::Exists { .. }
            ))
        ));
        assert_eq!(std::fs::read(&path).unwrap(), b"precious");
        let w = RecordWriter::create(&path, &Meta::default(), true).unwrap();
        w.finish(0, "x").unwrap();
        assert!(Recording::open(&path).unwrap().damage.is_none());
        let _ = std::fs::remove_dir_all(&d);
    }
}
