//! The paper's integrator (its Section 3, Eqs. 1–3; [`super::super::rk4`] for one storey)
//! generalised to the building (docs/model.md, "A multi-storey building"): a fixed-step
//! reference for [`super::simulate_building`], with the same model, conventions and response.
//!
//! Per sub-step `h = dt/substeps`:
//! 1. An interface is *at rest* if it was stuck in the previous sub-step or its relative velocity
//!    changed sign during it. Bodies joined by at-rest interfaces take their momentum-weighted
//!    velocity; joining two groups removes `½·m_a·m_b/(m_a + m_b)·Δv²`, booked as friction work
//!    of the interface that joins them.
//! 2. Top-down cluster rule (paper Eq. 1), stack by stack in the order given, each from its top
//!    block down: with every at-rest interface assumed stuck, a stuck interface whose required
//!    force exceeds `μ_s·N` slips with the kinetic force in the direction of that force. A run of
//!    stuck blocks that reaches its floor moves with the floor, whose absolute acceleration solves
//!    the building's equations `M_eff·A = F` at the sub-step's start: `M_eff` each floor's mass
//!    plus the blocks stuck to it, `F` the storey springs, the damping matrix on the floors'
//!    velocities and the friction of the slipping interfaces above the stuck runs. The floors are
//!    coupled only through the springs and dampers, whose forces the state fixes, so `M_eff` is
//!    diagonal; it is solved again after every split that changes a floor's cluster. A split
//!    here does not revisit the stacks already decided (the paper's single pass): a floor's
//!    stacks decided earlier see the change at the next sub-step. Going down, an interface is
//!    judged while those below it are still assumed stuck, so when a lower interface reverses an
//!    upper one can slip for a single sub-step where the Coulomb-consistent pattern of the exact
//!    integrator keeps it stuck: the switch count may then exceed the exact one.
//! 3. Classical RK4 integrates the floors' `u, u̇` and every block's `x, v` (relative to the
//!    ground) with that pattern and the slip directions frozen, together with the energy rates:
//!    input `−a_g·Σm·v` over all bodies, damping `u̇ᵀ·C·u̇`, friction `−f_k·s_k` per interface
//!    and, for yielding storeys, each storey's power `F_i·δ̇_i`.
//!
//! Yielding storeys (docs/model.md, "Yielding structure") take the textbook return mapping of
//! [`super::super::rk4`] storey by storey: within a sub-step storey `i`'s force is its last
//! elastic line clamped between the bounding lines ([`Hysteresis::force_n`] of the drift
//! `δ_i = u_i − u_{i−1}`), and at the end of the sub-step the line is moved to pass through the
//! new drift and force.
//!
//! Switches, yields and unloadings are resolved only to within a sub-step, so the method
//! converges at first order in `h` when blocks slide or storeys yield, and at fourth order on a
//! bare elastic building. Peaks are sampled: displacements, drifts and slips at the end of every
//! sub-step, absolute accelerations at its start.

// Parallel per-body, per-storey and per-interface arrays read best with index loops.
#![allow(clippy::needless_range_loop)]

use super::super::contact::Contact;
use super::super::model::Hysteresis;
use super::super::response::{Energy, History};
use super::super::rocking::RockingOnset;
use super::super::{Ground, SimError, Unwatched, Watch, watched};
use super::model::Building;
use super::response::BuildingResponse;
use crate::limits::{MAX_RK4_SUBSTEPS, RK4_MAX_OMEGA_STEP};

/// Runs the paper's RK4 on a building with `substeps` sub-steps per record interval.
///
/// Refuses `substeps` outside `1..=MAX_RK4_SUBSTEPS` ([`SimError::Substeps`]) and a step that is
/// unstable for the bare building's stiffest mode, the shortest of [`Building::periods_s`]
/// ([`SimError::Rk4Unstable`]).
pub fn simulate_building_rk4(
    building: &Building,
    ground: &Ground,
    substeps: usize,
    history: bool,
) -> Result<BuildingResponse, SimError> {
    simulate_building_rk4_watched(building, ground, substeps, history, &Unwatched)
}

/// [`simulate_building_rk4`] under `watch` ([`Watch`]).
pub fn simulate_building_rk4_watched(
    building: &Building,
    ground: &Ground,
    substeps: usize,
    history: bool,
    watch: &dyn Watch,
) -> Result<BuildingResponse, SimError> {
    ground.validate()?;
    if !(1..=MAX_RK4_SUBSTEPS).contains(&substeps) {
        return Err(SimError::Substeps(substeps));
    }
    let period_s = building
        .periods_s()
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let omega = std::f64::consts::TAU / period_s;
    let omega_step = omega * ground.dt_s / substeps as f64;
    if omega_step > RK4_MAX_OMEGA_STEP {
        return Err(SimError::Rk4Unstable {
            period_s,
            dt_s: ground.dt_s,
            substeps,
            omega_step,
            needed: (omega * ground.dt_s / RK4_MAX_OMEGA_STEP).ceil() as usize,
        });
    }
    let r = Rk4::new(building).run(ground, substeps, history, watch)?;
    r.check_finite()?;
    Ok(r)
}

/// Where a block is in the current pattern.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Holder {
    /// Stuck to floor `j` through every interface below it.
    Floor(usize),
    /// In free cluster `c` (a run of stuck blocks above a slipping or free interface).
    Free(usize),
}

struct Rk4<'b> {
    b: &'b Building,
    /// Storeys `N` and bodies (floors and blocks).
    n: usize,
    bodies: usize,
    contacts: Vec<Contact>,
    /// Friction force of each interface on the body above it for the current sub-step, N
    /// (slipping interfaces; 0 otherwise).
    force: Vec<f64>,
    /// Per storey, when the storeys yield.
    storeys: Option<Vec<Hysteresis>>,
    /// Per storey, a point `(δ, F)` (m, N) of its current elastic line.
    anchor: Vec<(f64, f64)>,
    /// Per storey, whether the last sub-step ended on a bounding line.
    plastic: Vec<bool>,
    /// `∫F_i dδ_i` so far per storey, J (yielding storeys only).
    spring_work: Vec<f64>,
    /// Per floor: its mass with the blocks stuck to it, kg, and the friction of the slipping
    /// interfaces just above those blocks, N (the floor's cluster feels `−f_top`).
    floor_mass: Vec<f64>,
    f_top: Vec<f64>,
    holder: Vec<Holder>,
    /// Absolute acceleration of each free cluster, m/s².
    free_accel: Vec<f64>,
    x: Vec<f64>,
    v: Vec<f64>,
    energy: Energy,
    /// Scratch of the at-rest merge: union-find parent, mass, momentum and velocity per group.
    parent: Vec<usize>,
    group_mass: Vec<f64>,
    group_momentum: Vec<f64>,
    group_velocity: Vec<f64>,
    /// Scratch of the pattern choice: the floors' forces and accelerations.
    floor_force: Vec<f64>,
    floor_accel: Vec<f64>,
}

impl<'b> Rk4<'b> {
    fn new(b: &'b Building) -> Self {
        let n = b.storeys();
        let blocks = b.blocks();
        let bodies = n + blocks;
        let storeys = b.springs().map(|springs| {
            let y = b
                .spec()
                .yielding
                .as_ref()
                .expect("a building has springs only when its storeys yield");
            springs
                .iter()
                .zip(&y.strength_ratios)
                .map(|(s, &c)| Hysteresis {
                    strength_ratio: c,
                    post_yield_ratio: y.post_yield_ratio,
                    stiffness: s.k,
                    yield_force_n: s.yield_force_n,
                    yield_displacement_m: s.yield_drift_m,
                })
                .collect()
        });
        Self {
            b,
            n,
            bodies,
            contacts: (0..blocks)
                .map(|k| {
                    if b.mu_static(k) == 0.0 {
                        Contact::Free
                    } else {
                        Contact::Stick
                    }
                })
                .collect(),
            force: vec![0.0; blocks],
            storeys,
            anchor: vec![(0.0, 0.0); n],
            plastic: vec![false; n],
            spring_work: vec![0.0; n],
            floor_mass: vec![0.0; n],
            f_top: vec![0.0; n],
            holder: vec![Holder::Floor(0); blocks],
            free_accel: Vec::with_capacity(blocks),
            x: vec![0.0; bodies],
            v: vec![0.0; bodies],
            energy: Energy {
                friction_per_interface: vec![0.0; blocks],
                ..Energy::default()
            },
            parent: vec![0; bodies],
            group_mass: vec![0.0; bodies],
            group_momentum: vec![0.0; bodies],
            group_velocity: vec![0.0; bodies],
            floor_force: vec![0.0; n],
            floor_accel: vec![0.0; n],
        }
    }

    /// Storey `i`'s drift `δ_i = u_i − u_{i−1}` (`u_{−1} = 0`, the ground), m.
    #[inline]
    fn drift(x: &[f64], i: usize) -> f64 {
        x[i] - if i > 0 { x[i - 1] } else { 0.0 }
    }

    /// Storey `i`'s restoring force at drift `d` (m), N.
    #[inline]
    fn storey_force(&self, i: usize, d: f64) -> f64 {
        match &self.storeys {
            Some(h) => h[i].force_n(d, self.anchor[i].0, self.anchor[i].1),
            None => self.b.stiffness()[i] * d,
        }
    }

    /// The spring and damper forces on each bare floor at a state, N (`F` of `M_eff·A = F`
    /// before the friction from above).
    fn floor_forces(&self, x: &[f64], v: &[f64], out: &mut [f64]) {
        let n = self.n;
        let c = self.b.damping();
        for j in 0..n {
            out[j] = -(0..n).map(|l| c[j * n + l] * v[l]).sum::<f64>();
        }
        for i in 0..n {
            let f = self.storey_force(i, Self::drift(x, i));
            out[i] -= f;
            if i > 0 {
                out[i - 1] += f;
            }
        }
    }

    /// Absolute accelerations of the floors' clusters (m/s²) from their spring and damper
    /// forces (N) in the current pattern: `M_eff·A = F − f_top`.
    fn solve_floors(&self, forces: &[f64], out: &mut [f64]) {
        for j in 0..self.n {
            out[j] = (forces[j] - self.f_top[j]) / self.floor_mass[j];
        }
    }

    /// The clusters of the current contacts and forces: each floor's mass with its stuck blocks
    /// and the friction on it from above, where every block is held, and the free clusters'
    /// accelerations.
    fn clusters(&mut self) {
        let (n, b) = (self.n, self.b);
        let m = b.masses();
        self.floor_mass.copy_from_slice(&m[..n]);
        self.f_top.fill(0.0);
        self.free_accel.clear();
        for s in b.stacks() {
            let mut e = 0;
            while e < s.blocks && self.contacts[s.first + e] == Contact::Stick {
                self.floor_mass[s.floor] += m[n + s.first + e];
                self.holder[s.first + e] = Holder::Floor(s.floor);
                e += 1;
            }
            if e < s.blocks {
                self.f_top[s.floor] += self.force[s.first + e];
            }
            let mut q = e;
            while q < s.blocks {
                let mut top = q;
                while top + 1 < s.blocks && self.contacts[s.first + top + 1] == Contact::Stick {
                    top += 1;
                }
                let mass: f64 = (q..=top).map(|t| m[n + s.first + t]).sum();
                let above = if top + 1 < s.blocks {
                    self.force[s.first + top + 1]
                } else {
                    0.0
                };
                let c = self.free_accel.len();
                self.free_accel
                    .push((self.force[s.first + q] - above) / mass);
                for t in q..=top {
                    self.holder[s.first + t] = Holder::Free(c);
                }
                q = top + 1;
            }
        }
    }

    /// Step 1 of the module doc: groups joined by at-rest interfaces take their
    /// momentum-weighted velocity, each join's kinetic-energy loss booked to its interface.
    /// Groups that already share a velocity (stuck through the last sub-step) keep it as it is.
    fn merge_at_rest(&mut self) {
        let (n, b) = (self.n, self.b);
        let m = b.masses();
        for j in 0..self.bodies {
            self.parent[j] = j;
            self.group_mass[j] = m[j];
            self.group_momentum[j] = m[j] * self.v[j];
            self.group_velocity[j] = self.v[j];
        }
        fn root(p: &mut [usize], mut a: usize) -> usize {
            while p[a] != a {
                p[a] = p[p[a]];
                a = p[a];
            }
            a
        }
        for k in 0..b.blocks() {
            if self.contacts[k] != Contact::Stick {
                continue;
            }
            let a = root(&mut self.parent, n + k);
            let c = root(&mut self.parent, b.below(k));
            let (ma, mc) = (self.group_mass[a], self.group_mass[c]);
            let (va, vc) = (self.group_velocity[a], self.group_velocity[c]);
            let (keep, gone) = (a.min(c), a.max(c));
            self.parent[gone] = keep;
            self.group_mass[keep] = ma + mc;
            self.group_momentum[keep] += self.group_momentum[gone];
            if va == vc {
                self.group_velocity[keep] = va;
            } else {
                let loss = 0.5 * ma * mc / (ma + mc) * (va - vc) * (va - vc);
                self.energy.friction_per_interface[k] += loss;
                self.energy.friction += loss;
                self.group_velocity[keep] = self.group_momentum[keep] / self.group_mass[keep];
            }
        }
        for j in 0..self.bodies {
            let r = root(&mut self.parent, j);
            self.v[j] = self.group_velocity[r];
        }
    }

    /// Steps 1 and 2 of the module doc: at-rest groups merged, the pattern chosen top-down.
    fn choose_pattern(&mut self) {
        self.merge_at_rest();
        let (n, b) = (self.n, self.b);
        let m = b.masses();
        for k in 0..b.blocks() {
            self.force[k] = match self.contacts[k] {
                Contact::Slip(d) => -b.kinetic_limit(k) * f64::from(d),
                _ => 0.0,
            };
        }
        self.clusters();
        let mut forces = std::mem::take(&mut self.floor_force);
        let mut accel = std::mem::take(&mut self.floor_accel);
        self.floor_forces(&self.x, &self.v, &mut forces);
        self.solve_floors(&forces, &mut accel);
        for s in b.stacks() {
            // Local bodies: 0 the floor, `q` the stack's block `q` (1-based); local interface
            // `q` (0-based, global `s.first + q`) lies between local bodies `q` and `q + 1`.
            let mass =
                |lo: usize, hi: usize| -> f64 { (lo..=hi).map(|q| m[n + s.first + q - 1]).sum() };
            let mut top = s.blocks;
            for q in (0..s.blocks).rev() {
                let k = s.first + q;
                if self.contacts[k] != Contact::Stick {
                    top = q;
                    continue;
                }
                let mut lo = q;
                while lo > 0 && self.contacts[s.first + lo - 1] == Contact::Stick {
                    lo -= 1;
                }
                let above = if top < s.blocks {
                    self.force[s.first + top]
                } else {
                    0.0
                };
                let acc = if lo == 0 {
                    accel[s.floor]
                } else {
                    (self.force[s.first + lo - 1] - above) / mass(lo, top)
                };
                let required = mass(q + 1, top) * acc + above;
                if required.abs() > b.static_limit(k) {
                    let dir: i8 = if required > 0.0 { -1 } else { 1 };
                    self.contacts[k] = Contact::Slip(dir);
                    self.force[k] = -b.kinetic_limit(k) * f64::from(dir);
                    top = q;
                    if lo == 0 {
                        self.clusters();
                        self.solve_floors(&forces, &mut accel);
                    }
                }
            }
        }
        self.clusters();
        self.floor_force = forces;
        self.floor_accel = accel;
    }

    /// Relative accelerations of all bodies at a state into `rel` and absolute ones into `abs`
    /// (m/s²), in the current pattern.
    fn accelerations(&self, x: &[f64], v: &[f64], ag: f64, rel: &mut [f64], abs: &mut [f64]) {
        let n = self.n;
        self.floor_forces(x, v, &mut abs[..n]);
        for j in 0..n {
            abs[j] = (abs[j] - self.f_top[j]) / self.floor_mass[j];
        }
        for q in 0..self.b.blocks() {
            abs[n + q] = match self.holder[q] {
                Holder::Floor(f) => abs[f],
                Holder::Free(c) => self.free_accel[c],
            };
        }
        for j in 0..self.bodies {
            rel[j] = abs[j] - ag;
        }
    }

    /// Energy rates at a state, W: `[input, damping, friction per interface…]`, then with
    /// yielding storeys each storey's power `F_i·δ̇_i`.
    fn rates(&self, x: &[f64], v: &[f64], ag: f64, out: &mut [f64]) {
        let (n, b) = (self.n, self.b);
        let blocks = b.blocks();
        out[0] = -ag * b.masses().iter().zip(v).map(|(m, v)| m * v).sum::<f64>();
        let c = b.damping();
        out[1] = (0..n)
            .map(|a| v[a] * (0..n).map(|l| c[a * n + l] * v[l]).sum::<f64>())
            .sum();
        for k in 0..blocks {
            out[2 + k] = -self.force[k] * (v[n + k] - v[b.below(k)]);
        }
        if self.storeys.is_some() {
            for i in 0..n {
                let rate = v[i] - if i > 0 { v[i - 1] } else { 0.0 };
                out[2 + blocks + i] = self.storey_force(i, Self::drift(x, i)) * rate;
            }
        }
    }

    /// Kinetic energy and all the storeys' spring work (recoverable plus hysteretic) now, J.
    fn state_energy(&self) -> (f64, f64) {
        let m = self.b.masses();
        let kinetic = 0.5
            * (0..self.bodies)
                .map(|j| m[j] * self.v[j] * self.v[j])
                .sum::<f64>();
        let strain = if self.storeys.is_some() {
            self.spring_work.iter().sum()
        } else {
            (0..self.n)
                .map(|i| 0.5 * self.b.stiffness()[i] * Self::drift(&self.x, i).powi(2))
                .sum()
        };
        (kinetic, strain)
    }

    fn run(
        mut self,
        ground: &Ground,
        substeps: usize,
        want_history: bool,
        watch: &dyn Watch,
    ) -> Result<BuildingResponse, SimError> {
        let (n, b) = (self.n, self.b);
        let blocks = b.blocks();
        let nb = self.bodies;
        let acc_g = ground.accel_mps2;
        let dt = ground.dt_s;
        let h = dt / substeps as f64;
        let steps = acc_g.len() - 1;
        let mut out = BuildingResponse::zeroed(n, blocks, b.stacks().len());
        let mut history = want_history.then(|| History::with_layout(steps + 1, nb, blocks));
        let nr = 2 + blocks + if self.storeys.is_some() { n } else { 0 };
        let mut kx = vec![vec![0.0; nb]; 4];
        let mut kv = vec![vec![0.0; nb]; 4];
        let mut ke = vec![vec![0.0; nr]; 4];
        let mut xs = vec![0.0; nb];
        let mut vs = vec![0.0; nb];
        let mut abs = vec![0.0; nb];
        let mut s_before = vec![0.0; blocks];
        let mut switches = 0u64;
        let mut prev = self.contacts.clone();
        let ag_at = |t_index: usize, frac: f64| -> f64 {
            let a0 = acc_g[t_index];
            let a1 = acc_g[(t_index + 1).min(steps)];
            a0 + (a1 - a0) * frac
        };
        let stage_frac = [0.0, 0.5, 0.5, 1.0];
        let mut input_peak = 0.0f64;
        // Each body's floor (a block: its stack's) and that floor's elevation, m: for the storey
        // shears and the overturning moment by Newton's sum over the bodies.
        let mut floor_of: Vec<usize> = (0..n).collect();
        floor_of.resize(nb, 0);
        for s in b.stacks() {
            for q in 0..s.blocks {
                floor_of[n + s.first + q] = s.floor;
            }
        }
        let elevation: Vec<f64> = (b.storey_heights_m().iter())
            .scan(0.0, |z, h| {
                *z += h;
                Some(*z)
            })
            .collect();
        let mut shears = vec![0.0; n];
        let load_kg: f64 = b.masses()[n..].iter().sum();
        // ∫ (mass of the blocks not stuck to their floor) dt, kg·s, by sub-step.
        let mut loose_mass_time = 0.0;
        // The ground's velocity at the sample, m/s (the record integrated exactly).
        let mut vg_k = 0.0;
        for k in 0..steps {
            watched(watch, k, steps)?;
            let slope = (acc_g[k + 1] - acc_g[k]) / dt;
            for sub in 0..substeps {
                let frac0 = sub as f64 / substeps as f64;
                let tau = sub as f64 * h;
                let vg = vg_k + tau * (acc_g[k] + 0.5 * slope * tau);
                let (floors, blocks_v) = self.v.split_at(n);
                for (p, v) in out.floor_peak_abs_velocity_mps.iter_mut().zip(floors) {
                    *p = p.max((v + vg).abs());
                }
                for (p, v) in out.block_peak_abs_velocity_mps.iter_mut().zip(blocks_v) {
                    *p = p.max((v + vg).abs());
                }
                self.choose_pattern();
                switches += self
                    .contacts
                    .iter()
                    .zip(&prev)
                    .filter(|(a, b)| a != b)
                    .count() as u64;
                prev.copy_from_slice(&self.contacts);
                for s in b.stacks() {
                    let stuck = (0..s.blocks)
                        .take_while(|&q| self.contacts[s.first + q] == Contact::Stick)
                        .count();
                    let loose: f64 = (stuck..s.blocks).map(|q| b.masses()[n + s.first + q]).sum();
                    loose_mass_time += loose * h;
                }
                if k == 0
                    && sub == 0
                    && let Some(hist) = history.as_mut()
                {
                    self.accelerations(&self.x, &self.v, acc_g[0], &mut kv[0], &mut abs);
                    self.record(hist, 0.0, acc_g[0], &abs);
                }
                for q in 0..blocks {
                    s_before[q] = self.v[n + q] - self.v[b.below(q)];
                }
                for st in 0..4 {
                    let ag = ag_at(k, frac0 + stage_frac[st] / substeps as f64);
                    if st == 0 {
                        xs.copy_from_slice(&self.x);
                        vs.copy_from_slice(&self.v);
                    } else {
                        let w = stage_frac[st] * h;
                        for j in 0..nb {
                            xs[j] = self.x[j] + w * kx[st - 1][j];
                            vs[j] = self.v[j] + w * kv[st - 1][j];
                        }
                    }
                    kx[st].copy_from_slice(&vs);
                    self.accelerations(&xs, &vs, ag, &mut kv[st], &mut abs);
                    if st == 0 {
                        for j in 0..n {
                            let p = &mut out.floor_peak_abs_accel_mps2[j];
                            *p = p.max(abs[j].abs());
                        }
                        for q in 0..blocks {
                            let p = &mut out.block_peak_abs_accel_mps2[q];
                            *p = p.max(abs[n + q].abs());
                        }
                        // Newton's sums over the bodies above each cut, independent of the exact
                        // integrator's storey and damper forces.
                        shears.fill(0.0);
                        let mut moment = 0.0;
                        for body in 0..nb {
                            let f = b.masses()[body] * abs[body];
                            shears[floor_of[body]] += f;
                            moment += elevation[floor_of[body]] * f;
                        }
                        for i in (0..n - 1).rev() {
                            shears[i] += shears[i + 1];
                        }
                        for i in 0..n {
                            let p = &mut out.storey_peak_shear_n[i];
                            *p = p.max(shears[i].abs());
                        }
                        out.peak_base_shear_n = out.storey_peak_shear_n[0];
                        out.peak_overturning_n_m = out.peak_overturning_n_m.max(moment.abs());
                        // Rocking, checked at the sub-steps' starts.
                        let t = k as f64 * dt + sub as f64 * h;
                        for (si, s) in b.stacks().iter().enumerate() {
                            let Some(r) = &s.rocking else { continue };
                            let blocks_at = n + s.first;
                            if out.rocking_onset[si].is_none()
                                && let Some(i) =
                                    r.rocking_interface(&abs[blocks_at..blocks_at + s.blocks])
                            {
                                out.rocking_onset[si] = Some(RockingOnset {
                                    block: i + 1,
                                    time_s: t,
                                });
                            }
                        }
                    }
                    self.rates(&xs, &vs, ag, &mut ke[st]);
                }
                for j in 0..nb {
                    self.x[j] += h / 6.0 * (kx[0][j] + 2.0 * kx[1][j] + 2.0 * kx[2][j] + kx[3][j]);
                    self.v[j] += h / 6.0 * (kv[0][j] + 2.0 * kv[1][j] + 2.0 * kv[2][j] + kv[3][j]);
                }
                let de =
                    |r: usize| h / 6.0 * (ke[0][r] + 2.0 * ke[1][r] + 2.0 * ke[2][r] + ke[3][r]);
                self.energy.input += de(0);
                self.energy.damping += de(1);
                for q in 0..blocks {
                    let w = de(2 + q);
                    self.energy.friction_per_interface[q] += w;
                    self.energy.friction += w;
                }
                if let Some(storeys) = &self.storeys {
                    for i in 0..n {
                        self.spring_work[i] += de(2 + blocks + i);
                        let d = Self::drift(&self.x, i);
                        let (a_d, a_f) = self.anchor[i];
                        let f = storeys[i].force_n(d, a_d, a_f);
                        let plastic = f != a_f + storeys[i].stiffness * (d - a_d);
                        if plastic != self.plastic[i] {
                            out.yield_events += 1;
                            self.plastic[i] = plastic;
                        }
                        self.anchor[i] = (d, f);
                    }
                }
                // Interfaces whose relative velocity changed sign are at rest next sub-step.
                for q in 0..blocks {
                    let s = self.v[n + q] - self.v[b.below(q)];
                    if let Contact::Slip(d) = self.contacts[q]
                        && (f64::from(d) * s <= 0.0 || s_before[q] * s < 0.0)
                    {
                        self.contacts[q] = Contact::Stick;
                    }
                    let slip = (self.x[n + q] - self.x[b.below(q)]).abs();
                    out.peak_slip_m[q] = out.peak_slip_m[q].max(slip);
                }
                for j in 0..n {
                    let p = &mut out.floor_peak_displacement_m[j];
                    *p = p.max(self.x[j].abs());
                    let p = &mut out.storey_peak_drift_m[j];
                    *p = p.max(Self::drift(&self.x, j).abs());
                }
            }
            vg_k += 0.5 * dt * (acc_g[k] + acc_g[k + 1]);
            let (kinetic, strain) = self.state_energy();
            input_peak = input_peak.max(self.energy.input.abs());
            if input_peak > 0.0 {
                let err = self.energy.residual_with(kinetic, strain).abs() / input_peak;
                out.energy_balance_error_max = out.energy_balance_error_max.max(err);
            }
            if let Some(hist) = history.as_mut() {
                // The recorded contacts hold the interfaces now at rest: so do the accelerations.
                self.clusters();
                self.accelerations(&self.x, &self.v, acc_g[k + 1], &mut kv[0], &mut abs);
                self.record(hist, (k + 1) as f64 * dt, acc_g[k + 1], &abs);
            }
        }
        out.stuck_mass_share = if load_kg > 0.0 {
            1.0 - loose_mass_time / (steps as f64 * dt * load_kg)
        } else {
            f64::NAN
        };
        Ok(self.finish(out, switches, history))
    }

    /// Appends the current state as a history row: bodies floors first, then blocks; one
    /// contact code per interface.
    fn record(&self, h: &mut History, t: f64, ag: f64, abs: &[f64]) {
        h.time_s.push(t);
        h.ground_accel_mps2.push(ag);
        h.displacement_m.extend_from_slice(&self.x);
        h.velocity_mps.extend_from_slice(&self.v);
        h.abs_accel_mps2.extend_from_slice(abs);
        h.contact.extend(self.contacts.iter().map(|c| c.code()));
    }

    fn finish(
        mut self,
        mut out: BuildingResponse,
        switches: u64,
        history: Option<History>,
    ) -> BuildingResponse {
        let n = self.n;
        let mut e = std::mem::take(&mut self.energy);
        let (kinetic, spring_work) = self.state_energy();
        e.kinetic = kinetic;
        match &self.storeys {
            Some(storeys) => {
                e.strain = (0..n)
                    .map(|i| storeys[i].recoverable_energy(self.anchor[i].1))
                    .sum();
                e.hysteretic = spring_work - e.strain;
                out.storey_ductility = Some(
                    (0..n)
                        .map(|i| out.storey_peak_drift_m[i] / storeys[i].yield_displacement_m)
                        .collect(),
                );
            }
            None => e.strain = spring_work,
        }
        for i in 0..n {
            out.storey_residual_drift_m[i] = Self::drift(&self.x, i);
        }
        for q in 0..self.b.blocks() {
            out.residual_slip_m[q] = self.x[n + q] - self.x[self.b.below(q)];
        }
        out.switches = switches;
        out.energy = e.per_kg(self.b.bare_mass_kg());
        out.history = history;
        out
    }
}
