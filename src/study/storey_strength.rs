//! A yielding building's storey strengths from its base-shear coefficient, distributed over the
//! height by IS 1893 (Part 1):2016, Clause 7.6.3 (docs/model.md, "Incremental dynamic analysis",
//! "In a building"):
//!
//! ```text
//! V_B = C_y·g·Σ_j m_j                    the base shear, C_y on the bare floors' mass
//! Q_i = V_B·m_i·h_i² / Σ_j m_j·h_j²       the lateral force at floor i, h_i its height
//! V_i = Σ_{j≥i} Q_j                      the shear (and strength F_y,i) of storey i
//! C_y,i = V_i / (g·Σ_{j≥i} m_j)           storey i's strength ratio as the model takes it
//! ```
//!
//! The seismic weights `W_i = m_i·g` are the bare floors' (the stack's weight is not in the
//! design force, as on one storey), and `h_i` the sum of the heights of storeys 1 … i.

/// `C_y,i`, storey 1 first, of a building whose base shear is `c_y` times its bare weight:
/// `floor_masses` relative (any scale), `storey_heights_m` storey 1 first. Storey 1 carries
/// the whole base shear, so `C_y,1 = c_y` exactly.
pub fn storey_strength_ratios(
    c_y: f64,
    floor_masses: &[f64],
    storey_heights_m: &[f64],
) -> Vec<f64> {
    let n = floor_masses.len();
    let mut height = 0.0;
    let moments: Vec<f64> = floor_masses
        .iter()
        .zip(storey_heights_m)
        .map(|(m, h)| {
            height += h;
            m * height * height
        })
        .collect();
    let total_mass: f64 = floor_masses.iter().sum();
    let total_moment: f64 = moments.iter().sum();
    let (mut mass_above, mut moment_above) = (0.0, 0.0);
    let mut c = vec![0.0; n];
    for i in (0..n).rev() {
        mass_above += floor_masses[i];
        moment_above += moments[i];
        c[i] = if i == 0 {
            c_y
        } else {
            c_y * total_mass * moment_above / (total_moment * mass_above)
        };
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three storeys by hand: masses 2, 1.5, 1; heights 4, 3, 3 m, so floors at 4, 7, 10 m and
    /// m·h² = 32, 73.5, 100 (Σ 205.5). With C_y = 0.1 on Σm = 4.5:
    /// V_3 = 0.1·4.5·100/205.5 over m = 1; V_2 = 0.1·4.5·173.5/205.5 over m = 2.5.
    #[test]
    fn the_is_1893_distribution_by_hand() {
        let c = storey_strength_ratios(0.1, &[2.0, 1.5, 1.0], &[4.0, 3.0, 3.0]);
        let want = [0.1, 0.45 * 173.5 / 205.5 / 2.5, 0.45 * 100.0 / 205.5];
        for (got, want) in c.iter().zip(want) {
            assert!((got - want).abs() <= 1e-15, "{c:?} vs {want}");
        }
        // Uniform masses and heights: C_y,i = C_y·N·Σ_{j≥i} j² / (Σ_j j²·(N − i + 1)).
        let n = 6;
        let c = storey_strength_ratios(0.2, &[1.0; 6], &[3.0; 6]);
        let sq = |a: usize| (a..=n).map(|j| (j * j) as f64).sum::<f64>();
        for i in 1..=n {
            let want = 0.2 * n as f64 * sq(i) / (sq(1) * (n - i + 1) as f64);
            assert!((c[i - 1] - want).abs() <= 1e-15, "{i}: {c:?}");
        }
        // Independent of the masses' scale; one storey is C_y itself.
        let scaled = storey_strength_ratios(0.1, &[20.0, 15.0, 10.0], &[4.0, 3.0, 3.0]);
        let c = storey_strength_ratios(0.1, &[2.0, 1.5, 1.0], &[4.0, 3.0, 3.0]);
        for (a, b) in scaled.iter().zip(&c) {
            assert!((a - b).abs() <= 1e-16);
        }
        assert_eq!(storey_strength_ratios(0.37, &[3.0], &[2.5]), vec![0.37]);
    }

    /// Through the building model, which takes `F_y,i = C_y,i·g·Σ_{j≥i} m_j`: each storey's
    /// yield force is its design shear `V_i = Σ_{j≥i} Q_j`, the floor forces summed by hand
    /// (1e-12 relative: a handful of roundings each).
    #[test]
    fn the_model_s_storey_yield_forces_are_the_design_shears() {
        use crate::dynamics::G;
        use crate::dynamics::building::{Building, BuildingSpec, StoreyYielding};
        let (m, h) = ([2.0, 1.5, 1.0], [4.0, 3.0, 3.0]);
        let spec = BuildingSpec {
            floor_masses: m.to_vec(),
            storey_stiffnesses: vec![3.0, 2.0, 1.0],
            yielding: Some(StoreyYielding {
                strength_ratios: storey_strength_ratios(0.1, &m, &h),
                post_yield_ratio: 0.05,
            }),
            ..BuildingSpec::uniform(3, 0.8)
        };
        let b = Building::new(&spec).unwrap();
        let v_b = 0.1 * G * 4.5;
        let q = [32.0, 73.5, 100.0].map(|mh| v_b * mh / 205.5);
        let want = [q[0] + q[1] + q[2], q[1] + q[2], q[2]];
        for (s, w) in b.springs().unwrap().iter().zip(want) {
            assert!(
                (s.yield_force_n - w).abs() <= 1e-12 * w,
                "{} vs {w}",
                s.yield_force_n
            );
        }
    }
}
