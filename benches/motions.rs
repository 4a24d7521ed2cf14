//! Ground-motion benchmark: response spectra and spectral matching, printed as tables.
//!
//! * Spectrum: 100 log-spaced periods (0.05–4 s) of a 6000-sample record, the exact spectrum
//!   (peaks between samples, eight lanes) against the textbook scalar loop over the samples
//!   only, timed in the same run; the ratio is the figure of merit.
//! * Matching: the eleven FEMA P695 fixtures matched to IS 1893 soil I, zones III and V, with the
//!   default settings, on one thread: time per record, iterations, worst misfit on the
//!   200-period check grid, drift, and the figure of merit, the time in units of one exact
//!   spectrum of the same record on the 200 check periods timed in the same run (a matching that
//!   needs fewer spectra' worth of work is faster on any machine).
//!
//! `cargo bench --bench motions`; `SLIDESTACK_BENCH_QUICK=1` runs three records only.

use slidestack::ground_motion::matching::{MatchSettings, log_space, match_record};
use slidestack::ground_motion::read_record;
use slidestack::spectrum::TargetSpectrum;
use slidestack::spectrum::response::{response_spectrum, sampled_peak};
use std::hint::black_box;
use std::time::Instant;

#[path = "../tests/common/mod.rs"]
mod common;
use common::{ELEVEN, fixture};

/// Median wall time of `reps` runs of `f`, s.
fn time(reps: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..reps)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[reps / 2]
}

fn spectrum_table() {
    // RSN1602 (Duzce) has 5590 samples: extend to 6000 with its own start, as the brief's case.
    let rec = read_record(&fixture("RSN1602_DUZCE_BOL090.AT2")).unwrap();
    let mut accel = rec.accel_mps2(1.0);
    let extra: Vec<f64> = accel[..6000 - accel.len()].to_vec();
    accel.extend(extra);
    let periods = log_space(0.05, 4.0, 100);
    let exact = time(21, || {
        black_box(response_spectrum(&accel, rec.dt_s, &periods, 0.05).unwrap());
    });
    let sampled = time(21, || {
        for &t in &periods {
            black_box(sampled_peak(&accel, rec.dt_s, t, 0.05));
        }
    });
    println!("\nResponse spectrum, 100 periods × 6000 samples, ζ = 0.05 (median of 21 runs)");
    println!("| method | time (ms) | ns per period-sample | ratio to scalar loop |");
    println!("|---|---|---|---|");
    for (name, t) in [
        ("exact, peaks between samples, 8 lanes", exact),
        ("scalar Nigam–Jennings loop, samples only", sampled),
    ] {
        println!(
            "| {name} | {:.3} | {:.2} | {:.2} |",
            t * 1e3,
            t * 1e9 / 600_000.0,
            t / sampled
        );
    }
}

fn matching_table(quick: bool) {
    let settings = MatchSettings::default();
    let check = settings.check_grid_s();
    let names: &[&str] = if quick { &ELEVEN[..3] } else { &ELEVEN };
    println!("\nSpectral matching to IS 1893:2016 soil I (Z·Sa/g), default settings, one thread");
    println!(
        "| zone | record | samples | time (ms) | in spectra | iterations | attempts | worst misfit | converged | PGA before→after (g) | final v (m/s) | final d (m) | Arias ratio |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mut total = 0.0;
    let mut in_spectra = Vec::new();
    for zone in ["III", "V"] {
        let target: TargetSpectrum = format!("is1893:zone={zone},soil=I").parse().unwrap();
        for name in names {
            let rec = read_record(&fixture(name)).unwrap();
            let spectrum = time(5, || {
                black_box(response_spectrum(&rec.accel_g, rec.dt_s, &check, 0.05).unwrap());
            });
            let start = Instant::now();
            let m = match_record(&rec.accel_g, rec.dt_s, &target, &settings).unwrap();
            let t = start.elapsed().as_secs_f64();
            total += t;
            in_spectra.push(t / spectrum);
            let r = &m.report;
            println!(
                "| {zone} | {name} | {} | {:.1} | {:.0} | {} | {} | {:.3} | {} | {:.3}→{:.3} | {:.2e} | {:.2e} | {:.2} |",
                rec.accel_g.len(),
                t * 1e3,
                t / spectrum,
                r.iterations,
                r.attempts,
                r.worst_misfit,
                r.converged,
                r.pga_before_g,
                r.pga_after_g,
                r.final_velocity_mps,
                r.final_displacement_m,
                r.arias_ratio
            );
        }
    }
    in_spectra.sort_by(f64::total_cmp);
    println!(
        "\nmean time per record: {:.1} ms; matching costs a median {:.0} exact spectra of its \
         record (200 periods), {:.0}–{:.0}",
        total * 1e3 / in_spectra.len() as f64,
        in_spectra[in_spectra.len() / 2],
        in_spectra[0],
        in_spectra[in_spectra.len() - 1]
    );
}

fn main() {
    let quick = std::env::var_os("SLIDESTACK_BENCH_QUICK").is_some();
    spectrum_table();
    // Matching is compared per record on one thread (as against REQPY), its baseline too.
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool")
        .install(|| matching_table(quick));
}
