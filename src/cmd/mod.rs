//! One module per subcommand; each starts with what it reads and writes.

pub mod bench;
pub mod fit;
pub mod matching;
pub mod motions;
pub mod report;
pub mod run;
pub mod simulate;
pub mod spectrum;
pub mod sweep;
pub mod tnew;

use anyhow::{Context, Result, bail};
use slidestack::motion::{ReadOptions, Record, Units, read_record_with};
use std::path::PathBuf;

/// Ground-motion files and how to read them, shared by the commands that take records.
#[derive(Debug, clap::Args)]
pub struct RecordArgs {
    /// Ground-motion files: PEER .AT2, two-column time/acceleration or single-column text.
    #[arg(long = "record", required = true, num_args = 1..)]
    pub records: Vec<PathBuf>,
    /// Units of the values when a file does not declare them: g, m/s2 or cm/s2 [default: g].
    #[arg(long)]
    pub units: Option<Units>,
    /// Time step, s, for single-column files that do not declare `# dt:`.
    #[arg(long)]
    pub dt: Option<f64>,
}

impl RecordArgs {
    /// Reads every record, refusing the whole call on the first bad file (names file and line).
    pub fn read(&self) -> Result<Vec<Record>> {
        if let Some(dt) = self.dt
            && !(dt.is_finite() && dt > 0.0)
        {
            bail!("--dt must be finite and > 0, got {dt}");
        }
        let opts = ReadOptions {
            units: self.units,
            dt_s: self.dt,
        };
        self.records
            .iter()
            .map(|p| read_record_with(p, &opts).map_err(anyhow::Error::from))
            .collect::<Result<Vec<_>>>()
            .context("cannot read the ground motions")
    }
}

/// Periods from `START:STOP:STEP` (linear, inclusive), `log:START:STOP:COUNT` (log-spaced) or a
/// comma-separated list, all in seconds; each must be finite and > 0.
pub fn parse_periods(text: &str) -> Result<Vec<f64>> {
    let num = |s: &str| -> Result<f64> {
        s.trim()
            .parse::<f64>()
            .with_context(|| format!("periods `{text}`: `{s}` is not a number"))
    };
    let periods = if let Some(rest) = text.strip_prefix("log:") {
        let parts: Vec<&str> = rest.split(':').collect();
        if parts.len() != 3 {
            bail!("periods `{text}`: expected log:START:STOP:COUNT");
        }
        let (a, b) = (num(parts[0])?, num(parts[1])?);
        let n: usize = parts[2]
            .trim()
            .parse()
            .with_context(|| format!("periods `{text}`: COUNT must be a whole number"))?;
        if n < 2 || !(a > 0.0 && b > a) {
            bail!("periods `{text}`: needs 0 < START < STOP and COUNT ≥ 2");
        }
        slidestack::motion::matching::log_space(a, b, n)
    } else if text.contains(':') {
        let parts: Vec<&str> = text.split(':').collect();
        if parts.len() != 3 {
            bail!("periods `{text}`: expected START:STOP:STEP");
        }
        let (a, b, step) = (num(parts[0])?, num(parts[1])?, num(parts[2])?);
        if !(step > 0.0 && b >= a) {
            bail!("periods `{text}`: needs STOP ≥ START and STEP > 0");
        }
        let n = ((b - a) / step + 1e-9).floor() as usize;
        if n > 1_000_000 {
            bail!("periods `{text}`: more than a million periods");
        }
        (0..=n).map(|i| a + step * i as f64).collect()
    } else {
        text.split(',').map(num).collect::<Result<Vec<_>>>()?
    };
    if let Some(bad) = periods.iter().find(|t| !(t.is_finite() && **t > 0.0)) {
        bail!("periods `{text}`: period {bad} s must be finite and > 0");
    }
    Ok(periods)
}
