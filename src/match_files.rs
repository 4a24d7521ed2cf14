//! Record files matched to a target spectrum, as `slidestack match` does it: each record matched
//! ([`crate::ground_motion::matching`]), the ones that meet the acceptance written as PEER `.AT2` files
//! (values in g, the record's base name), and `summary.csv` with one row per record (iterations,
//! worst misfit, PGA before and after, final velocity and displacement, Arias intensity ratio).

use crate::ground_motion::matching::{MatchError, MatchReport, MatchSettings, match_record};
use crate::ground_motion::{Record, RecordError, checked_at2};
use crate::spectrum::{TargetError, TargetSpectrum};
use crate::store::StoreError;
use crate::store::atomic::write_bytes;
use crate::study::config::{ConfigError, read_yaml_text, yaml_problem};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use thiserror::Error;

#[derive(Debug, Error)]
pub enum MatchFilesError {
    #[error(transparent)]
    Config(#[from] ConfigError),
    #[error("invalid settings {}: {why}", file.display())]
    Settings { file: PathBuf, why: String },
    #[error("the target does not cover the matching range: {0}")]
    Target(TargetError),
    #[error("cannot create {}: {source}", dir.display())]
    CreateDir {
        dir: PathBuf,
        source: std::io::Error,
    },
    #[error("{record}: matching failed: {source}")]
    Match { record: String, source: MatchError },
    #[error(transparent)]
    Record(#[from] RecordError),
    #[error(transparent)]
    Store(#[from] StoreError),
    #[error(
        "{} of {total} records did not meet the acceptance (every check period within [{lower}, \
         {upper}] of the target) and were left out: {}",
        records.len(),
        records.join(", ")
    )]
    LeftOut {
        records: Vec<String>,
        total: usize,
        lower: f64,
        upper: f64,
    },
}

/// Matching settings from a YAML file (the keys of [`MatchSettings`]), unknown keys and
/// impossible values refused.
pub fn read_settings(path: &Path) -> Result<MatchSettings, MatchFilesError> {
    let bad = |why: String| MatchFilesError::Settings {
        file: path.to_path_buf(),
        why,
    };
    let text = read_yaml_text(path)?;
    let s: MatchSettings =
        serde_yaml::from_str(&text).map_err(|e| bad(yaml_problem(&text, &e).to_string()))?;
    s.validate().map_err(|e| bad(e.to_string()))?;
    Ok(s)
}

/// `NAME.AT2` for a record read from `NAME.ext`.
pub fn at2_name(record: &Record) -> String {
    let stem = Path::new(&record.name)
        .file_stem()
        .map_or_else(|| record.name.clone(), |s| s.to_string_lossy().into_owned());
    format!("{stem}.AT2")
}

/// What matching did to one record file.
#[derive(Debug, Clone)]
pub struct MatchedFile {
    pub record: String,
    pub report: MatchReport,
    /// The `.AT2` file written, when the record met the acceptance.
    pub written: Option<String>,
}

/// Matches every record to `target` (in parallel) and writes the accepted ones and
/// `summary.csv` into `out` (created if missing); the target must cover the check range.
pub fn match_files(
    records: &[Record],
    target: &TargetSpectrum,
    settings: &MatchSettings,
    out: &Path,
) -> Result<Vec<MatchedFile>, MatchFilesError> {
    let (lo, hi) = settings.check_range_s;
    target
        .check_covers(lo, hi)
        .map_err(MatchFilesError::Target)?;
    std::fs::create_dir_all(out).map_err(|source| MatchFilesError::CreateDir {
        dir: out.to_path_buf(),
        source,
    })?;
    let matched = records
        .par_iter()
        .map(|rec| {
            match_record(&rec.accel_g, rec.dt_s, target, settings).map_err(|source| {
                MatchFilesError::Match {
                    record: rec.name.clone(),
                    source,
                }
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut files = Vec::new();
    for (rec, m) in records.iter().zip(matched) {
        let written = if m.report.converged {
            let name = at2_name(rec);
            let matched = Record {
                name: name.clone(),
                dt_s: rec.dt_s,
                accel_g: m.accel_g,
            };
            let desc = format!(
                "{} matched to {target} by slidestack {} (wavelet adjustment)",
                rec.name,
                env!("CARGO_PKG_VERSION")
            );
            let path = out.join(&name);
            let text = checked_at2(&matched, &desc, &path.display().to_string())?;
            write_bytes(&path, text.as_bytes())?;
            Some(name)
        } else {
            None
        };
        files.push(MatchedFile {
            record: rec.name.clone(),
            report: m.report,
            written,
        });
    }
    write_bytes(&out.join("summary.csv"), summary(&files).as_bytes())?;
    Ok(files)
}

/// `summary.csv`: one row per record (the `csv` crate quotes a record's name where it holds a
/// comma, a quote or a line break).
fn summary(files: &[MatchedFile]) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    let header = [
        "record",
        "converged",
        "iterations",
        "worst_misfit",
        "scale",
        "pga_before_g",
        "pga_after_g",
        "final_velocity_mps",
        "final_displacement_m",
        "arias_ratio",
        "output",
    ];
    w.write_record(header).expect("writing to memory");
    for f in files {
        let r = &f.report;
        w.write_record([
            f.record.clone(),
            r.converged.to_string(),
            r.iterations.to_string(),
            r.worst_misfit.to_string(),
            r.scale.to_string(),
            r.pga_before_g.to_string(),
            r.pga_after_g.to_string(),
            r.final_velocity_mps.to_string(),
            r.final_displacement_m.to_string(),
            r.arias_ratio.to_string(),
            f.written.clone().unwrap_or_default(),
        ])
        .expect("writing to memory");
    }
    let bytes = w.into_inner().expect("writing to memory");
    String::from_utf8(bytes).expect("UTF-8 fields")
}

/// Refuses a run in which some record did not meet the acceptance, naming them.
pub fn all_accepted(
    files: &[MatchedFile],
    settings: &MatchSettings,
) -> Result<(), MatchFilesError> {
    let records: Vec<String> = files
        .iter()
        .filter(|f| f.written.is_none())
        .map(|f| f.record.clone())
        .collect();
    if records.is_empty() {
        return Ok(());
    }
    Err(MatchFilesError::LeftOut {
        records,
        total: files.len(),
        lower: settings.lower,
        upper: settings.upper,
    })
}
