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
use slidestack::simulation::{CaseSettings, Integrator, StructureKind, Summary};
use slidestack::store::{HistoryLayout, write_history};
use slidestack::study::sweep::DampingBasis;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// YAML file with the case (keys: record, period, alpha, mu, mu_static, damping,
    /// damping_basis, scale, integrator, rk4_substeps, history, structure,
    /// yield_strength_ratio, post_yield_ratio); flags given on the command line override it.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Ground-motion record: PEER .AT2 or two-column time/acceleration text, values in g.
    #[arg(long)]
    record: Option<PathBuf>,
    /// Period of the bare structure T_p, s [default: 1.0].
    #[arg(long)]
    period: Option<f64>,
    /// Block mass ratios α_i = m_i/m_p, bottom block first [default: 0.5,0.5].
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    alpha: Option<Vec<f64>>,
    /// Kinetic friction coefficients μ_i, interface 1 (structure–block 1) first [default: 0.2,0.1].
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    mu: Option<Vec<f64>>,
    /// Static friction coefficients (≥ kinetic) [default: equal to --mu].
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    mu_static: Option<Vec<f64>>,
    /// Viscous damping ratio [default: 0.05], of the system --damping-basis names.
    #[arg(long)]
    damping: Option<f64>,
    /// `rigid`: the damping ratio is that of the structure with its whole stack rigidly attached
    /// (the study's default); `structure`: of the bare structure [default: rigid].
    #[arg(long)]
    damping_basis: Option<DampingBasis>,
    /// Factor applied to the record [default: 1.0].
    #[arg(long)]
    scale: Option<f64>,
    /// Integrator: exact or rk4 [default: exact].
    #[arg(long)]
    integrator: Option<Integrator>,
    /// RK4 sub-steps per record interval [default: 10].
    #[arg(long)]
    rk4_substeps: Option<usize>,
    /// Restoring force of the structure: elastic, epp or bilinear [default: elastic].
    #[arg(long)]
    structure: Option<StructureKind>,
    /// Yield strength ratio C_y = F_y/(m_p·g) of an epp or bilinear structure (m_p the bare
    /// structure's mass).
    #[arg(long)]
    yield_strength_ratio: Option<f64>,
    /// Post-yield stiffness over elastic stiffness r (0 ≤ r < 1) of a bilinear structure.
    #[arg(long)]
    post_yield_ratio: Option<f64>,
    /// Write the time history to this .h5 or .csv file.
    #[arg(long)]
    history: Option<PathBuf>,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
}

impl Args {
    fn settings(self) -> CaseSettings {
        CaseSettings {
            record: self.record,
            period: self.period,
            alpha: self.alpha,
            mu: self.mu,
            mu_static: self.mu_static,
            damping: self.damping,
            damping_basis: self.damping_basis,
            scale: self.scale,
            integrator: self.integrator,
            rk4_substeps: self.rk4_substeps,
            history: self.history,
            structure: self.structure,
            yield_strength_ratio: self.yield_strength_ratio,
            post_yield_ratio: self.post_yield_ratio,
        }
    }
}

pub fn run(args: Args) -> Result<()> {
    let json = args.json;
    let file = match &args.config {
        Some(path) => CaseSettings::read(path)?,
        None => CaseSettings::default(),
    };
    let case = args.settings().over(file).resolve()?;
    let accel = case.accel_mps2();
    for w in case.warnings(&accel) {
        eprintln!("simulate: warning: {w}");
    }
    let (summary, history) = case.simulate(&accel)?;
    if let (Some(path), Some(h)) = (&case.history, &history) {
        write_history(path, h, &HistoryLayout::one_storey(h.interfaces))?;
    }
    if json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else {
        print_table(&summary);
        if let Some(p) = &case.history {
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
