//! The case list and the tolerance rules (module doc of [`super`]).

use super::{Expect, GroundMotion, Reference, Scale, StressCase};
use slidestack::dynamics::{ExactOptions, G, SystemSpec};

/// Floor of the energy-balance tolerance (see the module doc).
pub const ENERGY_TOLERANCE_FLOOR: f64 = 1e-9;
/// Energy-balance tolerance per squared sample count of the longest period (see the module doc).
pub const ENERGY_TOLERANCE_PER_SAMPLES2: f64 = 2e-13;
/// Floor of the tolerance on agreement between two exact solutions (see the module doc).
pub const HISTORY_TOLERANCE_FLOOR: f64 = 1e-9;
/// Agreement tolerance per squared longest period, 1/s² (see the module doc).
pub const HISTORY_TOLERANCE_PER_S2: f64 = 2e-11;
/// Tolerance on the RK4 reference (see the module doc).
pub const RK4_TOLERANCE: f64 = 1e-3;
/// Tolerance on the step hand solution (see the module doc).
pub const STEP_HAND_TOLERANCE: f64 = 1e-3;
/// Switch budget of a case that may slide, per interface and second of record.
pub const SWITCHES_PER_INTERFACE_SECOND: f64 = 40.0;

/// Energy-balance tolerance for a system whose longest period (everything stuck) is
/// `t_rigid_s`, sampled at `dt_s`: `max(1e-9, 2e-13·(T_rigid/dt)²)`.
pub fn energy_tolerance(t_rigid_s: f64, dt_s: f64) -> f64 {
    let samples_per_period = t_rigid_s / dt_s;
    ENERGY_TOLERANCE_FLOOR.max(ENERGY_TOLERANCE_PER_SAMPLES2 * samples_per_period.powi(2))
}

/// Tolerance on the agreement of two exact solutions (refined record, closed forms, one-block
/// equivalent) for a system whose longest period is `t_rigid_s`: `max(1e-9, 2e-11·T_rigid²)`.
pub fn history_tolerance(t_rigid_s: f64) -> f64 {
    HISTORY_TOLERANCE_FLOOR.max(HISTORY_TOLERANCE_PER_S2 * t_rigid_s.powi(2))
}

/// Period with the whole stack attached, s (the longest the structure's cluster can have).
fn period_rigid_s(spec: &SystemSpec) -> f64 {
    spec.period_s * (1.0 + spec.alpha.iter().sum::<f64>()).sqrt()
}

/// Sample interval of most cases, s.
const DT_S: f64 = 0.01;

/// A stochastic record: the model's default strong-motion duration (`D5-95` 17.3 s, `t_mid`
/// 12.4 s, 99 % of the intensity by 29 s) from 30 s on, a proportionally shorter one below.
fn quake(seed: u64, duration_s: f64, dt_s: f64, scale: Scale) -> GroundMotion {
    let (d595_s, t_mid_s) = if duration_s >= 30.0 {
        (17.3, 12.4)
    } else {
        (0.4 * duration_s, 0.3 * duration_s)
    };
    GroundMotion::Stochastic {
        seed,
        dt_s,
        duration_s,
        d595_s,
        t_mid_s,
        scale,
    }
}

/// A 300 s stochastic record whose strong motion lasts 150 s (`t_mid` 100 s).
fn long_quake(seed: u64, pga_g: f64) -> GroundMotion {
    GroundMotion::Stochastic {
        seed,
        dt_s: DT_S,
        duration_s: 300.0,
        d595_s: 150.0,
        t_mid_s: 100.0,
        scale: Scale::PgaG(pga_g),
    }
}

fn spec(period_s: f64, alpha: &[f64], mu: &[f64]) -> SystemSpec {
    SystemSpec::new(period_s, alpha, mu)
}

fn spec_static(period_s: f64, alpha: &[f64], mu: &[f64], mu_static: &[f64]) -> SystemSpec {
    SystemSpec {
        mu_static: Some(mu_static.to_vec()),
        ..SystemSpec::new(period_s, alpha, mu)
    }
}

/// A reference with its tolerance chosen for the case's system (see the module doc).
#[derive(Debug, Clone, Copy)]
pub(super) enum Ref {
    Refined(usize),
    Zero,
    Rigid,
    Frictionless,
    OneBlock,
    StepHand { step_s: f64, accel_mps2: f64 },
    Rk4(usize),
}

fn reference(r: Ref, t_rigid_s: f64) -> Reference {
    let tolerance = history_tolerance(t_rigid_s);
    match r {
        Ref::Refined(factor) => Reference::Refined { factor, tolerance },
        Ref::Zero => Reference::Zero,
        Ref::Rigid => Reference::RigidSdof { tolerance },
        Ref::Frictionless => Reference::Frictionless { tolerance },
        Ref::OneBlock => Reference::OneBlock { tolerance },
        Ref::StepHand { step_s, accel_mps2 } => Reference::StepHand {
            step_s,
            accel_mps2,
            tolerance: STEP_HAND_TOLERANCE,
        },
        Ref::Rk4(substeps) => Reference::Rk4 {
            substeps,
            tolerance: RK4_TOLERANCE,
        },
    }
}

/// A case that must complete, with the suite's tolerances for its system and sampling: the
/// energy tolerance from the longest period and the step, the switch budget 0 when a reference
/// says nothing may slide and [`SWITCHES_PER_INTERFACE_SECOND`] otherwise.
pub(super) fn case(
    name: &'static str,
    stresses: &'static str,
    spec: SystemSpec,
    motion: GroundMotion,
    refs: &[Ref],
) -> StressCase {
    let t_rigid = period_rigid_s(&spec);
    let still = refs.iter().any(|r| matches!(r, Ref::Zero | Ref::Rigid));
    let switch_budget = if still {
        0
    } else {
        (SWITCHES_PER_INTERFACE_SECOND * spec.alpha.len() as f64 * motion.duration_s()).ceil()
            as u64
    };
    StressCase {
        name,
        stresses,
        energy_tolerance: energy_tolerance(t_rigid, motion.dt_s()),
        references: refs.iter().map(|&r| reference(r, t_rigid)).collect(),
        spec,
        motion,
        expect: Expect::Completes,
        max_switches_per_step: ExactOptions::default().max_switches_per_step,
        switch_budget,
    }
}

/// A polyline record sampled at [`DT_S`].
fn polyline_motion(duration_s: f64, points: &[(f64, f64)]) -> GroundMotion {
    GroundMotion::Polyline {
        dt_s: DT_S,
        duration_s,
        points: points.to_vec(),
    }
}

/// Every case of the suite, in the order of the table.
pub fn cases() -> Vec<StressCase> {
    let mut all = record_cases();
    all.extend(parameter_cases());
    all.extend(stack_cases());
    all.extend(sampling_cases());
    all.extend(limit_cases());
    all.push(zeno_case());
    all
}

/// The paper's two-block stack on a structure of period `period_s`.
fn paper(period_s: f64) -> SystemSpec {
    spec(period_s, &[0.5, 0.5], &[0.2, 0.1])
}

/// Zero, tiny and huge records.
fn record_cases() -> Vec<StressCase> {
    vec![
        case(
            "zero-record",
            "zero record, 30 s",
            paper(1.0),
            GroundMotion::Zero {
                dt_s: DT_S,
                duration_s: 30.0,
            },
            &[Ref::Zero],
        ),
        case(
            "record-x1e-12",
            "record scaled by 1e-12",
            paper(1.0),
            quake(1, 40.0, DT_S, Scale::Factor(1e-12)),
            &[Ref::Rigid, Ref::Refined(3)],
        ),
        case(
            "record-x1e3",
            "record scaled by 1e3 (PGA in the hundreds of g)",
            paper(0.5),
            quake(2, 20.0, DT_S, Scale::Factor(1e3)),
            &[Ref::Refined(4), Ref::Rk4(3200)],
        ),
    ]
}

/// Periods, mass ratios and friction coefficients at the ends of their ranges.
fn parameter_cases() -> Vec<StressCase> {
    vec![
        case(
            "stiff-rigid-stack",
            "T_p 0.01 s, μ 5: 5 blocks ride a stiff structure",
            spec(0.01, &[0.2; 5], &[5.0; 5]),
            quake(3, 30.0, DT_S, Scale::PgaG(1.0)),
            &[Ref::Rigid, Ref::Refined(2)],
        ),
        case(
            "stiff-coarse-dt",
            "T_p 0.01 s at dt 0.05 s: 5 periods per sample",
            spec(0.01, &[1.0], &[0.1]),
            quake(4, 40.0, 0.05, Scale::PgaG(0.5)),
            &[Ref::Refined(10), Ref::Rk4(1600)],
        ),
        case(
            "flexible-300s",
            "T_p 20 s, 300 s record",
            spec(20.0, &[0.5, 0.5], &[0.002, 0.001]),
            long_quake(5, 0.5),
            &[Ref::Refined(2)],
        ),
        case(
            "long-period-rigid",
            "T_p 20 s, α 100: T_rigid 201 s",
            spec(20.0, &[100.0], &[5.0]),
            quake(6, 60.0, DT_S, Scale::PgaG(0.5)),
            &[Ref::Rigid, Ref::Refined(2)],
        ),
        case(
            "exact-doc-limit",
            "T_p 5 s, α 12 (exact.rs's example): T_rigid 18 s",
            spec(5.0, &[12.0], &[0.1]),
            quake(7, 40.0, DT_S, Scale::PgaG(0.5)),
            &[Ref::Rigid, Ref::Refined(2)],
        ),
        case(
            "light-block",
            "α 1e-6",
            spec(1.0, &[1e-6], &[0.1]),
            quake(8, 40.0, DT_S, Scale::PgaG(0.5)),
            &[Ref::Refined(4), Ref::Rk4(400)],
        ),
        case(
            "heavy-block",
            "α 100 on T_p 0.5 s",
            spec(0.5, &[100.0], &[0.05]),
            quake(9, 40.0, DT_S, Scale::PgaG(0.8)),
            &[Ref::Refined(4), Ref::Rk4(400)],
        ),
        case(
            "frictionless",
            "μ 0 at every interface",
            spec(0.7, &[0.5, 2.0, 1e-6], &[0.0; 3]),
            quake(11, 40.0, DT_S, Scale::PgaG(0.5)),
            &[Ref::Frictionless, Ref::Refined(2)],
        ),
        case(
            "mu-5",
            "μ 5: nothing slides under 1 g",
            spec(1.0, &[1.0, 1.0], &[5.0, 5.0]),
            quake(12, 40.0, DT_S, Scale::PgaG(1.0)),
            &[Ref::Rigid, Ref::Refined(2)],
        ),
        case(
            "mu-s-25x",
            "μ_s 0.5 = 25 μ_k",
            spec_static(0.5, &[1.0], &[0.02], &[0.5]),
            quake(13, 40.0, DT_S, Scale::PgaG(0.8)),
            &[Ref::Refined(4), Ref::Rk4(400)],
        ),
    ]
}

/// Stacks: many blocks, extreme mass ratios, static far above kinetic.
fn stack_cases() -> Vec<StressCase> {
    let twenty_decreasing = {
        let mu: Vec<f64> = (0..20).map(|i| 0.4 - 0.019 * i as f64).collect();
        spec(1.5, &[0.05; 20], &mu)
    };
    // Mass ratios 1e-3 … 2 and friction 0 … 0.38 scattered over the stack, static 1–4 × kinetic.
    let twenty_mixed = {
        let alpha: Vec<f64> = (0..20)
            .map(|i| 10f64.powf(-3.0 + 3.3 * ((i * 7) % 20) as f64 / 19.0))
            .collect();
        let mu: Vec<f64> = (0..20)
            .map(|i| {
                if i % 7 == 3 {
                    0.0
                } else {
                    0.02 + 0.03 * ((i * 11) % 13) as f64
                }
            })
            .collect();
        let mu_s: Vec<f64> = mu
            .iter()
            .enumerate()
            .map(|(i, m)| m * (1.0 + (i % 4) as f64))
            .collect();
        spec_static(0.3, &alpha, &mu, &mu_s)
    };
    vec![
        case(
            "mass-ratios-1e8",
            "α 100, 1e-6, 1 in one stack",
            spec(0.5, &[100.0, 1e-6, 1.0], &[0.3, 0.05, 0.2]),
            quake(10, 40.0, DT_S, Scale::PgaG(0.8)),
            &[Ref::Refined(4)],
        ),
        case(
            "stack-mu-s-10x",
            "3 blocks, μ_s 10–15 × μ_k",
            spec_static(
                1.0,
                &[0.5, 0.3, 0.2],
                &[0.03, 0.02, 0.01],
                &[0.3, 0.2, 0.15],
            ),
            quake(14, 40.0, DT_S, Scale::PgaG(1.0)),
            &[Ref::Refined(4)],
        ),
        case(
            "twenty-decreasing",
            "20 blocks, μ falling upward (internal slips), 300 s",
            twenty_decreasing,
            long_quake(15, 0.6),
            &[Ref::Refined(2)],
        ),
        case(
            "twenty-mixed",
            "20 blocks, α 1e-3–2, μ 0–0.38, μ_s up to 4 μ_k",
            twenty_mixed,
            quake(16, 40.0, DT_S, Scale::PgaG(0.8)),
            &[Ref::Refined(2)],
        ),
    ]
}

/// Sample intervals and record lengths at the ends of their ranges.
fn sampling_cases() -> Vec<StressCase> {
    vec![
        case(
            "fine-dt",
            "dt 0.0005 s",
            paper(0.2),
            quake(17, 20.0, 0.0005, Scale::PgaG(0.6)),
            &[Ref::Refined(2)],
        ),
        case(
            "coarse-dt",
            "dt 0.05 s",
            paper(1.0),
            quake(18, 60.0, 0.05, Scale::PgaG(0.6)),
            &[Ref::Refined(5), Ref::Rk4(500)],
        ),
        case(
            "record-300s",
            "300 s record",
            paper(1.0),
            long_quake(19, 0.5),
            &[Ref::Refined(2)],
        ),
    ]
}

/// Ground motion at, around and stepping past `μ·g`, and a demand held exactly at the limit.
fn limit_cases() -> Vec<StressCase> {
    let g = G;
    let step_accel = 0.6 * g;
    vec![
        case(
            "graze-mu-g",
            "a_g ramps to exactly μ·g over 2 s and back (T_p 0.01 s)",
            spec(0.01, &[1.0], &[0.3]),
            polyline_motion(6.0, &[(0.0, 0.0), (2.0, 0.3 * g), (4.0, 0.0)]),
            &[Ref::Refined(4)],
        ),
        case(
            "hold-mu-g-stiff",
            "a_g held at exactly μ·g for 99 s: the loose block coasts (T_p 0.01 s)",
            spec(0.01, &[1.0], &[0.3]),
            polyline_motion(100.0, &[(0.0, 0.0), (1.0, 0.3 * g)]),
            &[Ref::Refined(2)],
        ),
        case(
            "hold-mu-g-flexible",
            "a_g held at exactly μ·g for 99 s: the loose block coasts (T_p 0.5 s)",
            spec(0.5, &[1.0], &[0.3]),
            polyline_motion(100.0, &[(0.0, 0.0), (1.0, 0.3 * g)]),
            &[Ref::Refined(2)],
        ),
        case(
            "stack-at-limit",
            "μ_2 = μ_1: the top interface's demand sits at μ_2·N_2 while block 1 slips",
            spec(1.0, &[0.5, 0.5], &[0.15, 0.15]),
            quake(20, 40.0, DT_S, Scale::PgaG(0.6)),
            &[Ref::OneBlock, Ref::Refined(2)],
        ),
        case(
            "stack-at-limit-hold",
            "as above for 99 s: a_g held at 0.5 g, μ 0.3 (T_p 0.01 s)",
            spec(0.01, &[0.5, 0.5], &[0.3, 0.3]),
            polyline_motion(100.0, &[(0.0, 0.0), (1.0, 0.5 * g)]),
            &[Ref::OneBlock, Ref::Refined(2)],
        ),
        case(
            "step-hand",
            "a_g steps to 0.6 g: μ_s 0.4, μ_k 0.2 (T_p 0.01 s)",
            spec_static(0.01, &[1.0], &[0.2], &[0.4]),
            GroundMotion::Polyline {
                dt_s: 0.005,
                duration_s: 10.0,
                points: vec![(0.0, 0.0), (0.5, 0.0), (0.505, step_accel)],
            },
            &[
                Ref::StepHand {
                    step_s: 0.5,
                    accel_mps2: step_accel,
                },
                Ref::Refined(4),
            ],
        ),
        case(
            "square-steps",
            "a_g steps between ±0.4 g every 0.5 s",
            paper(1.0),
            GroundMotion::Square {
                dt_s: DT_S,
                duration_s: 30.0,
                amplitude_mps2: 0.4 * g,
                half_period_s: 0.5,
            },
            &[Ref::Refined(4), Ref::Rk4(1600)],
        ),
        case(
            "resonant-sine",
            "0.1 g sine at 1/T_rigid for 60 s",
            spec(1.0, &[0.5, 0.5], &[0.05, 0.03]),
            GroundMotion::Sine {
                dt_s: DT_S,
                duration_s: 60.0,
                amplitude_mps2: 0.1 * g,
                frequency_hz: 1.0 / 2f64.sqrt(),
            },
            &[Ref::Refined(2), Ref::Rk4(400)],
        ),
    ]
}

/// The one case built to trip the switch guard: a limit of one switch per sample on a stack
/// that switches several times within a sample; the run must stop with
/// [`slidestack::dynamics::SimError::Zeno`].
fn zeno_case() -> StressCase {
    StressCase {
        expect: Expect::Zeno,
        max_switches_per_step: 1,
        ..case(
            "zeno-guard",
            "a guard of 1 switch per sample on 3 blocks under ±2 g steps at dt 0.05 s",
            spec(0.5, &[0.5, 0.3, 0.2], &[0.3, 0.2, 0.1]),
            GroundMotion::Square {
                dt_s: 0.05,
                duration_s: 10.0,
                amplitude_mps2: 2.0 * G,
                half_period_s: 0.05,
            },
            &[],
        )
    }
}
