//! `slidestack simulate`: one case, one ground motion.
//!
//! Reads a record (`--record`, a PEER `.AT2` or two-column time/acceleration file in g; the
//! built-in Northridge record when absent) and the case from flags or a YAML file (`--config`,
//! keys as the long flags with `_` for `-`; flags override it). Prints the peaks, slips, switch
//! count and energy terms as a table or, with `--json`, one JSON object on stdout. Writes the full
//! time history when `--history OUT.h5|OUT.csv` is given. `--structure epp|bilinear` makes the
//! structure yield (docs/model.md, "Yielding structure") and adds its ductility, residual
//! displacement and hysteretic energy.

use super::BadInput;
use anyhow::{Context, Result};
use clap::ValueEnum;
use serde::{Deserialize, Serialize};
use slidestack::dynamics::{
    ExactOptions, G, Ground, Response, System, SystemSpec, Yielding, simulate_exact, simulate_rk4,
};
use slidestack::motion::{self, Record};
use slidestack::store::write_history;
use slidestack::study::config::read_yaml_text;
use slidestack::study::sweep::{DampingBasis, Physics};
use std::path::PathBuf;

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Integrator {
    /// Event-driven closed-form integrator (exact for piecewise-linear ground motion).
    Exact,
    /// The paper's fixed-step RK4 with its top-down cluster rule.
    Rk4,
}

/// The structure's restoring force (docs/model.md, "Yielding structure").
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum StructureKind {
    /// Linear, the paper's structure.
    Elastic,
    /// Elastic–perfectly plastic (needs --yield-strength-ratio).
    Epp,
    /// Bilinear with kinematic hardening (needs --yield-strength-ratio and --post-yield-ratio).
    Bilinear,
}

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
    /// Integrator [default: exact].
    #[arg(long, value_enum)]
    integrator: Option<Integrator>,
    /// RK4 sub-steps per record interval [default: 10].
    #[arg(long)]
    rk4_substeps: Option<usize>,
    /// Restoring force of the structure [default: elastic].
    #[arg(long, value_enum)]
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

/// The case as a YAML file states it; every key optional, unknown keys refused.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct CaseFile {
    record: Option<PathBuf>,
    period: Option<f64>,
    alpha: Option<Vec<f64>>,
    mu: Option<Vec<f64>>,
    mu_static: Option<Vec<f64>>,
    damping: Option<f64>,
    damping_basis: Option<DampingBasis>,
    scale: Option<f64>,
    integrator: Option<Integrator>,
    rk4_substeps: Option<usize>,
    history: Option<PathBuf>,
    structure: Option<StructureKind>,
    yield_strength_ratio: Option<f64>,
    post_yield_ratio: Option<f64>,
}

#[derive(Debug, Serialize)]
struct EnergyJson {
    input: f64,
    kinetic: f64,
    strain: f64,
    damping: f64,
    friction: f64,
    friction_per_interface: Vec<f64>,
    /// `∫F_s du − F_s²/(2k)` of a yielding structure; 0 when elastic.
    hysteretic: f64,
}

/// The `--json` contract (README): field names are relied on by users and checks.
#[derive(Debug, Serialize)]
struct Output {
    record: String,
    dt_s: f64,
    npts: usize,
    scale: f64,
    period_s: f64,
    period_rigid_s: f64,
    /// The damping ratio as given, of the system `damping_basis` names.
    damping: f64,
    damping_basis: DampingBasis,
    /// The bare structure's damping ratio that gives the same damper.
    structure_damping: f64,
    alpha: Vec<f64>,
    mu: Vec<f64>,
    mu_static: Vec<f64>,
    integrator: Integrator,
    rk4_substeps: Option<usize>,
    structure: StructureKind,
    yield_strength_ratio: Option<f64>,
    post_yield_ratio: Option<f64>,
    yield_displacement_m: Option<f64>,
    peak_displacement_m: f64,
    peak_displacement_time_s: f64,
    peak_abs_accel_g: Vec<f64>,
    peak_slip_m: Vec<f64>,
    residual_slip_m: Vec<f64>,
    slip_time_s: Vec<f64>,
    switches: u64,
    /// Peak displacement over the yield displacement; null when elastic.
    ductility: Option<f64>,
    /// Structure displacement at the end of the record, m.
    residual_displacement_m: f64,
    /// Yield and unloading events (or, with rk4, changes of branch between sub-steps).
    yield_events: u64,
    energy: EnergyJson,
    energy_balance_error: f64,
    energy_balance_error_max: f64,
}

pub fn run(args: Args) -> Result<()> {
    let file = match &args.config {
        Some(path) => {
            let text = read_yaml_text(path)?;
            serde_yaml::from_str::<CaseFile>(&text).map_err(|e| {
                BadInput(format!(
                    "{}: {}",
                    path.display(),
                    slidestack::limits::excerpt_message(&e.to_string())
                ))
            })?
        }
        None => CaseFile::default(),
    };
    let basis = args
        .damping_basis
        .or(file.damping_basis)
        .unwrap_or_default();
    let alpha = args.alpha.or(file.alpha).unwrap_or_else(|| vec![0.5, 0.5]);
    let physics = Physics {
        damping: args.damping.or(file.damping).unwrap_or(0.05),
        basis,
        mu_static_ratio: 1.0,
    };
    let total: f64 = alpha.iter().sum();
    if total.is_finite() && total <= slidestack::limits::MAX_ALPHA {
        physics
            .check(total)
            .map_err(|why| BadInput(format!("invalid case: {why}")))?;
    }
    let spec = SystemSpec {
        period_s: args.period.or(file.period).unwrap_or(1.0),
        damping_ratio: physics.structure_damping(alpha.iter().sum()),
        mass_kg: 1.0,
        alpha,
        mu: args.mu.or(file.mu).unwrap_or_else(|| vec![0.2, 0.1]),
        mu_static: args.mu_static.or(file.mu_static),
    };
    let scale = args.scale.or(file.scale).unwrap_or(1.0);
    if !(scale.is_finite() && scale > 0.0 && scale <= 1e6) {
        return Err(BadInput(format!("scale must be finite, > 0 and ≤ 1e6, got {scale}")).into());
    }
    let integrator = args
        .integrator
        .or(file.integrator)
        .unwrap_or(Integrator::Exact);
    let substeps = args.rk4_substeps.or(file.rk4_substeps).unwrap_or(10);
    let history_path = args.history.or(file.history);
    if let Some(p) = &history_path {
        slidestack::store::HistoryFormat::from_path(p)?;
    }
    let structure = args
        .structure
        .or(file.structure)
        .unwrap_or(StructureKind::Elastic);
    let yielding = yielding(
        structure,
        args.yield_strength_ratio.or(file.yield_strength_ratio),
        args.post_yield_ratio.or(file.post_yield_ratio),
    )?;
    let mut system = System::new(&spec).map_err(|e| BadInput(format!("invalid case: {e}")))?;
    if let Some(y) = yielding {
        system = system
            .with_yielding(y)
            .map_err(|e| BadInput(format!("invalid case: {e}")))?;
    }
    let record: Record = match args.record.or(file.record) {
        Some(path) => motion::read_record(&path)?,
        None => motion::builtin(),
    };
    let accel = record.accel_mps2(scale);
    let ground = Ground {
        dt_s: record.dt_s,
        accel_mps2: &accel,
    };
    for w in slidestack::dynamics::accuracy_warnings(&system, &ground) {
        eprintln!("simulate: warning: {w}");
    }
    let want_history = history_path.is_some();
    let response = match integrator {
        Integrator::Exact => simulate_exact(
            &system,
            &ground,
            &ExactOptions {
                history: want_history,
                ..ExactOptions::default()
            },
        ),
        Integrator::Rk4 => simulate_rk4(&system, &ground, substeps, want_history),
    }
    .with_context(|| format!("simulation of {} failed", record.name))?;
    if let (Some(path), Some(h)) = (&history_path, &response.history) {
        write_history(path, h)?;
    }
    let out = output(
        &record, scale, &physics, &system, structure, integrator, substeps, &response,
    );
    if args.json {
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        print_table(&out);
        if let Some(p) = &history_path {
            println!("history written to {}", p.display());
        }
    }
    Ok(())
}

/// The yielding model the flags ask for; `None` for the elastic structure. Each flag is
/// refused where it does not apply, and required where it does.
fn yielding(
    structure: StructureKind,
    strength: Option<f64>,
    r: Option<f64>,
) -> Result<Option<Yielding>, BadInput> {
    match (structure, strength, r) {
        (StructureKind::Elastic, None, None) => Ok(None),
        (StructureKind::Elastic, _, _) => Err(BadInput(
            "--yield-strength-ratio and --post-yield-ratio apply only to --structure epp or \
             bilinear"
                .into(),
        )),
        (_, None, _) => Err(BadInput(format!(
            "--structure {} needs --yield-strength-ratio (C_y = F_y/(m_p·g))",
            structure.name()
        ))),
        (StructureKind::Epp, Some(c), None) => Ok(Some(Yielding::epp(c))),
        (StructureKind::Epp, Some(_), Some(r)) => Err(BadInput(format!(
            "--structure epp has no post-yield stiffness (r = 0), got --post-yield-ratio {r}; \
             use --structure bilinear"
        ))),
        (StructureKind::Bilinear, Some(_), None) => Err(BadInput(
            "--structure bilinear needs --post-yield-ratio (r, 0 ≤ r < 1)".into(),
        )),
        (StructureKind::Bilinear, Some(c), Some(r)) => Ok(Some(Yielding::bilinear(c, r))),
    }
}

impl StructureKind {
    fn name(self) -> &'static str {
        match self {
            StructureKind::Elastic => "elastic",
            StructureKind::Epp => "epp",
            StructureKind::Bilinear => "bilinear",
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn output(
    record: &Record,
    scale: f64,
    physics: &Physics,
    sys: &System,
    structure: StructureKind,
    integrator: Integrator,
    substeps: usize,
    r: &Response,
) -> Output {
    let e = &r.energy;
    let hyst = sys.hysteresis();
    Output {
        record: record.name.clone(),
        dt_s: record.dt_s,
        npts: record.accel_g.len(),
        scale,
        period_s: sys.period_s(),
        period_rigid_s: sys.period_rigid_s(),
        damping: physics.damping,
        damping_basis: physics.basis,
        structure_damping: sys.damping_ratio(),
        alpha: sys.masses()[1..]
            .iter()
            .map(|m| m / sys.mass_kg())
            .collect(),
        mu: sys.mu_kinetic().to_vec(),
        mu_static: sys.mu_static().to_vec(),
        integrator,
        rk4_substeps: (integrator == Integrator::Rk4).then_some(substeps),
        structure,
        yield_strength_ratio: hyst.map(|h| h.strength_ratio),
        post_yield_ratio: hyst.map(|h| h.post_yield_ratio),
        yield_displacement_m: hyst.map(|h| h.yield_displacement_m),
        peak_displacement_m: r.peak_displacement_m,
        peak_displacement_time_s: r.peak_displacement_time_s,
        peak_abs_accel_g: r.peak_abs_accel_mps2.iter().map(|a| a / G).collect(),
        peak_slip_m: r.peak_slip_m.clone(),
        residual_slip_m: r.residual_slip_m.clone(),
        slip_time_s: r.slip_time_s.clone(),
        switches: r.switches,
        ductility: r.ductility,
        residual_displacement_m: r.residual_displacement_m,
        yield_events: r.yield_events,
        energy: EnergyJson {
            input: e.input,
            kinetic: e.kinetic,
            strain: e.strain,
            damping: e.damping,
            friction: e.friction,
            friction_per_interface: e.friction_per_interface.clone(),
            hysteretic: e.hysteretic,
        },
        energy_balance_error: e.balance_error(),
        energy_balance_error_max: r.energy_balance_error_max,
    }
}

fn print_table(o: &Output) {
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
