//! Checksum sidecars: beside a result file `NAME`, a file `NAME.sha256` holding its SHA-256 in
//! the format of `sha256sum` (so `sha256sum -c NAME.sha256` checks it outside the tool too).
//! A file whose bytes no longer match its sidecar was changed, truncated or damaged after it was
//! written, or its write was cut short: it is never taken as a valid result.

use super::StoreError;
use super::atomic::{Temp, write_bytes};
use super::fingerprint::file_sha256;
use std::path::{Path, PathBuf};

/// The sidecar of `path`: `NAME.sha256` beside it.
pub fn sidecar_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".sha256");
    path.with_file_name(name)
}

/// A `sha256sum` line for the file `name` with digest `sha`.
pub fn line(sha: &str, name: &str) -> String {
    format!("{sha}  {name}\n")
}

/// Commits the written temporary `tmp` to `path` and writes its sidecar.
pub fn commit_with_sidecar(tmp: Temp, path: &Path) -> Result<(), StoreError> {
    let sha = file_sha256(tmp.path()).map_err(|e| StoreError::io(path, "cannot read back", e))?;
    tmp.commit(path)?;
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    write_bytes(&sidecar_path(path), line(&sha, &name).as_bytes())
}

/// Writes `bytes` to `path` atomically, then its sidecar.
pub fn write_with_sidecar(path: &Path, bytes: &[u8]) -> Result<(), StoreError> {
    write_bytes(path, bytes)?;
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    let sha = super::fingerprint::sha256_hex(bytes);
    write_bytes(&sidecar_path(path), line(&sha, &name).as_bytes())
}

/// `Ok(false)` when `path` does not exist; `Ok(true)` when it matches its sidecar; an error
/// naming the file otherwise.
pub fn verify(path: &Path) -> Result<bool, StoreError> {
    if !path.exists() {
        return Ok(false);
    }
    let sidecar = sidecar_path(path);
    let want = match std::fs::read_to_string(&sidecar) {
        Ok(text) => text.split_whitespace().next().unwrap_or("").to_string(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(StoreError::corrupt(
                path,
                format!(
                    "has no checksum file {} (its write was interrupted, or another program made it)",
                    sidecar.display()
                ),
            ));
        }
        Err(e) => return Err(StoreError::io(&sidecar, "cannot read", e)),
    };
    let got = file_sha256(path).map_err(|e| StoreError::io(path, "cannot read", e))?;
    if got != want {
        return Err(StoreError::corrupt(
            path,
            format!(
                "does not match its checksum in {}: it was changed or damaged after it was written",
                sidecar.display()
            ),
        ));
    }
    Ok(true)
}

/// Removes a file and its sidecar, if present.
pub fn remove_with_sidecar(path: &Path) -> Result<(), StoreError> {
    for p in [path.to_path_buf(), sidecar_path(path)] {
        match std::fs::remove_file(&p) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(StoreError::io(&p, "cannot remove", e)),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sidecar_catches_any_change_and_its_own_absence() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("fit.yaml");
        assert!(!verify(&p).unwrap());
        write_with_sidecar(&p, b"zones: []\n").unwrap();
        assert!(verify(&p).unwrap());
        assert_eq!(
            std::fs::read_to_string(sidecar_path(&p)).unwrap(),
            format!(
                "{}  fit.yaml\n",
                super::super::fingerprint::sha256_hex(b"zones: []\n")
            )
        );
        std::fs::write(&p, b"").unwrap();
        assert!(
            verify(&p)
                .unwrap_err()
                .to_string()
                .contains("does not match its checksum")
        );
        std::fs::remove_file(sidecar_path(&p)).unwrap();
        assert!(
            verify(&p)
                .unwrap_err()
                .to_string()
                .contains("has no checksum file")
        );
        remove_with_sidecar(&p).unwrap();
        assert!(!verify(&p).unwrap());
    }
}
