//! `slidestack simulate`: one case, one ground motion.
//!
//! Reads a record (`--record`, a PEER `.AT2` or two-column time/acceleration file in g; the
//! built-in Northridge record when absent) and the case from flags or a YAML file (`--config`,
//! keys as the long flags with `_` for `-`; flags override it). Prints the peaks, slips, switch
//! count and energy terms as a table or, with `--json`, one JSON object on stdout. Writes the full
//! time history when `--history OUT.h5|OUT.csv` is given. `--structure epp|bilinear` makes the
//! structure yield (docs/model.md, "Yielding structure") and adds its ductility, residual
//! displacement and hysteretic energy. The case and its checks: `slidestack::one_case`.

use anyhow::Result;
use slidestack::one_case::building::{BuildingSummary, history_layout};
use slidestack::one_case::floor_spectra::FloorSpectra;
use slidestack::one_case::{Model, Outcome, Settings, Summary};
use slidestack::store::{HistoryLayout, write_history};
use std::path::PathBuf;

/// A long case's estimated time, s, beyond which `simulate` says it before it runs.
const SAY_ESTIMATE_S: f64 = 15.0;

/// A case's estimated time, s, beyond which a terminal shows a bar.
const BAR_ESTIMATE_S: f64 = 1.0;

/// What watches a simulation on the command line: a bar on a terminal for a long case, Ctrl-C
/// (which stops it within [`slidestack::dynamics::WATCH_EVERY`] samples: exit 130), and the
/// test hook's point `simulate.samples` ([`slidestack::pipeline::pause`]).
struct Watch {
    bar: Option<indicatif::ProgressBar>,
}

impl Watch {
    /// For a case estimated at `estimate_s`: says the estimate on standard error when it is
    /// long, and draws a bar when standard error is a terminal and the case is not short.
    fn of(estimate_s: f64) -> Self {
        use std::io::IsTerminal;
        if estimate_s > SAY_ESTIMATE_S {
            eprintln!(
                "simulate: this case takes about {} on a 2-core machine like the project's \
                 (an estimate from its size); Ctrl-C stops it",
                duration(estimate_s)
            );
        }
        let bar = (estimate_s > BAR_ESTIMATE_S && std::io::stderr().is_terminal()).then(|| {
            let style =
                indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} samples, ETA {eta}")
                    .expect("valid template");
            indicatif::ProgressBar::new(0).with_style(style)
        });
        Self { bar }
    }
}

impl slidestack::dynamics::Watch for Watch {
    fn going_on(&self, sample: usize, samples: usize) -> bool {
        if let Some(b) = &self.bar {
            b.set_length(samples as u64);
            b.set_position(sample as u64);
        }
        let stop = super::interrupt::interrupted;
        slidestack::pipeline::pause::point("simulate.samples", &stop);
        !stop()
    }
}

impl Drop for Watch {
    fn drop(&mut self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

/// `3 s`, `4 min`, `2.5 h`, `85 days`.
fn duration(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.0} s")
    } else if s < 7200.0 {
        format!("{:.0} min", s / 60.0)
    } else if s < 172_800.0 {
        format!("{:.1} h", s / 3600.0)
    } else {
        format!("{:.0} days", s / 86_400.0)
    }
}

#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// YAML file with the case (its keys are the long flags below, with `_` for `-`); flags
    /// given on the command line override it.
    #[arg(long)]
    config: Option<PathBuf>,
    #[command(flatten)]
    settings: Settings,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
    /// For a building case: write an SVG figure of the stacks sliding against them rigidly
    /// attached (peak floor displacement and drift over the height, roof displacement and slips
    /// over time).
    #[arg(long)]
    figure: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    if let Some(path) = &args.figure {
        super::check_figure(path)?;
    }
    let file = match &args.config {
        Some(path) => Settings::read(path)?,
        None => Settings::default(),
    };
    let sim = args.settings.over(file)?.resolve()?;
    let accel = sim.accel_mps2();
    for w in sim.warnings(&accel) {
        eprintln!("simulate: warning: {w}");
    }
    if args.figure.is_some() && !matches!(sim.model, Model::Building { .. }) {
        return Err(super::BadInput(
            "--figure draws a building case: the case needs `building`".into(),
        )
        .into());
    }
    let watch = Watch::of(sim.cost_estimate_s());
    let (outcome, history) = sim.run_watched(&accel, sim.history.is_some(), &watch)?;
    if let (Some(path), Some(h)) = (&sim.history, &history) {
        let layout = match &sim.model {
            Model::OneStorey { .. } => HistoryLayout::one_storey(h.interfaces),
            Model::Building { building, .. } => history_layout(building),
        };
        write_history(path, h, &layout)?;
    }
    if let Some(path) = &args.figure
        && let Some(fig) = sim.building_figure(&accel, &watch)?
    {
        let svg = slidestack::render::chart::render(&fig)?;
        slidestack::store::atomic::write_bytes(path, svg.as_bytes())?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&outcome)?);
    } else {
        let floor_spectra = match &outcome {
            Outcome::OneStorey(s) => {
                print_table(s);
                &s.floor_spectra
            }
            Outcome::Building(b) => {
                print_building(b);
                &b.floor_spectra
            }
        };
        if let Some(fs) = floor_spectra {
            print_floor_spectra(fs);
        }
        if let Some(p) = &sim.history {
            println!("history written to {}", p.display());
        }
        if let Some(p) = &args.figure {
            println!("figure written to {}", p.display());
        }
    }
    Ok(())
}

/// Each floor's largest spectral acceleration and its period, per damping ratio (the spectra
/// themselves: `--json`).
fn print_floor_spectra(fs: &FloorSpectra) {
    for (z, floors) in fs.damping.iter().zip(&fs.psa_g) {
        let peaks: Vec<String> = (floors.iter().enumerate())
            .map(|(j, psa)| {
                let (k, top) = (psa.iter().enumerate()).fold((0, f64::MIN), |(bk, b), (k, &x)| {
                    if x > b { (k, x) } else { (bk, b) }
                });
                format!("floor {} {top:.4} g at {} s", j + 1, fs.periods_s[k])
            })
            .collect();
        println!("floor spectra     ζ {z}: largest PSA {}", peaks.join(", "));
    }
}

fn print_building(o: &BuildingSummary) {
    let list = |v: &[f64], prec: usize| {
        v.iter()
            .map(|x| format!("{x:.prec$}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let b = &o.building;
    println!(
        "record            {} ({} samples, dt {} s, scale {})",
        o.record, o.npts, o.dt_s, o.scale
    );
    println!(
        "building          {} storeys, T_1 {} s (modes [{}] s), damping {} ({} basis), {}",
        b.storeys,
        b.period_s,
        list(&o.modes_s, 4),
        o.damping,
        o.damping_basis.name(),
        b.structure.name()
    );
    println!(
        "integrator        {}",
        match o.rk4_substeps {
            Some(n) => format!("rk4, {n} sub-steps"),
            None => "exact".to_string(),
        }
    );
    println!("floor  peak u (m)   peak |a| (g)  peak |v| (m/s)");
    for j in 0..b.storeys {
        println!(
            "{:>5}  {:<11.6}  {:<12.4}  {:.4}",
            j + 1,
            o.floor_peak_displacement_m[j],
            o.floor_peak_abs_accel_g[j],
            o.floor_peak_abs_velocity_mps[j]
        );
    }
    println!("storey  peak drift (m)  residual drift (m)  ductility");
    for i in 0..b.storeys {
        let mu = o
            .storey_ductility
            .as_ref()
            .map_or("–".to_string(), |d| format!("{:.4}", d[i]));
        println!(
            "{:>6}  {:<14.6}  {:<18.6}  {mu}",
            i + 1,
            o.storey_peak_drift_m[i],
            o.storey_residual_drift_m[i]
        );
    }
    for (i, s) in o.stacks.iter().enumerate() {
        println!(
            "stack {} on floor {}: alpha [{}], mu [{}]; peak slip [{}] m, residual [{}] m, \
             peak |a| [{}] g, peak |v| [{}] m/s",
            i + 1,
            s.floor,
            list(&s.alpha, 3),
            list(&s.mu, 3),
            list(&s.peak_slip_m, 5),
            list(&s.residual_slip_m, 5),
            list(&s.peak_abs_accel_g, 4),
            list(&s.peak_abs_velocity_mps, 4)
        );
    }
    println!(
        "switches          {}, yield/unloading events {}",
        o.switches, o.yield_events
    );
    let e = &o.energy;
    println!(
        "energy (J/kg)     input {:.6}, kinetic {:.6}, strain {:.6}, damping {:.6}, friction \
         {:.6}, hysteretic {:.6}",
        e.input, e.kinetic, e.strain, e.damping, e.friction, e.hysteretic
    );
    println!(
        "energy balance    |residual|/input = {:.2e}",
        o.energy_balance_error
    );
}

fn print_table(o: &Summary) {
    let list = |v: &[f64], prec: usize| {
        v.iter()
            .map(|x| format!("{x:.prec$}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    println!(
        "record            {} ({} samples, dt {} s, scale {})",
        o.record, o.npts, o.dt_s, o.scale
    );
    println!(
        "structure         T_p {} s, damping {} ({} basis; bare structure {:.4}), T_rigid {:.4} s",
        o.period_s,
        o.damping,
        o.damping_basis.name(),
        o.structure_damping,
        o.period_rigid_s
    );
    println!(
        "stack             alpha [{}], mu [{}], mu_static [{}]",
        list(&o.alpha, 3),
        list(&o.mu, 3),
        list(&o.mu_static, 3)
    );
    let integ = match o.rk4_substeps {
        Some(n) => format!("rk4, {n} sub-steps"),
        None => "exact".to_string(),
    };
    println!("integrator        {integ}");
    if let (Some(c), Some(r), Some(uy)) = (
        o.yield_strength_ratio,
        o.post_yield_ratio,
        o.yield_displacement_m,
    ) {
        println!(
            "yielding          {}: C_y {c}, r {r}, u_y {uy:.6} m",
            o.structure.name()
        );
    }
    println!(
        "peak displacement {:.6} m at {:.4} s",
        o.peak_displacement_m, o.peak_displacement_time_s
    );
    println!(
        "peak abs accel    [{}] g (structure, blocks bottom-up)",
        list(&o.peak_abs_accel_g, 4)
    );
    println!(
        "peak abs velocity [{}] m/s",
        list(&o.peak_abs_velocity_mps, 4)
    );
    println!("peak slip         [{}] m", list(&o.peak_slip_m, 5));
    println!("residual slip     [{}] m", list(&o.residual_slip_m, 5));
    println!("slipping time     [{}] s", list(&o.slip_time_s, 3));
    println!("switches          {}", o.switches);
    if let Some(mu) = o.ductility {
        println!(
            "ductility         {mu:.4} ({} yield/unloading events), residual displacement {:.6} m",
            o.yield_events, o.residual_displacement_m
        );
    }
    let e = &o.energy;
    println!(
        "energy (J/kg)     input {:.6}, kinetic {:.6}, strain {:.6}, damping {:.6}, friction {:.6}",
        e.input, e.kinetic, e.strain, e.damping, e.friction
    );
    if o.ductility.is_some() {
        println!("                  hysteretic {:.6}", e.hysteretic);
    }
    println!(
        "energy balance    |residual|/input = {:.2e}",
        o.energy_balance_error
    );
}
