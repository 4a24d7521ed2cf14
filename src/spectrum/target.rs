//! Target spectra: the 5 %-damped pseudo-spectral acceleration a structure or a record set is
//! compared with.
//!
//! Each target is written as a SPEC string (command line, YAML configs) that
//! [`TargetSpectrum::from_str`] parses and [`Display`](fmt::Display) writes back:
//!
//! * `is1893:zone=V,soil=I[,scaling=z|z/2][,i=1][,r=1]`: IS 1893 (Part 1):2016, Clause 6.4.2 and
//!   Fig. 2 (response spectrum method), valued `factor·(I/R)·Sa/g` with `factor` the zone factor
//!   `Z` of Table 3 or `Z/2`. The paper's targets are `Z·Sa/g` on hard soil (docs/model.md,
//!   "Hazard: numbers checked by hand"), hence the default `scaling=z`; the code's design
//!   coefficient `Ah` is `scaling=z/2` with the building's `I` and `R`.
//! * `asce7:sds=1.0,sd1=0.6,tl=8`: the ASCE 7-16 §11.4.6 design response spectrum.
//! * `table:FILE`: two columns `period_s sa_g`, log-log interpolated.
//!
//! Keys and kinds are case-insensitive; items are separated by commas.

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use thiserror::Error;

use crate::dynamics::G;
use crate::limits::{InputFileError, MAX_FILE_BYTES, input_text, read_input_file};

/// The damping ratio of target (design) spectra, and so of the record spectra compared with
/// them: 5 %.
pub const TARGET_DAMPING: f64 = 0.05;

/// Seismic zone of IS 1893 (Part 1):2016, Fig. 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Zone {
    II,
    III,
    IV,
    V,
}

impl Zone {
    /// Zone factor `Z`, IS 1893 (Part 1):2016 Table 3.
    pub fn factor(self) -> f64 {
        match self {
            Zone::II => 0.10,
            Zone::III => 0.16,
            Zone::IV => 0.24,
            Zone::V => 0.36,
        }
    }

    /// Roman numeral, as in the standard.
    pub fn name(self) -> &'static str {
        match self {
            Zone::II => "II",
            Zone::III => "III",
            Zone::IV => "IV",
            Zone::V => "V",
        }
    }
}

/// Roman numeral (`"III"`, any case) or arabic digit (`"3"`).
impl FromStr for Zone {
    type Err = TargetError;

    fn from_str(s: &str) -> Result<Self, TargetError> {
        match s.trim().to_ascii_uppercase().as_str() {
            "II" | "2" => Ok(Zone::II),
            "III" | "3" => Ok(Zone::III),
            "IV" | "4" => Ok(Zone::IV),
            "V" | "5" => Ok(Zone::V),
            _ => Err(TargetError::UnknownZone(s.trim().to_string())),
        }
    }
}

impl fmt::Display for Zone {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Soil type of IS 1893 (Part 1):2016, Clause 6.4.2 and Fig. 2: I rock or hard soil, II medium
/// soil, III soft soil.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Soil {
    I,
    II,
    III,
}

impl Soil {
    /// Roman numeral, as in the standard.
    pub fn name(self) -> &'static str {
        match self {
            Soil::I => "I",
            Soil::II => "II",
            Soil::III => "III",
        }
    }

    /// End of the constant `Sa/g = 2.5` plateau, s.
    pub fn corner_period_s(self) -> f64 {
        match self {
            Soil::I => 0.40,
            Soil::II => 0.55,
            Soil::III => 0.67,
        }
    }

    /// Coefficient `c` of the descending branch `Sa/g = c/T`, s.
    pub fn descending_coefficient_s(self) -> f64 {
        match self {
            Soil::I => 1.00,
            Soil::II => 1.36,
            Soil::III => 1.67,
        }
    }

    /// Constant `Sa/g` beyond `T = 4 s`.
    pub fn long_period_sa_g(self) -> f64 {
        match self {
            Soil::I => 0.25,
            Soil::II => 0.34,
            Soil::III => 0.42,
        }
    }

    /// Normalised 5 %-damped spectral acceleration `Sa/g` for the response spectrum method,
    /// IS 1893 (Part 1):2016 Clause 6.4.2 (b) and Fig. 2:
    /// `1 + 15T` for `T < 0.10 s`, `2.5` up to the corner period, `c/T` up to `4 s`, then a
    /// constant. The coefficients are the standard's rounded ones, so the curve steps slightly
    /// where they do not meet: soil II drops from 2.5 to `1.36/0.55 = 2.473` at 0.55 s, soil III
    /// from 2.5 to `1.67/0.67 = 2.493` at 0.67 s and rises from `1.67/4 = 0.4175` to 0.42 at 4 s.
    /// Soil I is continuous, and all three are at 0.10 s.
    ///
    /// NaN for a negative or NaN period.
    pub fn sa_g(self, period_s: f64) -> f64 {
        if period_s.is_nan() || period_s < 0.0 {
            f64::NAN
        } else if period_s < 0.10 {
            1.0 + 15.0 * period_s
        } else if period_s <= self.corner_period_s() {
            2.5
        } else if period_s <= 4.0 {
            self.descending_coefficient_s() / period_s
        } else {
            self.long_period_sa_g()
        }
    }
}

/// Roman numeral (`"II"`, any case) or arabic digit (`"2"`).
impl FromStr for Soil {
    type Err = TargetError;

    fn from_str(s: &str) -> Result<Self, TargetError> {
        match s.trim().to_ascii_uppercase().as_str() {
            "I" | "1" => Ok(Soil::I),
            "II" | "2" => Ok(Soil::II),
            "III" | "3" => Ok(Soil::III),
            _ => Err(TargetError::UnknownSoil(s.trim().to_string())),
        }
    }
}

impl fmt::Display for Soil {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Which multiple of the zone factor scales `Sa/g`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ZoneScaling {
    /// `Z·Sa/g`: the paper's targets (docs/model.md, "Hazard: numbers checked by hand").
    Z,
    /// `(Z/2)·Sa/g`: the design level of IS 1893 (Part 1):2016 Clause 6.4.2, `Ah = (Z/2)(I/R)(Sa/g)`.
    HalfZ,
}

impl ZoneScaling {
    /// `Z` or `Z/2` for `zone`.
    pub fn factor(self, zone: Zone) -> f64 {
        match self {
            ZoneScaling::Z => zone.factor(),
            ZoneScaling::HalfZ => zone.factor() / 2.0,
        }
    }
}

/// `z` or `z/2`, any case.
impl FromStr for ZoneScaling {
    type Err = TargetError;

    fn from_str(s: &str) -> Result<Self, TargetError> {
        match s.trim().to_ascii_lowercase().as_str() {
            "z" => Ok(ZoneScaling::Z),
            "z/2" => Ok(ZoneScaling::HalfZ),
            _ => Err(TargetError::UnknownScaling(s.trim().to_string())),
        }
    }
}

impl fmt::Display for ZoneScaling {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ZoneScaling::Z => "z",
            ZoneScaling::HalfZ => "z/2",
        })
    }
}

/// A 5 %-damped target pseudo-acceleration spectrum.
#[derive(Debug, Clone, PartialEq)]
pub enum TargetSpectrum {
    /// IS 1893 (Part 1):2016, `scaling.factor(zone)·(importance/response_reduction)·Sa/g`
    /// (Clause 6.4.2). The standard also caps `I/R` at 1 for design; that cap is not applied.
    Is1893 {
        zone: Zone,
        soil: Soil,
        scaling: ZoneScaling,
        /// Importance factor `I` (Table 8), > 0.
        importance: f64,
        /// Response reduction factor `R` (Table 9), > 0.
        response_reduction: f64,
    },
    /// ASCE 7-16 §11.4.6 design response spectrum.
    Asce7 {
        /// Design short-period spectral acceleration `SDS`, g.
        sds_g: f64,
        /// Design 1-s spectral acceleration `SD1`, g.
        sd1_g: f64,
        /// Long-period transition period `TL`, s.
        tl_s: f64,
    },
    /// A tabulated spectrum, log-log interpolated between rows (linear in `T` on a segment that
    /// starts at `T = 0`). [`TargetSpectrum::from_table_file`] enforces what the interpolation
    /// needs: at least 2 rows, finite periods `≥ 0` strictly increasing, finite `Sa > 0`; a table
    /// built by hand must obey the same rules.
    Table {
        /// Where the table came from (the file path as given), for labels and the SPEC string.
        source: String,
        periods_s: Vec<f64>,
        sa_g: Vec<f64>,
    },
}

impl TargetSpectrum {
    /// Pseudo-spectral acceleration at `period_s`, g.
    ///
    /// Outside a table's period range the end value is returned unchanged: that keeps plots and
    /// sweeps total, but a table says nothing there, so callers must call
    /// [`TargetSpectrum::check_covers`] with the periods they use before relying on it.
    /// NaN for a negative or NaN period.
    pub fn sa_g(&self, period_s: f64) -> f64 {
        if period_s.is_nan() || period_s < 0.0 {
            return f64::NAN;
        }
        match self {
            TargetSpectrum::Is1893 {
                zone,
                soil,
                scaling,
                importance,
                response_reduction,
            } => scaling.factor(*zone) * (importance / response_reduction) * soil.sa_g(period_s),
            TargetSpectrum::Asce7 { sds_g, sd1_g, tl_s } => {
                asce7_sa_g(*sds_g, *sd1_g, *tl_s, period_s)
            }
            TargetSpectrum::Table {
                periods_s, sa_g, ..
            } => interpolate_log_log(periods_s, sa_g, period_s),
        }
    }

    /// Spectral displacement `Sd = Sa·g·(T/2π)²` at `period_s`, m.
    pub fn sd_m(&self, period_s: f64) -> f64 {
        let omega_rad_s = 2.0 * std::f64::consts::PI / period_s;
        self.sa_g(period_s) * G / (omega_rad_s * omega_rad_s)
    }

    /// Periods where the spectrum is defined, s: `(0, ∞)` for the codes, first and last row for a
    /// table.
    pub fn period_range_s(&self) -> (f64, f64) {
        match self {
            TargetSpectrum::Is1893 { .. } | TargetSpectrum::Asce7 { .. } => (0.0, f64::INFINITY),
            TargetSpectrum::Table { periods_s, .. } => (
                periods_s.first().copied().unwrap_or(f64::NAN),
                periods_s.last().copied().unwrap_or(f64::NAN),
            ),
        }
    }

    /// Ok when the spectrum is defined on all of `min_s ≤ T ≤ max_s`; otherwise an error naming
    /// the SPEC string, where it is defined and the range asked for.
    pub fn check_covers(&self, min_s: f64, max_s: f64) -> Result<(), TargetError> {
        if min_s.is_nan() || max_s.is_nan() || min_s > max_s {
            return Err(TargetError::BadRange { min_s, max_s });
        }
        let (from_s, to_s) = self.period_range_s();
        if min_s >= from_s && max_s <= to_s {
            Ok(())
        } else {
            Err(TargetError::NotCovered {
                spec: self.to_string(),
                from_s,
                to_s,
                min_s,
                max_s,
            })
        }
    }

    /// Human-readable description for plots and reports, e.g.
    /// `IS 1893:2016 zone III, soil I, Z·Sa/g`.
    pub fn label(&self) -> String {
        match self {
            TargetSpectrum::Is1893 {
                zone,
                soil,
                scaling,
                importance,
                response_reduction,
            } => {
                let factor = match scaling {
                    ZoneScaling::Z => "Z",
                    ZoneScaling::HalfZ => "(Z/2)",
                };
                if *importance == 1.0 && *response_reduction == 1.0 {
                    format!("IS 1893:2016 zone {zone}, soil {soil}, {factor}·Sa/g")
                } else {
                    format!(
                        "IS 1893:2016 zone {zone}, soil {soil}, {factor}·(I/R)·Sa/g, \
                         I = {importance}, R = {response_reduction}"
                    )
                }
            }
            TargetSpectrum::Asce7 { sds_g, sd1_g, tl_s } => {
                format!(
                    "ASCE 7-16 design spectrum, SDS = {sds_g} g, SD1 = {sd1_g} g, TL = {tl_s} s"
                )
            }
            TargetSpectrum::Table {
                source, periods_s, ..
            } => {
                let (from_s, to_s) = self.period_range_s();
                format!(
                    "table {source} ({} rows, {from_s} s to {to_s} s)",
                    periods_s.len()
                )
            }
        }
    }

    /// Reads a target table ([`TargetSpectrum::from_table_text`]), named by its path as given.
    pub fn from_table_file(path: &Path) -> Result<Self, TargetError> {
        let file = path.display().to_string();
        let bytes = read_table_bytes(path)?;
        TargetSpectrum::from_table_text(&bytes, &file, &file)
    }

    /// A target table from the bytes of its file: one row `period_s sa_g` per line, whitespace
    /// or comma separated, `#` starts a comment, blank lines are skipped, a byte-order mark is
    /// dropped. `source` names the table in its SPEC string and labels, `file` in errors, which
    /// give `file:line`.
    pub fn from_table_text(bytes: &[u8], source: &str, file: &str) -> Result<Self, TargetError> {
        let text = input_text(bytes).map_err(|source| TargetError::Io {
            file: file.to_string(),
            source,
        })?;
        let (periods_s, sa_g) = parse_table(text, file)?;
        Ok(TargetSpectrum::Table {
            source: source.to_string(),
            periods_s,
            sa_g,
        })
    }

    /// The FILE of a `table:FILE` SPEC string, trimmed, as written (`None` for the kinds that
    /// read no file). An empty FILE is `Some("")`, which parsing refuses.
    pub fn table_file(spec: &str) -> Option<&str> {
        let spec = spec.trim();
        let (kind, params) = spec.split_once(':').unwrap_or((spec, ""));
        kind.trim()
            .eq_ignore_ascii_case("table")
            .then(|| params.trim())
    }

    /// Zone numeral (`"III"`) of an IS 1893 target, `None` for the others.
    pub fn zone_name(&self) -> Option<&'static str> {
        match self {
            TargetSpectrum::Is1893 { zone, .. } => Some(zone.name()),
            _ => None,
        }
    }
}

/// What a program evaluating [`TargetSpectrum::sa_g`] elsewhere needs (the report's design
/// page does, in JavaScript), with the same numbers in the same operations: IS 1893 as
/// `factor·(importance/response_reduction)·Sa/g` with the soil's branch constants, ASCE 7 by
/// its three parameters, a table by its rows; `spec` is the SPEC string and `label` the
/// description.
impl serde::Serialize for TargetSpectrum {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut st = s.serialize_struct("TargetSpectrum", 9)?;
        st.serialize_field("spec", &self.to_string())?;
        st.serialize_field("label", &self.label())?;
        match self {
            TargetSpectrum::Is1893 {
                zone,
                soil,
                scaling,
                importance,
                response_reduction,
            } => {
                st.serialize_field("kind", "is1893")?;
                st.serialize_field("factor", &scaling.factor(*zone))?;
                st.serialize_field("importance", importance)?;
                st.serialize_field("response_reduction", response_reduction)?;
                st.serialize_field("corner_s", &soil.corner_period_s())?;
                st.serialize_field("descending_s", &soil.descending_coefficient_s())?;
                st.serialize_field("long_g", &soil.long_period_sa_g())?;
            }
            TargetSpectrum::Asce7 { sds_g, sd1_g, tl_s } => {
                st.serialize_field("kind", "asce7")?;
                st.serialize_field("sds_g", sds_g)?;
                st.serialize_field("sd1_g", sd1_g)?;
                st.serialize_field("tl_s", tl_s)?;
            }
            TargetSpectrum::Table {
                periods_s, sa_g, ..
            } => {
                st.serialize_field("kind", "table")?;
                st.serialize_field("periods_s", periods_s)?;
                st.serialize_field("sa_g", sa_g)?;
            }
        }
        st.end()
    }
}

/// The bytes of a target table file, refused above [`MAX_FILE_BYTES`] before they are read.
pub fn read_table_bytes(path: &Path) -> Result<Vec<u8>, TargetError> {
    let file = path.display().to_string();
    read_input_file(path).map_err(|e| match e {
        InputFileError::Io(source) => TargetError::Io { file, source },
        InputFileError::TooLarge(bytes) => TargetError::TableTooLarge { file, bytes },
    })
}

/// ASCE 7-16 §11.4.6: `SDS(0.4 + 0.6T/T0)` below `T0 = 0.2·SD1/SDS`, `SDS` up to
/// `TS = SD1/SDS`, `SD1/T` up to `TL`, `SD1·TL/T²` beyond.
fn asce7_sa_g(sds_g: f64, sd1_g: f64, tl_s: f64, period_s: f64) -> f64 {
    let ts_s = sd1_g / sds_g;
    let t0_s = 0.2 * ts_s;
    if period_s < t0_s {
        sds_g * (0.4 + 0.6 * period_s / t0_s)
    } else if period_s <= ts_s {
        sds_g
    } else if period_s <= tl_s {
        sd1_g / period_s
    } else {
        sd1_g * tl_s / (period_s * period_s)
    }
}

/// Straight line in `ln T`–`ln Sa` between the rows bracketing `period_s` (in `T`–`Sa` on a
/// segment starting at `T = 0`, where `ln T` does not exist); the end value outside the rows.
fn interpolate_log_log(periods_s: &[f64], sa_g: &[f64], period_s: f64) -> f64 {
    let n = periods_s.len().min(sa_g.len());
    if n == 0 {
        return f64::NAN;
    }
    if period_s <= periods_s[0] {
        return sa_g[0];
    }
    if period_s >= periods_s[n - 1] {
        return sa_g[n - 1];
    }
    let k = periods_s[..n].partition_point(|&t| t <= period_s);
    let (t0, t1, s0, s1) = (periods_s[k - 1], periods_s[k], sa_g[k - 1], sa_g[k]);
    if period_s == t0 {
        s0
    } else if t0 == 0.0 {
        s0 + (s1 - s0) * period_s / t1
    } else {
        s0 * (s1 / s0).powf((period_s / t0).ln() / (t1 / t0).ln())
    }
}

fn table_number(token: &str, file: &str, line: usize) -> Result<f64, TargetError> {
    let value: f64 = token.parse().map_err(|_| TargetError::TableNotANumber {
        file: file.to_string(),
        line,
        token: token.to_string(),
    })?;
    if !value.is_finite() {
        return Err(TargetError::TableNonFinite {
            file: file.to_string(),
            line,
            value,
        });
    }
    Ok(value)
}

/// `(periods_s, sa_g)` from the text of a table file named `file` in messages.
fn parse_table(text: &str, file: &str) -> Result<(Vec<f64>, Vec<f64>), TargetError> {
    let mut periods_s: Vec<f64> = Vec::new();
    let mut sa_g = Vec::new();
    let mut last_line = 1;
    for (idx, raw) in text.lines().enumerate() {
        let line = idx + 1;
        last_line = line;
        let content = raw.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let fields: Vec<&str> = if content.contains(',') {
            content.split(',').map(str::trim).collect()
        } else {
            content.split_whitespace().collect()
        };
        if fields.len() != 2 {
            return Err(TargetError::TableColumns {
                file: file.to_string(),
                line,
                found: fields.len(),
            });
        }
        let period = table_number(fields[0], file, line)?;
        let sa = table_number(fields[1], file, line)?;
        if period < 0.0 {
            return Err(TargetError::TableNegativePeriod {
                file: file.to_string(),
                line,
                period_s: period,
            });
        }
        if let Some(&previous_s) = periods_s.last()
            && period <= previous_s
        {
            return Err(TargetError::TablePeriodOrder {
                file: file.to_string(),
                line,
                period_s: period,
                previous_s,
            });
        }
        if sa <= 0.0 {
            return Err(TargetError::TableSa {
                file: file.to_string(),
                line,
                sa_g: sa,
            });
        }
        periods_s.push(period);
        sa_g.push(sa);
    }
    if periods_s.len() < 2 {
        return Err(TargetError::TableTooShort {
            file: file.to_string(),
            line: last_line,
            found: periods_s.len(),
        });
    }
    Ok((periods_s, sa_g))
}

const IS1893_KEYS: &[&str] = &["zone", "soil", "scaling", "i", "r"];
const ASCE7_KEYS: &[&str] = &["sds", "sd1", "tl"];
const ZONE_EXPECTED: &str = "II, III, IV or V (or 2, 3, 4, 5)";
const SOIL_EXPECTED: &str = "I, II or III (or 1, 2, 3)";
const SCALING_EXPECTED: &str = "z or z/2";

/// Values of `KEY=VALUE` items, in the order of `valid`.
fn parse_params<'a>(
    kind: &'static str,
    valid: &'static [&'static str],
    text: &'a str,
) -> Result<Vec<Option<&'a str>>, TargetError> {
    let mut values = vec![None; valid.len()];
    for item in text.split(',').map(str::trim).filter(|i| !i.is_empty()) {
        let (key, value) = item
            .split_once('=')
            .ok_or_else(|| TargetError::NotKeyValue {
                kind,
                item: item.to_string(),
            })?;
        let key = key.trim();
        let index = valid
            .iter()
            .position(|v| v.eq_ignore_ascii_case(key))
            .ok_or_else(|| TargetError::UnknownKey {
                kind,
                key: key.to_string(),
                valid: valid.join(", "),
            })?;
        if values[index].is_some() {
            return Err(TargetError::DuplicateKey {
                kind,
                key: valid[index],
            });
        }
        values[index] = Some(value.trim());
    }
    Ok(values)
}

fn required<'a>(
    kind: &'static str,
    key: &'static str,
    value: Option<&'a str>,
) -> Result<&'a str, TargetError> {
    value.ok_or(TargetError::MissingKey { kind, key })
}

/// A finite number > 0.
fn positive(kind: &'static str, key: &'static str, value: &str) -> Result<f64, TargetError> {
    let x: f64 = value.parse().map_err(|_| TargetError::BadValue {
        kind,
        key,
        value: value.to_string(),
        expected: "a number",
    })?;
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(TargetError::NotPositive {
            kind,
            key,
            value: x,
        })
    }
}

fn parse_is1893(params: &str) -> Result<TargetSpectrum, TargetError> {
    const KIND: &str = "is1893";
    let v = parse_params(KIND, IS1893_KEYS, params)?;
    let bad = |key: &'static str, value: &str, expected: &'static str| TargetError::BadValue {
        kind: KIND,
        key,
        value: value.to_string(),
        expected,
    };
    let zone_text = required(KIND, "zone", v[0])?;
    let zone = zone_text
        .parse()
        .map_err(|_| bad("zone", zone_text, ZONE_EXPECTED))?;
    let soil_text = required(KIND, "soil", v[1])?;
    let soil = soil_text
        .parse()
        .map_err(|_| bad("soil", soil_text, SOIL_EXPECTED))?;
    let scaling = match v[2] {
        Some(s) => s.parse().map_err(|_| bad("scaling", s, SCALING_EXPECTED))?,
        None => ZoneScaling::Z,
    };
    let importance = v[3].map_or(Ok(1.0), |s| positive(KIND, "i", s))?;
    let response_reduction = v[4].map_or(Ok(1.0), |s| positive(KIND, "r", s))?;
    Ok(TargetSpectrum::Is1893 {
        zone,
        soil,
        scaling,
        importance,
        response_reduction,
    })
}

fn parse_asce7(params: &str) -> Result<TargetSpectrum, TargetError> {
    const KIND: &str = "asce7";
    let v = parse_params(KIND, ASCE7_KEYS, params)?;
    let sds_g = positive(KIND, "sds", required(KIND, "sds", v[0])?)?;
    let sd1_g = positive(KIND, "sd1", required(KIND, "sd1", v[1])?)?;
    let tl_s = positive(KIND, "tl", required(KIND, "tl", v[2])?)?;
    let ts_s = sd1_g / sds_g;
    if tl_s <= ts_s {
        return Err(TargetError::TlNotAfterTs { tl_s, ts_s });
    }
    Ok(TargetSpectrum::Asce7 { sds_g, sd1_g, tl_s })
}

/// Parses a SPEC string `KIND:PARAMS` (see the module documentation); `table:FILE` reads FILE.
impl FromStr for TargetSpectrum {
    type Err = TargetError;

    fn from_str(spec: &str) -> Result<Self, TargetError> {
        let spec = spec.trim();
        let (kind, params) = spec.split_once(':').unwrap_or((spec, ""));
        let kind = kind.trim();
        match kind.to_ascii_lowercase().as_str() {
            "is1893" => parse_is1893(params),
            "asce7" => parse_asce7(params),
            "table" => match params.trim() {
                "" => Err(TargetError::MissingFile),
                file => TargetSpectrum::from_table_file(Path::new(file)),
            },
            _ => Err(TargetError::UnknownKind(kind.to_string())),
        }
    }
}

/// The canonical SPEC string, every key written out (`is1893:zone=III,soil=I,scaling=z,i=1,r=1`);
/// [`TargetSpectrum::from_str`] reads it back to an equal value (for a table, as long as the file
/// is unchanged).
impl fmt::Display for TargetSpectrum {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TargetSpectrum::Is1893 {
                zone,
                soil,
                scaling,
                importance,
                response_reduction,
            } => write!(
                f,
                "is1893:zone={zone},soil={soil},scaling={scaling},i={importance},r={response_reduction}"
            ),
            TargetSpectrum::Asce7 { sds_g, sd1_g, tl_s } => {
                write!(f, "asce7:sds={sds_g},sd1={sd1_g},tl={tl_s}")
            }
            TargetSpectrum::Table { source, .. } => write!(f, "table:{source}"),
        }
    }
}

/// `lo s ≤ T ≤ hi s`, or `T ≥ lo s` when unbounded above.
fn range_text(from_s: f64, to_s: f64) -> String {
    if to_s.is_infinite() {
        format!("T ≥ {from_s} s")
    } else {
        format!("{from_s} s ≤ T ≤ {to_s} s")
    }
}

#[derive(Debug, Error)]
pub enum TargetError {
    #[error(
        "unknown target spectrum kind `{0}`: expected is1893, asce7 or table \
         (e.g. `is1893:zone=III,soil=I`)"
    )]
    UnknownKind(String),
    #[error("{kind}: `{item}` is not KEY=VALUE")]
    NotKeyValue { kind: &'static str, item: String },
    #[error("{kind}: unknown key `{key}`; valid keys: {valid}")]
    UnknownKey {
        kind: &'static str,
        key: String,
        valid: String,
    },
    #[error("{kind}: key `{key}` is given more than once")]
    DuplicateKey {
        kind: &'static str,
        key: &'static str,
    },
    #[error("{kind}: missing key `{key}`")]
    MissingKey {
        kind: &'static str,
        key: &'static str,
    },
    #[error("{kind}: bad value `{value}` for `{key}`: expected {expected}")]
    BadValue {
        kind: &'static str,
        key: &'static str,
        value: String,
        expected: &'static str,
    },
    #[error("{kind}: `{key}` must be finite and > 0, got {value}")]
    NotPositive {
        kind: &'static str,
        key: &'static str,
        value: f64,
    },
    #[error("asce7: tl = {tl_s} s must exceed TS = SD1/SDS = {ts_s} s (ASCE 7-16 §11.4.6)")]
    TlNotAfterTs { tl_s: f64, ts_s: f64 },
    #[error("unknown seismic zone `{0}`: expected {ZONE_EXPECTED}")]
    UnknownZone(String),
    #[error("unknown soil type `{0}`: expected {SOIL_EXPECTED}")]
    UnknownSoil(String),
    #[error("unknown zone scaling `{0}`: expected {SCALING_EXPECTED}")]
    UnknownScaling(String),
    #[error("table: missing file name, write `table:FILE`")]
    MissingFile,
    #[error("{file}: cannot read: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: {bytes} bytes: a target table may have at most {MAX_FILE_BYTES}")]
    TableTooLarge { file: String, bytes: u64 },
    #[error("{file}:{line}: expected 2 columns (period_s sa_g), found {found}")]
    TableColumns {
        file: String,
        line: usize,
        found: usize,
    },
    #[error("{file}:{line}: `{token}` is not a number")]
    TableNotANumber {
        file: String,
        line: usize,
        token: String,
    },
    #[error("{file}:{line}: value {value} is not finite")]
    TableNonFinite {
        file: String,
        line: usize,
        value: f64,
    },
    #[error("{file}:{line}: period {period_s} s is negative")]
    TableNegativePeriod {
        file: String,
        line: usize,
        period_s: f64,
    },
    #[error(
        "{file}:{line}: period {period_s} s is not greater than the previous row's {previous_s} s \
         (periods must be strictly increasing)"
    )]
    TablePeriodOrder {
        file: String,
        line: usize,
        period_s: f64,
        previous_s: f64,
    },
    #[error("{file}:{line}: Sa must be > 0 g, got {sa_g}")]
    TableSa {
        file: String,
        line: usize,
        sa_g: f64,
    },
    #[error("{file}:{line}: a target table needs at least 2 rows, found {found}")]
    TableTooShort {
        file: String,
        line: usize,
        found: usize,
    },
    #[error("period range {min_s} s to {max_s} s is empty or not a number")]
    BadRange { min_s: f64, max_s: f64 },
    #[error(
        "target spectrum `{spec}` is defined only for {}, but periods {min_s} s to {max_s} s \
         are needed",
        range_text(*.from_s, *.to_s)
    )]
    NotCovered {
        spec: String,
        from_s: f64,
        to_s: f64,
        min_s: f64,
        max_s: f64,
    },
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn close(got: f64, want: f64, tol: f64) {
        assert!(
            (got - want).abs() <= tol,
            "got {got}, want {want} (tol {tol})"
        );
    }

    fn is1893(zone: Zone, soil: Soil) -> TargetSpectrum {
        TargetSpectrum::Is1893 {
            zone,
            soil,
            scaling: ZoneScaling::Z,
            importance: 1.0,
            response_reduction: 1.0,
        }
    }

    fn asce7() -> TargetSpectrum {
        TargetSpectrum::Asce7 {
            sds_g: 1.0,
            sd1_g: 0.6,
            tl_s: 8.0,
        }
    }

    fn table(periods_s: &[f64], sa_g: &[f64]) -> TargetSpectrum {
        TargetSpectrum::Table {
            source: "t.txt".to_string(),
            periods_s: periods_s.to_vec(),
            sa_g: sa_g.to_vec(),
        }
    }

    fn spec_err(spec: &str) -> String {
        spec.parse::<TargetSpectrum>().unwrap_err().to_string()
    }

    fn table_err(text: &str) -> String {
        parse_table(text, "t.txt").unwrap_err().to_string()
    }

    #[test]
    fn notes_zone_iii_and_v_hard_soil_at_0_7_s() {
        // docs/model.md: hard soil, T = 0.7 s is on the 1/T branch (0.40 < 0.7 ≤ 4), Sa/g = 1/0.7 = 1.4286;
        // Z·Sa/g = 0.16/0.7 = 0.2286 g (zone III) and 0.36/0.7 = 0.5143 g (zone V).
        let iii = is1893(Zone::III, Soil::I).sa_g(0.7);
        let v = is1893(Zone::V, Soil::I).sa_g(0.7);
        close(iii, 0.16 / 0.7, 1e-15);
        close(v, 0.36 / 0.7, 1e-15);
        close(iii, 0.2286, 5e-5);
        close(v, 0.5143, 5e-5);
    }

    #[test]
    fn notes_sd_zone_iii_at_1_38_s() {
        // 1/T branch: Sd = (0.16/T)·g·T²/(4π²) = 0.16·g·T/(4π²);
        // T = 1.38 s: 0.16·9.80665·1.38 / 39.47842 = 0.054848 m = 5.48 cm, the paper's 5.49 cm
        // to the precision of T (5.49 cm gives T = 1.3813 s).
        let sd = is1893(Zone::III, Soil::I).sd_m(1.38);
        close(sd, 0.16 * G * 1.38 / (4.0 * PI * PI), 1e-15);
        close(sd, 0.054848, 5e-7);
        close(0.0549 * 4.0 * PI * PI / (0.16 * G), 1.3813, 5e-5);
    }

    #[test]
    fn is1893_soil_i_every_branch_and_breakpoint() {
        // 1 + 15T below 0.10 s; 2.5 on [0.10, 0.40]; 1.00/T on (0.40, 4.00]; 0.25 beyond.
        let s = Soil::I;
        close(s.sa_g(0.0), 1.0, 0.0);
        close(s.sa_g(0.05), 1.75, 1e-15); // 1 + 15·0.05
        close(s.sa_g(0.10), 2.5, 0.0);
        close(s.sa_g(0.25), 2.5, 0.0);
        close(s.sa_g(0.40), 2.5, 0.0);
        close(s.sa_g(0.50), 2.0, 1e-15); // 1/0.5
        close(s.sa_g(2.0), 0.5, 1e-15);
        close(s.sa_g(4.0), 0.25, 1e-15); // 1/4
        close(s.sa_g(5.0), 0.25, 0.0);
        close(s.sa_g(100.0), 0.25, 0.0);
    }

    #[test]
    fn is1893_soil_ii_every_branch_and_breakpoint() {
        // 1 + 15T below 0.10 s; 2.5 on [0.10, 0.55]; 1.36/T on (0.55, 4.00]; 0.34 beyond.
        let s = Soil::II;
        close(s.sa_g(0.0), 1.0, 0.0);
        close(s.sa_g(0.08), 2.2, 1e-15); // 1 + 15·0.08
        close(s.sa_g(0.10), 2.5, 0.0);
        close(s.sa_g(0.55), 2.5, 0.0);
        close(s.sa_g(0.68), 2.0, 1e-15); // 1.36/0.68
        close(s.sa_g(1.0), 1.36, 1e-15);
        close(s.sa_g(4.0), 0.34, 1e-15); // 1.36/4
        close(s.sa_g(4.5), 0.34, 0.0);
    }

    #[test]
    fn is1893_soil_iii_every_branch_and_breakpoint() {
        // 1 + 15T below 0.10 s; 2.5 on [0.10, 0.67]; 1.67/T on (0.67, 4.00]; 0.42 beyond.
        let s = Soil::III;
        close(s.sa_g(0.0), 1.0, 0.0);
        close(s.sa_g(0.02), 1.3, 1e-15); // 1 + 15·0.02
        close(s.sa_g(0.10), 2.5, 0.0);
        close(s.sa_g(0.67), 2.5, 0.0);
        close(s.sa_g(1.67), 1.0, 1e-15); // 1.67/1.67
        close(s.sa_g(4.0), 0.4175, 1e-15); // 1.67/4
        close(s.sa_g(4.01), 0.42, 0.0);
    }

    #[test]
    fn is1893_continuity_at_breakpoints_is_as_the_rounded_coefficients_give() {
        let eps = 1e-9;
        for soil in [Soil::I, Soil::II, Soil::III] {
            // 0.10 s: 1 + 15·0.10 = 2.5 exactly, for every soil.
            close(soil.sa_g(0.10 - eps), 2.5, 1e-7);
        }
        // Corner periods: soil I meets (1.00/0.40 = 2.5); soil II drops to 1.36/0.55 = 2.4727;
        // soil III drops to 1.67/0.67 = 2.4925.
        close(Soil::I.sa_g(0.40 + eps), 2.5, 1e-7);
        close(Soil::II.sa_g(0.55 + eps), 2.472_727, 1e-6);
        close(Soil::III.sa_g(0.67 + eps), 2.492_537, 1e-6);
        // 4 s: soil I meets (1.00/4 = 0.25), soil II meets (1.36/4 = 0.34), soil III steps up
        // from 1.67/4 = 0.4175 to 0.42.
        close(Soil::I.sa_g(4.0 + eps), Soil::I.sa_g(4.0), 1e-12);
        close(Soil::II.sa_g(4.0 + eps), Soil::II.sa_g(4.0), 1e-12);
        close(
            Soil::III.sa_g(4.0 + eps) - Soil::III.sa_g(4.0),
            0.0025,
            1e-12,
        );
    }

    #[test]
    fn is1893_half_z_with_importance_and_r() {
        // Zone IV, soil II, Ah = (Z/2)(I/R)(Sa/g) = 0.12·(1.5/5)·Sa/g = 0.036·Sa/g:
        // T = 0.3 s plateau 0.036·2.5 = 0.09; T = 1 s 0.036·1.36 = 0.04896.
        let t = TargetSpectrum::Is1893 {
            zone: Zone::IV,
            soil: Soil::II,
            scaling: ZoneScaling::HalfZ,
            importance: 1.5,
            response_reduction: 5.0,
        };
        close(t.sa_g(0.3), 0.09, 1e-15);
        close(t.sa_g(1.0), 0.04896, 1e-15);
        // Table 3 factors.
        let z: Vec<f64> = [Zone::II, Zone::III, Zone::IV, Zone::V]
            .iter()
            .map(|z| z.factor())
            .collect();
        assert_eq!(z, [0.10, 0.16, 0.24, 0.36]);
        close(ZoneScaling::HalfZ.factor(Zone::V), 0.18, 1e-15);
    }

    #[test]
    fn negative_or_nan_period_gives_nan_and_sd_is_zero_at_zero() {
        assert!(is1893(Zone::V, Soil::I).sa_g(-0.1).is_nan());
        assert!(asce7().sa_g(f64::NAN).is_nan());
        assert!(table(&[0.5, 2.0], &[2.0, 0.5]).sa_g(-1.0).is_nan());
        assert_eq!(asce7().sd_m(0.0), 0.0);
    }

    #[test]
    fn asce7_every_branch() {
        // SDS = 1.0, SD1 = 0.6, TL = 8: T0 = 0.2·0.6/1 = 0.12 s, TS = 0.6 s.
        let a = asce7();
        close(a.sa_g(0.0), 0.4, 1e-15); // SDS·0.4
        close(a.sa_g(0.06), 0.7, 1e-15); // 1·(0.4 + 0.6·0.06/0.12)
        close(a.sa_g(0.12), 1.0, 1e-15); // T0: SDS
        close(a.sa_g(0.3), 1.0, 0.0);
        close(a.sa_g(0.6), 1.0, 0.0); // TS: SDS = SD1/TS
        close(a.sa_g(1.0), 0.6, 1e-15); // SD1/1
        close(a.sa_g(8.0), 0.075, 1e-15); // SD1/TL = 0.6/8
        close(a.sa_g(10.0), 0.048, 1e-15); // SD1·TL/T² = 0.6·8/100
        // Continuous at T0, TS, TL.
        let eps = 1e-9;
        close(a.sa_g(0.12 - eps), 1.0, 1e-7);
        close(a.sa_g(0.6 + eps), 1.0, 1e-7);
        close(a.sa_g(8.0 + eps), 0.075, 1e-7);
        // Sd at 1 s: 0.6·9.80665/(4π²) = 5.88399/39.47842 = 0.149043 m.
        close(a.sd_m(1.0), 0.149_043, 5e-7);
    }

    #[test]
    fn table_log_log_interpolation() {
        // (0.5, 2.0)–(2.0, 0.5): T = 1 is the geometric midpoint, so Sa = sqrt(2.0·0.5) = 1.0.
        let t = table(&[0.5, 2.0], &[2.0, 0.5]);
        close(t.sa_g(1.0), 1.0, 1e-15);
        // (0.1, 1.0)–(1.0, 0.1) is Sa·T = 0.1 in log-log: T = 0.5 gives 0.2, T = sqrt(0.1) gives sqrt(0.1).
        let t = table(&[0.1, 1.0], &[1.0, 0.1]);
        close(t.sa_g(0.5), 0.2, 1e-15);
        close(t.sa_g(0.1_f64.sqrt()), 0.1_f64.sqrt(), 1e-15);
        // Rows themselves are returned exactly.
        assert_eq!(t.sa_g(0.1), 1.0);
        assert_eq!(t.sa_g(1.0), 0.1);
    }

    #[test]
    fn table_row_at_zero_period_is_linear_on_its_segment() {
        // (0, 0.4)–(0.2, 1.0) linear: T = 0.1 gives 0.7; (0.2, 1.0)–(1.0, 0.2) is Sa·T = 0.2 in
        // log-log: T = 0.5 gives 0.4.
        let t = table(&[0.0, 0.2, 1.0], &[0.4, 1.0, 0.2]);
        close(t.sa_g(0.0), 0.4, 0.0);
        close(t.sa_g(0.1), 0.7, 1e-15);
        close(t.sa_g(0.5), 0.4, 1e-15);
        assert_eq!(t.period_range_s(), (0.0, 1.0));
        t.check_covers(0.0, 1.0).unwrap();
    }

    #[test]
    fn table_clamps_outside_its_range_but_check_covers_refuses() {
        let t = table(&[0.5, 2.0], &[2.0, 0.5]);
        assert_eq!(t.sa_g(0.1), 2.0);
        assert_eq!(t.sa_g(3.0), 0.5);
        t.check_covers(0.5, 2.0).unwrap();
        assert_eq!(
            t.check_covers(0.1, 1.0).unwrap_err().to_string(),
            "target spectrum `table:t.txt` is defined only for 0.5 s ≤ T ≤ 2 s, \
             but periods 0.1 s to 1 s are needed"
        );
        assert_eq!(
            t.check_covers(1.0, 3.0).unwrap_err().to_string(),
            "target spectrum `table:t.txt` is defined only for 0.5 s ≤ T ≤ 2 s, \
             but periods 1 s to 3 s are needed"
        );
    }

    #[test]
    fn codes_cover_every_nonnegative_period() {
        assert_eq!(asce7().period_range_s(), (0.0, f64::INFINITY));
        asce7().check_covers(0.0, f64::INFINITY).unwrap();
        is1893(Zone::II, Soil::III).check_covers(0.0, 10.0).unwrap();
        assert_eq!(
            asce7().check_covers(-1.0, 3.0).unwrap_err().to_string(),
            "target spectrum `asce7:sds=1,sd1=0.6,tl=8` is defined only for T ≥ 0 s, \
             but periods -1 s to 3 s are needed"
        );
        assert_eq!(
            asce7().check_covers(2.0, 1.0).unwrap_err().to_string(),
            "period range 2 s to 1 s is empty or not a number"
        );
        assert_eq!(
            asce7().check_covers(f64::NAN, 1.0).unwrap_err().to_string(),
            "period range NaN s to 1 s is empty or not a number"
        );
    }

    #[test]
    fn zone_soil_scaling_parse_and_display() {
        assert_eq!("III".parse::<Zone>().unwrap(), Zone::III);
        assert_eq!(" iv ".parse::<Zone>().unwrap(), Zone::IV);
        assert_eq!("5".parse::<Zone>().unwrap(), Zone::V);
        assert_eq!("ii".parse::<Soil>().unwrap(), Soil::II);
        assert_eq!("3".parse::<Soil>().unwrap(), Soil::III);
        assert_eq!("Z/2".parse::<ZoneScaling>().unwrap(), ZoneScaling::HalfZ);
        for z in [Zone::II, Zone::III, Zone::IV, Zone::V] {
            assert_eq!(z.to_string().parse::<Zone>().unwrap(), z);
        }
        for s in [Soil::I, Soil::II, Soil::III] {
            assert_eq!(s.to_string().parse::<Soil>().unwrap(), s);
        }
        for s in [ZoneScaling::Z, ZoneScaling::HalfZ] {
            assert_eq!(s.to_string().parse::<ZoneScaling>().unwrap(), s);
        }
        assert_eq!(
            "VI".parse::<Zone>().unwrap_err().to_string(),
            "unknown seismic zone `VI`: expected II, III, IV or V (or 2, 3, 4, 5)"
        );
        assert_eq!(
            "0".parse::<Soil>().unwrap_err().to_string(),
            "unknown soil type `0`: expected I, II or III (or 1, 2, 3)"
        );
        assert_eq!(
            "z/3".parse::<ZoneScaling>().unwrap_err().to_string(),
            "unknown zone scaling `z/3`: expected z or z/2"
        );
    }

    #[test]
    fn is1893_spec_defaults_and_round_trip() {
        let t: TargetSpectrum = "is1893:zone=V,soil=I".parse().unwrap();
        assert_eq!(t, is1893(Zone::V, Soil::I));
        assert_eq!(t.to_string(), "is1893:zone=V,soil=I,scaling=z,i=1,r=1");
        assert_eq!(t.to_string().parse::<TargetSpectrum>().unwrap(), t);

        let t: TargetSpectrum = " IS1893: Zone = iii , soil=3, scaling=Z/2, I=1.2, R=5 "
            .parse()
            .unwrap();
        assert_eq!(
            t,
            TargetSpectrum::Is1893 {
                zone: Zone::III,
                soil: Soil::III,
                scaling: ZoneScaling::HalfZ,
                importance: 1.2,
                response_reduction: 5.0,
            }
        );
        assert_eq!(
            t.to_string(),
            "is1893:zone=III,soil=III,scaling=z/2,i=1.2,r=5"
        );
        assert_eq!(t.to_string().parse::<TargetSpectrum>().unwrap(), t);
    }

    #[test]
    fn asce7_spec_round_trip() {
        let t: TargetSpectrum = "asce7:sds=1.0,sd1=0.6,tl=8".parse().unwrap();
        assert_eq!(t, asce7());
        assert_eq!(t.to_string(), "asce7:sds=1,sd1=0.6,tl=8");
        assert_eq!(t.to_string().parse::<TargetSpectrum>().unwrap(), t);
        // Values that need all 17 digits survive the round trip too.
        let t = TargetSpectrum::Asce7 {
            sds_g: 0.1 + 0.2,
            sd1_g: 1.0 / 3.0,
            tl_s: 12.0,
        };
        assert_eq!(t.to_string().parse::<TargetSpectrum>().unwrap(), t);
    }

    #[test]
    fn table_file_parse_and_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("target.txt");
        std::fs::write(
            &path,
            "# period_s  sa_g\n0.0  0.4\n\n0.2, 1.0   # plateau\n1.0 ,0.2\n",
        )
        .unwrap();
        let t = TargetSpectrum::from_table_file(&path).unwrap();
        let file = path.display().to_string();
        assert_eq!(
            t,
            TargetSpectrum::Table {
                source: file.clone(),
                periods_s: vec![0.0, 0.2, 1.0],
                sa_g: vec![0.4, 1.0, 0.2],
            }
        );
        assert_eq!(t.to_string(), format!("table:{file}"));
        assert_eq!(t.to_string().parse::<TargetSpectrum>().unwrap(), t);
        assert_eq!(t.label(), format!("table {file} (3 rows, 0 s to 1 s)"));
        assert_eq!(t.zone_name(), None);

        let missing = dir.path().join("missing.txt");
        let err = format!("table:{}", missing.display())
            .parse::<TargetSpectrum>()
            .unwrap_err();
        assert!(matches!(err, TargetError::Io { .. }));
        assert!(
            err.to_string()
                .starts_with(&format!("{}: cannot read: ", missing.display()))
        );
    }

    #[test]
    fn labels_and_zone_name() {
        let t = is1893(Zone::III, Soil::I);
        assert_eq!(t.label(), "IS 1893:2016 zone III, soil I, Z·Sa/g");
        assert_eq!(t.zone_name(), Some("III"));
        let t = TargetSpectrum::Is1893 {
            zone: Zone::IV,
            soil: Soil::II,
            scaling: ZoneScaling::HalfZ,
            importance: 1.5,
            response_reduction: 5.0,
        };
        assert_eq!(
            t.label(),
            "IS 1893:2016 zone IV, soil II, (Z/2)·(I/R)·Sa/g, I = 1.5, R = 5"
        );
        assert_eq!(
            asce7().label(),
            "ASCE 7-16 design spectrum, SDS = 1 g, SD1 = 0.6 g, TL = 8 s"
        );
        assert_eq!(asce7().zone_name(), None);
    }

    #[test]
    fn spec_errors_are_exact() {
        let cases = [
            (
                "foo:x=1",
                "unknown target spectrum kind `foo`: expected is1893, asce7 or table \
                 (e.g. `is1893:zone=III,soil=I`)",
            ),
            ("is1893:zone=III,soil", "is1893: `soil` is not KEY=VALUE"),
            (
                "is1893:zone=III,soil=I,damping=5",
                "is1893: unknown key `damping`; valid keys: zone, soil, scaling, i, r",
            ),
            (
                "asce7:sds=1,sd1=0.6,t=8",
                "asce7: unknown key `t`; valid keys: sds, sd1, tl",
            ),
            (
                "is1893:zone=III,soil=I,Zone=V",
                "is1893: key `zone` is given more than once",
            ),
            ("is1893", "is1893: missing key `zone`"),
            ("is1893:soil=I", "is1893: missing key `zone`"),
            ("is1893:zone=III", "is1893: missing key `soil`"),
            ("asce7:sd1=0.6,tl=8", "asce7: missing key `sds`"),
            ("asce7:sds=1,tl=8", "asce7: missing key `sd1`"),
            ("asce7:sds=1,sd1=0.6", "asce7: missing key `tl`"),
            (
                "is1893:zone=VI,soil=I",
                "is1893: bad value `VI` for `zone`: expected II, III, IV or V (or 2, 3, 4, 5)",
            ),
            (
                "is1893:zone=V,soil=IV",
                "is1893: bad value `IV` for `soil`: expected I, II or III (or 1, 2, 3)",
            ),
            (
                "is1893:zone=V,soil=I,scaling=2z",
                "is1893: bad value `2z` for `scaling`: expected z or z/2",
            ),
            (
                "is1893:zone=V,soil=I,i=abc",
                "is1893: bad value `abc` for `i`: expected a number",
            ),
            (
                "asce7:sds=,sd1=0.6,tl=8",
                "asce7: bad value `` for `sds`: expected a number",
            ),
            (
                "is1893:zone=V,soil=I,i=-1",
                "is1893: `i` must be finite and > 0, got -1",
            ),
            (
                "is1893:zone=V,soil=I,r=0",
                "is1893: `r` must be finite and > 0, got 0",
            ),
            (
                "asce7:sds=0,sd1=0.6,tl=8",
                "asce7: `sds` must be finite and > 0, got 0",
            ),
            (
                "asce7:sds=inf,sd1=0.6,tl=8",
                "asce7: `sds` must be finite and > 0, got inf",
            ),
            (
                "asce7:sds=1,sd1=-0.6,tl=8",
                "asce7: `sd1` must be finite and > 0, got -0.6",
            ),
            (
                "asce7:sds=1,sd1=0.6,tl=0",
                "asce7: `tl` must be finite and > 0, got 0",
            ),
            (
                "asce7:sds=1,sd1=0.6,tl=0.5",
                "asce7: tl = 0.5 s must exceed TS = SD1/SDS = 0.6 s (ASCE 7-16 §11.4.6)",
            ),
            ("table:", "table: missing file name, write `table:FILE`"),
            ("table: ", "table: missing file name, write `table:FILE`"),
        ];
        for (spec, want) in cases {
            assert_eq!(spec_err(spec), want, "spec `{spec}`");
        }
    }

    #[test]
    fn table_errors_are_exact() {
        let cases = [
            (
                "0.1 1.0\n0.2\n",
                "t.txt:2: expected 2 columns (period_s sa_g), found 1",
            ),
            (
                "0.1 1.0 3\n",
                "t.txt:1: expected 2 columns (period_s sa_g), found 3",
            ),
            (
                "0.1,,1.0\n",
                "t.txt:1: expected 2 columns (period_s sa_g), found 3",
            ),
            ("period sa\n", "t.txt:1: `period` is not a number"),
            ("0.1 1.0\n0.2 abc\n", "t.txt:2: `abc` is not a number"),
            ("0.1 inf\n", "t.txt:1: value inf is not finite"),
            ("-0.1 1.0\n0.2 1.0\n", "t.txt:1: period -0.1 s is negative"),
            (
                "0.1 1\n0.1 2\n",
                "t.txt:2: period 0.1 s is not greater than the previous row's 0.1 s \
                 (periods must be strictly increasing)",
            ),
            (
                "0.1 1\n\n0.05 2\n",
                "t.txt:3: period 0.05 s is not greater than the previous row's 0.1 s \
                 (periods must be strictly increasing)",
            ),
            ("0.1 0\n0.2 1\n", "t.txt:1: Sa must be > 0 g, got 0"),
            ("0.1 1\n0.2 -0.5\n", "t.txt:2: Sa must be > 0 g, got -0.5"),
            (
                "# only one row\n0.1 1\n",
                "t.txt:2: a target table needs at least 2 rows, found 1",
            ),
            ("", "t.txt:1: a target table needs at least 2 rows, found 0"),
        ];
        for (text, want) in cases {
            assert_eq!(table_err(text), want, "table {text:?}");
        }
    }
}
