//! Response spectra against an independent exact reference: the 4×4 matrix exponential of the
//! oscillator with a linear load (`common::sdof_oracle`), with its peaks located by bisection.

mod common;

use common::{max_rel_diff, real_records, sdof_oracle};
use slidestack::dynamics::G;
use slidestack::sdof::Step;
use slidestack::spectrum::response::sampled_peak;
use slidestack::spectrum::{peak_response, response_spectrum};
use std::f64::consts::TAU;

/// Linear interpolation onto `dt/m`: the same piecewise-linear ground motion, so the oracle's
/// bisection (which looks for velocity sign changes between samples) sees every peak when the
/// sub-step is short against the period.
fn refine(accel: &[f64], m: usize) -> Vec<f64> {
    let mut out = Vec::with_capacity((accel.len() - 1) * m + 1);
    for w in accel.windows(2) {
        for i in 0..m {
            out.push(w[0] + (w[1] - w[0]) * i as f64 / m as f64);
        }
    }
    out.push(*accel.last().unwrap());
    out
}

#[test]
fn recurrence_equals_matrix_exponential_at_every_sample() {
    // Over the whole ωh range of a study (T from 0.02 s to 20 s, dt 0.005–0.02 s) and damping
    // 0, 5 % and 50 %, the displacement history equals the oracle's to 5e-11 of its peak: both
    // are exact, the difference is round-off accumulated over ~3000 steps, which an undamped
    // oscillator never forgets (largest seen: 1.3e-11 at ζ = 0, T = 0.1 s; the step
    // coefficients themselves equal the textbook closed form to 1e-15, a unit test in
    // `spectrum::response`).
    for rec in real_records() {
        let accel = rec.accel_mps2(1.0);
        for &period in &[0.02, 0.1, 1.0, 4.0, 20.0] {
            for &zeta in &[0.0, 0.05, 0.5] {
                let w = TAU / period;
                let oracle = sdof_oracle(w, zeta, rec.dt_s, &accel);
                let step = Step::new(w, zeta, rec.dt_s);
                let mut u = vec![0.0];
                let (mut x, mut v) = (0.0, 0.0);
                for s in accel.windows(2) {
                    (x, v) = step.step(x, v, s[0], s[1]);
                    u.push(x);
                }
                let scale = oracle.peak;
                let err = max_rel_diff(&u, &oracle.displacement, scale);
                assert!(err < 5e-11, "{} T={period} ζ={zeta}: {err:e}", rec.name);
            }
        }
    }
}

#[test]
fn spectrum_equals_oracle_peaks_on_real_records() {
    // Peaks, including those between samples, equal the oracle's to 1e-10 relative. For short
    // periods the oracle runs on the record refined to at most T/16 per sub-step (exact, see
    // `refine`) so that its velocity-sign test cannot miss a peak.
    let periods = [
        0.03, 0.05, 0.1, 0.2, 0.3, 0.5, 0.75, 1.0, 2.0, 4.0, 8.0, 15.0,
    ];
    for rec in real_records() {
        let accel = rec.accel_mps2(1.0);
        let spec = response_spectrum(&accel, rec.dt_s, &periods, 0.05).unwrap();
        for (i, &period) in periods.iter().enumerate() {
            let m = (16.0 * rec.dt_s / period).ceil().max(1.0) as usize;
            let fine = refine(&accel, m);
            let oracle = sdof_oracle(TAU / period, 0.05, rec.dt_s / m as f64, &fine);
            let got = spec.peaks[i].sd_m;
            let rel = (got - oracle.peak).abs() / oracle.peak;
            assert!(
                rel < 1e-10,
                "{} T={period}: {got} vs {} ({rel:e})",
                rec.name,
                oracle.peak
            );
            // The peak's time and sign are those of the displacement there.
            let t = spec.peaks[i].time_s;
            assert!((0.0..=rec.duration_s() + 1e-9).contains(&t));
            assert_eq!(spec.peaks[i].u_m.abs(), got);
        }
    }
}

#[test]
fn sampling_alone_is_low_and_the_exact_peak_is_not() {
    // At T = 0.05 s and dt = 0.02 s the sampled peak can be low by up to 1 − cos(π·dt/T) = 69 %.
    // Independent reference: the oracle's displacement at every sample of the record refined to
    // at most T/200 per sub-step (the same piecewise-linear motion), whose largest magnitude is
    // low by at most 1 − cos(π/200) = 1.2e-4. The exact peak lies within that of it, never
    // below it; the peak of the record's own samples falls well short somewhere.
    let mut shortfall = 0.0f64;
    for rec in real_records() {
        let accel = rec.accel_mps2(1.0);
        for &period in &[0.04, 0.05, 0.07, 0.1] {
            let m = (200.0 * rec.dt_s / period).ceil() as usize;
            let fine = refine(&accel, m);
            let oracle = sdof_oracle(TAU / period, 0.05, rec.dt_s / m as f64, &fine);
            let fine_peak = oracle
                .displacement
                .iter()
                .fold(0.0f64, |p, u| p.max(u.abs()));
            let exact = peak_response(&accel, rec.dt_s, period, 0.05).unwrap().sd_m;
            assert!(
                exact >= fine_peak * (1.0 - 1e-10) && exact <= fine_peak * (1.0 + 1.3e-4),
                "{} T={period}: exact {exact} vs fine-sampled {fine_peak}",
                rec.name
            );
            let sampled = sampled_peak(&accel, rec.dt_s, period, 0.05);
            shortfall = shortfall.max(1.0 - sampled / fine_peak);
        }
    }
    assert!(
        shortfall > 0.01,
        "sampling alone is low by at most {shortfall}"
    );
}

#[test]
fn lanes_do_not_change_results() {
    // Periods advance four at a time; each result is bit-identical to computing it alone.
    let rec = &real_records()[1];
    let accel = rec.accel_mps2(1.0);
    let periods: Vec<f64> = (1..=11).map(|i| 0.1 * i as f64 * i as f64).collect();
    let all = response_spectrum(&accel, rec.dt_s, &periods, 0.05).unwrap();
    for (i, &t) in periods.iter().enumerate() {
        let one = peak_response(&accel, rec.dt_s, t, 0.05).unwrap();
        assert_eq!(one, all.peaks[i]);
    }
}

#[test]
fn short_period_limit_is_the_peak_ground_acceleration() {
    // A very stiff oscillator follows the ground: PSA → PGA. What remains is the ringing at the
    // kinks of the piecewise-linear record: a slope change Δr leaves a free vibration of
    // pseudo-acceleration Δr/ω, so |PSA − PGA| stays within a few times max|Δr|/ω.
    let w = TAU / 0.001;
    for rec in real_records() {
        let accel = rec.accel_mps2(1.0);
        let spec = response_spectrum(&accel, rec.dt_s, &[0.001], 0.05).unwrap();
        let psa = spec.psa_g()[0];
        let ring_g = accel
            .windows(3)
            .map(|s| (s[2] - 2.0 * s[1] + s[0]).abs() / rec.dt_s)
            .fold(0.0, f64::max)
            / w
            / G;
        let diff = (psa - rec.pga_g()).abs();
        assert!(
            diff < 3.0 * ring_g,
            "{}: PSA {psa} vs PGA {} (ring {ring_g})",
            rec.name,
            rec.pga_g()
        );
        assert!(diff < 0.01 * rec.pga_g());
        let psv = spec.psv_mps()[0];
        assert!((psv * TAU / 0.001 / G - psa).abs() < 1e-12 * psa);
    }
}
