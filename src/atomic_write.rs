//! Files that appear whole or not at all.
//!
//! Every output vlab writes (traces, summaries, tables, plots) goes through
//! [`write_atomic`]: the bytes go to a hidden temporary file next to the target,
//! which is renamed over the target only once everything was written and flushed.
//! A run that fails half-way, or is killed, never leaves a truncated CSV behind.

use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// Writes `path` atomically: `write` fills a buffered temporary file in the same
/// directory, which then replaces `path` by a rename. On any error the temporary
/// file is removed and `path` is left as it was.
pub fn write_atomic<F>(path: &Path, write: F) -> io::Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> io::Result<()>,
{
    let tmp = temporary_name(path);
    let result = (|| {
        let mut out = BufWriter::new(File::create(&tmp)?);
        write(&mut out)?;
        let file = out.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Writes a whole byte string atomically.
pub fn write_bytes_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_atomic(path, |w| w.write_all(bytes))
}

/// An output folder made before a long run, so that an unwritable path fails
/// at once; if the run fails, [`OutputDir::keep_if_ok`] removes every folder it
/// made again (innermost first, and only while empty).
#[derive(Debug)]
pub struct OutputDir {
    created: Vec<PathBuf>,
}

impl OutputDir {
    /// Creates `path` and any missing parents.
    pub fn prepare(path: &Path) -> io::Result<Self> {
        if path.is_file() {
            return Err(io::Error::new(
                io::ErrorKind::AlreadyExists,
                format!("{} is a file, not a folder", path.display()),
            ));
        }
        let created: Vec<PathBuf> = path
            .ancestors()
            .take_while(|p| !p.as_os_str().is_empty() && !p.exists())
            .map(Path::to_path_buf)
            .collect();
        fs::create_dir_all(path)?;
        Ok(OutputDir { created })
    }

    /// Passes `result` through; on error removes the folders this run made.
    pub fn keep_if_ok<T, E>(&self, result: Result<T, E>) -> Result<T, E> {
        if result.is_err() {
            for dir in &self.created {
                if fs::remove_dir(dir).is_err() {
                    break;
                }
            }
        }
        result
    }
}

fn temporary_name(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".to_string());
    path.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch_dir(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("vlab-atomic-{tag}-{}", std::process::id()));
        fs::create_dir_all(&dir).expect("create scratch dir");
        dir
    }

    #[test]
    fn writes_whole_file() {
        let dir = scratch_dir("ok");
        let path = dir.join("a.txt");
        write_bytes_atomic(&path, b"hello").expect("write");
        assert_eq!(fs::read(&path).expect("read"), b"hello");
        fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn failed_write_leaves_no_file_and_no_temporary() {
        let dir = scratch_dir("fail");
        let path = dir.join("b.txt");
        let err = write_atomic(&path, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("simulated failure"))
        });
        assert!(err.is_err());
        assert!(!path.exists());
        let leftovers: Vec<_> = fs::read_dir(&dir).expect("list").collect();
        assert!(leftovers.is_empty(), "temporary file left behind");
        fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn failed_rewrite_keeps_previous_content() {
        let dir = scratch_dir("keep");
        let path = dir.join("c.txt");
        write_bytes_atomic(&path, b"old").expect("write");
        let _ = write_atomic(&path, |_| Err(io::Error::other("boom")));
        assert_eq!(fs::read(&path).expect("read"), b"old");
        fs::remove_dir_all(dir).ok();
    }
}
