//! Digital Butterworth filter sections (the high-pass baseline correction of
//! [`crate::ground_motion::process`]).

use std::f64::consts::PI;

/// A second-order (or, with `b2 = a2 = 0`, first-order) digital filter section,
/// `H(z) = (b0 + b1 z⁻¹ + b2 z⁻²)/(1 + a1 z⁻¹ + a2 z⁻²)`.
#[derive(Debug, Clone, Copy)]
pub struct Biquad {
    pub b0: f64,
    pub b1: f64,
    pub b2: f64,
    pub a1: f64,
    pub a2: f64,
}

impl Biquad {
    /// Filters `x` in place from zero initial state (direct form II transposed).
    pub fn run(&self, x: &mut [f64]) {
        let (mut z1, mut z2) = (0.0, 0.0);
        for v in x.iter_mut() {
            let u = *v;
            let y = self.b0 * u + z1;
            z1 = self.b1 * u - self.a1 * y + z2;
            z2 = self.b2 * u - self.a2 * y;
            *v = y;
        }
    }
}

/// Sections of a digital Butterworth high-pass of `order` poles with its corner at `corner_hz`
/// for the step `dt`: bilinear transform of the analog prototype with the corner prewarped,
/// `K = tan(π·fc·dt)`. Each analog pair `s²/(s² + s·ωc/Q + ωc²)`, `1/(2Q) = sin((2k−1)π/(2n))`,
/// becomes `(1 − z⁻¹)²/((1 + K/Q + K²) + 2(K² − 1)z⁻¹ + (1 − K/Q + K²)z⁻²)`; an odd order adds the
/// real pole `s/(s + ωc)` → `(1 − z⁻¹)/((1 + K) + (K − 1)z⁻¹)`.
pub fn butterworth_high_pass(corner_hz: f64, order: usize, dt: f64) -> Vec<Biquad> {
    let k = (PI * corner_hz * dt).tan();
    let mut sections = Vec::with_capacity(order / 2 + 1);
    for i in 1..=order / 2 {
        let two_zeta = 2.0 * ((2 * i - 1) as f64 * PI / (2 * order) as f64).sin();
        let norm = 1.0 / (1.0 + two_zeta * k + k * k);
        sections.push(Biquad {
            b0: norm,
            b1: -2.0 * norm,
            b2: norm,
            a1: 2.0 * (k * k - 1.0) * norm,
            a2: (1.0 - two_zeta * k + k * k) * norm,
        });
    }
    if order % 2 == 1 {
        let norm = 1.0 / (1.0 + k);
        sections.push(Biquad {
            b0: norm,
            b1: -norm,
            b2: 0.0,
            a1: (k - 1.0) * norm,
            a2: 0.0,
        });
    }
    sections
}
