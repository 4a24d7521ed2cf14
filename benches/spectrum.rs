//! Criterion bench of the exact response spectrum against the scalar recurrence, one thread.
//!
//! The case of the issue: 100 log-spaced periods (0.05–4 s), 5 % damping, a 6000-sample real
//! record (RSN1602 Duzce, 5590 samples, extended with its own first 410). Two measurements in the
//! same run:
//! * `exact`: `response_spectrum` (peaks between samples included) in a one-thread rayon pool;
//! * `scalar_recurrence`: the textbook Nigam–Jennings loop over the samples only, one period after
//!   another (`sampled_peak`), the baseline the exact spectrum is compared with.
//!
//! `cargo bench --bench spectrum`; the ratio of the two medians is the figure of merit.

use criterion::{Criterion, criterion_group, criterion_main};
use slidestack::ground_motion::matching::log_space;
use slidestack::ground_motion::read_record;
use slidestack::spectrum::response::{response_spectrum, sampled_peak};
use std::hint::black_box;

#[path = "../tests/common/mod.rs"]
mod common;

fn record_6000() -> (Vec<f64>, f64) {
    let rec = read_record(&common::fixture("RSN1602_DUZCE_BOL090.AT2")).unwrap();
    let mut accel = rec.accel_mps2(1.0);
    let extra: Vec<f64> = accel[..6000 - accel.len()].to_vec();
    accel.extend(extra);
    (accel, rec.dt_s)
}

fn spectrum(c: &mut Criterion) {
    let (accel, dt) = record_6000();
    let periods = log_space(0.05, 4.0, 100);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut g = c.benchmark_group("spectrum_100_periods_6000_samples");
    // Elements: oscillator-samples (periods × record samples).
    g.throughput(criterion::Throughput::Elements(
        (periods.len() * accel.len()) as u64,
    ));
    g.bench_function("exact", |b| {
        b.iter(|| {
            pool.install(|| black_box(response_spectrum(&accel, dt, &periods, 0.05).unwrap()))
        })
    });
    g.bench_function("scalar_recurrence", |b| {
        b.iter(|| {
            for &t in &periods {
                black_box(sampled_peak(&accel, dt, t, 0.05));
            }
        })
    });
    g.finish();
}

criterion_group!(benches, spectrum);
criterion_main!(benches);
