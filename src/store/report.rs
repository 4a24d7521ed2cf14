//! The report directory as a whole: its files are written into a new temporary directory beside
//! it with a `MANIFEST.sha256` (every file's SHA-256, in the format of `sha256sum -c`) and a
//! `FINGERPRINT`, then the directory replaces the old one. A report is therefore never a mix of
//! two runs, holds no stale figure of an earlier one, and proves on reading that it is whole.

use super::StoreError;
use super::atomic::{sync_dir, temp_path};
use super::checksum::line;
use super::fingerprint::sha256_hex;
use std::io::Write;
use std::path::Path;

pub const MANIFEST: &str = "MANIFEST.sha256";
pub const FINGERPRINT: &str = "FINGERPRINT";

/// Replaces `dir` by a directory holding exactly `files` (`(name, bytes)`, names without
/// directories), its manifest and `fingerprint`.
pub fn write_report_dir(
    dir: &Path,
    fingerprint: &str,
    files: &[(String, Vec<u8>)],
) -> Result<(), StoreError> {
    let tmp = temp_path(dir);
    let result = (|| {
        std::fs::create_dir_all(&tmp).map_err(|e| StoreError::io(dir, "cannot create", e))?;
        let mut manifest = String::new();
        let fp = (
            FINGERPRINT.to_string(),
            format!("{fingerprint}\n").into_bytes(),
        );
        for (name, bytes) in files.iter().chain(std::iter::once(&fp)) {
            let p = tmp.join(name);
            let mut f = std::fs::File::create(&p)
                .map_err(|e| StoreError::io(&dir.join(name), "cannot create", e))?;
            f.write_all(bytes)
                .and_then(|()| f.sync_all())
                .map_err(|e| StoreError::io(&dir.join(name), "cannot write", e))?;
            manifest += &line(&sha256_hex(bytes), name);
        }
        let p = tmp.join(MANIFEST);
        let mut f = std::fs::File::create(&p)
            .map_err(|e| StoreError::io(&dir.join(MANIFEST), "cannot create", e))?;
        f.write_all(manifest.as_bytes())
            .and_then(|()| f.sync_all())
            .map_err(|e| StoreError::io(&dir.join(MANIFEST), "cannot write", e))?;
        sync_dir(&p)?;
        let old = temp_path(dir);
        if dir.exists() {
            std::fs::rename(dir, &old).map_err(|e| StoreError::io(dir, "cannot move aside", e))?;
        }
        std::fs::rename(&tmp, dir).map_err(|e| StoreError::io(dir, "cannot rename", e))?;
        sync_dir(dir)?;
        if old.exists() {
            std::fs::remove_dir_all(&old)
                .map_err(|e| StoreError::io(&old, "cannot remove the old report", e))?;
        }
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_dir_all(&tmp);
    }
    result
}

/// The fingerprint of the report in `dir`: `None` when there is none; an error when a file of
/// its manifest is missing or does not match.
pub fn stored_fingerprint(dir: &Path) -> Result<Option<String>, StoreError> {
    let manifest = dir.join(MANIFEST);
    let text = match std::fs::read_to_string(&manifest) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return if dir.join("index.html").exists() {
                Err(StoreError::corrupt(
                    dir,
                    format!("has no {MANIFEST} (an interrupted or foreign report)"),
                ))
            } else {
                Ok(None)
            };
        }
        Err(e) => return Err(StoreError::io(&manifest, "cannot read", e)),
    };
    let mut has_fp = false;
    for l in text.lines() {
        let (sha, name) = l
            .split_once("  ")
            .ok_or_else(|| StoreError::corrupt(&manifest, format!("bad line `{l}`")))?;
        let p = dir.join(name);
        let bytes = std::fs::read(&p).map_err(|e| StoreError::io(&p, "cannot read", e))?;
        if sha256_hex(&bytes) != sha {
            return Err(StoreError::corrupt(
                &p,
                format!("does not match {}", manifest.display()),
            ));
        }
        has_fp |= name == FINGERPRINT;
    }
    if !has_fp {
        return Err(StoreError::corrupt(&manifest, "does not list FINGERPRINT"));
    }
    let fp = std::fs::read_to_string(dir.join(FINGERPRINT))
        .map_err(|e| StoreError::io(&dir.join(FINGERPRINT), "cannot read", e))?;
    Ok(Some(fp.trim().to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_the_whole_directory_and_checks_itself() {
        let dir = tempfile::tempdir().unwrap();
        let r = dir.path().join("report");
        assert_eq!(stored_fingerprint(&r).unwrap(), None);
        let files = |names: &[&str]| -> Vec<(String, Vec<u8>)> {
            names
                .iter()
                .map(|n| (n.to_string(), n.as_bytes().to_vec()))
                .collect()
        };
        write_report_dir(&r, "one", &files(&["index.html", "a.svg", "old.svg"])).unwrap();
        assert_eq!(stored_fingerprint(&r).unwrap().as_deref(), Some("one"));
        write_report_dir(&r, "two", &files(&["index.html", "a.svg"])).unwrap();
        assert_eq!(stored_fingerprint(&r).unwrap().as_deref(), Some("two"));
        // No stale figure of the first report, no temporaries beside it.
        assert!(!r.join("old.svg").exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        std::fs::write(r.join("a.svg"), "changed").unwrap();
        let e = stored_fingerprint(&r).unwrap_err().to_string();
        assert!(e.contains("a.svg") && e.contains("does not match"), "{e}");
    }
}
