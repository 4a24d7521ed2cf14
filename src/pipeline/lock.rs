//! The output directory's lock: an advisory `flock` on `OUT/.slidestack.lock`, held for the life
//! of a stage (or of a whole `run`). The kernel releases it when the process ends, however it
//! ends, so `kill -9` never leaves a stale lock behind.
//!
//! Every stage takes it exclusively; the shards of a sweep take it shared, so the tasks of a job
//! array run side by side while no other stage can write into the directory. A second process
//! waits for the holder (named by its PID and command) or, without waiting, refuses naming it.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Name of the lock file inside the output directory.
pub const LOCK_FILE: &str = ".slidestack.lock";

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LockMode {
    /// One writer: every stage but a sweep shard.
    Exclusive,
    /// Sweep shards: side by side with each other, never with an exclusive holder.
    Shared,
}

#[derive(Debug, Error)]
pub enum LockError {
    #[error(
        "output directory {}: cannot create it: {source} (is its parent writable?)",
        dir.display()
    )]
    CreateDir {
        dir: PathBuf,
        source: std::io::Error,
    },
    #[error(
        "output directory {}: cannot create the lock file {LOCK_FILE}: {source} (is the directory writable?)",
        dir.display()
    )]
    Open {
        dir: PathBuf,
        source: std::io::Error,
    },
    #[error(
        "output directory {} is in use by {holder}; wait for it to finish",
        dir.display()
    )]
    Busy { dir: PathBuf, holder: String },
    #[error("output directory {}: cannot lock {LOCK_FILE}: {source}", dir.display())]
    Lock {
        dir: PathBuf,
        source: std::io::Error,
    },
}

/// What the holder of a lock wrote into the lock file: its PID and command line.
fn holder_text(file: &mut File) -> String {
    let mut s = String::new();
    let _ = file.rewind();
    let _ = file.take(4096).read_to_string(&mut s);
    let s = s.trim();
    if s.is_empty() {
        "another slidestack process".to_string()
    } else {
        s.to_string()
    }
}

/// The held lock; released when dropped (or when the process ends).
#[derive(Debug)]
pub struct OutputLock {
    _file: Option<File>,
    /// Whether the file system refused locking altogether (then nothing is held).
    pub unsupported: bool,
}

impl OutputLock {
    /// Creates `dir` if needed and takes its lock. With `wait`, blocks until the holder is done,
    /// calling `on_wait(holder)` once first; without, refuses naming the holder. On a file
    /// system without locks (some network mounts) it returns an unheld lock with
    /// `unsupported = true`, for the caller to warn about.
    pub fn acquire(
        dir: &Path,
        mode: LockMode,
        wait: bool,
        on_wait: impl FnOnce(&str),
    ) -> Result<Self, LockError> {
        std::fs::create_dir_all(dir).map_err(|source| LockError::CreateDir {
            dir: dir.to_path_buf(),
            source,
        })?;
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(dir.join(LOCK_FILE))
            .map_err(|source| LockError::Open {
                dir: dir.to_path_buf(),
                source,
            })?;
        let tried = match mode {
            LockMode::Exclusive => file.try_lock(),
            LockMode::Shared => file.try_lock_shared(),
        };
        match tried {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                let holder = holder_text(&mut file);
                if !wait {
                    return Err(LockError::Busy {
                        dir: dir.to_path_buf(),
                        holder,
                    });
                }
                on_wait(&holder);
                let got = match mode {
                    LockMode::Exclusive => file.lock(),
                    LockMode::Shared => file.lock_shared(),
                };
                got.map_err(|source| LockError::Lock {
                    dir: dir.to_path_buf(),
                    source,
                })?;
            }
            Err(TryLockError::Error(e)) if is_unsupported(&e) => {
                return Ok(Self {
                    _file: None,
                    unsupported: true,
                });
            }
            Err(TryLockError::Error(source)) => {
                return Err(LockError::Lock {
                    dir: dir.to_path_buf(),
                    source,
                });
            }
        }
        // Name the holder for whoever waits next (best effort: the lock is what matters).
        let me = format!(
            "PID {} ({})",
            std::process::id(),
            std::env::args().collect::<Vec<_>>().join(" ")
        );
        if mode == LockMode::Exclusive {
            let _ = file.set_len(0);
        }
        let _ = file.rewind();
        let _ = file.write_all(me.as_bytes());
        let _ = file.set_len(me.len() as u64);
        Ok(Self {
            _file: Some(file),
            unsupported: false,
        })
    }
}

fn is_unsupported(e: &std::io::Error) -> bool {
    e.kind() == std::io::ErrorKind::Unsupported
        || matches!(
            e.raw_os_error(),
            Some(libc::ENOLCK | libc::EOPNOTSUPP | libc::ENOSYS)
        )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exclusive_excludes_and_names_the_holder_shared_shares() {
        let dir = tempfile::tempdir().unwrap();
        let a = OutputLock::acquire(dir.path(), LockMode::Exclusive, false, |_| {}).unwrap();
        let e = OutputLock::acquire(dir.path(), LockMode::Exclusive, false, |_| {}).unwrap_err();
        let text = e.to_string();
        assert!(
            text.contains("is in use by PID") && text.contains(&std::process::id().to_string()),
            "{text}"
        );
        assert!(OutputLock::acquire(dir.path(), LockMode::Shared, false, |_| {}).is_err());
        drop(a);
        let s1 = OutputLock::acquire(dir.path(), LockMode::Shared, false, |_| {}).unwrap();
        let s2 = OutputLock::acquire(dir.path(), LockMode::Shared, false, |_| {}).unwrap();
        assert!(OutputLock::acquire(dir.path(), LockMode::Exclusive, false, |_| {}).is_err());
        drop((s1, s2));
        OutputLock::acquire(dir.path(), LockMode::Exclusive, false, |_| {}).unwrap();
    }

    #[test]
    fn a_waiter_gets_the_lock_when_the_holder_lets_go() {
        let dir = tempfile::tempdir().unwrap();
        let held = OutputLock::acquire(dir.path(), LockMode::Exclusive, false, |_| {}).unwrap();
        let path = dir.path().to_path_buf();
        let waiter = std::thread::spawn(move || {
            let mut told = String::new();
            let l = OutputLock::acquire(&path, LockMode::Exclusive, true, |h| told = h.into());
            (l.is_ok(), told)
        });
        std::thread::sleep(std::time::Duration::from_millis(100));
        drop(held);
        let (ok, told) = waiter.join().unwrap();
        assert!(ok && told.starts_with("PID "), "{told}");
    }
}
