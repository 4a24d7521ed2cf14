//! The unit files of the stages that can be split (the sweep, `tnew`, the IDA): one small file
//! per finished work unit (the sweep's: one zone, one motion, one `T_p`), so that an interrupted
//! or sharded stage resumes where it stopped.
//!
//! A unit file records which unit it is (its [`UnitId`]: the stage's fingerprint, the zone, the
//! motion's index and name, the period's index and value, …) and ends with the SHA-256 of everything
//! before it. It is written atomically ([`super::atomic`]), so it is either whole or absent;
//! reading it checks the checksum and the identity, so a damaged unit, or one swapped with
//! another's, is refused instead of merged.
//!
//! ```text
//! "SLUNIT02"  u32 header length, header (JSON of UnitId)
//! u32 f64 columns, u32 u8 columns; each column: u64 length, values (little-endian)
//! SHA-256 of all the bytes above (32 bytes)
//! ```

use super::StoreError;
use super::atomic::write_bytes;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"SLUNIT02";

/// Which unit a file holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UnitId {
    /// Fingerprint of the stage that made it.
    pub fingerprint: String,
    pub zone: String,
    /// The motion's index and name (absent for a unit over every motion of its zone: `tnew`'s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motion_index: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motion: Option<String>,
    pub period_index: usize,
    pub period_s: f64,
    /// A building study's frame: its index and `storeys`/`stack_floor` (absent on one storey).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame: Option<(usize, String)>,
    /// The total `α` of a unit over the cases sharing it (`tnew`'s), absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha_total: Option<f64>,
}

impl std::fmt::Display for UnitId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "zone {}", self.zone)?;
        if let (Some(i), Some(name)) = (self.motion_index, &self.motion) {
            write!(f, ", motion {} `{name}`", i + 1)?;
        }
        if let Some((_, frame)) = &self.frame {
            write!(f, ", frame `{frame}`")?;
        }
        write!(f, ", T_p {} s", self.period_s)?;
        if let Some(a) = self.alpha_total {
            write!(f, ", total α {a}")?;
        }
        Ok(())
    }
}

/// A unit's values, as columns.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Columns {
    pub f64s: Vec<Vec<f64>>,
    pub u8s: Vec<Vec<u8>>,
}

/// What a unit file holds for a wanted unit.
#[derive(Debug, Clone, PartialEq)]
pub enum Stored {
    /// No file.
    Missing,
    /// A whole file made by a sweep with other inputs (another fingerprint): to be recomputed.
    Stale,
    Valid(Columns),
}

/// File name of unit (zone, motion, frame of a building study, period) inside the units
/// directory.
pub fn unit_path(
    dir: &Path,
    zone: &str,
    motion: usize,
    frame: Option<usize>,
    period: usize,
) -> PathBuf {
    match frame {
        None => dir.join(format!("{zone}_{motion:03}_{period:03}.unit")),
        Some(f) => dir.join(format!("{zone}_{motion:03}_f{f:03}_{period:03}.unit")),
    }
}

/// Removes a stage's directory of unit files (once its output was verified, or left over from an
/// interrupted cleanup); a directory that is not there is fine.
pub fn remove_units(dir: &Path) -> Result<(), StoreError> {
    match std::fs::remove_dir_all(dir) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(StoreError::io(dir, "cannot remove", e)),
    }
}

/// Writes a unit atomically.
pub fn write_unit(path: &Path, id: &UnitId, data: &Columns) -> Result<(), StoreError> {
    let header = serde_json::to_vec(id).expect("a UnitId serialises");
    let mut buf = Vec::new();
    buf.extend_from_slice(MAGIC);
    buf.extend_from_slice(&(header.len() as u32).to_le_bytes());
    buf.extend_from_slice(&header);
    buf.extend_from_slice(&(data.f64s.len() as u32).to_le_bytes());
    buf.extend_from_slice(&(data.u8s.len() as u32).to_le_bytes());
    for c in &data.f64s {
        buf.extend_from_slice(&(c.len() as u64).to_le_bytes());
        for x in c {
            buf.extend_from_slice(&x.to_le_bytes());
        }
    }
    for c in &data.u8s {
        buf.extend_from_slice(&(c.len() as u64).to_le_bytes());
        buf.extend_from_slice(c);
    }
    let sum = Sha256::digest(&buf);
    buf.extend_from_slice(&sum);
    write_bytes(path, &buf)
}

/// Reads the unit at `path` expected to be `want`; see [`Stored`]. A file that fails its
/// checksum, is cut short, or holds another unit of the same sweep is an error naming it.
pub fn read_unit(path: &Path, want: &UnitId) -> Result<Stored, StoreError> {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Stored::Missing),
        Err(e) => return Err(StoreError::io(path, "cannot read", e)),
    };
    let bad = |why: &str| StoreError::corrupt(path, why.to_string());
    if bytes.len() < MAGIC.len() + 32 || &bytes[..MAGIC.len()] != MAGIC {
        return Err(bad("is not a slidestack unit file"));
    }
    let (body, sum) = bytes.split_at(bytes.len() - 32);
    if Sha256::digest(body).as_slice() != sum {
        return Err(bad(
            "fails its checksum: it was damaged after it was written",
        ));
    }
    let mut at = MAGIC.len();
    let mut take = |n: usize| -> Result<&[u8], StoreError> {
        let s = body
            .get(at..at.checked_add(n).ok_or_else(|| bad("bad length"))?)
            .ok_or_else(|| bad("is cut short"))?;
        at += n;
        Ok(s)
    };
    let u32_at = |s: &[u8]| u32::from_le_bytes(s.try_into().expect("4 bytes")) as usize;
    let hl = u32_at(take(4)?);
    let id: UnitId =
        serde_json::from_slice(take(hl)?).map_err(|_| bad("has an unreadable header"))?;
    if id.fingerprint != want.fingerprint {
        return Ok(Stored::Stale);
    }
    if id != *want {
        return Err(bad(&format!(
            "holds unit ({id}) where unit ({want}) belongs"
        )));
    }
    let nf = u32_at(take(4)?);
    let nu = u32_at(take(4)?);
    let u64_at = |s: &[u8]| u64::from_le_bytes(s.try_into().expect("8 bytes")) as usize;
    let mut data = Columns::default();
    for _ in 0..nf {
        let n = u64_at(take(8)?);
        let raw = take(n.checked_mul(8).ok_or_else(|| bad("bad length"))?)?;
        data.f64s.push(
            raw.chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
                .collect(),
        );
    }
    for _ in 0..nu {
        let n = u64_at(take(8)?);
        data.u8s.push(take(n)?.to_vec());
    }
    if at != body.len() {
        return Err(bad("has trailing bytes"));
    }
    Ok(Stored::Valid(data))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn id(motion: usize) -> UnitId {
        UnitId {
            fingerprint: "fp".into(),
            zone: "III".into(),
            motion_index: Some(motion),
            motion: Some(format!("m{motion}")),
            period_index: 4,
            period_s: 0.5,
            frame: None,
            alpha_total: None,
        }
    }

    #[test]
    fn round_trip_and_every_kind_of_damage() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("u.unit");
        let data = Columns {
            f64s: vec![vec![1.0, -2.5, f64::NAN], vec![]],
            u8s: vec![vec![0, 1, 2]],
        };
        assert_eq!(read_unit(&p, &id(0)).unwrap(), Stored::Missing);
        write_unit(&p, &id(0), &data).unwrap();
        match read_unit(&p, &id(0)).unwrap() {
            Stored::Valid(c) => {
                assert_eq!(c.f64s[0][..2], data.f64s[0][..2]);
                assert!(c.f64s[0][2].is_nan() && c.f64s[1].is_empty() && c.u8s == data.u8s);
            }
            other => panic!("{other:?}"),
        }
        // Another sweep's unit: stale, recomputed without fuss.
        let mut other = id(0);
        other.fingerprint = "other".into();
        assert_eq!(read_unit(&p, &other).unwrap(), Stored::Stale);
        // Another unit of the same sweep (swapped files): refused, naming both.
        let e = read_unit(&p, &id(1)).unwrap_err().to_string();
        assert!(e.contains("holds unit") && e.contains("m1"), "{e}");
        // A flipped bit anywhere, or a cut: refused.
        let good = std::fs::read(&p).unwrap();
        for at in [9, good.len() / 2, good.len() - 1] {
            let mut b = good.clone();
            b[at] ^= 1;
            std::fs::write(&p, &b).unwrap();
            let e = read_unit(&p, &id(0)).unwrap_err().to_string();
            assert!(
                e.contains("checksum") || e.contains("not a slidestack"),
                "{e}"
            );
        }
        std::fs::write(&p, &good[..good.len() - 5]).unwrap();
        assert!(read_unit(&p, &id(0)).is_err());
    }
}
