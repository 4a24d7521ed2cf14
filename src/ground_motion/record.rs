//! Readers for PEER NGA `.AT2` files (both header styles) and plain-text records (one or two
//! columns), and a writer for `.AT2` files that reads back bit-identical.
//!
//! Every error names the file and the 1-based line it found the problem on.
//!
//! # Units and time step
//!
//! A [`Record`] always holds acceleration in g. Files may be in g, m/s² or cm/s² ([`Units`]):
//!
//! * `.AT2`: line 3 normally says `... IN UNITS OF G`; `CM/S/S`, `CM/SEC/SEC`, `M/S/S`, `GAL` and
//!   the like are converted. The time step is the header's `DT`.
//! * plain text: comment lines may declare `# units: cm/s2` and `# dt: 0.005` (seconds). A file
//!   with one number per line needs a `dt`; a file with two columns (`time_s accel`) takes its step
//!   from the time column, which must be uniform to `1e-6` of the step.
//!
//! [`ReadOptions`] supply the units and step a file does not declare. When both the file and the
//! options give one, they must agree (the step within `1e-6` relative, the same tolerance as the
//! uniform-step check), otherwise the read fails naming the line of the file's declaration.
//! Undeclared units default to g.

use std::fmt;
use std::path::Path;
use std::str::FromStr;
use thiserror::Error;

use crate::dynamics::G;
use crate::limits::{
    DT_RANGE_S, InputFileError, MAX_FILE_BYTES, MAX_SAMPLES, excerpt, input_text, read_input_file,
};

/// Relative tolerance for "the same time step": the uniform-sampling check of two-column files
/// and the agreement between a file's step and [`ReadOptions::dt_s`].
const DT_REL_TOL: f64 = 1e-6;

/// An acceleration record sampled at a constant step.
/// Peak `|v_g|`, m/s, of a ground acceleration linear between samples (`accel_mps2`, m/s², step
/// `dt_s`, s) starting at rest: exact, the velocity being the trapezoid sums at the samples and
/// a parabola between them, whose extremum lies where the acceleration changes sign.
pub fn peak_ground_velocity_mps(accel_mps2: &[f64], dt_s: f64) -> f64 {
    let (mut v, mut peak) = (0.0f64, 0.0f64);
    for w in accel_mps2.windows(2) {
        let (a0, a1) = (w[0], w[1]);
        if a0 * a1 < 0.0 {
            // a(τ) = a0 + (a1 − a0)·τ/dt = 0 at τ = dt·a0/(a0 − a1).
            let tau = dt_s * a0 / (a0 - a1);
            peak = peak.max((v + 0.5 * a0 * tau).abs());
        }
        v += 0.5 * dt_s * (a0 + a1);
        peak = peak.max(v.abs());
    }
    peak
}

#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// File name (or a label), for messages and output.
    pub name: String,
    /// Sample interval, s.
    pub dt_s: f64,
    /// Ground acceleration at `t = k·dt`, in g.
    pub accel_g: Vec<f64>,
}

impl Record {
    /// The record linearly interpolated to `1/refinement` of its step: the same
    /// piecewise-linear ground motion, sampled `refinement` times as densely (floor response
    /// spectra, [`crate::spectrum::floor`]).
    pub fn refined(&self, refinement: usize) -> Record {
        let a = &self.accel_g;
        let mut fine = Vec::with_capacity((a.len().saturating_sub(1)) * refinement + 1);
        for w in a.windows(2) {
            for i in 0..refinement {
                fine.push(w[0] + (w[1] - w[0]) * (i as f64 / refinement as f64));
            }
        }
        fine.extend(a.last());
        Record {
            name: self.name.clone(),
            dt_s: self.dt_s / refinement as f64,
            accel_g: fine,
        }
    }

    /// Refuses a record whose [`Self::refined`] history a spectrum cannot take (too many
    /// samples, too short a step: [`crate::limits`]), before any run.
    pub fn check_refinable(&self, refinement: usize) -> Result<(), String> {
        use crate::limits::{DT_RANGE_S, MAX_SAMPLES};
        let samples = (self.accel_g.len().saturating_sub(1)).saturating_mul(refinement) + 1;
        let dt_s = self.dt_s / refinement as f64;
        if samples > MAX_SAMPLES || dt_s < DT_RANGE_S.0 {
            return Err(format!(
                "`floor_spectra`: the record refined {refinement} times has {samples} samples \
                 {dt_s:e} s apart; the spectrum takes at most {MAX_SAMPLES} samples at least {:e} \
                 s apart",
                DT_RANGE_S.0
            ));
        }
        Ok(())
    }

    /// Acceleration in m/s², multiplied by `scale`.
    pub fn accel_mps2(&self, scale: f64) -> Vec<f64> {
        self.accel_g.iter().map(|a| a * scale * G).collect()
    }

    /// Peak ground acceleration, g.
    pub fn pga_g(&self) -> f64 {
        self.accel_g.iter().fold(0.0, |m, a| m.max(a.abs()))
    }

    /// Peak ground velocity, m/s, of the record multiplied by `scale`
    /// ([`peak_ground_velocity_mps`]).
    pub fn pgv_mps(&self, scale: f64) -> f64 {
        peak_ground_velocity_mps(&self.accel_mps2(scale), self.dt_s)
    }

    pub fn duration_s(&self) -> f64 {
        self.accel_g.len().saturating_sub(1) as f64 * self.dt_s
    }

    /// A record from samples in memory (`accel_g` in g at step `dt_s`, s), checked as a file's
    /// samples are: 2 to [`MAX_SAMPLES`] finite values, a step within [`DT_RANGE_S`].
    pub fn from_samples(name: &str, dt_s: f64, accel_g: Vec<f64>) -> Result<Self, RecordError> {
        crate::spectrum::response::validate_record(&accel_g, dt_s).map_err(|source| {
            RecordError::Samples {
                name: name.to_string(),
                source,
            }
        })?;
        Ok(Self {
            name: name.to_string(),
            dt_s,
            accel_g,
        })
    }
}

/// Units of acceleration a record file may be written in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Units {
    /// Standard gravity, `G` = 9.80665 m/s².
    G,
    /// m/s².
    Mps2,
    /// cm/s² (gal).
    Cmps2,
}

impl Units {
    /// Factor converting a value in these units to g: `value_g = value * to_g()`. Exactly 1 for g,
    /// so records in g are read without any rounding.
    pub fn to_g(self) -> f64 {
        match self {
            Units::G => 1.0,
            Units::Mps2 => 1.0 / G,
            Units::Cmps2 => 1.0 / (100.0 * G),
        }
    }

    /// Recognises a unit name, case-insensitively and ignoring spaces: `g`; `m/s2`, `m/s^2`,
    /// `m/s**2`, `m/s/s`, `m/sec2`, `m/sec^2`, `m/sec/sec`; the same with `cm`; `gal`.
    fn from_name(name: &str) -> Option<Units> {
        let s: String = name
            .chars()
            .filter(|c| !c.is_whitespace())
            .collect::<String>()
            .to_ascii_lowercase();
        let s = s.trim_end_matches(['.', ',', ';']);
        if s == "g" {
            return Some(Units::G);
        }
        if s == "gal" || s == "gals" {
            return Some(Units::Cmps2);
        }
        let (units, per_time_sq) = if let Some(rest) = s.strip_prefix("cm") {
            (Units::Cmps2, rest)
        } else if let Some(rest) = s.strip_prefix('m') {
            (Units::Mps2, rest)
        } else {
            return None;
        };
        matches!(
            per_time_sq,
            "/s2" | "/s^2" | "/s**2" | "/s/s" | "/sec2" | "/sec^2" | "/sec**2" | "/sec/sec"
        )
        .then_some(units)
    }
}

impl fmt::Display for Units {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Units::G => "g",
            Units::Mps2 => "m/s2",
            Units::Cmps2 => "cm/s2",
        })
    }
}

/// A unit name [`Units::from_str`] does not know.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("unknown acceleration unit `{0}`: expected g, m/s2 (or m/s^2), cm/s2 (or cm/s^2, gal)")]
pub struct UnknownUnits(pub String);

impl FromStr for Units {
    type Err = UnknownUnits;

    /// Accepts `g`, `m/s2`, `m/s^2`, `cm/s2`, `cm/s^2`, `gal` (case-insensitive), and the AT2
    /// spellings `m/s/s`, `cm/sec/sec` and the like.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Units::from_name(s).ok_or_else(|| UnknownUnits(s.trim().to_string()))
    }
}

/// What the caller knows about a file that the file itself may not say.
///
/// Each field is used only when the file does not declare it; when both do, they must agree.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ReadOptions {
    /// Units of the acceleration values in the file.
    pub units: Option<Units>,
    /// Sample interval, s (needed by single-column files that do not declare `# dt:`).
    pub dt_s: Option<f64>,
}

/// A record file that cannot be read as a ground motion: the file and, for a problem with its
/// contents, the line ([`Problem`]).
#[derive(Debug, Error)]
pub enum RecordError {
    #[error("{file}: cannot read: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: {bytes} bytes: a record file may have at most {MAX_FILE_BYTES}")]
    TooLarge { file: String, bytes: u64 },
    /// No bytes, or only white space.
    #[error("{file}: empty file")]
    Empty { file: String },
    #[error("{file}:{line}: {problem}")]
    Located {
        file: String,
        line: usize,
        problem: Problem,
    },
    /// A reading option out of range, named as the library names settings.
    #[error("`{setting}` must be finite and > 0, got {value}")]
    Setting { setting: &'static str, value: f64 },
    /// Samples given in memory ([`Record::from_samples`]), named by their label.
    #[error("{name}: {source}")]
    Samples {
        name: String,
        source: crate::spectrum::SpectrumError,
    },
}

/// What is wrong on a line of a record file.
#[derive(Debug, Error)]
pub enum Problem {
    #[error("missing AT2 header: expected `NPTS= n, DT= x SEC` or `n x NPTS, DT` on line 4")]
    MissingHeader,
    #[error("`{token}` is not a number")]
    NotANumber { token: String },
    #[error("value {value} is not finite")]
    NonFinite { value: f64 },
    #[error(
        "time step dt = {dt:?} s is outside {} … {} s (a unit or header mistake?)",
        DT_RANGE_S.0, DT_RANGE_S.1
    )]
    TimeStep { dt: f64 },
    #[error("{npts:?} samples: a record may have at most {MAX_SAMPLES}")]
    TooMany { npts: f64 },
    #[error("header says NPTS = {expected} but the file has {found} values")]
    Count { expected: usize, found: usize },
    #[error("expected 2 columns (time, acceleration in g), found {found}")]
    Columns { found: usize },
    #[error("expected 1 value per line (single-column record, as on line {first}), found {found}")]
    SingleColumn { first: usize, found: usize },
    #[error("expected 1 column (acceleration) or 2 columns (time, acceleration), found {found}")]
    Layout { found: usize },
    #[error("time step {found} s differs from the first step {expected} s (non-uniform sampling)")]
    NonUniform { expected: f64, found: f64 },
    #[error("a record needs at least 2 samples, found {found}")]
    TooShort { found: usize },
    #[error("{source}")]
    UnknownUnits {
        #[source]
        source: UnknownUnits,
    },
    #[error("the file says units {in_file} but {given} was given")]
    UnitsConflict { in_file: Units, given: Units },
    #[error("the file says dt = {in_file} s but dt = {given} s was given")]
    DtConflict { in_file: f64, given: f64 },
    #[error("`{key}: {value}` contradicts `{key}: {first_value}` on line {first}")]
    Redeclared {
        key: &'static str,
        value: String,
        first: usize,
        first_value: String,
    },
    #[error(
        "`# dt: {declared}` disagrees with the time column, whose step is {step} s (line {step_line})"
    )]
    DtColumn {
        declared: f64,
        step: f64,
        step_line: usize,
    },
    #[error("single-column record needs a time step: add `# dt: <s>` to the file or give dt")]
    NoTimeStep,
    #[error("this is a {kind} time series, not an acceleration record")]
    NotAcceleration { kind: &'static str },
}

/// `problem` on `line` of `file`.
fn at(file: &str, line: usize, problem: Problem) -> RecordError {
    RecordError::Located {
        file: file.to_string(),
        line,
        problem,
    }
}

/// Reads a `.AT2` file (detected by extension or a `PEER` first line) or a plain-text record
/// (`#` starts a comment) in g unless the file declares other units. Same as
/// [`read_record_with`] with no options.
pub fn read_record(path: &Path) -> Result<Record, RecordError> {
    read_record_with(path, &ReadOptions::default())
}

/// Reads a `.AT2` file (detected by extension or a `PEER` first line) or a plain-text record (see
/// [`parse_text`]), converting to g. `opts` supplies the units and step the file does not
/// declare; a disagreement with the file is an error (module docs).
pub fn read_record_with(path: &Path, opts: &ReadOptions) -> Result<Record, RecordError> {
    parse_record(&read_record_file(path)?, path, opts)
}

/// The bytes of a record file, refused above [`MAX_FILE_BYTES`] before they are read.
pub fn read_record_file(path: &Path) -> Result<Vec<u8>, RecordError> {
    let file = path.display().to_string();
    read_input_file(path).map_err(|e| match e {
        InputFileError::Io(source) => RecordError::Io { file, source },
        InputFileError::TooLarge(bytes) => RecordError::TooLarge { file, bytes },
    })
}

/// The record in the bytes of the file `path` (its name and extension tell the format), as
/// [`read_record_with`] reads it.
pub fn parse_record(bytes: &[u8], path: &Path, opts: &ReadOptions) -> Result<Record, RecordError> {
    if let Some(dt) = opts.dt_s
        && !(dt.is_finite() && dt > 0.0)
    {
        return Err(RecordError::Setting {
            setting: "dt",
            value: dt,
        });
    }
    let file = path.display().to_string();
    let text = input_text(bytes).map_err(|source| RecordError::Io {
        file: file.clone(),
        source,
    })?;
    let is_at2 = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("at2"))
        || text
            .lines()
            .next()
            .is_some_and(|l| l.to_ascii_uppercase().contains("PEER"));
    if is_at2 {
        parse_at2_with(text, &file, opts)
    } else {
        parse_text(text, &file, opts)
    }
}

/// `Err` for a file of no text but white space.
fn not_empty(text: &str, file: &str) -> Result<(), RecordError> {
    if text.trim().is_empty() {
        return Err(RecordError::Empty {
            file: file.to_string(),
        });
    }
    Ok(())
}

fn number(tok: &str, file: &str, line: usize) -> Result<f64, RecordError> {
    let v: f64 = tok.parse().map_err(|_| {
        let token = excerpt(tok);
        at(file, line, Problem::NotANumber { token })
    })?;
    if !v.is_finite() {
        return Err(at(file, line, Problem::NonFinite { value: v }));
    }
    Ok(v)
}

fn same_dt(a: f64, b: f64) -> bool {
    (a - b).abs() <= DT_REL_TOL * a.abs().max(b.abs())
}

/// Checks a step given in options: finite and > 0, reported against `line`.
fn checked_dt(dt: f64, file: &str, line: usize) -> Result<f64, RecordError> {
    if (DT_RANGE_S.0..=DT_RANGE_S.1).contains(&dt) {
        Ok(dt)
    } else {
        Err(at(file, line, Problem::TimeStep { dt }))
    }
}

/// Units of the record: the file's (declared on `line`) unless absent, then the options', then g.
fn resolve_units(
    in_file: Option<(Units, usize)>,
    opts: &ReadOptions,
    file: &str,
) -> Result<Units, RecordError> {
    match (in_file, opts.units) {
        (Some((f, line)), Some(given)) if f != given => {
            Err(at(file, line, Problem::UnitsConflict { in_file: f, given }))
        }
        (Some((f, _)), _) => Ok(f),
        (None, Some(given)) => Ok(given),
        (None, None) => Ok(Units::G),
    }
}

/// Fails if the options give a step that differs from the file's (declared on `line`).
fn check_dt_agrees(
    in_file: f64,
    line: usize,
    opts: &ReadOptions,
    file: &str,
) -> Result<(), RecordError> {
    match opts.dt_s {
        Some(given) if !same_dt(in_file, given) => {
            Err(at(file, line, Problem::DtConflict { in_file, given }))
        }
        _ => Ok(()),
    }
}

fn to_g(mut values: Vec<f64>, units: Units) -> Vec<f64> {
    if units != Units::G {
        let k = units.to_g();
        values.iter_mut().for_each(|v| *v *= k);
    }
    values
}

/// `(npts, dt)` from an AT2 header line of either style, if it is one.
fn at2_header(line: &str) -> Option<(String, String)> {
    let up = line.to_ascii_uppercase();
    if let (Some(n), Some(d)) = (up.find("NPTS="), up.find("DT=")) {
        // NGA-West2 style: `NPTS=  5590, DT=   .0050 SEC`
        let take = |from: usize| -> String {
            up[from..]
                .trim_start()
                .split(|c: char| c.is_whitespace() || c == ',')
                .next()
                .unwrap_or("")
                .to_string()
        };
        return Some((take(n + 5), take(d + 3)));
    }
    if up.contains("NPTS") && up.contains("DT") {
        // Older NGA style: `  5590    0.00500    NPTS, DT`
        let mut it = up.split_whitespace();
        let a = it.next()?.trim_end_matches(',').to_string();
        let b = it.next()?.trim_end_matches(',').to_string();
        return Some((a, b));
    }
    None
}

/// Units named on AT2 line 3 (`ACCELERATION TIME SERIES IN UNITS OF G`), if it names any.
fn at2_units(line: &str, file: &str, no: usize) -> Result<Option<Units>, RecordError> {
    let up = line.trim().to_ascii_uppercase();
    for kind in ["VELOCITY", "DISPLACEMENT"] {
        if up.starts_with(kind) {
            let kind = if kind == "VELOCITY" {
                "velocity"
            } else {
                "displacement"
            };
            return Err(at(file, no, Problem::NotAcceleration { kind }));
        }
    }
    let Some(from) = up.find("UNITS OF") else {
        return Ok(None);
    };
    let name = up[from + "UNITS OF".len()..]
        .split_whitespace()
        .next()
        .unwrap_or("");
    name.parse::<Units>()
        .map(Some)
        .map_err(|source| at(file, no, Problem::UnknownUnits { source }))
}

/// Parses the text of a PEER `.AT2` file in g or the units its line 3 names. Same as
/// [`parse_at2_with`] with no options.
pub fn parse_at2(text: &str, file: &str) -> Result<Record, RecordError> {
    parse_at2_with(text, file, &ReadOptions::default())
}

/// Parses the text of a PEER `.AT2` file: four header lines (the third may name the units, the
/// fourth gives NPTS and DT), then the values, any number per line, converted to g.
pub fn parse_at2_with(text: &str, file: &str, opts: &ReadOptions) -> Result<Record, RecordError> {
    not_empty(text, file)?;
    let mut lines = text.lines().enumerate();
    let mut header = None;
    let mut units_line = None;
    for (idx, line) in lines.by_ref().take(4) {
        if idx == 2 {
            units_line = at2_units(line, file, idx + 1)?.map(|u| (u, idx + 1));
        }
        if idx == 3 {
            header = at2_header(line).map(|h| (h, idx + 1));
        }
    }
    let ((npts_tok, dt_tok), hline) = header.ok_or_else(|| at(file, 4, Problem::MissingHeader))?;
    let units = resolve_units(units_line, opts, file)?;
    let npts_f = number(&npts_tok, file, hline)?;
    if npts_f < 0.0 || npts_f.fract() != 0.0 {
        let token = excerpt(&npts_tok);
        return Err(at(file, hline, Problem::NotANumber { token }));
    }
    if npts_f > MAX_SAMPLES as f64 {
        return Err(at(file, hline, Problem::TooMany { npts: npts_f }));
    }
    let npts = npts_f as usize;
    let dt = checked_dt(number(&dt_tok, file, hline)?, file, hline)?;
    check_dt_agrees(dt, hline, opts, file)?;
    let mut accel = Vec::with_capacity(npts);
    let mut last_line = hline;
    for (idx, line) in lines {
        for tok in line.split_whitespace() {
            let v = number(tok, file, idx + 1)?;
            if accel.len() == npts {
                return Err(at(
                    file,
                    idx + 1,
                    Problem::Count {
                        expected: npts,
                        found: accel.len() + 1,
                    },
                ));
            }
            accel.push(v);
            last_line = idx + 1;
        }
    }
    if accel.len() != npts {
        return Err(at(
            file,
            last_line,
            Problem::Count {
                expected: npts,
                found: accel.len(),
            },
        ));
    }
    if npts < 2 {
        return Err(at(file, last_line, Problem::TooShort { found: npts }));
    }
    Ok(Record {
        name: base_name(file),
        dt_s: dt,
        accel_g: to_g(accel, units),
    })
}

/// Parses plain text in g (or its declared units). Kept for callers of the two-column reader;
/// same as [`parse_text`] with no options, so it also reads single-column files that declare
/// `# dt:`.
pub fn parse_two_column(text: &str, file: &str) -> Result<Record, RecordError> {
    parse_text(text, file, &ReadOptions::default())
}

/// A `# key: value` declaration found in a comment.
struct Declared<T> {
    value: T,
    text: String,
    line: usize,
}

/// Records a declaration, refusing a second one that says something else.
fn declare<T: PartialEq>(
    slot: &mut Option<Declared<T>>,
    new: Declared<T>,
    key: &'static str,
    file: &str,
) -> Result<(), RecordError> {
    match slot {
        Some(old) if old.value != new.value => Err(at(
            file,
            new.line,
            Problem::Redeclared {
                key,
                value: new.text,
                first: old.line,
                first_value: old.text.clone(),
            },
        )),
        Some(_) => Ok(()),
        None => {
            *slot = Some(new);
            Ok(())
        }
    }
}

/// Parses a plain-text record: `#` starts a comment; a comment `# units: <unit>` declares the
/// units of the acceleration values (see [`Units`]), `# dt: <seconds>` the step. Data lines hold
/// either one value (acceleration; the step comes from `# dt:` or `opts.dt_s`) or two
/// (`time_s accel`, separated by blanks or commas; the step is the first time difference, uniform to
/// `1e-6` of itself). Values are converted to g.
///
/// The record's step is the declared `# dt:` if any, else `opts.dt_s`, else (two columns) the first
/// time difference; any two of these must agree within `1e-6` relative.
pub fn parse_text(text: &str, file: &str, opts: &ReadOptions) -> Result<Record, RecordError> {
    not_empty(text, file)?;
    let mut units: Option<Declared<Units>> = None;
    let mut dt_decl: Option<Declared<f64>> = None;
    // Columns per data line (1 or 2), fixed by the first data line, and that line.
    let mut layout: Option<(usize, usize)> = None;
    let mut times = Vec::new();
    let mut accel = Vec::new();
    let mut step = 0.0;
    let mut step_line = 0;
    let mut last_line = 0;
    for (idx, raw) in text.lines().enumerate() {
        let no = idx + 1;
        let (data, comment) = raw.split_once('#').unwrap_or((raw, ""));
        let comment = comment.trim();
        if let Some((key, value)) = comment.split_once(':') {
            let value = value.trim();
            match key.trim().to_ascii_lowercase().as_str() {
                "units" => {
                    let u = value
                        .parse::<Units>()
                        .map_err(|source| at(file, no, Problem::UnknownUnits { source }))?;
                    let new = Declared {
                        value: u,
                        text: value.to_string(),
                        line: no,
                    };
                    declare(&mut units, new, "units", file)?;
                }
                "dt" => {
                    let lower = value.to_ascii_lowercase();
                    let tok = lower
                        .strip_suffix("sec")
                        .or_else(|| lower.strip_suffix('s'))
                        .unwrap_or(&lower)
                        .trim();
                    let dt = checked_dt(number(tok, file, no)?, file, no)?;
                    let new = Declared {
                        value: dt,
                        text: value.to_string(),
                        line: no,
                    };
                    declare(&mut dt_decl, new, "dt", file)?;
                }
                _ => {}
            }
        }
        let cols: Vec<&str> = data
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|t| !t.is_empty())
            .collect();
        if cols.is_empty() {
            continue;
        }
        let (ncols, first) = *layout.get_or_insert((cols.len(), no));
        match (ncols, cols.len()) {
            _ if accel.len() == MAX_SAMPLES => {
                let npts = (MAX_SAMPLES + 1) as f64;
                return Err(at(file, no, Problem::TooMany { npts }));
            }
            (1, 1) => accel.push(number(cols[0], file, no)?),
            (1, found) => {
                return Err(at(file, no, Problem::SingleColumn { first, found }));
            }
            (2, 2) => {
                let t = number(cols[0], file, no)?;
                let a = number(cols[1], file, no)?;
                if let Some(&prev) = times.last() {
                    let this = t - prev;
                    if times.len() == 1 {
                        step = this;
                        step_line = no;
                        checked_dt(step, file, no)?;
                    } else if (this - step).abs() > DT_REL_TOL * step {
                        return Err(at(
                            file,
                            no,
                            Problem::NonUniform {
                                expected: step,
                                found: this,
                            },
                        ));
                    }
                }
                times.push(t);
                accel.push(a);
            }
            (2, found) => {
                return Err(at(file, no, Problem::Columns { found }));
            }
            (_, found) => {
                return Err(at(file, no, Problem::Layout { found }));
            }
        }
        last_line = no;
    }
    if accel.len() < 2 {
        return Err(at(
            file,
            last_line.max(1),
            Problem::TooShort { found: accel.len() },
        ));
    }
    let units = resolve_units(units.map(|d| (d.value, d.line)), opts, file)?;
    let first_data_line = layout.map_or(1, |(_, line)| line);
    let dt = match (&dt_decl, opts.dt_s) {
        (Some(d), _) => {
            check_dt_agrees(d.value, d.line, opts, file)?;
            d.value
        }
        (None, Some(given)) => checked_dt(given, file, first_data_line)?,
        (None, None) if times.is_empty() => {
            return Err(at(file, first_data_line, Problem::NoTimeStep));
        }
        (None, None) => step,
    };
    if !times.is_empty() {
        // The time column is the file's own statement of the step.
        if let Some(d) = &dt_decl
            && !same_dt(step, d.value)
        {
            return Err(at(
                file,
                d.line,
                Problem::DtColumn {
                    declared: d.value,
                    step,
                    step_line,
                },
            ));
        }
        check_dt_agrees(step, step_line, opts, file)?;
    }
    Ok(Record {
        name: base_name(file),
        dt_s: dt,
        accel_g: to_g(accel, units),
    })
}

fn base_name(file: &str) -> String {
    Path::new(file)
        .file_name()
        .map_or_else(|| file.to_string(), |f| f.to_string_lossy().into_owned())
}

/// `v` in PEER's `%.7E` style (`-6.0784200E-04`: seven decimals, a signed exponent of at least two
/// digits) when that is exact, otherwise with as many more digits as it takes: the mantissa is
/// Rust's shortest representation that reads back to the same `f64`, padded with zeros.
fn at2_number(v: f64) -> String {
    let s = format!("{v:E}");
    let Some((mantissa, exp)) = s.split_once('E') else {
        return s;
    };
    let mut mantissa = mantissa.to_string();
    let decimals = match mantissa.find('.') {
        Some(dot) => mantissa.len() - dot - 1,
        None => {
            mantissa.push('.');
            0
        }
    };
    mantissa.extend(std::iter::repeat_n('0', 7usize.saturating_sub(decimals)));
    let (sign, digits) = exp.strip_prefix('-').map_or(("+", exp), |d| ("-", d));
    format!("{mantissa}E{sign}{digits:0>2}")
}

/// The text of a PEER NGA-West2 style `.AT2` file holding `record` (in g): four header lines
/// (`PEER NGA STRONG MOTION DATABASE RECORD`, `description` with line breaks turned into spaces,
/// `ACCELERATION TIME SERIES IN UNITS OF G`, `NPTS=  n, DT=   x SEC`), then five values per line.
///
/// Values are written like PEER's `%15.7E` when eight significant digits hold them exactly, and
/// with up to 17 (Rust's shortest round-trip digits) otherwise; `DT` is written in Rust's shortest
/// round-trip form. So [`parse_at2`] gives back the same `dt_s` and `accel_g` bit for bit (for
/// finite values; [`checked_at2`] refuses others), and a record read from a PEER file is written
/// back with the same digits.
pub fn format_at2(record: &Record, description: &str) -> String {
    let description: String = description
        .chars()
        .map(|c| if c == '\n' || c == '\r' { ' ' } else { c })
        .collect();
    let mut out = String::with_capacity(200 + record.accel_g.len() * 16);
    out.push_str("PEER NGA STRONG MOTION DATABASE RECORD\n");
    out.push_str(&description);
    out.push('\n');
    out.push_str("ACCELERATION TIME SERIES IN UNITS OF G\n");
    out.push_str(&format!(
        "NPTS= {:>5}, DT= {:>9} SEC\n",
        record.accel_g.len(),
        record.dt_s
    ));
    for chunk in record.accel_g.chunks(5) {
        for &v in chunk {
            out.push_str(&format!(" {:>14}", at2_number(v)));
        }
        out.push('\n');
    }
    out
}

/// [`format_at2`] of `record`, after refusing a step outside the readable range or a
/// non-finite value, naming the line of the file `file` it would have gone to. Write the text
/// with [`crate::store::atomic::write_bytes`].
pub fn checked_at2(record: &Record, description: &str, file: &str) -> Result<String, RecordError> {
    checked_dt(record.dt_s, file, 4)?;
    if let Some((k, &value)) = record
        .accel_g
        .iter()
        .enumerate()
        .find(|(_, v)| !v.is_finite())
    {
        return Err(at(file, 5 + k / 5, Problem::NonFinite { value }));
    }
    Ok(format_at2(record, description))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        parse_at2(text, "bad.AT2").unwrap_err().to_string()
    }

    const HEAD: &str =
        "PEER NGA STRONG MOTION DATABASE RECORD\nx\nACCELERATION TIME SERIES IN UNITS OF G\n";

    #[test]
    fn both_header_styles() {
        let a = parse_at2(
            &format!("{HEAD}NPTS=  3, DT=   .0100 SEC\n 0.1 -0.2\n .3E-1\n"),
            "a",
        )
        .unwrap();
        assert_eq!(a.accel_g, vec![0.1, -0.2, 0.03]);
        assert_eq!(a.dt_s, 0.01);
        let b = parse_at2(
            &format!("{HEAD}    3    0.02000    NPTS, DT\n 0.1 -0.2 0.3\n"),
            "b",
        )
        .unwrap();
        assert_eq!(b.accel_g.len(), 3);
        assert_eq!(b.dt_s, 0.02);
    }

    #[test]
    fn malformed_at2_names_file_and_line() {
        assert_eq!(
            err(&format!("{HEAD}nothing here\n1 2 3\n")),
            "bad.AT2:4: missing AT2 header: expected `NPTS= n, DT= x SEC` or `n x NPTS, DT` on line 4"
        );
        assert_eq!(err("PEER\nshort\n"), err("PEER\nshort\n"));
        assert!(err("PEER\nshort\n").starts_with("bad.AT2:4: missing AT2 header"));
        assert_eq!(
            err(&format!("{HEAD}NPTS=  4, DT= .01 SEC\n 0.1 0.2\n 0.3\n")),
            "bad.AT2:6: header says NPTS = 4 but the file has 3 values"
        );
        assert_eq!(
            err(&format!("{HEAD}NPTS=  2, DT= .01 SEC\n 0.1 0.2\n 0.3\n")),
            "bad.AT2:6: header says NPTS = 2 but the file has 3 values"
        );
        assert_eq!(
            err(&format!("{HEAD}NPTS=  3, DT= .01 SEC\n 0.1 0.2\n 0.x3\n")),
            "bad.AT2:6: `0.x3` is not a number"
        );
        assert_eq!(
            err(&format!("{HEAD}NPTS=  3, DT= .01 SEC\n 0.1 NaN 0.3\n")),
            "bad.AT2:5: value NaN is not finite"
        );
        assert_eq!(
            err(&format!("{HEAD}NPTS=  3, DT= .01 SEC\n 0.1 inf 0.3\n")),
            "bad.AT2:5: value inf is not finite"
        );
        assert_eq!(
            err(&format!("{HEAD}NPTS=  2, DT= 0.0 SEC\n 0.1 0.2\n")),
            "bad.AT2:4: time step dt = 0.0 s is outside 0.00001 … 1 s (a unit or header mistake?)"
        );
        assert_eq!(
            err(&format!("{HEAD}    2   -0.01  NPTS, DT\n 0.1 0.2\n")),
            "bad.AT2:4: time step dt = -0.01 s is outside 0.00001 … 1 s (a unit or header mistake?)"
        );
    }

    #[test]
    fn two_column() {
        let r = parse_two_column("# t a\n0 0\n0.01 0.1\n0.02 -0.1\n", "tc.txt").unwrap();
        assert_eq!(r.dt_s, 0.01);
        assert_eq!(r.accel_g, vec![0.0, 0.1, -0.1]);
        let e = parse_two_column("0 0\n0.01 0.1\n0.03 -0.1\n", "tc.txt").unwrap_err();
        assert_eq!(
            e.to_string(),
            "tc.txt:3: time step 0.019999999999999997 s differs from the first step 0.01 s (non-uniform sampling)"
        );
        let e = parse_two_column("0 0\n0.01 0.1 7\n", "tc.txt").unwrap_err();
        assert_eq!(
            e.to_string(),
            "tc.txt:2: expected 2 columns (time, acceleration in g), found 3"
        );
        let e = parse_two_column("0 0\n0 0.1\n", "tc.txt").unwrap_err();
        assert_eq!(
            e.to_string(),
            "tc.txt:2: time step dt = 0.0 s is outside 0.00001 … 1 s (a unit or header mistake?)"
        );
        let e = parse_two_column("0 0\n", "tc.txt").unwrap_err();
        assert_eq!(
            e.to_string(),
            "tc.txt:1: a record needs at least 2 samples, found 1"
        );
    }

    fn text(t: &str, opts: &ReadOptions) -> Result<Record, String> {
        parse_text(t, "r.txt", opts).map_err(|e| e.to_string())
    }

    fn at2(t: &str, opts: &ReadOptions) -> Result<Record, String> {
        parse_at2_with(t, "r.AT2", opts).map_err(|e| e.to_string())
    }

    const NONE: ReadOptions = ReadOptions {
        units: None,
        dt_s: None,
    };

    #[test]
    fn units_names() {
        for (s, u) in [
            ("g", Units::G),
            ("G", Units::G),
            ("m/s2", Units::Mps2),
            ("M/S^2", Units::Mps2),
            ("m/s/s", Units::Mps2),
            ("cm/s2", Units::Cmps2),
            ("cm/s^2", Units::Cmps2),
            ("Gal", Units::Cmps2),
            ("CM/SEC/SEC", Units::Cmps2),
            (" cm / s2 ", Units::Cmps2),
        ] {
            assert_eq!(s.parse::<Units>(), Ok(u), "{s}");
            assert_eq!(u.to_string().parse::<Units>(), Ok(u));
        }
        assert_eq!(Units::Cmps2.to_string(), "cm/s2");
        assert_eq!(Units::Mps2.to_string(), "m/s2");
        assert_eq!(Units::G.to_string(), "g");
        assert_eq!(
            "ft/s2".parse::<Units>().unwrap_err().to_string(),
            "unknown acceleration unit `ft/s2`: expected g, m/s2 (or m/s^2), cm/s2 (or cm/s^2, gal)"
        );
        assert!("".parse::<Units>().is_err());
        assert!("s2".parse::<Units>().is_err());
        assert_eq!(Units::G.to_g(), 1.0);
        // One rounding each for the factor and the check: 1e-15 relative.
        assert!((Units::Mps2.to_g() * crate::dynamics::G - 1.0).abs() < 1e-15);
        assert!((Units::Cmps2.to_g() * 100.0 * crate::dynamics::G - 1.0).abs() < 1e-15);
    }

    #[test]
    fn single_column_with_declarations_and_options() {
        // 98.0665 cm/s² = 0.1 g; tolerance 1e-15 relative (a rounding in the parse, the factor
        // and the product).
        let r = text("# units: cm/s2\n# DT: 0.01 s\n98.0665\n-196.133\n", &NONE).unwrap();
        assert_eq!(r.dt_s, 0.01);
        assert!((r.accel_g[0] - 0.1).abs() < 1e-15 * 0.1);
        assert!((r.accel_g[1] + 0.2).abs() < 1e-15 * 0.2);
        // The options fill in what the file does not say.
        let opts = ReadOptions {
            units: Some(Units::G),
            dt_s: Some(0.02),
        };
        let r = text("0.1\n0.2 # a comment\n\n0.3\n", &opts).unwrap();
        assert_eq!((r.dt_s, r.accel_g), (0.02, vec![0.1, 0.2, 0.3]));
        // Agreeing declarations are fine.
        let r = text(
            "# units: gal\n# dt: 0.02\n1\n2\n",
            &ReadOptions {
                units: Some(Units::Cmps2),
                dt_s: Some(0.02),
            },
        )
        .unwrap();
        assert_eq!(r.dt_s, 0.02);
        // Other comments with colons are not declarations.
        let r = text("# source: PEER\n# dt: 0.01\n1\n2\n", &NONE).unwrap();
        assert_eq!(r.accel_g, vec![1.0, 2.0]);
    }

    #[test]
    fn plain_text_errors_name_file_and_line() {
        assert_eq!(
            text("# units: cm/s2\n0.1\n0.2\n", &NONE).unwrap_err(),
            "r.txt:2: single-column record needs a time step: add `# dt: <s>` to the file or give dt"
        );
        assert_eq!(
            text(
                "# units: cm/s2\n# dt: 0.01\n1\n2\n",
                &ReadOptions {
                    units: Some(Units::Mps2),
                    dt_s: None,
                }
            )
            .unwrap_err(),
            "r.txt:1: the file says units cm/s2 but m/s2 was given"
        );
        assert_eq!(
            text(
                "# units: cm/s2\n# dt: 0.01\n1\n2\n",
                &ReadOptions {
                    units: None,
                    dt_s: Some(0.005),
                }
            )
            .unwrap_err(),
            "r.txt:2: the file says dt = 0.01 s but dt = 0.005 s was given"
        );
        assert_eq!(
            text(
                "0 1\n0.01 2\n0.02 3\n",
                &ReadOptions {
                    units: None,
                    dt_s: Some(0.02),
                }
            )
            .unwrap_err(),
            "r.txt:2: the file says dt = 0.01 s but dt = 0.02 s was given"
        );
        assert_eq!(
            text("# dt: 0.02\n0 1\n0.01 2\n", &NONE).unwrap_err(),
            "r.txt:1: `# dt: 0.02` disagrees with the time column, whose step is 0.01 s (line 3)"
        );
        assert_eq!(
            text("# units: g\n# dt: 0.01\n1\n# units: gal\n2\n", &NONE).unwrap_err(),
            "r.txt:4: `units: gal` contradicts `units: g` on line 1"
        );
        assert_eq!(
            text("# units: furlong/s2\n", &NONE).unwrap_err(),
            "r.txt:1: unknown acceleration unit `furlong/s2`: expected g, m/s2 (or m/s^2), cm/s2 (or cm/s^2, gal)"
        );
        assert_eq!(
            text("# dt: fast\n", &NONE).unwrap_err(),
            "r.txt:1: `fast` is not a number"
        );
        assert_eq!(
            text("# dt: -0.01\n", &NONE).unwrap_err(),
            "r.txt:1: time step dt = -0.01 s is outside 0.00001 … 1 s (a unit or header mistake?)"
        );
        assert_eq!(
            text(
                "0.1\n0.2\n",
                &ReadOptions {
                    units: None,
                    dt_s: Some(0.0),
                }
            )
            .unwrap_err(),
            "r.txt:1: time step dt = 0.0 s is outside 0.00001 … 1 s (a unit or header mistake?)"
        );
        assert_eq!(
            text("# dt: 0.01\n0.1\n0.2 0.3\n", &NONE).unwrap_err(),
            "r.txt:3: expected 1 value per line (single-column record, as on line 2), found 2"
        );
        assert_eq!(
            text("0 0.1 7\n", &NONE).unwrap_err(),
            "r.txt:1: expected 1 column (acceleration) or 2 columns (time, acceleration), found 3"
        );
        assert_eq!(
            text("# dt: 0.01\n0.1\n-inf\n", &NONE).unwrap_err(),
            "r.txt:3: value -inf is not finite"
        );
    }

    #[test]
    fn at2_units_line() {
        let body = "NPTS=  2, DT= .01 SEC\n 98.0665 -196.133\n";
        for line3 in [
            "ACCELERATION TIME SERIES IN UNITS OF CM/S/S",
            "ACCELERATION TIME SERIES IN UNITS OF CM/SEC/SEC",
            "Acceleration in units of gal",
        ] {
            let r = at2(&format!("PEER\nx\n{line3}\n{body}"), &NONE).unwrap();
            assert!((r.accel_g[0] - 0.1).abs() < 1e-15 * 0.1, "{line3}");
            assert!((r.accel_g[1] + 0.2).abs() < 1e-15 * 0.2, "{line3}");
        }
        let r = at2(
            &format!("PEER\nx\nACCELERATION TIME SERIES IN UNITS OF M/S/S\n{body}"),
            &NONE,
        )
        .unwrap();
        assert!((r.accel_g[0] - 10.0).abs() < 1e-15 * 10.0);
        // Line 3 naming no unit: the options decide, else g.
        let bare = format!("PEER\nx\nno unit here\n{body}");
        assert_eq!(at2(&bare, &NONE).unwrap().accel_g, vec![98.0665, -196.133]);
        let r = at2(
            &bare,
            &ReadOptions {
                units: Some(Units::Cmps2),
                dt_s: Some(0.01),
            },
        )
        .unwrap();
        assert!((r.accel_g[0] - 0.1).abs() < 1e-15 * 0.1);
        let g_file = format!("{HEAD}{body}");
        assert_eq!(
            at2(
                &g_file,
                &ReadOptions {
                    units: Some(Units::Cmps2),
                    dt_s: None,
                }
            )
            .unwrap_err(),
            "r.AT2:3: the file says units g but cm/s2 was given"
        );
        assert_eq!(
            at2(
                &g_file,
                &ReadOptions {
                    units: Some(Units::G),
                    dt_s: Some(0.005),
                }
            )
            .unwrap_err(),
            "r.AT2:4: the file says dt = 0.01 s but dt = 0.005 s was given"
        );
        assert_eq!(
            at2(
                &format!("PEER\nx\nACCELERATION IN UNITS OF FT/S/S\n{body}"),
                &NONE
            )
            .unwrap_err(),
            "r.AT2:3: unknown acceleration unit `FT/S/S`: expected g, m/s2 (or m/s^2), cm/s2 (or cm/s^2, gal)"
        );
        assert_eq!(
            at2(
                &format!("PEER\nx\nVELOCITY TIME SERIES IN UNITS OF CM/S\n{body}"),
                &NONE
            )
            .unwrap_err(),
            "r.AT2:3: this is a velocity time series, not an acceleration record"
        );
    }

    #[test]
    fn at2_number_style() {
        assert_eq!(at2_number(-6.07842e-4), "-6.0784200E-04");
        assert_eq!(at2_number(1.5), "1.5000000E+00");
        assert_eq!(at2_number(0.0), "0.0000000E+00");
        assert_eq!(at2_number(-0.0), "-0.0000000E+00");
        assert_eq!(at2_number(1e300), "1.0000000E+300");
        assert_eq!(at2_number(5e-324), "5.0000000E-324");
        assert_eq!(at2_number(0.1 + 0.2), "3.0000000000000004E-01");
        assert_eq!(at2_number(1.0 / 3.0), "3.333333333333333E-01");
    }

    #[test]
    fn format_at2_layout() {
        let r = Record {
            name: "x".into(),
            dt_s: 0.005,
            accel_g: vec![0.1, -0.2, 0.3, 0.4, 0.5, 0.6],
        };
        let t = format_at2(&r, "Somewhere, 2024,\nstation");
        let lines: Vec<&str> = t.lines().collect();
        assert_eq!(lines[0], "PEER NGA STRONG MOTION DATABASE RECORD");
        assert_eq!(lines[1], "Somewhere, 2024, station");
        assert_eq!(lines[2], "ACCELERATION TIME SERIES IN UNITS OF G");
        assert_eq!(lines[3], "NPTS=     6, DT=     0.005 SEC");
        assert_eq!(lines[4].split_whitespace().count(), 5);
        assert_eq!(
            lines[4],
            "  1.0000000E-01 -2.0000000E-01  3.0000000E-01  4.0000000E-01  5.0000000E-01"
        );
        assert_eq!(lines[5], "  6.0000000E-01");
        assert_eq!(lines.len(), 6);
        assert_eq!(parse_at2(&t, "x").unwrap(), r);
    }

    /// Bit-identical round trip: the shortest round-trip digits identify every `f64` (padding them
    /// with zeros changes nothing), and Rust's float parsing is correctly rounded.
    #[test]
    fn at2_round_trip_is_bit_identical_on_random_bits() {
        let mut s = 0x9E37_79B9_7F4A_7C15_u64;
        let mut next = move || {
            s ^= s >> 12;
            s ^= s << 25;
            s ^= s >> 27;
            s.wrapping_mul(0x2545_F491_4F6C_DD1D)
        };
        let mut values = vec![0.0, -0.0, f64::MIN_POSITIVE, -5e-324, f64::MAX, f64::MIN];
        // Arbitrary bit patterns (all exponents, subnormals included) and typical magnitudes.
        while values.len() < 20_000 {
            let v = f64::from_bits(next());
            if v.is_finite() {
                values.push(v);
            }
            values.push((next() >> 11) as f64 / (1u64 << 53) as f64 - 0.5);
        }
        for dt_s in [0.005, 0.01, 1.0 / 3.0, 0.1 + 0.2, 1.7e-5] {
            let r = Record {
                name: "rt".into(),
                dt_s,
                accel_g: values.clone(),
            };
            let back = parse_at2(&format_at2(&r, "random"), "rt").unwrap();
            assert_eq!(back.dt_s.to_bits(), dt_s.to_bits());
            assert_eq!(back.accel_g.len(), values.len());
            for (a, b) in back.accel_g.iter().zip(&values) {
                assert_eq!(a.to_bits(), b.to_bits(), "{a:e} vs {b:e}");
            }
        }
    }
}
