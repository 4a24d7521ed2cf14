//! Work-precision benchmark: the exact event-driven integrator against the paper's fixed-step RK4.
//!
//! For every fixture record × system, the exact integrator is the reference; RK4 runs at several
//! sub-step counts and is scored on
//! * the relative error of the peak structure displacement,
//! * the max-norm error of the structure displacement history (one value per record sample)
//!   divided by the exact peak,
//! * the wall time per simulation (peak-only runs, `history = false`) and its ratio to exact.
//!
//! Prints Markdown to stdout. Everything except the timings is deterministic.
//!
//! `cargo bench --bench integrators`; `SLIDESTACK_BENCH_QUICK=1` uses sub-steps 1, 10, 100 and a
//! single timed run per method.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use slidestack::dynamics::{
    ExactOptions, Ground, Response, System, SystemSpec, simulate_exact, simulate_rk4,
};
use slidestack::motion::{Record, read_record};

const SUBSTEPS_FULL: &[usize] = &[1, 2, 5, 10, 20, 50, 100, 200];
const SUBSTEPS_QUICK: &[usize] = &[1, 10, 100];
/// Minimum total timed wall time per method (full mode).
const MIN_TOTAL: Duration = Duration::from_millis(200);
/// Minimum number of timed batches per method (full mode).
const MIN_BATCHES: usize = 3;
/// Target wall time of one batch; the batch size is set from a warm-up run.
const BATCH_TARGET_S: f64 = 0.05;
/// Relative peak-error targets for the "sub-steps needed" summary.
const TOLERANCES: [f64; 2] = [1e-3, 1e-6];
/// Orders are fitted over these sub-step counts and above.
const ORDER_FIT_MIN_SUBSTEPS: usize = 10;

struct SystemCase {
    period_s: f64,
    alpha: &'static [f64],
    mu: &'static [f64],
}

const SYSTEMS: &[SystemCase] = &[
    SystemCase {
        period_s: 0.5,
        alpha: &[1.0],
        mu: &[0.15],
    },
    SystemCase {
        period_s: 1.0,
        alpha: &[0.5, 0.5],
        mu: &[0.2, 0.1],
    },
    SystemCase {
        period_s: 1.5,
        alpha: &[0.3, 0.3, 0.3],
        mu: &[0.3, 0.1, 0.2],
    },
    // Friction far above any demand: never slides, a plain linear SDOF of mass 1 + α.
    SystemCase {
        period_s: 0.3,
        alpha: &[0.5, 0.5],
        mu: &[5.0, 5.0],
    },
];

impl SystemCase {
    fn label(&self) -> String {
        let list = |v: &[f64]| {
            v.iter()
                .map(|x| format!("{x}"))
                .collect::<Vec<_>>()
                .join(",")
        };
        format!(
            "T={} α=[{}] μ=[{}]",
            self.period_s,
            list(self.alpha),
            list(self.mu)
        )
    }
}

/// One RK4 run scored against the exact reference.
struct Rk4Row {
    substeps: usize,
    time_s: f64,
    /// |û_max − u_max| / u_max.
    peak_err: f64,
    /// (û_max − u_max) / u_max.
    peak_err_signed: f64,
    hist_err: f64,
    switches: u64,
}

/// Everything measured for one record × system.
struct CaseResult {
    record: String,
    system: String,
    samples: usize,
    exact_time_s: f64,
    exact_peak_m: f64,
    exact_switches: u64,
    exact_energy_err: f64,
    rows: Vec<Rk4Row>,
}

struct Config {
    quick: bool,
    substeps: &'static [usize],
}

fn main() -> Result<()> {
    let quick = std::env::var("SLIDESTACK_BENCH_QUICK").is_ok_and(|v| v == "1");
    let cfg = Config {
        quick,
        substeps: if quick { SUBSTEPS_QUICK } else { SUBSTEPS_FULL },
    };

    println!("# slidestack integrators: work-precision\n");
    println!("{}\n", machine_description());
    println!(
        "Mode: {}; sub-steps {:?}; timings are peak-only runs (history off), {}.\n",
        if cfg.quick { "QUICK" } else { "full" },
        cfg.substeps,
        if cfg.quick {
            "a single run each".to_string()
        } else {
            format!(
                "median over >= {MIN_BATCHES} batches totalling >= {} s",
                MIN_TOTAL.as_secs_f64()
            )
        }
    );

    let records = load_records()?;
    let mut results = Vec::new();
    for record in &records {
        let accel = record.accel_mps2(1.0);
        let ground = Ground {
            dt_s: record.dt_s,
            accel_mps2: &accel,
        };
        for case in SYSTEMS {
            let sys = System::new(&SystemSpec::new(case.period_s, case.alpha, case.mu))
                .with_context(|| format!("system {}", case.label()))?;
            let res = run_case(&cfg, &record.name, &case.label(), &sys, &ground)
                .with_context(|| format!("{} × {}", record.name, case.label()))?;
            results.push(res);
        }
    }

    print_details(&results);
    print_orders(&cfg, &results);
    print_summary(&results);
    print_exact_throughput(&results);
    Ok(())
}

fn machine_description() -> String {
    let nproc = std::thread::available_parallelism().map_or(0, |n| n.get());
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|text| {
            text.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".to_string());
    format!(
        "Machine: nproc = {nproc}, CPU = {model}, {}-{}",
        std::env::consts::OS,
        std::env::consts::ARCH
    )
}

fn load_records() -> Result<Vec<Record>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/records");
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .with_context(|| format!("listing {}", dir.display()))?
        .map(|e| e.map(|e| e.path()))
        .collect::<std::io::Result<_>>()?;
    paths.retain(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("at2")));
    paths.sort();
    if paths.is_empty() {
        bail!("no .AT2 records in {}", dir.display());
    }
    paths
        .iter()
        .map(|p| read_record(p).map_err(Into::into))
        .collect()
}

/// Wall time per call of `f`: one warm-up call sets the batch size; then batches run until both
/// [`MIN_BATCHES`] and [`MIN_TOTAL`] are reached, and the median per-call time is returned. In
/// quick mode a single call is timed.
fn time_per_call<T>(quick: bool, mut f: impl FnMut() -> T) -> f64 {
    let start = Instant::now();
    black_box(f());
    let warm = start.elapsed().as_secs_f64();
    if quick {
        return warm;
    }
    let batch = ((BATCH_TARGET_S / warm.max(1e-9)).ceil() as usize).max(1);
    let mut per_call = Vec::new();
    let mut total = Duration::ZERO;
    while per_call.len() < MIN_BATCHES || total < MIN_TOTAL {
        let start = Instant::now();
        for _ in 0..batch {
            black_box(f());
        }
        let el = start.elapsed();
        total += el;
        per_call.push(el.as_secs_f64() / batch as f64);
    }
    median(&mut per_call)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Structure (body 0) displacement at every record sample.
fn structure_history(resp: &Response) -> Result<Vec<f64>> {
    let h = resp
        .history
        .as_ref()
        .context("history was requested but not returned")?;
    Ok(h.displacement_m.iter().step_by(h.bodies).copied().collect())
}

fn run_case(
    cfg: &Config,
    record: &str,
    system: &str,
    sys: &System,
    ground: &Ground,
) -> Result<CaseResult> {
    let with_hist = ExactOptions {
        history: true,
        ..Default::default()
    };
    let peak_only = ExactOptions {
        history: false,
        ..Default::default()
    };

    let reference = simulate_exact(sys, ground, &with_hist)?;
    let ref_u = structure_history(&reference)?;
    let peak = reference.peak_displacement_m;
    if peak.is_nan() || peak <= 0.0 {
        bail!("exact peak displacement is {peak}, cannot form relative errors");
    }
    let exact_time_s = time_per_call(cfg.quick, || simulate_exact(sys, ground, &peak_only));

    let mut rows = Vec::new();
    for &substeps in cfg.substeps {
        let resp = simulate_rk4(sys, ground, substeps, true)?;
        let u = structure_history(&resp)?;
        if u.len() != ref_u.len() {
            bail!(
                "rk4 history has {} rows, exact has {} (substeps {substeps})",
                u.len(),
                ref_u.len()
            );
        }
        let hist_err = u
            .iter()
            .zip(&ref_u)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
            / peak;
        let time_s = time_per_call(cfg.quick, || simulate_rk4(sys, ground, substeps, false));
        rows.push(Rk4Row {
            substeps,
            time_s,
            peak_err: (resp.peak_displacement_m - peak).abs() / peak,
            peak_err_signed: (resp.peak_displacement_m - peak) / peak,
            hist_err,
            switches: resp.switches,
        });
    }
    Ok(CaseResult {
        record: record.trim_end_matches(".AT2").to_string(),
        system: system.to_string(),
        samples: ground.accel_mps2.len(),
        exact_time_s,
        exact_peak_m: peak,
        exact_switches: reference.switches,
        exact_energy_err: reference.energy_balance_error_max,
        rows,
    })
}

fn fmt_time(s: f64) -> String {
    if s >= 1.0 {
        format!("{s:.3} s")
    } else if s >= 1e-3 {
        format!("{:.3} ms", s * 1e3)
    } else {
        format!("{:.1} µs", s * 1e6)
    }
}

fn fmt_opt(x: Option<f64>, digits: usize) -> String {
    x.map_or_else(|| "–".to_string(), |v| format!("{v:.digits$}"))
}

fn print_details(results: &[CaseResult]) {
    println!("## Per method\n");
    println!(
        "Errors are against the exact integrator: peak = (û_max − u_max) / u_max, signed \
         (RK4 samples its peak at sub-step ends, so an accurate RK4 can only fall short: > 0 \
         means RK4 overshoots the exact peak); history = max_k |û(t_k) − u(t_k)| / u_max over the record samples (structure).\n"
    );
    println!(
        "| record | system | method | time / sim | × exact | peak rel. err (signed) | history err / peak | switches |"
    );
    println!("|---|---|---|---:|---:|---:|---:|---:|");
    for c in results {
        println!(
            "| {} | {} | exact | {} | 1.00 | 0 (ref, u_max = {:.6e} m) | 0 (ref) | {} |",
            c.record,
            c.system,
            fmt_time(c.exact_time_s),
            c.exact_peak_m,
            c.exact_switches
        );
        for r in &c.rows {
            println!(
                "| {} | {} | rk4 ×{} | {} | {:.2} | {:+.3e} | {:.3e} | {} |",
                c.record,
                c.system,
                r.substeps,
                fmt_time(r.time_s),
                r.time_s / c.exact_time_s,
                r.peak_err_signed,
                r.hist_err,
                r.switches
            );
        }
    }
    println!();
}

/// Least-squares slope of log(err) against log(h) (h ∝ 1/substeps) over sub-steps
/// `>= ORDER_FIT_MIN_SUBSTEPS` with a positive error; `None` with fewer than two points.
fn ls_order(rows: &[Rk4Row], err: impl Fn(&Rk4Row) -> f64) -> Option<f64> {
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.substeps >= ORDER_FIT_MIN_SUBSTEPS && err(r) > 0.0)
        .map(|r| (-(r.substeps as f64).ln(), err(r).ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    Some(sxy / sxx)
}

/// log2(err(s)/err(2s)) for every pair of sub-step counts that double.
fn doubling_orders(rows: &[Rk4Row], err: impl Fn(&Rk4Row) -> f64) -> Vec<(usize, f64)> {
    rows.iter()
        .filter_map(|a| {
            let b = rows.iter().find(|b| b.substeps == 2 * a.substeps)?;
            (err(a) > 0.0 && err(b) > 0.0).then(|| (a.substeps, (err(a) / err(b)).log2()))
        })
        .collect()
}

fn print_orders(cfg: &Config, results: &[CaseResult]) {
    println!("## Observed RK4 convergence order\n");
    println!(
        "LS = least-squares slope of log err vs log h over sub-steps ≥ {ORDER_FIT_MIN_SUBSTEPS}; \
         s→2s = log2(err(s)/err(2s)).{}\n",
        if cfg.quick {
            " (quick mode: no doubling pairs.)"
        } else {
            ""
        }
    );
    println!(
        "| record | system | LS order (peak) | LS order (history) | s→2s (peak) | s→2s (history) |"
    );
    println!("|---|---|---:|---:|---|---|");
    for c in results {
        let pairs = |err: fn(&Rk4Row) -> f64| {
            let v = doubling_orders(&c.rows, err);
            if v.is_empty() {
                "–".to_string()
            } else {
                v.iter()
                    .map(|(s, p)| format!("{s}→{}: {p:.2}", 2 * s))
                    .collect::<Vec<_>>()
                    .join(", ")
            }
        };
        println!(
            "| {} | {} | {} | {} | {} | {} |",
            c.record,
            c.system,
            fmt_opt(ls_order(&c.rows, |r| r.peak_err), 2),
            fmt_opt(ls_order(&c.rows, |r| r.hist_err), 2),
            pairs(|r| r.peak_err),
            pairs(|r| r.hist_err)
        );
    }
    println!();
}

/// Smallest sub-step count from which the relative peak error stays `<= tol` at every finer count
/// tried, and whether a coarser count touched the tolerance first (non-monotone error).
fn substeps_for(rows: &[Rk4Row], tol: f64) -> Option<(&Rk4Row, bool)> {
    let first_touch = rows.iter().position(|r| r.peak_err <= tol)?;
    let stays = rows
        .iter()
        .rposition(|r| r.peak_err > tol)
        .map_or(0, |i| i + 1);
    rows.get(stays).map(|r| (r, first_touch < stays))
}

fn print_summary(results: &[CaseResult]) {
    println!("## Summary\n");
    println!(
        "Sub-steps needed: smallest count from which the relative peak error stays below the \
         target at all finer counts tried (`*`: a coarser count touched it first); slowdown = RK4 \
         time there / exact time.\n"
    );
    println!(
        "| record | system | exact time | exact switches | RK4 order peak / history (LS) | \
         1e-3: sub-steps (slowdown) | 1e-6: sub-steps (slowdown) | finest RK4 peak err |"
    );
    println!("|---|---|---:|---:|---|---|---|---:|");
    for c in results {
        let need = |tol: f64| match substeps_for(&c.rows, tol) {
            Some((r, early)) => format!(
                "{}{} ({:.1}×)",
                r.substeps,
                if early { "*" } else { "" },
                r.time_s / c.exact_time_s
            ),
            None => "not reached".to_string(),
        };
        println!(
            "| {} | {} | {} | {} | {} / {} | {} | {} | {:.2e} |",
            c.record,
            c.system,
            fmt_time(c.exact_time_s),
            c.exact_switches,
            fmt_opt(ls_order(&c.rows, |r| r.peak_err), 2),
            fmt_opt(ls_order(&c.rows, |r| r.hist_err), 2),
            need(TOLERANCES[0]),
            need(TOLERANCES[1]),
            c.rows.last().map_or(f64::NAN, |r| r.peak_err)
        );
    }
    println!();
}

fn print_exact_throughput(results: &[CaseResult]) {
    println!("## Exact integrator throughput\n");
    println!(
        "| record | system | samples | time / sim | sims / s | ns / record sample | max energy balance err |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|");
    for c in results {
        println!(
            "| {} | {} | {} | {} | {:.0} | {:.1} | {:.1e} |",
            c.record,
            c.system,
            c.samples,
            fmt_time(c.exact_time_s),
            1.0 / c.exact_time_s,
            c.exact_time_s * 1e9 / c.samples as f64,
            c.exact_energy_err
        );
    }
    let total_s: f64 = results.iter().map(|c| c.exact_time_s).sum();
    let total_n: usize = results.iter().map(|c| c.samples).sum();
    println!(
        "\nOverall exact: {:.0} sims/s averaged over the {} cases, {:.1} ns per record sample.",
        results.len() as f64 / total_s,
        results.len(),
        total_s * 1e9 / total_n as f64
    );
}
