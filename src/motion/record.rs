//! Readers for PEER NGA `.AT2` files (both header styles) and two-column time/acceleration text.
//!
//! Every error names the file and the 1-based line it found the problem on.

use std::path::Path;
use thiserror::Error;

/// An acceleration record sampled at a constant step.
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
    /// Acceleration in m/s², multiplied by `scale`.
    pub fn accel_mps2(&self, scale: f64) -> Vec<f64> {
        self.accel_g
            .iter()
            .map(|a| a * scale * crate::dynamics::G)
            .collect()
    }

    /// Peak ground acceleration, g.
    pub fn pga_g(&self) -> f64 {
        self.accel_g.iter().fold(0.0, |m, a| m.max(a.abs()))
    }

    pub fn duration_s(&self) -> f64 {
        self.accel_g.len().saturating_sub(1) as f64 * self.dt_s
    }
}

#[derive(Debug, Error)]
pub enum RecordError {
    #[error("{file}: cannot read: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    #[error(
        "{file}:{line}: missing AT2 header: expected `NPTS= n, DT= x SEC` or `n x NPTS, DT` on line 4"
    )]
    MissingHeader { file: String, line: usize },
    #[error("{file}:{line}: `{token}` is not a number")]
    NotANumber {
        file: String,
        line: usize,
        token: String,
    },
    #[error("{file}:{line}: value {value} is not finite")]
    NonFinite {
        file: String,
        line: usize,
        value: f64,
    },
    #[error("{file}:{line}: time step dt must be > 0, got {dt}")]
    TimeStep { file: String, line: usize, dt: f64 },
    #[error("{file}:{line}: header says NPTS = {expected} but the file has {found} values")]
    Count {
        file: String,
        line: usize,
        expected: usize,
        found: usize,
    },
    #[error("{file}:{line}: expected 2 columns (time, acceleration in g), found {found}")]
    Columns {
        file: String,
        line: usize,
        found: usize,
    },
    #[error(
        "{file}:{line}: time step {found} s differs from the first step {expected} s (non-uniform sampling)"
    )]
    NonUniform {
        file: String,
        line: usize,
        expected: f64,
        found: f64,
    },
    #[error("{file}:{line}: a record needs at least 2 samples, found {found}")]
    TooShort {
        file: String,
        line: usize,
        found: usize,
    },
}

/// Reads a `.AT2` file (detected by extension or a `PEER` first line) or a two-column
/// time/acceleration file in g (`#` starts a comment).
pub fn read_record(path: &Path) -> Result<Record, RecordError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| RecordError::Io {
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
        parse_at2(&text, &file)
    } else {
        parse_two_column(&text, &file)
    }
}

fn number(tok: &str, file: &str, line: usize) -> Result<f64, RecordError> {
    let v: f64 = tok.parse().map_err(|_| RecordError::NotANumber {
        file: file.to_string(),
        line,
        token: tok.to_string(),
    })?;
    if !v.is_finite() {
        return Err(RecordError::NonFinite {
            file: file.to_string(),
            line,
            value: v,
        });
    }
    Ok(v)
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

/// Parses the text of a PEER `.AT2` file: four header lines (the fourth gives NPTS and DT), then
/// the values in g, any number per line.
pub fn parse_at2(text: &str, file: &str) -> Result<Record, RecordError> {
    let mut lines = text.lines().enumerate();
    let mut header = None;
    for (idx, line) in lines.by_ref().take(4) {
        if idx == 3 {
            header = at2_header(line).map(|h| (h, idx + 1));
        }
    }
    let ((npts_tok, dt_tok), hline) = header.ok_or_else(|| RecordError::MissingHeader {
        file: file.to_string(),
        line: 4,
    })?;
    let npts_f = number(&npts_tok, file, hline)?;
    if npts_f < 0.0 || npts_f.fract() != 0.0 {
        return Err(RecordError::NotANumber {
            file: file.to_string(),
            line: hline,
            token: npts_tok,
        });
    }
    let npts = npts_f as usize;
    let dt = number(&dt_tok, file, hline)?;
    if dt <= 0.0 {
        return Err(RecordError::TimeStep {
            file: file.to_string(),
            line: hline,
            dt,
        });
    }
    let mut accel = Vec::with_capacity(npts);
    let mut last_line = hline;
    for (idx, line) in lines {
        for tok in line.split_whitespace() {
            let v = number(tok, file, idx + 1)?;
            if accel.len() == npts {
                return Err(RecordError::Count {
                    file: file.to_string(),
                    line: idx + 1,
                    expected: npts,
                    found: accel.len() + 1,
                });
            }
            accel.push(v);
            last_line = idx + 1;
        }
    }
    if accel.len() != npts {
        return Err(RecordError::Count {
            file: file.to_string(),
            line: last_line,
            expected: npts,
            found: accel.len(),
        });
    }
    if npts < 2 {
        return Err(RecordError::TooShort {
            file: file.to_string(),
            line: last_line,
            found: npts,
        });
    }
    Ok(Record {
        name: base_name(file),
        dt_s: dt,
        accel_g: accel,
    })
}

/// Parses two-column text `time_s accel_g`; the step must be uniform to `1e-6` of itself.
pub fn parse_two_column(text: &str, file: &str) -> Result<Record, RecordError> {
    let mut times = Vec::new();
    let mut accel = Vec::new();
    let mut dt = 0.0;
    let mut last_line = 0;
    for (idx, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("");
        let cols: Vec<&str> = line
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|t| !t.is_empty())
            .collect();
        if cols.is_empty() {
            continue;
        }
        let no = idx + 1;
        if cols.len() != 2 {
            return Err(RecordError::Columns {
                file: file.to_string(),
                line: no,
                found: cols.len(),
            });
        }
        let t = number(cols[0], file, no)?;
        let a = number(cols[1], file, no)?;
        if let Some(&prev) = times.last() {
            let step = t - prev;
            if times.len() == 1 {
                dt = step;
                if dt <= 0.0 {
                    return Err(RecordError::TimeStep {
                        file: file.to_string(),
                        line: no,
                        dt,
                    });
                }
            } else if (step - dt).abs() > 1e-6 * dt {
                return Err(RecordError::NonUniform {
                    file: file.to_string(),
                    line: no,
                    expected: dt,
                    found: step,
                });
            }
        }
        times.push(t);
        accel.push(a);
        last_line = no;
    }
    if accel.len() < 2 {
        return Err(RecordError::TooShort {
            file: file.to_string(),
            line: last_line.max(1),
            found: accel.len(),
        });
    }
    Ok(Record {
        name: base_name(file),
        dt_s: dt,
        accel_g: accel,
    })
}

fn base_name(file: &str) -> String {
    Path::new(file)
        .file_name()
        .map_or_else(|| file.to_string(), |f| f.to_string_lossy().into_owned())
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
            "bad.AT2:4: time step dt must be > 0, got 0"
        );
        assert_eq!(
            err(&format!("{HEAD}    2   -0.01  NPTS, DT\n 0.1 0.2\n")),
            "bad.AT2:4: time step dt must be > 0, got -0.01"
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
        assert_eq!(e.to_string(), "tc.txt:2: time step dt must be > 0, got 0");
        let e = parse_two_column("0 0\n", "tc.txt").unwrap_err();
        assert_eq!(
            e.to_string(),
            "tc.txt:1: a record needs at least 2 samples, found 1"
        );
    }
}
