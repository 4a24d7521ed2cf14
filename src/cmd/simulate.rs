//! `slidestack simulate`: one case, one ground motion.
//!
//! Reads a record (`--record`, a PEER `.AT2` or two-column time/acceleration file in g; the
//! built-in Northridge record when absent) and the case from flags or a YAML file (`--config`,
//! keys as the long flags with `_` for `-`; flags override it). Prints the peaks, slips, switch
//! count and energy terms as a table or, with `--json`, one JSON object on stdout. Writes the full
//! time history when `--history OUT.h5|OUT.csv` is given. `--structure epp|bilinear` makes the
//! structure yield (docs/model.md, "Yielding structure") and adds its ductility, residual
//! displacement and hysteretic energy. The case and its checks: `slidestack::simulation`.

use anyhow::Result;
use slidestack::simulation::{Settings, Summary};
use slidestack::store::{HistoryLayout, write_history};
use std::path::PathBuf;

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
}

pub fn run(args: Args) -> Result<()> {
    let file = match &args.config {
        Some(path) => Settings::read(path)?,
        None => Settings::default(),
    };
    let sim = args.settings.over(file)?.resolve()?;
    let accel = sim.accel_mps2();
    for w in sim.warnings(&accel) {
        eprintln!("simulate: warning: {w}");
    }
    let (summary, history) = sim.run(&accel)?;
    if let (Some(path), Some(h)) = (&sim.history, &history) {
        write_history(path, h, &HistoryLayout::one_storey(h.interfaces))?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else {
        print_table(&summary);
        if let Some(p) = &sim.history {
            println!("history written to {}", p.display());
        }
    }
    Ok(())
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
