//! The study configuration file (YAML). Unknown keys are refused and every value is checked
//! before any work starts; errors name the key.
//!
//! ```yaml
//! output_dir: out/quick            # relative to the working directory; `--out` overrides it
//! zones:                           # hazard levels: HDF5 groups `zone_<name>`
//!   - { name: III, target: "is1893:zone=III,soil=I" }
//!   - { name: V, target: "is1893:zone=V,soil=I" }
//! motions:
//!   seeds:                         # either stochastic …
//!     stochastic: { count: 11, seed: 2016 }      # optional `model:` (StochasticModel keys)
//!   # … or records (paths relative to this file):
//!   #   records: { files: [a.AT2, b.AT2], units: g, dt_s: 0.01 }
//!   matching: { passes: [10, 25, 50] }           # MatchSettings keys, defaults for the rest
//!   set_mean_min: 1.0              # the set's mean spectrum / target must not fall below this
//!   allow_unmatched: false         # true: keep motions outside the band, flagged
//! ```

use crate::motion::matching::{MatchError, MatchSettings};
use crate::motion::stochastic::{StochasticError, StochasticModel};
use crate::motion::{ReadOptions, Units};
use crate::spectrum::{TargetError, TargetSpectrum};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyConfig {
    pub output_dir: PathBuf,
    pub zones: Vec<ZoneConfig>,
    pub motions: MotionsConfig,
    /// The parameter grid of the sweep; required by `sweep` and later stages.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grid: Option<GridConfig>,
}

/// A list of values, or an inclusive range `{ from, to, step }`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Values {
    List(Vec<f64>),
    Range(Range),
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Range {
    pub from: f64,
    pub to: f64,
    pub step: f64,
}

impl Values {
    /// The values in order; a range is `from + k·step` up to `to` (within 1e-9 of a step), each
    /// rounded to 12 significant digits so that `0.1 + 2·0.1` reads back as `0.3`.
    pub fn values(&self) -> Vec<f64> {
        match self {
            Values::List(v) => v.clone(),
            Values::Range(r) => {
                if !(r.step > 0.0 && r.to >= r.from && r.step.is_finite()) {
                    return Vec::new();
                }
                let n = ((r.to - r.from) / r.step + 1e-9).floor() as usize;
                (0..=n)
                    .map(|k| {
                        let v = r.from + r.step * k as f64;
                        format!("{v:.12e}").parse().unwrap_or(v)
                    })
                    .collect()
            }
        }
    }
}

/// The sweep's grid (paper Section 7.3): structure periods, block mass ratios per block (bottom
/// first) and kinetic friction coefficients per interface (interface 1 first).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridConfig {
    /// Periods `T_p` of the bare structure, s.
    pub period_s: Values,
    /// `α_i = m_i/m_p` per block.
    pub alpha: Vec<Values>,
    /// Kinetic `μ_i` per interface.
    pub mu: Vec<Values>,
    /// Static coefficients are `mu_static_ratio·μ_i` (≥ 1; 1: static equals kinetic, the paper).
    #[serde(default = "one")]
    pub mu_static_ratio: f64,
    /// Damping ratio of the bare structure.
    #[serde(default = "five_percent")]
    pub damping: f64,
}

fn five_percent() -> f64 {
    0.05
}

/// One hazard level: its name (the group `zone_<name>`) and its target spectrum (SPEC string).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ZoneConfig {
    pub name: String,
    pub target: String,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionsConfig {
    pub seeds: SeedsConfig,
    #[serde(default)]
    pub matching: MatchSettings,
    /// Lowest accepted ratio of the set's mean spectrum to the target on the check grid
    /// (ASCE 7-16 asks 0.9; the study's default is 1.0).
    #[serde(default = "one")]
    pub set_mean_min: f64,
    /// Keep a motion that does not meet the matching acceptance (or leaves the band once the
    /// set is scaled), flagged in the report, instead of refusing the stage.
    #[serde(default)]
    pub allow_unmatched: bool,
}

fn one() -> f64 {
    1.0
}

fn three() -> usize {
    3
}

/// Where the motions come from: exactly one of `stochastic` and `records`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SeedsConfig {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stochastic: Option<StochasticSeeds>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub records: Option<RecordSeeds>,
}

/// The seeds, once it is known which kind.
#[derive(Debug, Clone, PartialEq)]
pub enum Seeds<'a> {
    Stochastic(&'a StochasticSeeds),
    Records(&'a RecordSeeds),
}

impl SeedsConfig {
    /// Panics only if called on an unvalidated config with neither kind.
    pub fn kind(&self) -> Seeds<'_> {
        match (&self.stochastic, &self.records) {
            (Some(s), _) => Seeds::Stochastic(s),
            (None, Some(r)) => Seeds::Records(r),
            (None, None) => panic!("validated configs name one kind of seeds"),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StochasticSeeds {
    /// Motions wanted per zone.
    pub count: usize,
    pub seed: u64,
    /// Extra seeds drawn so that `count` motions remain when some fail the matching
    /// acceptance; the first `count` accepted (in seed order) are kept.
    #[serde(default = "three")]
    pub spare: usize,
    #[serde(default)]
    pub model: StochasticModel,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordSeeds {
    /// Record files, relative to the config file.
    pub files: Vec<PathBuf>,
    /// Units of files that do not declare them: `g`, `m/s2`, `cm/s2`.
    #[serde(default)]
    pub units: Option<String>,
    /// Time step of single-column files that do not declare it, s.
    #[serde(default)]
    pub dt_s: Option<f64>,
}

#[derive(Debug, Error)]
pub enum ConfigError {
    #[error("{file}: cannot read: {source}")]
    Io {
        file: String,
        source: std::io::Error,
    },
    #[error("{file}: {source}")]
    Yaml {
        file: String,
        source: serde_yaml::Error,
    },
    #[error("{file}: `{key}`: {why}")]
    Invalid {
        file: String,
        key: String,
        why: String,
    },
}

impl StudyConfig {
    /// Reads and validates a study file; relative record paths become relative to its folder.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Io {
            file: file.clone(),
            source,
        })?;
        let mut cfg: StudyConfig =
            serde_yaml::from_str(&text).map_err(|source| ConfigError::Yaml {
                file: file.clone(),
                source,
            })?;
        let base = path.parent().unwrap_or(Path::new("."));
        if let Some(r) = &mut cfg.motions.seeds.records {
            for f in &mut r.files {
                if f.is_relative() {
                    *f = base.join(&*f);
                }
            }
        }
        cfg.validate()
            .map_err(|(key, why)| ConfigError::Invalid { file, key, why })?;
        Ok(cfg)
    }

    /// Every check that needs no computation; `Err((key, why))`.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let err = |k: &str, w: String| Err((k.to_string(), w));
        if self.zones.is_empty() {
            return err("zones", "needs at least one zone".into());
        }
        for (i, z) in self.zones.iter().enumerate() {
            let key = format!("zones[{i}]");
            if z.name.is_empty()
                || !z
                    .name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
            {
                return err(
                    &format!("{key}.name"),
                    format!("`{}` must be letters, digits, `_` or `-`", z.name),
                );
            }
            if self.zones[..i].iter().any(|o| o.name == z.name) {
                return err(
                    &format!("{key}.name"),
                    format!("`{}` appears twice", z.name),
                );
            }
            let t = self
                .target(i)
                .map_err(|e| (format!("{key}.target"), e.to_string()))?;
            let (lo, hi) = self.motions.matching.check_range_s;
            t.check_covers(lo, hi)
                .map_err(|e| (format!("{key}.target"), e.to_string()))?;
        }
        self.motions
            .matching
            .validate()
            .map_err(|e: MatchError| ("motions.matching".to_string(), e.to_string()))?;
        let m = self.motions.set_mean_min;
        if !(m.is_finite() && m > 0.0 && m <= self.motions.matching.upper) {
            return err(
                "motions.set_mean_min",
                format!("{m} must be in (0, matching.upper]"),
            );
        }
        if let Some(g) = &self.grid {
            validate_grid(g)?;
        }
        let seeds = &self.motions.seeds;
        if seeds.stochastic.is_some() == seeds.records.is_some() {
            return err(
                "motions.seeds",
                "give exactly one of `stochastic` and `records`".into(),
            );
        }
        match seeds.kind() {
            Seeds::Stochastic(s) => {
                if s.count == 0 {
                    return err("motions.seeds.stochastic.count", "must be ≥ 1".into());
                }
                s.model.validate().map_err(|e: StochasticError| {
                    ("motions.seeds.stochastic.model".to_string(), e.to_string())
                })?;
            }
            Seeds::Records(r) => {
                if r.files.is_empty() {
                    return err(
                        "motions.seeds.records.files",
                        "needs at least one file".into(),
                    );
                }
                if let Some(u) = &r.units {
                    u.parse::<Units>()
                        .map_err(|e| ("motions.seeds.records.units".to_string(), e.to_string()))?;
                }
                if let Some(dt) = r.dt_s
                    && !(dt.is_finite() && dt > 0.0)
                {
                    return err("motions.seeds.records.dt_s", format!("{dt} must be > 0"));
                }
                for f in &r.files {
                    if !f.is_file() {
                        return err(
                            "motions.seeds.records.files",
                            format!("{} does not exist", f.display()),
                        );
                    }
                }
            }
        }
        Ok(())
    }

    /// The grid, or an error naming the missing section.
    pub fn grid(&self) -> Result<&GridConfig, ConfigError> {
        self.grid.as_ref().ok_or_else(|| ConfigError::Invalid {
            file: "study".into(),
            key: "grid".into(),
            why: "this stage needs a `grid` section".into(),
        })
    }

    /// The target spectrum of zone `i`.
    pub fn target(&self, i: usize) -> Result<TargetSpectrum, TargetError> {
        self.zones[i].target.parse()
    }

    /// Reading options of record seeds.
    pub fn read_options(r: &RecordSeeds) -> ReadOptions {
        ReadOptions {
            units: r.units.as_deref().and_then(|u| u.parse().ok()),
            dt_s: r.dt_s,
        }
    }
}

fn validate_grid(g: &GridConfig) -> Result<(), (String, String)> {
    let check = |key: String, v: &Values, lo: f64, lo_open: bool| -> Result<(), (String, String)> {
        let vals = v.values();
        if vals.is_empty() {
            return Err((
                key,
                "needs at least one value (a range needs step > 0, to ≥ from)".into(),
            ));
        }
        for x in &vals {
            let ok = x.is_finite() && if lo_open { *x > lo } else { *x >= lo };
            if !ok {
                let rel = if lo_open { ">" } else { "≥" };
                return Err((key, format!("value {x} must be finite and {rel} {lo}")));
            }
        }
        if vals.windows(2).any(|w| w[1] <= w[0]) {
            return Err((key, "values must be strictly increasing".into()));
        }
        Ok(())
    };
    check("grid.period_s".into(), &g.period_s, 0.0, true)?;
    if g.alpha.is_empty() {
        return Err((
            "grid.alpha".into(),
            "needs one list per block (at least one block)".into(),
        ));
    }
    if g.mu.len() != g.alpha.len() {
        return Err((
            "grid.mu".into(),
            format!(
                "needs one list per interface: {} blocks, {} lists",
                g.alpha.len(),
                g.mu.len()
            ),
        ));
    }
    for (i, a) in g.alpha.iter().enumerate() {
        check(format!("grid.alpha[{i}]"), a, 0.0, true)?;
    }
    for (i, m) in g.mu.iter().enumerate() {
        check(format!("grid.mu[{i}]"), m, 0.0, false)?;
    }
    if !(g.mu_static_ratio.is_finite() && g.mu_static_ratio >= 1.0) {
        return Err((
            "grid.mu_static_ratio".into(),
            format!("{} must be ≥ 1", g.mu_static_ratio),
        ));
    }
    if !(g.damping.is_finite() && (0.0..1.0).contains(&g.damping)) {
        return Err((
            "grid.damping".into(),
            format!("{} must be in [0, 1)", g.damping),
        ));
    }
    Ok(())
}
