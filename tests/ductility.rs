//! Constant-ductility spectra (`spectrum::ductility`, Chopra Section 7.5) against their known
//! limits: `μ = 1` is the elastic spectrum, the strength found has the target ductility, short
//! periods need the elastic strength and long ones follow equal displacement, and where several
//! strengths give the target the largest is taken.

mod common;

use common::{eleven_records, fixture};
use slidestack::dynamics::{ExactOptions, G, Ground, System, SystemSpec, Yielding, simulate_exact};
use slidestack::ground_motion::read_record;
use slidestack::spectrum::ductility::{DuctilityOptions, constant_ductility_spectrum};
use slidestack::spectrum::response_spectrum;

const EPP: DuctilityOptions = DuctilityOptions {
    damping: 0.05,
    post_yield_ratio: 0.0,
};

/// `μ = 1` gives `C_y = C_e`, the elastic pseudo-acceleration, computed here by the exact
/// integrator; the oracle is the φ-function Nigam–Jennings spectrum (`spectrum::response`), an
/// independent exact method. Tolerance 1e-12 relative (both exact to round-off; measured 4e-14
/// over the eleven records).
#[test]
fn unit_ductility_is_the_elastic_spectrum() {
    let periods = [0.05, 0.2, 0.5, 1.0, 2.0, 3.0];
    let mut worst = 0.0f64;
    for rec in eleven_records() {
        let a = rec.accel_mps2(1.0);
        let one = constant_ductility_spectrum(&a, rec.dt_s, &periods, 1.0, EPP).unwrap();
        let psa = response_spectrum(&a, rec.dt_s, &periods, 0.05)
            .unwrap()
            .psa_g();
        for (p, want) in one.iter().zip(&psa) {
            let rel = (p.strength_ratio / want - 1.0).abs();
            worst = worst.max(rel);
            assert!(rel < 1e-12, "{} T={}: {rel:e}", rec.name, p.period_s);
            assert_eq!(p.reduction_factor, 1.0);
            assert_eq!(p.ductility, 1.0);
        }
    }
    eprintln!("μ = 1 against the elastic spectrum: worst {worst:.1e}");
}

/// The strength returned has the target ductility: an independent run of the exact integrator
/// at that `C_y` gives `u_m/u_y` within 1e-8 of the target (the bisection stops at 1e-10 in
/// `C_y`), for EPP and bilinear oscillators.
#[test]
fn the_strength_found_has_the_target_ductility() {
    let rec = read_record(&fixture("RSN1602_DUZCE_BOL090.AT2")).unwrap();
    let a = rec.accel_mps2(1.0);
    let ground = Ground {
        dt_s: rec.dt_s,
        accel_mps2: &a,
    };
    let periods = [0.1, 0.4, 1.0, 2.5];
    for r in [0.0, 0.05] {
        let opts = DuctilityOptions {
            damping: 0.05,
            post_yield_ratio: r,
        };
        for mu in [1.5, 2.0, 4.0, 8.0] {
            for p in constant_ductility_spectrum(&a, rec.dt_s, &periods, mu, opts).unwrap() {
                let mut spec = SystemSpec::new(p.period_s, &[], &[]);
                spec.damping_ratio = 0.05;
                let sys = System::new(&spec)
                    .unwrap()
                    .with_yielding(Yielding::bilinear(p.strength_ratio, r))
                    .unwrap();
                let got = simulate_exact(&sys, &ground, &ExactOptions::default()).unwrap();
                let reached = got.ductility.unwrap();
                assert!(
                    (reached - mu).abs() < 1e-8 * mu,
                    "r={r} μ={mu} T={}: {reached}",
                    p.period_s
                );
                assert_eq!(reached, p.ductility);
                let uy = p.strength_ratio * G / (std::f64::consts::TAU / p.period_s).powi(2);
                assert!((p.yield_displacement_m - uy).abs() < 1e-14 * uy);
                assert!((p.peak_displacement_m - mu * uy).abs() < 1e-8 * mu * uy);
            }
        }
    }
}

/// The known limits of `R_y = C_e/C_y` (Chopra, Section 7.6): a very stiff oscillator moves with
/// the ground, whatever its strength, so `R_y → 1` (measured at `T = 0.01 s`: mean over the
/// eleven records 1.04, 1.06, 1.10 for `μ = 2, 4, 8`); at long periods the peak displacement of
/// the yielding oscillator is about the elastic one (equal displacement), so `R_y ≈ μ`
/// (measured mean `R_y/μ` 1.06–1.10 at `T = 3` and 5 s for `μ = 2` and 4, single records 0.6–1.8).
/// Asserted: mean `R_y` below 1.15 at 0.01 s; mean `R_y/μ` within 0.9–1.2 at 3 and 5 s.
#[test]
fn short_periods_need_the_elastic_strength_long_ones_follow_equal_displacement() {
    let records = eleven_records();
    let mean_over_records = |t: f64, mu: f64| {
        records
            .iter()
            .map(|rec| {
                let a = rec.accel_mps2(1.0);
                constant_ductility_spectrum(&a, rec.dt_s, &[t], mu, EPP).unwrap()[0]
                    .reduction_factor
            })
            .sum::<f64>()
            / records.len() as f64
    };
    for mu in [2.0, 4.0, 8.0] {
        let r = mean_over_records(0.01, mu);
        eprintln!("T = 0.01 s, μ = {mu}: mean R_y {r:.3}");
        assert!((1.0..1.15).contains(&r), "μ={mu}: {r}");
    }
    for t in [3.0, 5.0] {
        for mu in [2.0, 4.0] {
            let ratio = mean_over_records(t, mu) / mu;
            eprintln!("T = {t} s, μ = {mu}: mean R_y/μ {ratio:.3}");
            assert!((0.9..1.2).contains(&ratio), "T={t} μ={mu}: {ratio}");
        }
    }
}

/// Where several strengths give the target ductility, the largest is returned. The cases are
/// from a scan of `μ(f̄_y)` in 0.5 % steps over the eleven records (three crossings each); the
/// returned `f̄_y` must lie in the highest crossing's step, and a lower crossing is confirmed by
/// a sign change of `μ − μ_target` across its step.
#[test]
fn the_largest_of_several_strengths_is_taken() {
    // (record, T_p, μ, highest crossing's step, a lower crossing's step) in f̄_y.
    let cases = [
        (
            "RSN725_SUPERST_B-POE270.AT2",
            0.7,
            4.0,
            (0.4462, 0.4485),
            (0.2758, 0.2772),
        ),
        (
            "RSN1111_KOBE_NIS000.AT2",
            1.5,
            2.0,
            (0.6696, 0.6730),
            (0.5264, 0.5291),
        ),
        (
            "RSN68_SFERN_PEL090.AT2",
            0.3,
            1.5,
            (0.6832, 0.6867),
            (0.4786, 0.4811),
        ),
    ];
    for (name, t, mu, top, lower) in cases {
        let rec = read_record(&fixture(name)).unwrap();
        let a = rec.accel_mps2(1.0);
        let p = constant_ductility_spectrum(&a, rec.dt_s, &[t], mu, EPP).unwrap()[0];
        let f = 1.0 / p.reduction_factor;
        assert!(
            f > top.0 && f < top.1,
            "{name} T={t} μ={mu}: f̄_y = {f}, expected in {top:?}"
        );
        let ground = Ground {
            dt_s: rec.dt_s,
            accel_mps2: &a,
        };
        let mu_at = |fbar: f64| {
            let mut spec = SystemSpec::new(t, &[], &[]);
            spec.damping_ratio = 0.05;
            let sys = System::new(&spec)
                .unwrap()
                .with_yielding(Yielding::epp(fbar * p.elastic_strength_ratio))
                .unwrap();
            simulate_exact(&sys, &ground, &ExactOptions::default())
                .unwrap()
                .ductility
                .unwrap()
        };
        let (m_lo, m_hi) = (mu_at(lower.0), mu_at(lower.1));
        assert!(
            (m_lo - mu) * (m_hi - mu) < 0.0,
            "{name}: no second strength with μ = {mu} in {lower:?} ({m_lo}, {m_hi})"
        );
    }
}
