//! Period lists as users write them: `START:STOP:STEP` (linear, inclusive),
//! `log:START:STOP:COUNT` (log-spaced) or `a,b,c`, in seconds. The one parser of period lists.

use crate::grid::linear_range;
use crate::limits::{MAX_PERIODS, PERIOD_RANGE_S, excerpt};
use thiserror::Error;

#[derive(Debug, Error, PartialEq)]
#[error("periods `{text}`: {why}")]
pub struct PeriodsError {
    /// The list as given (shortened).
    pub text: String,
    pub why: String,
}

/// `n` log-spaced values from `lo` to `hi` inclusive.
pub fn log_space(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let r = (hi / lo).ln();
    (0..n)
        .map(|i| lo * (r * i as f64 / (n - 1) as f64).exp())
        .collect()
}

/// Periods given as numbers (a case file's list, a Python sequence), checked as [`parse_periods`]
/// checks a list: each written back in shortest round-trip form, so the values are the given
/// ones.
pub fn periods_from_list(values: &[f64]) -> Result<Vec<f64>, PeriodsError> {
    let text: Vec<String> = values.iter().map(f64::to_string).collect();
    parse_periods(&text.join(","))
}

/// Parses a period list (module doc): at most [`MAX_PERIODS`] periods, each within
/// [`PERIOD_RANGE_S`], counted before anything is allocated.
pub fn parse_periods(text: &str) -> Result<Vec<f64>, PeriodsError> {
    let fail = |why: String| PeriodsError {
        text: excerpt(text),
        why,
    };
    let num = |s: &str| -> Result<f64, PeriodsError> {
        s.trim()
            .parse::<f64>()
            .map_err(|_| fail(format!("`{}` is not a number", excerpt(s.trim()))))
    };
    let periods = if let Some(rest) = text.strip_prefix("log:") {
        let parts: Vec<&str> = rest.split(':').collect();
        if parts.len() != 3 {
            return Err(fail("expected log:START:STOP:COUNT".into()));
        }
        let (a, b) = (num(parts[0])?, num(parts[1])?);
        let n: usize = parts[2]
            .trim()
            .parse()
            .map_err(|_| fail("COUNT must be a whole number".into()))?;
        if !((2..=MAX_PERIODS).contains(&n) && a > 0.0 && b > a) {
            return Err(fail(format!(
                "needs 0 < START < STOP and 2 ≤ COUNT ≤ {MAX_PERIODS}"
            )));
        }
        log_space(a, b, n)
    } else if text.contains(':') {
        let parts: Vec<&str> = text.split(':').collect();
        if parts.len() != 3 {
            return Err(fail("expected START:STOP:STEP".into()));
        }
        let (a, b, step) = (num(parts[0])?, num(parts[1])?, num(parts[2])?);
        linear_range(a, b, step, MAX_PERIODS).map_err(fail)?
    } else {
        let n = text.split(',').count();
        if n > MAX_PERIODS {
            return Err(fail(format!("{n} periods; at most {MAX_PERIODS}")));
        }
        text.split(',').map(num).collect::<Result<Vec<_>, _>>()?
    };
    if let Some(bad) = periods
        .iter()
        .find(|t| !(PERIOD_RANGE_S.0..=PERIOD_RANGE_S.1).contains(*t))
    {
        return Err(fail(format!(
            "period {bad:?} s is outside {} … {} s",
            PERIOD_RANGE_S.0, PERIOD_RANGE_S.1
        )));
    }
    Ok(periods)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_forms_and_their_limits() {
        assert_eq!(parse_periods("0.1:0.3:0.1").unwrap(), vec![0.1, 0.2, 0.3]);
        assert_eq!(parse_periods("0.5, 2").unwrap(), vec![0.5, 2.0]);
        let l = parse_periods("log:0.1:10:3").unwrap();
        assert!((l[1] - 1.0).abs() < 1e-15 && (l[2] - 10.0).abs() < 1e-14);
        for (text, want) in [
            ("log:0.1:1:10000000", "2 ≤ COUNT ≤ 100000"),
            ("0:1e12:1e-6", "at most 100000"),
            ("1e-300", "period 1e-300 s is outside 0.001 … 10000 s"),
            ("1,x", "`x` is not a number"),
            ("1:2", "expected START:STOP:STEP"),
        ] {
            let e = parse_periods(text).unwrap_err().to_string();
            assert!(e.contains(want), "{text}: {e}");
        }
        let long = "1".repeat(10_000);
        let e = parse_periods(&format!("x{long}")).unwrap_err().to_string();
        assert!(e.len() < 200, "{e}");
    }
}
