//! Criterion bench of the linear building kernel (`LinearBuilding`) against the event-driven
//! integrator (`simulate_building`) on the same linear building: 3, 6 and 20 storeys with 0.3 of
//! two stacks attached (the building of a `λ` evaluation: `C` not classical for its masses),
//! one thread, one real record (RSN960, 1999 samples at 0.01 s). Criterion's throughput is
//! record samples, so `1e9 / (elements per second)` is the time per sample; the ratio of the
//! `exact/N` and `kernel/N` rows of one run is the kernel's speed-up (every output: floor
//! displacements and accelerations, drifts, storey shears, overturning moment);
//! `base_shear/N` is the base shear alone (what a `λ` evaluation needs); `new/N` is the
//! kernel's set-up (modal basis and output rows), paid once per building; `records/N` is the
//! base shear under each of the eleven FEMA P-695 records of the study's seeds (their first
//! passes four records at a time, `LinearBuilding::peaks_of_records`), its throughput their
//! samples together.
//!
//! `cargo bench --bench linear`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use slidestack::dynamics::building::{
    Building, BuildingSpec, LinearBuilding, LinearOutput, StackSpec, simulate_building,
};
use slidestack::dynamics::{ExactOptions, Ground};
use slidestack::ground_motion::read_record;
use std::hint::black_box;

#[path = "../tests/common/mod.rs"]
mod common;

fn linear(c: &mut Criterion) {
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
    let mut g = c.benchmark_group("linear");
    g.throughput(Throughput::Elements(accel.len() as u64));
    let mut rows = Vec::new();
    for (n, period_s) in [(3, 0.6), (6, 0.8), (20, 2.0)] {
        let mut spec = BuildingSpec::uniform(n, period_s);
        spec.stacks = vec![
            StackSpec::new(n, &[0.5, 0.5], &[0.2, 0.1]),
            StackSpec::new(n.div_ceil(2), &[1.0], &[0.15]),
        ];
        let b = Building::new(&spec)
            .unwrap()
            .with_stacks_attached_fraction(0.3);
        let lin = LinearBuilding::new(&b).unwrap();
        g.bench_function(format!("kernel/{n}"), |bn| {
            bn.iter(|| black_box(lin.run(&ground).unwrap()))
        });
        g.bench_function(format!("base_shear/{n}"), |bn| {
            bn.iter(|| black_box(lin.peak_base_shear_n(&ground).unwrap()))
        });
        g.bench_function(format!("exact/{n}"), |bn| {
            bn.iter(|| black_box(simulate_building(&b, &ground, &opts).unwrap()))
        });
        g.bench_function(format!("new/{n}"), |bn| {
            bn.iter(|| black_box(LinearBuilding::new(&b).unwrap()))
        });
        rows.push((n, lin));
    }
    g.finish();

    let eleven: Vec<(f64, Vec<f64>)> = (common::eleven_records().iter())
        .map(|r| (r.dt_s, r.accel_mps2(1.0)))
        .collect();
    let grounds: Vec<Ground> = (eleven.iter())
        .map(|(dt_s, a)| Ground::new(*dt_s, a))
        .collect();
    let mut g = c.benchmark_group("linear");
    g.throughput(Throughput::Elements(
        eleven.iter().map(|(_, a)| a.len() as u64).sum(),
    ));
    for (n, lin) in &rows {
        let base = lin.select(&[LinearOutput::StoreyShear(0)]);
        g.bench_function(format!("records/{n}"), |bn| {
            bn.iter(|| black_box(lin.peaks_of_records(&base, &grounds).unwrap()))
        });
    }
    g.finish();
}

criterion_group!(benches, linear);
criterion_main!(benches);
