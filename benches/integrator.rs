//! Criterion bench of the exact integrators per regime, one thread, one real record (RSN960,
//! Northridge, 1999 samples at 0.01 s): criterion's throughput is record samples, so
//! `1e9 / (elements per second)` is the time per simulated sample, the figure the sweep prints.
//!
//! * `sdof/*`: the one-storey integrator (`simulate_exact`) as the sweep runs it (no energy
//!   balance): a stack that never slides, the paper's Section 7.1 case (sliding), the same on a
//!   yielding structure, and a long period (`T_p` = 20 s, the φ-function branch);
//! * `building/*`: the multi-storey integrator (`simulate_building`) on the same record: the
//!   Section 7.1 case on one storey (the general modal path, against `sdof/sliding`), three
//!   storeys with two stacks on different floors, elastic and yielding, and six, ten and twenty
//!   storeys with a stack on the roof and one half-way up.
//!
//! `cargo bench --bench integrator`; ratios between rows of one run are the figures of merit.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use slidestack::dynamics::building::{
    Building, BuildingSpec, DampingBasis, StackSpec, StoreyYielding, simulate_building,
};
use slidestack::dynamics::{ExactOptions, Ground, System, SystemSpec, Yielding, simulate_exact};
use slidestack::ground_motion::read_record;
use std::hint::black_box;

#[path = "../tests/common/mod.rs"]
mod common;

fn integrators(c: &mut Criterion) {
    let rec = read_record(&common::fixture("RSN960_NORTHR_LOS270.AT2")).unwrap();
    let accel = rec.accel_mps2(1.0);
    let ground = Ground {
        dt_s: rec.dt_s,
        accel_mps2: &accel,
    };
    let opts = ExactOptions {
        energy_balance: false,
        abs_velocity: false,
        ..ExactOptions::default()
    };
    let mut g = c.benchmark_group("integrator");
    g.throughput(Throughput::Elements(accel.len() as u64));

    let sdof = |tp: f64, mu: [f64; 2], y: Option<Yielding>| {
        let mut spec = SystemSpec::new(tp, &[0.5, 0.5], &mu);
        spec.damping_ratio = 0.05 * 2f64.sqrt();
        let sys = System::new(&spec).unwrap();
        match y {
            Some(y) => sys.with_yielding(y).unwrap(),
            None => sys,
        }
    };
    for (name, sys) in [
        ("sdof/stuck", sdof(1.0, [5.0, 5.0], None)),
        ("sdof/sliding", sdof(1.0, [0.2, 0.1], None)),
        (
            "sdof/yielding",
            sdof(1.0, [0.2, 0.1], Some(Yielding::bilinear(0.15, 0.05))),
        ),
        ("sdof/long_period", sdof(20.0, [0.2, 0.1], None)),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| black_box(simulate_exact(&sys, &ground, &opts).unwrap()))
        });
    }

    let mut one = BuildingSpec::uniform(1, 1.0);
    one.stacks = vec![StackSpec::new(1, &[0.5, 0.5], &[0.2, 0.1])];
    let mut three = BuildingSpec::uniform(3, 0.6);
    three.storey_stiffnesses = vec![3.0, 2.0, 1.0];
    three.damping_basis = DampingBasis::Rigid;
    three.stacks = vec![
        StackSpec::new(3, &[0.5, 0.5], &[0.2, 0.1]),
        StackSpec::new(1, &[1.0], &[0.3]),
    ];
    let mut three_yielding = three.clone();
    three_yielding.yielding = Some(StoreyYielding {
        strength_ratios: vec![0.15, 0.12, 0.1],
        post_yield_ratio: 0.05,
    });
    let storeys = |n: usize, period_s: f64| {
        let mut b = BuildingSpec::uniform(n, period_s);
        b.stacks = vec![
            StackSpec::new(n, &[0.5, 0.5], &[0.2, 0.1]),
            StackSpec::new(n.div_ceil(2), &[1.0], &[0.15]),
        ];
        b
    };
    let mut twenty = BuildingSpec::uniform(20, 2.0);
    twenty.stacks = vec![
        StackSpec::new(20, &[0.5, 0.5], &[0.2, 0.1]),
        StackSpec::new(10, &[1.0], &[0.15]),
    ];
    for (name, spec) in [
        ("building/1_storey_sliding", one),
        ("building/3_storeys_2_stacks", three),
        ("building/3_storeys_2_stacks_yielding", three_yielding),
        ("building/6_storeys_2_stacks", storeys(6, 0.8)),
        ("building/10_storeys_2_stacks", storeys(10, 1.2)),
        ("building/20_storeys_2_stacks", twenty),
    ] {
        let b = Building::new(&spec).unwrap();
        g.bench_function(name, |bn| {
            bn.iter(|| black_box(simulate_building(&b, &ground, &opts).unwrap()))
        });
    }
    g.finish();
}

criterion_group!(benches, integrators);
criterion_main!(benches);
