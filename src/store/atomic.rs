//! Checked atomic writes: a file is written under a temporary name unique to this process and
//! call, flushed to the storage device (`fsync`), renamed over its final name and the directory
//! entry synced too. A reader therefore sees the old file or the whole new one, never part of
//! one; two processes writing the same file never share a temporary; and every failure (a full
//! disk, a missing directory, a read-only file system) is returned naming the file, with the
//! temporary removed and the old file left as it was.

use super::StoreError;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Suffix of every temporary this module makes (`.NAME.PID.N.tmp` beside the final file).
pub const TEMP_SUFFIX: &str = ".tmp";

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// A temporary path beside `path`, unique to this process and call.
pub fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "file".into(), |n| n.to_string_lossy().into_owned());
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{name}.{}.{n}{TEMP_SUFFIX}", std::process::id()))
}

/// Whether `name` is a temporary made by [`temp_path`] (of any process).
pub fn is_temp_name(name: &str) -> bool {
    name.starts_with('.')
        && name.ends_with(TEMP_SUFFIX)
        && name
            .trim_end_matches(TEMP_SUFFIX)
            .rsplitn(3, '.')
            .take(2)
            .all(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()))
}

/// Why a file cannot be written at the path a user gave, known before any work.
#[derive(Debug, thiserror::Error)]
pub enum OutputPathError {
    #[error("{}: directory {} does not exist", path.display(), dir.display())]
    NoDirectory { path: PathBuf, dir: PathBuf },
    #[error("{}: {} is not a directory", path.display(), dir.display())]
    NotADirectory { path: PathBuf, dir: PathBuf },
    #[error("{}: is a directory, not a file", path.display())]
    IsADirectory { path: PathBuf },
    /// The file's format is given by its extension: one of `extensions`.
    #[error(
        "{}: {what} must end in {}",
        path.display(),
        (extensions.iter().map(|e| format!(".{e}")).collect::<Vec<_>>().join(" or "))
    )]
    Extension {
        path: PathBuf,
        what: &'static str,
        extensions: &'static [&'static str],
    },
}

/// `Err` unless a file can be made at `path`: its directory exists (the working directory for a
/// bare name) and `path` is not a directory. Checked before any work, so that a run is not lost
/// to a typing mistake in where its output goes.
pub fn check_output_file(path: &Path) -> Result<(), OutputPathError> {
    if path.is_dir() {
        return Err(OutputPathError::IsADirectory {
            path: path.to_path_buf(),
        });
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => return Ok(()),
    };
    let (path, dir) = (path.to_path_buf(), dir.to_path_buf());
    match std::fs::metadata(&dir) {
        Ok(m) if m.is_dir() => Ok(()),
        Ok(_) => Err(OutputPathError::NotADirectory { path, dir }),
        Err(e)
            if matches!(
                e.kind(),
                std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory
            ) =>
        {
            Err(OutputPathError::NoDirectory { path, dir })
        }
        // Anything else (a directory it may not read) is for the write to report.
        Err(_) => Ok(()),
    }
}

/// [`check_output_file`], and `path` ends in one of `extensions` (`svg`, no dot; any case),
/// the format of `what` (`a figure (SVG)`).
pub fn check_output_extension(
    path: &Path,
    what: &'static str,
    extensions: &'static [&'static str],
) -> Result<(), OutputPathError> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if !extensions.iter().any(|e| e.eq_ignore_ascii_case(ext)) {
        return Err(OutputPathError::Extension {
            path: path.to_path_buf(),
            what,
            extensions,
        });
    }
    check_output_file(path)
}

/// A temporary file, removed when dropped unless [`Temp::commit`]ted.
#[derive(Debug)]
pub struct Temp {
    path: PathBuf,
    committed: bool,
}

impl Temp {
    /// A new temporary name for the final file `path` (nothing is created yet).
    pub fn for_path(path: &Path) -> Self {
        Self {
            path: temp_path(path),
            committed: false,
        }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Syncs the temporary to the device, renames it to `path` and syncs the directory.
    pub fn commit(mut self, path: &Path) -> Result<(), StoreError> {
        sync_file(&self.path)?;
        std::fs::rename(&self.path, path).map_err(|e| StoreError::io(path, "cannot rename", e))?;
        self.committed = true;
        sync_dir(path)
    }
}

impl Drop for Temp {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

/// `fsync` of a written file.
pub fn sync_file(path: &Path) -> Result<(), StoreError> {
    std::fs::File::open(path)
        .and_then(|f| f.sync_all())
        .map_err(|e| StoreError::io(path, "cannot flush to disk", e))
}

/// `fsync` of the directory holding `path`, so that a rename survives a crash.
pub fn sync_dir(path: &Path) -> Result<(), StoreError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    std::fs::File::open(dir)
        .and_then(|f| f.sync_all())
        .map_err(|e| StoreError::io(dir, "cannot flush the directory to disk", e))
}

/// Writes `bytes` to `path` atomically (see the module doc).
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), StoreError> {
    let tmp = Temp::for_path(path);
    let mut f = std::fs::File::create(tmp.path())
        .map_err(|e| StoreError::io(path, "cannot create a temporary for", e))?;
    f.write_all(bytes)
        .and_then(|()| f.flush())
        .map_err(|e| StoreError::io(path, "cannot write", e))?;
    drop(f);
    tmp.commit(path)
}

/// Removes the temporaries of [`temp_path`] left in `dir` by processes that were killed.
/// Only call this while holding the output directory's exclusive lock.
pub fn remove_stale_temps(dir: &Path) -> Result<usize, StoreError> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(0);
    };
    let mut removed = 0;
    for e in entries.flatten() {
        if e.file_name().to_str().is_some_and(is_temp_name) {
            let p = e.path();
            let gone = if p.is_dir() {
                std::fs::remove_dir_all(&p)
            } else {
                std::fs::remove_file(&p)
            };
            gone.map_err(|err| StoreError::io(&p, "cannot remove the stale temporary", err))?;
            removed += 1;
        }
    }
    Ok(removed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temporaries_are_unique_and_recognised() {
        let a = temp_path(Path::new("/x/sweep.h5"));
        let b = temp_path(Path::new("/x/sweep.h5"));
        assert_ne!(a, b);
        let name = a.file_name().unwrap().to_str().unwrap();
        assert!(
            name.starts_with(".sweep.h5.") && is_temp_name(name),
            "{name}"
        );
        for not in [
            "sweep.h5",
            ".sweep.h5.tmp",
            ".a.b.tmp",
            ".slidestack.lock",
            "x.12.3.tmp",
        ] {
            assert!(!is_temp_name(not), "{not}");
        }
    }

    #[test]
    fn stale_temporaries_are_recognised_and_removed() {
        let dir = tempfile::tempdir().unwrap();
        let keep = [
            "sweep.h5",
            "sweep.h5.sha256",
            ".slidestack.lock",
            "notes.tmp",
        ];
        for k in keep {
            std::fs::write(dir.path().join(k), "").unwrap();
        }
        std::fs::write(temp_path(&dir.path().join("fit.h5")), "").unwrap();
        std::fs::create_dir(temp_path(&dir.path().join("report"))).unwrap();
        assert_eq!(remove_stale_temps(dir.path()).unwrap(), 2);
        let mut left: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        left.sort();
        let mut want: Vec<String> = keep.iter().map(|s| s.to_string()).collect();
        want.sort();
        assert_eq!(left, want);
    }

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_bytes(&p, b"old").unwrap();
        // A directory in the way of the rename: the write fails and names the file.
        let q = dir.path().join("sub");
        std::fs::create_dir(&q).unwrap();
        std::fs::write(q.join("x"), b"").unwrap();
        let e = write_bytes(&q, b"new").unwrap_err().to_string();
        assert!(e.contains("sub") && e.contains("cannot rename"), "{e}");
        assert_eq!(std::fs::read(&p).unwrap(), b"old");
        let left: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        assert!(left.iter().all(|n| !is_temp_name(n)), "{left:?}");
        write_bytes(&p, b"new").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"new");
    }
}
