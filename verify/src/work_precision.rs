//! `slidestack-verify accuracy`: work-precision of the integrators on real records.
//!
//! Reads ground-motion records (`--record`; by default three fixtures under
//! `tests/fixtures/records/` with sample intervals of 0.005, 0.01 and 0.02 s) and runs six fixed
//! systems under each (1–3 blocks; sliding, and a stack that never slides; `T_p` from 0.1 to 3 s;
//! static = kinetic friction so that OpenSees can model them) with
//! * the exact integrator: the reference, timed; also rerun on the record refined ×8 by linear
//!   interpolation (the same piecewise-linear ground motion), a self-check that must agree to
//!   round-off;
//! * the paper's RK4 at 1 to 1000 sub-steps per record interval (`--quick`: 1, 10, 100);
//! * with `--opensees PYTHON` (a Python with openseespy, such as `.venv-peers/bin/python` made by
//!   `scripts/bench-peers`), the OpenSees model of `scripts/opensees_stack.py` at several time
//!   steps and stick stiffnesses.
//!
//! Errors are of the structure's displacement relative to the ground at the record samples,
//! against the exact history, relative to its peak over the same samples ([`accuracy::errors`]).
//! Times are CPU time per simulation without history, of the thread that runs it: median of
//! batches in this process (Rust), or one run in the Python process (OpenSees: model build plus
//! analysis). CPU time, unlike wall time, barely changes with other load on a shared machine.
//!
//! Writes into `--out` (default `docs/evidence`): `accuracy.md` (also printed), `accuracy.csv`
//! (one row per case and method), `accuracy.svg` and `accuracy-peak.svg` (work-precision plots)
//! and `accuracy.html` (the page with both).

use crate::accuracy::{self, Errors, geometric_mean, needed_for, observed_order};
use crate::timing::{Timing, fmt_time, machine_description};
use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use slidestack::dynamics::{
    ExactOptions, Ground, Response, System, SystemSpec, simulate_exact, simulate_rk4,
};
use slidestack::ground_motion::{self, Record, read_record};
use slidestack::render::{self, Series, sci};
use std::path::{Path, PathBuf};
use std::process::Command;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Records to run (PEER .AT2 or plain text in g) [default: three fixtures under
    /// tests/fixtures/records/, run from the repository root].
    #[arg(long = "record", num_args = 1..)]
    records: Vec<PathBuf>,
    /// Directory for accuracy.{md,csv,svg,html}.
    #[arg(long, default_value = "docs/evidence")]
    out: PathBuf,
    /// Fewer sub-steps (1, 10, 100), OpenSees at two settings, one timed run per method.
    #[arg(long)]
    quick: bool,
    /// Python with openseespy: adds the OpenSees model to the comparison.
    #[arg(long, value_name = "PYTHON")]
    opensees: Option<PathBuf>,
    /// The OpenSees model script.
    #[arg(long, default_value = "scripts/opensees_stack.py")]
    opensees_script: PathBuf,
}

const DEFAULT_RECORDS: [&str; 3] = [
    "tests/fixtures/records/RSN1158_KOCAELI_DZC270.AT2",
    "tests/fixtures/records/RSN960_NORTHR_LOS270.AT2",
    "tests/fixtures/records/RSN829_CAPEMEND_RIO360.AT2",
];
const SUBSTEPS_FULL: &[usize] = &[1, 2, 5, 10, 20, 50, 100, 200, 500, 1000];
const SUBSTEPS_QUICK: &[usize] = &[1, 10, 100];
/// OpenSees settings: (steps per record interval, stick stiffness / structure stiffness).
const OPENSEES_FULL: &[(usize, f64)] =
    &[(1, 1e3), (5, 1e3), (20, 1e3), (1, 1e5), (5, 1e5), (20, 1e5)];
const OPENSEES_QUICK: &[(usize, f64)] = &[(1, 1e4), (10, 1e4)];
/// Relative peak-error targets of the summary.
const TOLERANCES: [f64; 2] = [1e-3, 1e-6];
/// Orders are fitted over these sub-step counts and above.
const ORDER_MIN_SUBSTEPS: usize = 10;
/// The self-check reruns the exact integrator on the record refined by this factor.
const REFINE: usize = 8;
/// Errors below this are drawn at it (an exactly zero error has no place on a log axis).
const ERROR_FLOOR: f64 = 1e-16;

/// A system of the benchmark: `T_p` (s), `α`, `μ` (static = kinetic), what it exercises.
struct SystemCase {
    period_s: f64,
    alpha: &'static [f64],
    mu: &'static [f64],
    what: &'static str,
}

const SYSTEMS: &[SystemCase] = &[
    SystemCase {
        period_s: 0.5,
        alpha: &[1.0],
        mu: &[0.15],
        what: "one block, slides",
    },
    SystemCase {
        period_s: 1.0,
        alpha: &[0.5, 0.5],
        mu: &[0.2, 0.1],
        what: "two blocks, the paper's Section 7.1 case",
    },
    SystemCase {
        period_s: 1.5,
        alpha: &[0.3, 0.3, 0.3],
        mu: &[0.2, 0.05, 0.1],
        what: "three blocks",
    },
    SystemCase {
        period_s: 0.3,
        alpha: &[0.5, 0.5],
        mu: &[5.0, 5.0],
        what: "never slides: a linear SDOF of mass 1 + Σα",
    },
    SystemCase {
        period_s: 0.1,
        alpha: &[0.5],
        mu: &[0.1],
        what: "short T_p",
    },
    SystemCase {
        period_s: 3.0,
        alpha: &[0.5, 0.5],
        mu: &[0.05, 0.03],
        what: "long T_p",
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
            "T_p={} α=[{}] μ=[{}]",
            self.period_s,
            list(self.alpha),
            list(self.mu)
        )
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Method {
    Exact,
    ExactRefined,
    Rk4,
    OpenSees { stiffness: f64 },
}

/// One method at one setting on one case.
#[derive(Debug, Clone)]
struct Row {
    method: Method,
    /// Sub-steps (RK4) or analysis steps (OpenSees) per record interval; the refinement factor
    /// for the self-check; 1 for the exact run.
    steps: usize,
    /// CPU time per simulation, s (NaN where not timed).
    time_s: f64,
    errors: Errors,
    switches: Option<u64>,
}

impl Row {
    fn method_label(&self) -> String {
        match self.method {
            Method::Exact => "exact".to_string(),
            Method::ExactRefined => format!("exact on record ×{}", self.steps),
            Method::Rk4 => format!("RK4 ×{}", self.steps),
            Method::OpenSees { stiffness } => {
                format!("OpenSees ×{}, s={stiffness:.0e}", self.steps)
            }
        }
    }
}

struct CaseResult {
    record: String,
    system: String,
    samples: usize,
    /// The exact integrator's structure displacement at the record samples, m.
    reference: Vec<f64>,
    /// Its peak between samples, m.
    exact_peak_m: f64,
    exact_time_s: f64,
    exact_switches: u64,
    exact_energy_error: f64,
    rows: Vec<Row>,
}

impl CaseResult {
    fn rk4(&self) -> impl Iterator<Item = &Row> {
        self.rows.iter().filter(|r| r.method == Method::Rk4)
    }

    fn refined(&self) -> Option<&Row> {
        self.rows.iter().find(|r| r.method == Method::ExactRefined)
    }
}

pub fn run(args: &Args) -> Result<()> {
    if let Some(python) = &args.opensees {
        for (what, path) in [
            ("Python", python),
            ("OpenSees script", &args.opensees_script),
        ] {
            if !path.exists() {
                bail!(
                    "{what} {} not found (`scripts/bench-peers --only simulation` makes \
                     .venv-peers/bin/python with openseespy; run from the repository root)",
                    path.display()
                );
            }
        }
    }
    let records = read_records(&args.records)?;
    let (substeps, timing, opensees_runs) = if args.quick {
        (SUBSTEPS_QUICK, Timing::SINGLE, OPENSEES_QUICK)
    } else {
        (SUBSTEPS_FULL, Timing::FULL, OPENSEES_FULL)
    };
    let mut cases = Vec::new();
    for record in &records {
        for system in SYSTEMS {
            eprintln!("accuracy: {} × {}", record.name, system.label());
            let case = run_case(record, system, substeps, &timing)
                .with_context(|| format!("{} × {}", record.name, system.label()))?;
            cases.push(case);
        }
    }
    let opensees_version = match &args.opensees {
        Some(python) => {
            let input = opensees_input(&records, &cases, opensees_runs);
            let output = run_opensees(python, &args.opensees_script, &args.out, &input)?;
            add_opensees_rows(&mut cases, &output)?;
            Some(output.opensees_version)
        }
        None => None,
    };

    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let machine = machine_description();
    let tables = Tables::new(&cases);
    let markdown = markdown(&machine, args, opensees_version.as_deref(), &tables);
    let (svg_history, svg_peak) = charts(&cases);
    let write = |name: &str, text: &str| -> Result<()> {
        let path = args.out.join(name);
        std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))
    };
    write("accuracy.md", &markdown)?;
    write("accuracy.csv", &csv(&cases))?;
    write("accuracy.svg", &svg_history)?;
    write("accuracy-peak.svg", &svg_peak)?;
    write(
        "accuracy.html",
        &html(&machine, &tables, &svg_history, &svg_peak),
    )?;
    print!("{markdown}");
    eprintln!("accuracy: wrote {}/accuracy.*", args.out.display());
    Ok(())
}

fn read_records(paths: &[PathBuf]) -> Result<Vec<Record>> {
    let defaults: Vec<PathBuf> = DEFAULT_RECORDS.iter().map(PathBuf::from).collect();
    let paths = if paths.is_empty() { &defaults } else { paths };
    paths
        .iter()
        .map(|p| {
            if !p.exists() {
                bail!(
                    "record {} not found: run from the repository root or pass --record FILE…",
                    p.display()
                );
            }
            read_record(p).map_err(anyhow::Error::from)
        })
        .collect()
}

/// The structure's displacement at every record sample.
fn structure_history(resp: &Response) -> Result<Vec<f64>> {
    let h = resp
        .history
        .as_ref()
        .context("history was requested but not returned")?;
    Ok(h.displacement_m.iter().step_by(h.bodies).copied().collect())
}

fn run_case(
    record: &Record,
    system: &SystemCase,
    substeps: &[usize],
    timing: &Timing,
) -> Result<CaseResult> {
    let sys = System::new(&SystemSpec::new(system.period_s, system.alpha, system.mu))?;
    let accel = record.accel_mps2(1.0);
    let ground = Ground {
        dt_s: record.dt_s,
        accel_mps2: &accel,
    };
    let with_history = ExactOptions {
        history: true,
        ..ExactOptions::default()
    };
    let exact = simulate_exact(&sys, &ground, &with_history)?;
    let reference = structure_history(&exact)?;
    let exact_time_s = timing.per_call(|| simulate_exact(&sys, &ground, &ExactOptions::default()));
    let exact_errors = accuracy::errors(&reference, &reference)?;
    let mut rows = vec![Row {
        method: Method::Exact,
        steps: 1,
        time_s: exact_time_s,
        errors: exact_errors,
        switches: Some(exact.switches),
    }];

    let fine = ground_motion::process::refine(record, REFINE);
    let fine_accel = fine.accel_mps2(1.0);
    let fine_ground = Ground {
        dt_s: fine.dt_s,
        accel_mps2: &fine_accel,
    };
    let refined = simulate_exact(&sys, &fine_ground, &with_history)?;
    let refined_u: Vec<f64> = structure_history(&refined)?
        .into_iter()
        .step_by(REFINE)
        .collect();
    rows.push(Row {
        method: Method::ExactRefined,
        steps: REFINE,
        time_s: f64::NAN,
        errors: accuracy::errors(&refined_u, &reference)?,
        switches: Some(refined.switches),
    });

    for &s in substeps {
        let resp = simulate_rk4(&sys, &ground, s, true)?;
        let u = structure_history(&resp)?;
        rows.push(Row {
            method: Method::Rk4,
            steps: s,
            time_s: timing.per_call(|| simulate_rk4(&sys, &ground, s, false)),
            errors: accuracy::errors(&u, &reference).with_context(|| format!("RK4 ×{s}"))?,
            switches: Some(resp.switches),
        });
    }
    Ok(CaseResult {
        record: record.name.trim_end_matches(".AT2").to_string(),
        system: system.label(),
        samples: accel.len(),
        reference,
        exact_peak_m: exact.peak_displacement_m,
        exact_time_s,
        exact_switches: exact.switches,
        exact_energy_error: exact.energy_balance_error_max,
        rows,
    })
}

// ------------------------------------------------------------------------------------ OpenSees

/// `scripts/opensees_stack.py`'s input (see its docstring for the protocol).
#[derive(Serialize)]
struct OsInput {
    /// "cpu": time OpenSees by the CPU time of its thread, as the Rust side is timed.
    clock: &'static str,
    cases: Vec<OsCase>,
}

#[derive(Serialize)]
struct OsCase {
    id: String,
    dt_s: f64,
    accel_g: Vec<f64>,
    period_s: f64,
    damping_ratio: f64,
    alpha: Vec<f64>,
    mu: Vec<f64>,
    runs: Vec<OsRunSpec>,
    repeats: usize,
}

#[derive(Serialize)]
struct OsRunSpec {
    steps_per_sample: usize,
    stick_stiffness: f64,
}

#[derive(Deserialize)]
struct OsOutput {
    opensees_version: String,
    cases: Vec<OsCaseOut>,
}

#[derive(Deserialize)]
struct OsCaseOut {
    id: String,
    runs: Vec<OsRun>,
}

#[derive(Deserialize)]
struct OsRun {
    steps_per_sample: usize,
    stick_stiffness: f64,
    ok: bool,
    message: String,
    time_s: Option<f64>,
    u_m: Option<Vec<f64>>,
}

fn case_id(i: usize) -> String {
    format!("case{i}")
}

fn opensees_input(records: &[Record], cases: &[CaseResult], runs: &[(usize, f64)]) -> OsInput {
    let mut out = Vec::new();
    for (ri, record) in records.iter().enumerate() {
        for (si, system) in SYSTEMS.iter().enumerate() {
            let i = ri * SYSTEMS.len() + si;
            debug_assert_eq!(cases[i].system, system.label());
            out.push(OsCase {
                id: case_id(i),
                dt_s: record.dt_s,
                accel_g: record.accel_g.clone(),
                period_s: system.period_s,
                damping_ratio: SystemSpec::new(system.period_s, system.alpha, system.mu)
                    .damping_ratio,
                alpha: system.alpha.to_vec(),
                mu: system.mu.to_vec(),
                runs: runs
                    .iter()
                    .map(|&(steps_per_sample, stick_stiffness)| OsRunSpec {
                        steps_per_sample,
                        stick_stiffness,
                    })
                    .collect(),
                repeats: 1,
            });
        }
    }
    OsInput {
        clock: "cpu",
        cases: out,
    }
}

/// The directory of the shared libraries bundled with the openseespy wheel in the virtual
/// environment of `python` (`<venv>/lib/python*/site-packages/openseespylinux/lib`): the dynamic
/// loader must be told about it when Python starts (see `scripts/opensees_stack.py`).
fn opensees_lib_dir(python: &Path) -> Option<PathBuf> {
    let venv = python.parent()?.parent()?;
    std::fs::read_dir(venv.join("lib"))
        .ok()?
        .filter_map(|e| e.ok())
        .map(|e| e.path().join("site-packages/openseespylinux/lib"))
        .find(|p| p.is_dir())
}

fn run_opensees(python: &Path, script: &Path, out: &Path, input: &OsInput) -> Result<OsOutput> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let in_path = out.join(".opensees-in.json");
    let out_path = out.join(".opensees-out.json");
    std::fs::write(&in_path, serde_json::to_vec(input)?)
        .with_context(|| format!("cannot write {}", in_path.display()))?;
    let mut cmd = Command::new(python);
    cmd.arg(script).arg(&in_path).arg(&out_path);
    if let Some(lib) = opensees_lib_dir(python) {
        let mut paths = vec![lib];
        if let Some(old) = std::env::var_os("LD_LIBRARY_PATH") {
            paths.extend(std::env::split_paths(&old));
        }
        cmd.env("LD_LIBRARY_PATH", std::env::join_paths(paths)?);
    }
    eprintln!(
        "accuracy: OpenSees on {} cases ({})",
        input.cases.len(),
        python.display()
    );
    let status = cmd
        .status()
        .with_context(|| format!("cannot start {}", python.display()))?;
    if !status.success() {
        bail!(
            "{} {} failed ({status}); exit code 3 means openseespy cannot be imported: \
             `scripts/bench-peers --only simulation` installs it into .venv-peers",
            python.display(),
            script.display()
        );
    }
    let text =
        std::fs::read(&out_path).with_context(|| format!("cannot read {}", out_path.display()))?;
    let _ = std::fs::remove_file(&in_path);
    let _ = std::fs::remove_file(&out_path);
    serde_json::from_slice(&text).context("OpenSees output is not what opensees_stack.py writes")
}

fn add_opensees_rows(cases: &mut [CaseResult], output: &OsOutput) -> Result<()> {
    for case_out in &output.cases {
        let i: usize = case_out
            .id
            .strip_prefix("case")
            .and_then(|s| s.parse().ok())
            .filter(|i| *i < cases.len())
            .with_context(|| format!("unknown OpenSees case id {}", case_out.id))?;
        let case = &mut cases[i];
        for run in &case_out.runs {
            let (true, Some(time_s), Some(u)) = (run.ok, run.time_s, run.u_m.as_ref()) else {
                eprintln!(
                    "accuracy: OpenSees ×{} s={:e} failed on {} × {}: {}",
                    run.steps_per_sample,
                    run.stick_stiffness,
                    case.record,
                    case.system,
                    run.message
                );
                continue;
            };
            let errors = accuracy::errors(u, &case.reference)
                .with_context(|| format!("OpenSees on {} × {}", case.record, case.system))?;
            case.rows.push(Row {
                method: Method::OpenSees {
                    stiffness: run.stick_stiffness,
                },
                steps: run.steps_per_sample,
                time_s,
                errors,
                switches: None,
            });
        }
    }
    Ok(())
}

// ------------------------------------------------------------------------------------- output

/// A table as header and already formatted rows, rendered as Markdown or HTML.
struct Table {
    header: Vec<&'static str>,
    rows: Vec<Vec<String>>,
}

impl Table {
    fn markdown(&self) -> String {
        let mut s = format!("| {} |\n", self.header.join(" | "));
        s += &format!("|{}\n", "---|".repeat(self.header.len()));
        for r in &self.rows {
            s += &format!("| {} |\n", r.join(" | "));
        }
        s
    }

    fn html(&self) -> String {
        render::table(&self.header, &self.rows)
    }
}

struct Tables {
    summary: Table,
    overall: Vec<String>,
    details: Table,
}

fn opt(x: Option<f64>, digits: usize) -> String {
    x.map_or_else(|| "–".to_string(), |v| format!("{v:.digits$}"))
}

impl Tables {
    fn new(cases: &[CaseResult]) -> Self {
        let mut summary = Vec::new();
        // Per tolerance: the sub-step counts needed and the slowdowns there, over all cases.
        let mut needed: [Vec<(usize, f64)>; 2] = [Vec::new(), Vec::new()];
        let mut missed = [0usize; 2];
        for c in cases {
            let rk4: Vec<&Row> = c.rk4().collect();
            let pts: Vec<(usize, f64)> = rk4.iter().map(|r| (r.steps, r.errors.peak())).collect();
            let hist: Vec<(usize, f64)> = rk4.iter().map(|r| (r.steps, r.errors.history)).collect();
            let mut need = |k: usize| match needed_for(&pts, TOLERANCES[k]) {
                Some(n) => {
                    let r = rk4[n.index];
                    let slow = r.time_s / c.exact_time_s;
                    needed[k].push((r.steps, slow));
                    format!(
                        "{}{} ({slow:.1}×)",
                        r.steps,
                        if n.touched_earlier { "*" } else { "" }
                    )
                }
                None => {
                    missed[k] += 1;
                    "not reached".to_string()
                }
            };
            let (n3, n6) = (need(0), need(1));
            let best_os = c
                .rows
                .iter()
                .filter(|r| matches!(r.method, Method::OpenSees { .. }))
                .min_by(|a, b| a.errors.history.total_cmp(&b.errors.history));
            summary.push(vec![
                c.record.clone(),
                c.system.clone(),
                c.samples.to_string(),
                fmt_time(c.exact_time_s),
                format!("{:.0}", c.exact_time_s * 1e9 / c.samples as f64),
                c.exact_switches.to_string(),
                sci(c.exact_energy_error),
                c.refined().map_or("–".into(), |r| sci(r.errors.history)),
                format!(
                    "{} / {}",
                    opt(observed_order(&pts, ORDER_MIN_SUBSTEPS), 2),
                    opt(observed_order(&hist, ORDER_MIN_SUBSTEPS), 2)
                ),
                n3,
                n6,
                rk4.last().map_or("–".into(), |r| sci(r.errors.history)),
                best_os.map_or("–".into(), |r| {
                    format!(
                        "{} at {} ({:.0}×)",
                        sci(r.errors.history),
                        r.method_label().trim_start_matches("OpenSees "),
                        r.time_s / c.exact_time_s
                    )
                }),
            ]);
        }
        let mut overall = Vec::new();
        for (k, tol) in TOLERANCES.iter().enumerate() {
            let v = &needed[k];
            if v.is_empty() {
                overall.push(format!(
                    "Peak error ≤ {tol:.0e}: RK4 reaches it on none of the {} cases within the \
                     sub-steps tried.",
                    cases.len()
                ));
                continue;
            }
            let worst = v.iter().map(|x| x.0).max().unwrap_or(0);
            let mut slow: Vec<f64> = v.iter().map(|x| x.1).collect();
            slow.sort_by(f64::total_cmp);
            overall.push(format!(
                "Peak error ≤ {tol:.0e}: RK4 needs up to {worst} sub-steps per record interval \
                 ({} of {} cases reach it{}); there it takes {:.1}× (median; {:.1}–{:.1}×) the \
                 exact integrator's time.",
                v.len(),
                cases.len(),
                if missed[k] > 0 {
                    format!(", {} do not within the sub-steps tried", missed[k])
                } else {
                    String::new()
                },
                slow[slow.len() / 2],
                slow[0],
                slow[slow.len() - 1]
            ));
        }
        let total_s: f64 = cases.iter().map(|c| c.exact_time_s).sum();
        let total_n: usize = cases.iter().map(|c| c.samples).sum();
        overall.push(format!(
            "Exact integrator: {:.0} simulations/s over these {} cases, {:.0} ns per record \
             sample; its history on the ×{REFINE} refined record differs by at most {} of the \
             peak.",
            cases.len() as f64 / total_s,
            cases.len(),
            total_s * 1e9 / total_n as f64,
            sci(cases
                .iter()
                .filter_map(|c| c.refined().map(|r| r.errors.history))
                .fold(0.0, f64::max))
        ));

        let mut details = Vec::new();
        for c in cases {
            for r in &c.rows {
                details.push(vec![
                    c.record.clone(),
                    c.system.clone(),
                    r.method_label(),
                    fmt_time(r.time_s),
                    if r.time_s.is_finite() {
                        format!("{:.2}", r.time_s / c.exact_time_s)
                    } else {
                        "–".into()
                    },
                    format!("{:+.2e}", r.errors.peak_signed),
                    sci(r.errors.history),
                    r.switches.map_or("–".into(), |s| s.to_string()),
                ]);
            }
        }
        Tables {
            summary: Table {
                header: vec![
                    "record",
                    "system",
                    "samples",
                    "exact CPU time",
                    "ns / sample",
                    "switches",
                    "energy balance err",
                    "exact vs ×8 record",
                    "RK4 order peak / history",
                    "RK4 for peak 1e-3 (× exact time)",
                    "RK4 for peak 1e-6 (× exact time)",
                    "RK4 ×finest history err",
                    "best OpenSees history err",
                ],
                rows: summary,
            },
            overall,
            details: Table {
                header: vec![
                    "record",
                    "system",
                    "method",
                    "CPU time / sim",
                    "× exact",
                    "peak err (signed)",
                    "history err",
                    "switches",
                ],
                rows: details,
            },
        }
    }
}

fn markdown(machine: &str, args: &Args, opensees: Option<&str>, t: &Tables) -> String {
    let mut s = String::from("# Work-precision: exact integrator, the paper's RK4, OpenSees\n\n");
    s += &format!(
        "Generated by `slidestack-verify accuracy{}{}`. Machine: {machine}.\n\n",
        if args.quick { " --quick" } else { "" },
        if args.opensees.is_some() {
            " --opensees …"
        } else {
            ""
        }
    );
    s += "Errors are of the structure's displacement at the record samples against the exact \
          integrator, relative to its peak over those samples: peak = (max|û| − max|u|)/max|u| \
          (signed), history = max|û − u|/max|u|. Times are CPU time of the running thread per \
          simulation without history (Rust: median of batches in-process; OpenSees: one run in \
          Python, model build plus analysis). `*`: a coarser sub-step count already met the tolerance before the error \
          rose above it again. Static = kinetic friction throughout.\n\n";
    s += &match opensees {
        Some(v) => format!(
            "OpenSees {v}: scripts/opensees_stack.py (zeroLength springs, elastic-perfectly-plastic \
             friction links of stick stiffness s·k, Newmark average acceleration, Newton).\n\n"
        ),
        None => "OpenSees: not run (pass `--opensees PYTHON`).\n\n".to_string(),
    };
    s += "Systems (5 % damping, each under every record):\n\n";
    for system in SYSTEMS {
        s += &format!("- {}: {}\n", system.label(), system.what);
    }
    s += "\n## Summary\n\n";
    for line in &t.overall {
        s += &format!("- {line}\n");
    }
    s += "\n";
    s += &t.summary.markdown();
    s += "\n![history error against time](accuracy.svg)\n\n";
    s += "## Every method and setting\n\n";
    s += &t.details.markdown();
    s
}

fn html(machine: &str, t: &Tables, svg_history: &str, svg_peak: &str) -> String {
    let summary = format!(
        "<p>Machine: {}</p><ul>{}</ul>{}",
        render::escape(machine),
        t.overall
            .iter()
            .map(|l| format!("<li>{}</li>", render::escape(l)))
            .collect::<String>(),
        t.summary.html()
    );
    render::page(
        "slidestack: work-precision of the integrators",
        &[
            ("Summary".to_string(), summary),
            (
                "Work-precision".to_string(),
                format!("{svg_history}{svg_peak}"),
            ),
            ("Every method and setting".to_string(), t.details.html()),
        ],
    )
}

fn csv(cases: &[CaseResult]) -> String {
    let mut s = String::from(
        "record,system,samples,method,steps_per_interval,stick_stiffness,cpu_time_per_sim_s,\
         time_over_exact,peak_err_signed,history_err,switches,exact_peak_between_samples_m\n",
    );
    for c in cases {
        for r in &c.rows {
            let (method, stiffness) = match r.method {
                Method::Exact => ("exact", String::new()),
                Method::ExactRefined => ("exact_refined_record", String::new()),
                Method::Rk4 => ("rk4", String::new()),
                Method::OpenSees { stiffness } => ("opensees", format!("{stiffness:e}")),
            };
            s += &format!(
                "{},\"{}\",{},{method},{},{stiffness},{:e},{:e},{:e},{:e},{},{:e}\n",
                c.record,
                c.system,
                c.samples,
                r.steps,
                r.time_s,
                r.time_s / c.exact_time_s,
                r.errors.peak_signed,
                r.errors.history,
                r.switches.map_or(String::new(), |s| s.to_string()),
                c.exact_peak_m
            );
        }
    }
    s
}

/// The work-precision plots: per method setting, the geometric means over the cases of the time
/// relative to the exact integrator and of the error (history, then peak); RK4's per-case curves
/// faint behind.
fn charts(cases: &[CaseResult]) -> (String, String) {
    let draw = |err: fn(&Errors) -> f64, what: &str| {
        let mut series = Vec::new();
        for c in cases {
            let (x, y): (Vec<f64>, Vec<f64>) = c
                .rk4()
                .map(|r| (r.time_s / c.exact_time_s, err(&r.errors).max(ERROR_FLOOR)))
                .unzip();
            series.push(Series::faint(x, y));
        }
        let mean_curve = |pick: &dyn Fn(&Row) -> bool| -> (Vec<f64>, Vec<f64>) {
            let mut steps: Vec<usize> = cases
                .iter()
                .flat_map(|c| c.rows.iter().filter(|r| pick(r)).map(|r| r.steps))
                .collect();
            steps.sort_unstable();
            steps.dedup();
            steps
                .iter()
                .filter_map(|&s| {
                    let rows = || {
                        cases.iter().flat_map(move |c| {
                            c.rows
                                .iter()
                                .filter(move |r| pick(r) && r.steps == s)
                                .map(move |r| (c, r))
                        })
                    };
                    let t = geometric_mean(rows().map(|(c, r)| r.time_s / c.exact_time_s), 0.0)?;
                    let e = geometric_mean(rows().map(|(_, r)| err(&r.errors)), ERROR_FLOOR)?;
                    Some((t, e))
                })
                .unzip()
        };
        let (x, y) = mean_curve(&|r| r.method == Method::Rk4);
        series.push(Series::line("RK4, 1 to 1000 sub-steps", x, y));
        let mut stiffnesses: Vec<f64> = cases
            .iter()
            .flat_map(|c| c.rows.iter())
            .filter_map(|r| match r.method {
                Method::OpenSees { stiffness } => Some(stiffness),
                _ => None,
            })
            .collect();
        stiffnesses.sort_by(f64::total_cmp);
        stiffnesses.dedup();
        for s in stiffnesses {
            let (x, y) = mean_curve(&|r| r.method == Method::OpenSees { stiffness: s });
            series.push(Series::line(format!("OpenSees, stick {s:.0e}·k"), x, y));
        }
        // The exact integrator at time ratio 1, at its difference from itself on the refined record.
        let self_check = cases
            .iter()
            .filter_map(|c| c.refined().map(|r| err(&r.errors)));
        if let Some(y) = geometric_mean(self_check, ERROR_FLOOR) {
            series.push(Series::points(
                "exact (vs itself on a ×8 record)",
                vec![1.0],
                vec![y],
            ));
        }
        render::chart_log_log(
            &format!("{what} error against time (geometric means over the cases)"),
            "CPU time per simulation / exact integrator's",
            &format!("{what} error / peak"),
            &series,
        )
    };
    (draw(|e| e.history, "History"), draw(|e| e.peak(), "Peak"))
}
