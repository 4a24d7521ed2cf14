//! The study configuration file (YAML). Unknown keys are refused and every value is checked
//! before any work starts; errors name the key.
//!
//! ```yaml
//! output_dir: out/quick            # relative to the working directory; `--out` overrides it
//! zones:                           # hazard levels: HDF5 groups `zone_<name>`
//!   - { name: III, target: "is1893:zone=III,soil=I" }
//!   - { name: V, target: "is1893:zone=V,soil=I" }   # or "table:FILE", relative to this file
//! motions:
//!   seeds:                         # either stochastic …
//!     stochastic: { count: 11, seed: 2016 }      # optional `model:` (StochasticModel keys)
//!   # … or records (paths relative to this file):
//!   #   records: { files: [a.AT2, b.AT2], units: g, dt_s: 0.01 }
//!   matching: { passes: [10, 25, 50] }           # MatchSettings keys, defaults for the rest
//!   set_mean_min: 1.0              # the set's mean spectrum / target must not fall below this
//!   allow_unmatched: false         # true: keep motions outside the band, flagged
//! ```

use super::building::{BuildingSection, FloorKey, Frame, OneOrList};
use super::ida::IdaConfig;
use super::physics::{DampingBasis, Physics};
use super::yaml::{checked_value, shown};
use crate::dynamics::building::Building;
use crate::grid::linear_range;
use crate::grid::{BuildingAxes, Grid};
use crate::ground_motion::matching::{MatchError, MatchSettings};
use crate::ground_motion::stochastic::{StochasticError, StochasticModel};
use crate::ground_motion::{ReadOptions, Units};
use crate::limits::{
    InputFileError, MAX_ALPHA, MAX_AXIS_VALUES, MAX_BLOCKS, MAX_CASE_RESULTS, MAX_FILE_BYTES,
    MAX_MOTIONS, MAX_MU, MAX_YAML_DEPTH, PERIOD_RANGE_S, excerpt, excerpt_message, input_text,
    read_input_file, yaml_depth,
};
use crate::spectrum::target::read_table_bytes;
use crate::spectrum::{TargetError, TargetSpectrum};
use crate::store::fingerprint::sha256_hex;
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
    /// Incremental dynamic analysis of a yielding structure; required by `ida`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ida: Option<IdaConfig>,
    /// Floor response spectra of listed cases on every frame; required by `floors`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floor_spectra: Option<super::floors::FloorsConfig>,
    /// A study over buildings: the structure is a shear building (docs/model.md, "A study over
    /// buildings").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub building: Option<BuildingSection>,
    /// What the report sets beside this study's own numbers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub report: Option<ReportConfig>,
    /// The config file and the files it names, as [`StudyConfig::load`] read them.
    #[serde(skip)]
    pub loaded: Loaded,
}

/// The `report:` section.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReportConfig {
    /// Another building study's config (relative to this one's folder) whose answer the
    /// report's building section sets beside this one's, frame by frame: the same buildings and
    /// grid under the other damping basis, or other motions. Its stages must be run first.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compare_with: Option<PathBuf>,
}

/// What [`StudyConfig::load`] read besides the YAML keys, each file once: what the study uses
/// and what the motions stage's fingerprint hashes are the same bytes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Loaded {
    /// SHA-256 of the config file's bytes.
    pub config_sha256: String,
    /// Each zone's target spectrum, in `zones` order.
    pub targets: Vec<ZoneTarget>,
    /// SHA-256 of each record file, in `motions.seeds.records.files` order (empty for
    /// stochastic seeds).
    pub record_sha256: Vec<String>,
}

/// A zone's target spectrum as the study uses it.
#[derive(Debug, Clone, PartialEq)]
pub struct ZoneTarget {
    pub spectrum: TargetSpectrum,
    /// The table file of a `table:FILE` target: its path (resolved against the config's folder)
    /// and the SHA-256 of the bytes the spectrum was parsed from.
    pub table: Option<(PathBuf, String)>,
}

impl ZoneTarget {
    /// The target of SPEC string `spec`; a table's FILE is taken relative to `base` (the config's
    /// folder) and read once. The table keeps FILE as written for its SPEC string and labels.
    fn load(spec: &str, base: &Path) -> Result<Self, TargetError> {
        let Some(file) = TargetSpectrum::table_file(spec).filter(|f| !f.is_empty()) else {
            return Ok(Self {
                spectrum: spec.parse()?,
                table: None,
            });
        };
        let path = base.join(file);
        let bytes = read_table_bytes(&path)?;
        let spectrum = TargetSpectrum::from_table_text(&bytes, file, &path.display().to_string())?;
        Ok(Self {
            spectrum,
            table: Some((path, sha256_hex(&bytes))),
        })
    }
}

/// A list of values, or an inclusive range `{ from, to, step }`.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Values {
    List(Vec<f64>),
    Range(Range),
}

impl<'de> Deserialize<'de> for Values {
    /// A list of numbers or a range; anything else refused in words ([`checked_value`]).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde_yaml::Value;
        checked_value(d, |v| match v {
            Value::Sequence(items) => (items.iter())
                .map(|x| {
                    (x.as_f64())
                        .ok_or_else(|| format!("expected a number in the list, got {}", shown(x)))
                })
                .collect::<Result<_, _>>()
                .map(Values::List),
            Value::Mapping(_) => serde_yaml::from_value(v)
                .map(Values::Range)
                .map_err(|e| format!("a range {{ from, to, step }}: {e}")),
            x => Err(format!(
                "expected a list of numbers or a range {{ from, to, step }}, got {}",
                shown(&x)
            )),
        })
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Range {
    pub from: f64,
    pub to: f64,
    pub step: f64,
}

impl Values {
    /// The values in order (a range expanded by [`linear_range`]), at most
    /// [`MAX_AXIS_VALUES`].
    pub fn expand(&self) -> Result<Vec<f64>, String> {
        match self {
            Values::List(v) if v.len() > MAX_AXIS_VALUES => {
                Err(format!("{} values; at most {MAX_AXIS_VALUES}", v.len()))
            }
            Values::List(v) => Ok(v.clone()),
            Values::Range(r) => linear_range(r.from, r.to, r.step, MAX_AXIS_VALUES),
        }
    }

    /// The values of a validated list or range.
    pub fn values(&self) -> Vec<f64> {
        self.expand().unwrap_or_default()
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
    /// Viscous damping ratio, of the system `damping_basis` names.
    #[serde(default = "default_damping")]
    pub damping: f64,
    /// `rigid` (default): `damping` is the ratio of the structure with its whole load rigidly
    /// attached, one damper for every system; `structure`: of the bare structure.
    #[serde(default)]
    pub damping_basis: DampingBasis,
    /// With a `building:` section: the floor the stack stands on, `roof` (the default), `all`
    /// (a stack on every floor), or a list of them (the `stack_floor` axis).
    #[serde(
        default,
        deserialize_with = "super::building::stack_floors",
        skip_serializing_if = "Option::is_none"
    )]
    pub stack_floor: Option<OneOrList<FloorKey>>,
    /// Width over height of each block, bottom first: the sweep then stores whether each case
    /// would start to rock under each motion (`rocks_stack`; docs/model.md, "Rocking: when a
    /// case leaves the model"). Absent: not checked.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aspect: Option<Vec<f64>>,
}

impl GridConfig {
    /// The grid's axes, expanded.
    pub fn axes(&self) -> Grid {
        Grid {
            periods_s: self.period_s.values(),
            alpha: self.alpha.iter().map(Values::values).collect(),
            mu: self.mu.iter().map(Values::values).collect(),
        }
    }

    /// The physics settings of every case.
    pub fn physics(&self) -> Physics {
        Physics {
            damping: self.damping,
            basis: self.damping_basis,
            mu_static_ratio: self.mu_static_ratio,
        }
    }
}

fn default_damping() -> f64 {
    Physics::DEFAULT.damping
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
    /// Not valid YAML or not a study file ([`yaml_problem`]): the message names the file's
    /// keys as it writes them, not a command's flags.
    #[error("{file}: {problem}")]
    Yaml { file: String, problem: YamlProblem },
    #[error("{file}: `{key}`: {why}")]
    Invalid {
        file: String,
        key: String,
        why: String,
    },
}

impl ConfigError {
    /// The error without the line of a YAML problem: for YAML written by a program from other
    /// data (the Python module's config dict), whose lines mean nothing to its reader.
    pub fn without_line(self) -> Self {
        match self {
            ConfigError::Yaml { file, problem } => ConfigError::Yaml {
                file,
                problem: YamlProblem {
                    line: None,
                    ..problem
                },
            },
            e => e,
        }
    }
}

/// The text of a YAML file, checked before any parser sees it: at most [`MAX_FILE_BYTES`],
/// UTF-8, a byte-order mark dropped, nesting at most [`MAX_YAML_DEPTH`] deep.
pub fn read_yaml_text(path: &Path) -> Result<String, ConfigError> {
    yaml_text(&read_yaml_bytes(path)?, path)
}

/// The bytes of a YAML file, refused above [`MAX_FILE_BYTES`] before they are read.
fn read_yaml_bytes(path: &Path) -> Result<Vec<u8>, ConfigError> {
    let file = path.display().to_string();
    read_input_file(path).map_err(|e| match e {
        InputFileError::Io(source) => ConfigError::Io { file, source },
        InputFileError::TooLarge(bytes) => ConfigError::Invalid {
            file,
            key: "(file)".into(),
            why: format!("{bytes} bytes: a YAML file may have at most {MAX_FILE_BYTES}"),
        },
    })
}

/// The text of the YAML file `path`'s bytes: UTF-8, a byte-order mark dropped, nesting at most
/// [`MAX_YAML_DEPTH`] deep.
fn yaml_text(bytes: &[u8], path: &Path) -> Result<String, ConfigError> {
    let file = path.display().to_string();
    let text = input_text(bytes).map_err(|source| ConfigError::Io {
        file: file.clone(),
        source,
    })?;
    let depth = yaml_depth(text);
    if depth > MAX_YAML_DEPTH {
        return Err(ConfigError::Invalid {
            file,
            key: "(file)".into(),
            why: format!("nested {depth} levels deep; a config nests at most {MAX_YAML_DEPTH}"),
        });
    }
    Ok(text.to_string())
}

/// What a YAML parser found wrong with a file, in the file's own words ([`yaml_problem`]).
#[derive(Debug, Clone, PartialEq)]
pub struct YamlProblem {
    /// The line of the key or value at fault.
    pub line: Option<usize>,
    /// `` `key`: what ``: the key as the file writes it (`building.storeys`, `stacks[0].floor`;
    /// never a command's flag) and what is wrong with it.
    pub message: String,
}

impl std::fmt::Display for YamlProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self.line {
            Some(l) => write!(f, "line {l}: {}", self.message),
            None => f.write_str(&self.message),
        }
    }
}

/// A YAML parser's error about `text` in the file's own words: the line of the key or value at
/// fault (for a key given twice, the second one), the key and what is wrong, an unknown key with
/// the keys allowed there. The parser's own message, shortened, for what it does not recognise.
pub fn yaml_problem(text: &str, e: &serde_yaml::Error) -> YamlProblem {
    let full = e.to_string();
    let location = e.location();
    let mut body = full.as_str();
    if let Some(l) = &location {
        body = body
            .strip_suffix(&format!(" at line {} column {}", l.line(), l.column()))
            .unwrap_or(body);
    }
    let is_path = |p: &str| {
        !p.is_empty()
            && p.chars()
                .all(|c| c.is_alphanumeric() || "_-.[]".contains(c))
    };
    let (path, body) = match body.split_once(": ") {
        Some((p, rest)) if is_path(p) => (Some(p), rest),
        _ => (None, body),
    };
    let mut line = location.as_ref().map(serde_yaml::Location::line);
    let quoted = |rest: &str| {
        rest.split_once('`')
            .map(|(k, after)| (k.to_string(), after.to_string()))
    };
    let what = if let Some((key, _)) = body.strip_prefix("duplicate field `").and_then(quoted) {
        if let Some(l) = &location {
            line = second_key_line(text, l.line(), l.column(), &key).or(line);
        }
        format!("`{key}` is given twice")
    } else if let Some((key, expected)) = body.strip_prefix("unknown field `").and_then(quoted) {
        let keys: Vec<String> = (expected.split('`').skip(1).step_by(2))
            .map(|k| format!("`{k}`"))
            .collect();
        let allowed = match (keys.is_empty(), path) {
            (true, _) => "no key is allowed here".to_string(),
            (false, Some(p)) => format!("the keys of `{p}` are {}", keys.join(", ")),
            (false, None) => format!("the keys are {}", keys.join(", ")),
        };
        format!("unknown key `{}`; {allowed}", excerpt(&key))
    } else if let Some((key, _)) = body.strip_prefix("missing field `").and_then(quoted) {
        format!("missing key `{key}`")
    } else {
        excerpt_message(body)
    };
    let message = match path {
        Some(p) => format!("`{p}`: {what}"),
        None => what,
    };
    YamlProblem { line, message }
}

/// The line of the second `key` of the block mapping whose first key is on `line` at `column`
/// (1-based, as the parser reports a mapping's start); `None` in a flow mapping or when not
/// found.
fn second_key_line(text: &str, line: usize, column: usize, key: &str) -> Option<usize> {
    let indent = column.checked_sub(1)?;
    let mut seen = 0;
    for (i, l) in text.lines().enumerate().skip(line.checked_sub(1)?) {
        let body = l.trim_start();
        if body.is_empty() || body.starts_with('#') {
            continue;
        }
        if i + 1 > line && l.len() - body.len() < indent {
            return None;
        }
        let Some(at) = l.get(indent..) else { continue };
        let name = [key.to_string(), format!("\"{key}\""), format!("'{key}'")]
            .into_iter()
            .find_map(|k| at.strip_prefix(&k));
        if name.is_some_and(|rest| rest.trim_start().starts_with(':')) {
            seen += 1;
            if seen == 2 {
                return Some(i + 1);
            }
        }
    }
    None
}

impl StudyConfig {
    /// Reads and validates a study file. Record files and target tables are found relative to
    /// its folder, like any file it names, and each file is read once ([`Loaded`]).
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let bytes = read_yaml_bytes(path)?;
        Self::parse(&bytes, path, path.parent().unwrap_or(Path::new(".")))
    }

    /// Validates a study's YAML `bytes` as [`StudyConfig::load`] does a file's: `path` names it
    /// in messages and the files it names are found relative to `base` (the Python module passes
    /// a mapping this way, relative to the working directory).
    pub fn parse(bytes: &[u8], path: &Path, base: &Path) -> Result<Self, ConfigError> {
        let file = path.display().to_string();
        let text = yaml_text(bytes, path)?;
        let mut cfg: StudyConfig = serde_yaml::from_str(&text).map_err(|e| ConfigError::Yaml {
            file: file.clone(),
            problem: yaml_problem(&text, &e),
        })?;
        cfg.loaded.config_sha256 = sha256_hex(bytes);
        let invalid = |key: String, why: String| ConfigError::Invalid {
            file: file.clone(),
            key,
            why,
        };
        if let Some(r) = &mut cfg.motions.seeds.records {
            for f in &mut r.files {
                if f.is_relative() {
                    *f = base.join(&*f);
                }
            }
        }
        for (i, z) in cfg.zones.iter().enumerate() {
            let target = ZoneTarget::load(&z.target, base)
                .map_err(|e| invalid(format!("zones[{i}].target"), e.to_string()))?;
            cfg.loaded.targets.push(target);
        }
        if let Some(other) = cfg.report.as_mut().and_then(|r| r.compare_with.as_mut())
            && other.is_relative()
        {
            *other = base.join(&*other);
        }
        if let Some(ida) = cfg.ida.as_mut().filter(|ida| ida.cases.from_grid) {
            let Some(g) = &cfg.grid else {
                let why = "`grid` takes every case of the `grid` section, and the config has none";
                return Err(invalid("ida.cases".into(), why.into()));
            };
            validate_grid(g).map_err(|(key, why)| invalid(key, why))?;
            (ida.cases.expand(&g.axes())).map_err(|why| invalid("ida.cases".into(), why))?;
        }
        cfg.validate().map_err(|(key, why)| invalid(key, why))?;
        if let Some(r) = &cfg.motions.seeds.records {
            for f in &r.files {
                let bytes = read_input_file(f).map_err(|e| match e {
                    InputFileError::Io(source) => ConfigError::Io {
                        file: f.display().to_string(),
                        source,
                    },
                    InputFileError::TooLarge(bytes) => invalid(
                        "motions.seeds.records.files".into(),
                        format!("{}: {bytes} bytes; at most {MAX_FILE_BYTES}", f.display()),
                    ),
                })?;
                cfg.loaded.record_sha256.push(sha256_hex(&bytes));
            }
        }
        Ok(cfg)
    }

    /// Every check that needs no computation; `Err((key, why))`.
    fn validate(&self) -> Result<(), (String, String)> {
        let err = |k: &str, w: String| Err((k.to_string(), w));
        if self.zones.is_empty() {
            return err("zones", "needs at least one zone".into());
        }
        if let Some(other) = self.report.as_ref().and_then(|r| r.compare_with.as_ref()) {
            let key = "report.compare_with";
            if self.building.is_none() {
                return err(
                    key,
                    "compares building studies: the config needs `building`".into(),
                );
            }
            if !other.is_file() {
                return err(key, format!("{}: no such config file", other.display()));
            }
        }
        for (i, z) in self.zones.iter().enumerate() {
            let key = format!("zones[{i}]");
            let earlier = self.zones[..i].iter().map(|o| o.name.as_str());
            crate::limits::check_name(&z.name, earlier)
                .map_err(|why| (format!("{key}.name"), why))?;
            let (lo, hi) = self.motions.matching.check_range_s;
            self.target(i)
                .check_covers(lo, hi)
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
        let frames = self.validate_building()?;
        if let Some(g) = &self.grid {
            validate_grid(g)?;
            let per_zone = match (&self.motions.seeds.stochastic, &self.motions.seeds.records) {
                (Some(s), _) => s.count,
                (None, Some(r)) => r.files.len(),
                (None, None) => 0,
            };
            // Counted in floating point: a product of axis lengths can overflow any integer.
            let cases: f64 = g.axes().shape().iter().map(|&n| n as f64).product::<f64>()
                * frames.as_ref().map_or(1, BuildingAxes::frame_count) as f64;
            let results = cases * per_zone as f64 * self.zones.len() as f64;
            if results > MAX_CASE_RESULTS as f64 {
                return err(
                    "grid",
                    format!(
                        "{results} case results (cases × motions × zones); at most \
                         {MAX_CASE_RESULTS} (sweep.h5 is assembled in memory)"
                    ),
                );
            }
        }
        if let Some(ida) = &self.ida {
            let physics = self.physics();
            let targets: Vec<_> = (0..self.zones.len())
                .map(|i| (self.zones[i].name.clone(), self.target(i).clone()))
                .collect();
            let frames: Option<Vec<Frame>> = frames.as_ref().map(|a| {
                (0..a.frame_count())
                    .filter_map(|i| self.frame(a, i))
                    .collect()
            });
            ida.validate(&physics, &targets, frames.as_deref())?;
        }
        if let Some(floors) = &self.floor_spectra {
            let frames: Option<Vec<Frame>> = frames.as_ref().map(|a| {
                (0..a.frame_count())
                    .filter_map(|i| self.frame(a, i))
                    .collect()
            });
            floors.validate(&self.physics(), frames.as_deref())?;
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
                if s.count == 0 || s.count > MAX_MOTIONS {
                    return err(
                        "motions.seeds.stochastic.count",
                        format!("must be ≥ 1 and ≤ {MAX_MOTIONS}"),
                    );
                }
                if s.spare > MAX_MOTIONS {
                    return err(
                        "motions.seeds.stochastic.spare",
                        format!("must be ≤ {MAX_MOTIONS}"),
                    );
                }
                s.model.validate().map_err(|e: StochasticError| {
                    ("motions.seeds.stochastic.model".to_string(), e.to_string())
                })?;
            }
            Seeds::Records(r) => {
                if r.files.len() > MAX_MOTIONS {
                    return err(
                        "motions.seeds.records.files",
                        format!("{} files; at most {MAX_MOTIONS}", r.files.len()),
                    );
                }
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
                    let why = if f.is_dir() {
                        "is a directory, not a record file"
                    } else if !f.exists() {
                        "does not exist"
                    } else {
                        continue;
                    };
                    return err(
                        "motions.seeds.records.files",
                        format!("{} {why}", f.display()),
                    );
                }
            }
        }
        Ok(())
    }

    /// The `building:` section against the grid; the building axes of a building study.
    fn validate_building(&self) -> Result<Option<BuildingAxes>, (String, String)> {
        let stack_floor = self.grid.as_ref().and_then(|g| g.stack_floor.as_ref());
        let Some(b) = &self.building else {
            if stack_floor.is_some() {
                let why = "needs a `building` section (a one-storey study has one floor)";
                return Err(("grid.stack_floor".into(), why.into()));
            }
            return Ok(None);
        };
        let axes = b.axes(stack_floor)?;
        if let Some(g) = &self.grid {
            let periods = g.period_s.values();
            let physics = g.physics();
            for &n in &axes.storeys {
                for p in [periods.first(), periods.last()].into_iter().flatten() {
                    let frame = b.frame(n, crate::grid::StackFloor::Roof);
                    Building::new(&physics.bare_building(*p, &frame))
                        .map_err(|e| ("building".to_string(), e.to_string()))?;
                }
            }
        }
        Ok(Some(axes))
    }

    /// The building axes of a building study (`None` without a `building:` section).
    pub fn building_axes(&self) -> Option<BuildingAxes> {
        let b = self.building.as_ref()?;
        b.axes(self.grid.as_ref().and_then(|g| g.stack_floor.as_ref()))
            .ok()
    }

    /// Frame `index` of the building axes (see [`BuildingAxes::frame`]).
    pub fn frame(&self, axes: &BuildingAxes, index: usize) -> Option<Frame> {
        let (n, floor) = axes.frame(index);
        Some(self.building.as_ref()?.frame(n, floor))
    }

    /// The physics of every case (`grid.damping`, `grid.mu_static_ratio`; the defaults without a
    /// grid).
    pub fn physics(&self) -> Physics {
        self.grid
            .as_ref()
            .map_or(Physics::DEFAULT, GridConfig::physics)
    }

    /// The grid, or an error naming the missing section.
    pub fn grid(&self) -> Result<&GridConfig, ConfigError> {
        self.grid.as_ref().ok_or_else(|| ConfigError::Invalid {
            file: "study".into(),
            key: "grid".into(),
            why: "this stage needs a `grid` section".into(),
        })
    }

    /// The target spectrum of zone `i`, as loaded.
    pub fn target(&self, i: usize) -> &TargetSpectrum {
        &self.loaded.targets[i].spectrum
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
    let check = |key: String, v: &Values, lo: f64, lo_open: bool, hi: f64| {
        let vals = v.expand().map_err(|why| (key.clone(), why))?;
        if vals.is_empty() {
            return Err((key, "needs at least one value".into()));
        }
        for x in &vals {
            let ok = x.is_finite() && (if lo_open { *x > lo } else { *x >= lo }) && *x <= hi;
            if !ok {
                let rel = if lo_open { ">" } else { "≥" };
                return Err((
                    key,
                    format!("value {x:?} must be finite, {rel} {lo} and ≤ {hi}"),
                ));
            }
        }
        if vals.windows(2).any(|w| w[1] <= w[0]) {
            return Err((key, "values must be strictly increasing".into()));
        }
        Ok(())
    };
    check(
        "grid.period_s".into(),
        &g.period_s,
        PERIOD_RANGE_S.0,
        false,
        PERIOD_RANGE_S.1,
    )?;
    if g.alpha.is_empty() || g.alpha.len() > MAX_BLOCKS {
        return Err((
            "grid.alpha".into(),
            format!(
                "needs one list per block, 1 to {MAX_BLOCKS} blocks (HDF5 stores at most 32 \
                 dimensions), got {}",
                g.alpha.len()
            ),
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
        check(format!("grid.alpha[{i}]"), a, 0.0, true, MAX_ALPHA)?;
    }
    let heaviest: f64 = g
        .alpha
        .iter()
        .map(|a| a.values().into_iter().fold(0.0, f64::max))
        .sum();
    if heaviest > MAX_ALPHA {
        return Err((
            "grid.alpha".into(),
            format!(
                "the heaviest stack has α = {heaviest}; at most {MAX_ALPHA} (beyond it round-off \
                 spoils the energy balance)"
            ),
        ));
    }
    for (i, m) in g.mu.iter().enumerate() {
        check(format!("grid.mu[{i}]"), m, 0.0, false, MAX_MU)?;
    }
    if let Some(aspect) = &g.aspect {
        if aspect.len() != g.alpha.len() {
            return Err((
                "grid.aspect".into(),
                format!(
                    "needs one ratio per block: {} blocks, {} ratios",
                    g.alpha.len(),
                    aspect.len()
                ),
            ));
        }
        if let Some((i, r)) =
            (aspect.iter().enumerate()).find(|(_, r)| !(r.is_finite() && **r > 0.0))
        {
            return Err((
                format!("grid.aspect[{i}]"),
                format!(
                    "{r} (width over height of block {}) must be finite and > 0",
                    i + 1
                ),
            ));
        }
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
    g.physics()
        .check(heaviest)
        .map_err(|why| ("grid.damping".to_string(), why))?;
    Ok(())
}
