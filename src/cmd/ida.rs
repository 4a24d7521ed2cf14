//! `slidestack ida CONFIG [--figure SVG | --shard K/N]`: the incremental dynamic analysis stage
//! ([`slidestack::pipeline::ida`]), then its fragility table and optionally a figure of the
//! first case's IDA curves; with `--shard` only that shard's units (side by side with the other
//! shards: it takes the output directory's lock shared).

use super::{CliReporter, StudyArgs, print_outcome};
use anyhow::Result;
use slidestack::pipeline::lock::LockMode;
use slidestack::pipeline::{Session, StageId, execute, execute_shard, report};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub study: StudyArgs,
    /// Also write the first case's IDA curves (each zone, stack and rigid load) as SVG here.
    #[arg(long)]
    pub figure: Option<PathBuf>,
    /// Trace only shard K of N of the work units (1 ≤ K ≤ N ≤ units) into their unit files;
    /// a later `slidestack ida` without it traces what is left and assembles ida.h5.
    #[arg(long, value_parser = super::parse_shard, conflicts_with = "figure")]
    pub shard: Option<(usize, usize)>,
}

pub fn run(args: Args) -> Result<()> {
    if let Some(path) = &args.figure {
        super::check_figure(path)?;
    }
    let study = args.study.study()?;
    // Without an `ida` section: refused before the output directory is touched.
    study.fingerprint(StageId::Ida)?;
    // A shard shares the output directory with the other shards.
    let mode = match args.shard {
        Some(_) => LockMode::Shared,
        None => LockMode::Exclusive,
    };
    let session = Session::open(study, mode, !args.study.no_wait, &CliReporter)?;
    if let Some((k, n)) = args.shard {
        let outcome = execute_shard(&session, StageId::Ida, (k, n), args.study.options())?;
        print_outcome(StageId::Ida, &outcome, &args.study.config);
        return Ok(());
    }
    let outcome = execute(&session, StageId::Ida, args.study.options())?;
    print_outcome(StageId::Ida, &outcome, &args.study.config);
    let rows = report::ida::fragility_table(&session.study)?;
    println!(
        "{:<5} {:>4} {:<6} {:<10} {:>8} {:>17} {:>6} {:>15}  status",
        "zone", "case", "system", "limit", "θ (g)", "95 % CI θ", "β", "95 % CI β"
    );
    for r in &rows {
        let frame = r
            .frame
            .as_ref()
            .map_or(String::new(), |f| format!("  ({f})"));
        println!(
            "{:<5} {:>4} {:<6} {:<10} {:>8.3} {:>8.3}–{:<8.3} {:>6.3} {:>7.3}–{:<7.3}  {}{frame}",
            r.zone,
            r.case,
            r.system,
            r.limit_state,
            r.theta_sa_g,
            r.theta_ci_sa_g.0,
            r.theta_ci_sa_g.1,
            r.beta,
            r.beta_ci.0,
            r.beta_ci.1,
            r.status
        );
    }
    let medians = report::ida::median_demand(&session.study)?;
    println!(
        "median {} at multiples of the zone's target Sa(T_p) (the matched motions' level):",
        medians.first().map_or("ductility", |m| m.demand.as_str())
    );
    for m in medians {
        let frame = m.frame.as_ref().map_or(String::new(), |f| format!(", {f}"));
        let p = if m.frame.is_some() { 4 } else { 3 };
        println!(
            "{:<5} case {:>3}{frame} (T_p {} s, α {:?}, μ {:?}) at {:.2} × {:.3} g: stack {:.p$}, rigid {:.p$} ({:+.1} %); largest slip of any run of the case {:.4} m",
            m.zone,
            m.case,
            m.period_s,
            m.alpha,
            m.mu,
            m.factor,
            m.target_sa_g,
            m.stack,
            m.rigid,
            100.0 * (m.stack / m.rigid - 1.0),
            m.stack_max_slip_m
        );
    }
    if let Some(path) = &args.figure {
        let svg = report::ida::figure(&session.study)?;
        slidestack::store::atomic::write_bytes(path, svg.as_bytes())?;
        println!("ida: wrote {}", path.display());
    }
    Ok(())
}
