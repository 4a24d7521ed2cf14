//! The paper's integrator (its Section 3, Eqs. 1–3): fixed-step classical RK4 on the cluster
//! equations, with the stick/slip pattern decided once per sub-step by the top-down cluster rule.
//! Kept as a reference and for the accuracy-versus-time comparison; the default is
//! [`super::exact`].
//!
//! Per sub-step `h = dt/substeps`:
//! 1. An interface is *at rest* if it was stuck in the previous sub-step or its relative velocity
//!    changed sign during it (the paper's `sign()` would otherwise chatter). Runs of bodies joined
//!    by at-rest interfaces take their momentum-weighted velocity (the kinetic energy removed is
//!    booked as friction work).
//! 2. Top-down cluster rule (paper Eq. 1): with every at-rest interface assumed stuck, each
//!    cluster's acceleration follows from Eqs. 2–3. Going down from the top, an at-rest
//!    interface whose required force exceeds `μ_s·N` slips with kinetic force in the direction of
//!    that force; its cluster splits and the accelerations below are recomputed.
//! 3. RK4 integrates the cluster equations with that pattern and the slip directions frozen,
//!    together with the energy rates (input, damping, friction).
//!
//! Switches are resolved only to within a sub-step, so the method converges at first order in
//! `h` on records that slide, whatever RK4's order on smooth pieces.
//!
//! A yielding structure (docs/model.md, "Yielding structure") is the textbook return mapping:
//! within a sub-step its force is the last elastic line clamped between the bounding lines
//! ([`Hysteresis::force_n`]), and at the end of the sub-step the line is moved to pass through the
//! new state. The spring's work `∫F_s·u̇` is integrated with the other energy rates. Yield and
//! unloading are resolved only to within a sub-step too.

// Parallel per-body and per-interface arrays read best with index loops.
#![allow(clippy::needless_range_loop)]

use super::contact::Contact;
use super::model::{Hysteresis, System};
use super::response::{Energy, History, Response};
use super::rocking::RockingOnset;
use super::{Ground, SimError};
use crate::limits::{MAX_RK4_SUBSTEPS, RK4_MAX_OMEGA_STEP};

/// Runs the paper's RK4 with `substeps` sub-steps per record interval.
pub fn simulate_rk4(
    sys: &System,
    ground: &Ground,
    substeps: usize,
    history: bool,
) -> Result<Response, SimError> {
    simulate_rk4_watched(sys, ground, substeps, history, &super::Unwatched)
}

/// [`simulate_rk4`] under `watch` ([`super::Watch`]).
pub fn simulate_rk4_watched(
    sys: &System,
    ground: &Ground,
    substeps: usize,
    history: bool,
    watch: &dyn super::Watch,
) -> Result<Response, SimError> {
    ground.validate()?;
    if !(1..=MAX_RK4_SUBSTEPS).contains(&substeps) {
        return Err(SimError::Substeps(substeps));
    }
    // The stiffest mode is the bare structure (every block sliding): ω_p = 2π/T_p.
    let omega = std::f64::consts::TAU / sys.period_s();
    let omega_step = omega * ground.dt_s / substeps as f64;
    if omega_step > RK4_MAX_OMEGA_STEP {
        return Err(SimError::Rk4Unstable {
            period_s: sys.period_s(),
            dt_s: ground.dt_s,
            substeps,
            omega_step,
            needed: (omega * ground.dt_s / RK4_MAX_OMEGA_STEP).ceil() as usize,
        });
    }
    let r = Rk4::new(sys).run(ground, substeps, history, watch)?;
    r.check_finite()?;
    Ok(r)
}

struct Rk4<'s> {
    sys: &'s System,
    n: usize,
    masses: Vec<f64>,
    lim_s: Vec<f64>,
    lim_k: Vec<f64>,
    contacts: Vec<Contact>,
    /// Friction force of each interface for the current sub-step (slipping ones), N.
    force: Vec<f64>,
    /// Cluster index of each body and each cluster's absolute acceleration.
    cluster_of: Vec<usize>,
    x: Vec<f64>,
    v: Vec<f64>,
    energy: Energy,
    hysteresis: Option<Hysteresis>,
    /// A point `(u, F)` (m, N) of the yielding structure's current elastic line.
    anchor: (f64, f64),
    /// `∫F_s du` so far, J (yielding structure only).
    spring_work: f64,
    /// Whether the last sub-step ended on a bounding line.
    plastic: bool,
}

impl<'s> Rk4<'s> {
    fn new(sys: &'s System) -> Self {
        let n = sys.blocks();
        Self {
            sys,
            n,
            masses: sys.masses().to_vec(),
            lim_s: (1..=n).map(|i| sys.static_limit(i)).collect(),
            lim_k: (1..=n).map(|i| sys.kinetic_limit(i)).collect(),
            contacts: sys
                .mu_static()
                .iter()
                .map(|&m| {
                    if m == 0.0 {
                        Contact::Free
                    } else {
                        Contact::Stick
                    }
                })
                .collect(),
            force: vec![0.0; n],
            cluster_of: vec![0; n + 1],
            x: vec![0.0; n + 1],
            v: vec![0.0; n + 1],
            energy: Energy {
                friction_per_interface: vec![0.0; n],
                ..Energy::default()
            },
            hysteresis: sys.hysteresis().copied(),
            anchor: (0.0, 0.0),
            spring_work: 0.0,
            plastic: false,
        }
    }

    /// The structure's restoring force at displacement `u`, N.
    #[inline]
    fn restoring(&self, u: f64) -> f64 {
        match &self.hysteresis {
            Some(h) => h.force_n(u, self.anchor.0, self.anchor.1),
            None => self.sys.stiffness() * u,
        }
    }

    /// Mass of bodies `lo..=hi`.
    fn mass(&self, lo: usize, hi: usize) -> f64 {
        self.masses[lo..=hi].iter().sum()
    }

    /// Absolute acceleration of the cluster `lo..=hi` for the given state and current forces.
    fn cluster_accel(&self, lo: usize, hi: usize, x0: f64, v0: f64) -> f64 {
        let below = if lo > 0 { self.force[lo - 1] } else { 0.0 };
        let above = if hi < self.n { self.force[hi] } else { 0.0 };
        let mut f = below - above;
        if lo == 0 {
            f -= self.sys.damping() * v0 + self.restoring(x0);
        }
        f / self.mass(lo, hi)
    }

    /// Step 1 and 2 of the module doc: velocities of at-rest runs merged, pattern chosen top-down.
    fn choose_pattern(&mut self) {
        let n = self.n;
        // Merge at-rest runs.
        let mut j0 = 0;
        while j0 <= n {
            let mut j1 = j0;
            while j1 < n && self.contacts[j1] == Contact::Stick {
                j1 += 1;
            }
            if j1 > j0 {
                let mass = self.mass(j0, j1);
                let vm = (j0..=j1).map(|j| self.masses[j] * self.v[j]).sum::<f64>() / mass;
                let loss: f64 = (j0..=j1)
                    .map(|j| 0.5 * self.masses[j] * (self.v[j] - vm).powi(2))
                    .sum();
                self.energy.friction_per_interface[j0] += loss;
                self.energy.friction += loss;
                for j in j0..=j1 {
                    self.v[j] = vm;
                }
            }
            j0 = j1 + 1;
        }
        for i in 0..n {
            self.force[i] = match self.contacts[i] {
                Contact::Slip(d) => -self.lim_k[i] * f64::from(d),
                _ => 0.0,
            };
        }
        // Top-down: check each stuck interface against its cluster's acceleration.
        let mut top = n;
        let mut i = n;
        while i > 0 {
            let iface = i - 1; // between bodies i-1 and i
            if self.contacts[iface] != Contact::Stick {
                top = i - 1;
                i -= 1;
                continue;
            }
            let mut lo = i - 1;
            while lo > 0 && self.contacts[lo - 1] == Contact::Stick {
                lo -= 1;
            }
            let acc = self.cluster_accel(lo, top, self.x[0], self.v[0]);
            let above = if top < n { self.force[top] } else { 0.0 };
            let required = self.mass(i, top) * acc + above;
            if required.abs() > self.lim_s[iface] {
                let dir: i8 = if required > 0.0 { -1 } else { 1 };
                self.contacts[iface] = Contact::Slip(dir);
                self.force[iface] = -self.lim_k[iface] * f64::from(dir);
                top = i - 1;
            }
            i -= 1;
        }
        let mut c = 0;
        for j in 0..=n {
            if j > 0 && self.contacts[j - 1] != Contact::Stick {
                c += 1;
            }
            self.cluster_of[j] = c;
        }
    }

    /// Relative accelerations of all bodies (bodies of a cluster share one) into `acc`,
    /// absolute accelerations into `abs`.
    fn accelerations(&self, x: &[f64], v: &[f64], ag: f64, acc: &mut [f64], abs: &mut [f64]) {
        let n = self.n;
        let mut lo = 0;
        while lo <= n {
            let mut hi = lo;
            while hi < n && self.contacts[hi] == Contact::Stick {
                hi += 1;
            }
            let a = self.cluster_accel(lo, hi, x[0], v[0]);
            for j in lo..=hi {
                abs[j] = a;
                acc[j] = a - ag;
            }
            lo = hi + 1;
        }
    }

    /// Energy rates `[input, damping, friction_1..n]` at a state, and with a yielding structure
    /// the spring's power `F_s·u̇` last.
    fn rates(&self, x: &[f64], v: &[f64], ag: f64, out: &mut [f64]) {
        out[0] = -ag * self.masses.iter().zip(v).map(|(m, v)| m * v).sum::<f64>();
        out[1] = self.sys.damping() * v[0] * v[0];
        for i in 0..self.n {
            out[2 + i] = -self.force[i] * (v[i + 1] - v[i]);
        }
        if self.hysteresis.is_some() {
            out[2 + self.n] = self.restoring(x[0]) * v[0];
        }
    }

    fn run(
        mut self,
        ground: &Ground,
        substeps: usize,
        want_history: bool,
        watch: &dyn super::Watch,
    ) -> Result<Response, SimError> {
        let n = self.n;
        let nb = n + 1;
        let acc_g = ground.accel_mps2;
        let dt = ground.dt_s;
        let h = dt / substeps as f64;
        let steps = acc_g.len() - 1;
        let mut out = Response {
            peak_abs_accel_mps2: vec![0.0; nb],
            peak_abs_velocity_mps: vec![0.0; nb],
            peak_slip_m: vec![0.0; n],
            residual_slip_m: vec![0.0; n],
            slip_time_s: vec![0.0; n],
            ..Response::default()
        };
        let mut history = want_history.then(|| History::with_capacity(steps + 1, nb));
        let mut stages = Stages::new(nb, 2 + n + usize::from(self.hysteresis.is_some()));
        let mut s_before = vec![0.0; n];
        let mut switches = 0u64;
        let mut prev = self.contacts.clone();
        let ag_at = |t_index: usize, frac: f64| -> f64 {
            let a0 = acc_g[t_index];
            let a1 = acc_g[(t_index + 1).min(steps)];
            a0 + (a1 - a0) * frac
        };
        let mut input_peak = 0.0f64;
        // The ground's velocity at the sample, m/s (the record integrated exactly).
        let mut vg_k = 0.0;
        for k in 0..steps {
            super::watched(watch, k, steps)?;
            let slope = (acc_g[k + 1] - acc_g[k]) / dt;
            for sub in 0..substeps {
                let frac0 = sub as f64 / substeps as f64;
                let t = k as f64 * dt + sub as f64 * h;
                let tau = sub as f64 * h;
                let vg = vg_k + tau * (acc_g[k] + 0.5 * slope * tau);
                for (p, v) in out.peak_abs_velocity_mps.iter_mut().zip(&self.v) {
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
                if k == 0
                    && sub == 0
                    && let Some(hist) = history.as_mut()
                {
                    let st = &mut stages;
                    self.accelerations(&self.x, &self.v, acc_g[0], &mut st.kv[0], &mut st.abs);
                    record(
                        hist,
                        0.0,
                        acc_g[0],
                        &self.x,
                        &self.v,
                        &st.abs,
                        &self.contacts,
                    );
                }
                for i in 0..n {
                    s_before[i] = self.v[i + 1] - self.v[i];
                }
                let ag = |stage_frac: f64| ag_at(k, frac0 + stage_frac / substeps as f64);
                self.step(h, ag, &mut stages, &mut out.peak_abs_accel_mps2);
                // Rocking, checked at the sub-steps' starts.
                if let Some(r) = self.sys.rocking()
                    && out.rocking_onset.is_none()
                    && let Some(i) = r.rocking_interface(&stages.abs_start[1..])
                {
                    out.rocking_onset = Some(RockingOnset {
                        block: i + 1,
                        time_s: t,
                    });
                }
                self.after_step(h, t, &s_before, &mut out);
            }
            vg_k += 0.5 * dt * (acc_g[k] + acc_g[k + 1]);
            let mut e = self.energy.clone();
            self.fill_state_energy(&mut e);
            input_peak = input_peak.max(e.input.abs());
            if input_peak > 0.0 {
                let err = e.residual().abs() / input_peak;
                out.energy_balance_error_max = out.energy_balance_error_max.max(err);
            }
            if let Some(hist) = history.as_mut() {
                let t1 = (k + 1) as f64 * dt;
                let st = &mut stages;
                self.accelerations(&self.x, &self.v, acc_g[k + 1], &mut st.kv[0], &mut st.abs);
                record(
                    hist,
                    t1,
                    acc_g[k + 1],
                    &self.x,
                    &self.v,
                    &st.abs,
                    &self.contacts,
                );
            }
        }
        let mut e = std::mem::take(&mut self.energy);
        self.fill_state_energy(&mut e);
        let e = e.per_kg(self.sys.mass_kg());
        for i in 0..n {
            out.residual_slip_m[i] = self.x[i + 1] - self.x[i];
        }
        out.residual_displacement_m = self.x[0];
        if let Some(h) = &self.hysteresis {
            out.ductility = Some(out.peak_displacement_m / h.yield_displacement_m);
        }
        out.switches = switches;
        out.energy = e;
        out.history = history;
        Ok(out)
    }

    /// One classical RK4 step of length `h` over the current contact pattern, of the state and
    /// the energy integrals; `ag(f)` is the ground acceleration a fraction `f` of the step in.
    /// The absolute accelerations at the step's start raise `peak_abs_accel_mps2`.
    fn step(
        &mut self,
        h: f64,
        ag: impl Fn(f64) -> f64,
        st: &mut Stages,
        peak_abs_accel_mps2: &mut [f64],
    ) {
        let nb = self.n + 1;
        let stage_frac = [0.0, 0.5, 0.5, 1.0];
        for s in 0..4 {
            let ag = ag(stage_frac[s]);
            if s == 0 {
                st.xs.copy_from_slice(&self.x);
                st.vs.copy_from_slice(&self.v);
            } else {
                let w = stage_frac[s] * h;
                for j in 0..nb {
                    st.xs[j] = self.x[j] + w * st.kx[s - 1][j];
                    st.vs[j] = self.v[j] + w * st.kv[s - 1][j];
                }
            }
            st.kx[s].copy_from_slice(&st.vs);
            self.accelerations(&st.xs, &st.vs, ag, &mut st.kv[s], &mut st.abs);
            if s == 0 {
                for j in 0..nb {
                    peak_abs_accel_mps2[j] = peak_abs_accel_mps2[j].max(st.abs[j].abs());
                }
                st.abs_start.copy_from_slice(&st.abs);
            }
            self.rates(&st.xs, &st.vs, ag, &mut st.ke[s]);
        }
        let (kx, kv) = (&st.kx, &st.kv);
        for j in 0..nb {
            self.x[j] += h / 6.0 * (kx[0][j] + 2.0 * kx[1][j] + 2.0 * kx[2][j] + kx[3][j]);
            self.v[j] += h / 6.0 * (kv[0][j] + 2.0 * kv[1][j] + 2.0 * kv[2][j] + kv[3][j]);
        }
        let ke = &st.ke;
        let de = |r: usize| h / 6.0 * (ke[0][r] + 2.0 * ke[1][r] + 2.0 * ke[2][r] + ke[3][r]);
        self.energy.input += de(0);
        self.energy.damping += de(1);
        for i in 0..self.n {
            let w = de(2 + i);
            self.energy.friction_per_interface[i] += w;
            self.energy.friction += w;
        }
        if self.hysteresis.is_some() {
            self.spring_work += de(2 + self.n);
        }
    }

    /// After a step of length `h` that started at `t` with relative velocities `s_before`: the
    /// structure's branch, the interfaces that come to rest, the peaks and slip times.
    fn after_step(&mut self, h: f64, t: f64, s_before: &[f64], out: &mut Response) {
        if self.hysteresis.is_some() {
            let u = self.x[0];
            let f = self.restoring(u);
            let plastic = f != self.anchor.1 + self.sys.stiffness() * (u - self.anchor.0);
            if plastic != self.plastic {
                out.yield_events += 1;
                self.plastic = plastic;
            }
            self.anchor = (u, f);
        }
        // Interfaces whose relative velocity changed sign are at rest next sub-step.
        for i in 0..self.n {
            if let Contact::Slip(d) = self.contacts[i] {
                out.slip_time_s[i] += h;
                let s = self.v[i + 1] - self.v[i];
                if f64::from(d) * s <= 0.0 || s_before[i] * s < 0.0 {
                    self.contacts[i] = Contact::Stick;
                }
            }
            out.peak_slip_m[i] = out.peak_slip_m[i].max((self.x[i + 1] - self.x[i]).abs());
        }
        let u = self.x[0].abs();
        if u > out.peak_displacement_m {
            out.peak_displacement_m = u;
            out.peak_displacement_time_s = t + h;
        }
    }

    fn fill_state_energy(&self, e: &mut Energy) {
        e.set_state(self.sys.masses(), &self.v, self.sys.stiffness(), self.x[0]);
        if let Some(h) = &self.hysteresis {
            e.strain = h.recoverable_energy(self.restoring(self.x[0]));
            e.hysteretic = self.spring_work - e.strain;
        }
    }
}

/// The scratch of an RK4 step: each stage's slopes of the displacements, velocities and energy
/// integrals, the state a stage is evaluated at, and the absolute accelerations there.
struct Stages {
    kx: Vec<Vec<f64>>,
    kv: Vec<Vec<f64>>,
    ke: Vec<Vec<f64>>,
    xs: Vec<f64>,
    vs: Vec<f64>,
    abs: Vec<f64>,
    /// The absolute accelerations at the step's start, m/s².
    abs_start: Vec<f64>,
}

impl Stages {
    /// For `bodies` bodies and `rates` energy rates.
    fn new(bodies: usize, rates: usize) -> Self {
        Self {
            kx: vec![vec![0.0; bodies]; 4],
            kv: vec![vec![0.0; bodies]; 4],
            ke: vec![vec![0.0; rates]; 4],
            xs: vec![0.0; bodies],
            vs: vec![0.0; bodies],
            abs: vec![0.0; bodies],
            abs_start: vec![0.0; bodies],
        }
    }
}

fn record(h: &mut History, t: f64, ag: f64, x: &[f64], v: &[f64], abs: &[f64], c: &[Contact]) {
    h.time_s.push(t);
    h.ground_accel_mps2.push(ag);
    h.displacement_m.extend_from_slice(x);
    h.velocity_mps.extend_from_slice(v);
    h.abs_accel_mps2.extend_from_slice(abs);
    h.contact.extend(c.iter().map(|c| c.code()));
}
