//! Coulomb-consistent choice of the stick/slip pattern at an instant (docs/model.md, "The physical
//! system").
//!
//! At an instant where some interfaces have zero relative velocity, their friction forces `f_i`
//! are unknown. With static friction equal to kinetic, the consistent forces are the unique
//! minimiser of the dual of "kinetic-energy distance to the free motion plus friction
//! dissipation": over the box `|f_i| ≤ μ_s,i·N_i`, minimise
//! `Φ(f) = ½·Σ_j (E_j + f_j − f_{j+1})² / m_j`,
//! where `E_j` is every other force on body `j`. `∂Φ/∂f_i` is the relative acceleration `ṡ_i`, so
//! the KKT conditions are exactly Coulomb's law: an interior `f_i` sticks (`ṡ_i = 0`), a force at
//! its bound slips away from it. The Hessian is tridiagonal and positive definite; a primal
//! active-set method with a Thomas solve finds the minimiser in a finite number of steps.
//!
//! With `μ_s > μ_k` several patterns can be consistent. The rule used here, **progressive
//! release**: solve with the static bounds; every interface whose force is pinned at its static
//! bound with a nonzero relative acceleration is released to slip with its kinetic force, a
//! released interface whose relative acceleration the later releases have reversed is reopened,
//! and the rest is solved again until nothing changes. Interfaces stick wherever static friction
//! can hold them given the ones that must slip. Should release and reopening cycle (bounded at
//! `4p + 4` rounds for `p` interfaces), the kinetic solution (all bounds at `μ_k·N`) is taken: it
//! is always consistent. With `μ_s = μ_k` the first solve is final and the pattern unique.

// Parallel per-interface arrays read best with index loops.
#![allow(clippy::needless_range_loop)]

use thiserror::Error;

/// State of one interface.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Contact {
    /// No relative motion; the friction force is whatever keeps it so, within the static limit.
    Stick,
    /// Relative velocity `s_i = v_i − v_{i−1}` has sign `dir` (±1); force `−μ_k·N·dir`.
    Slip(i8),
    /// `μ_s = 0`: no friction can ever act; the bodies move independently.
    Free,
}

impl Contact {
    /// Small integer code used in histories: 0 stick, 1 slip forward, −1 slip backward, 2 free.
    pub fn code(self) -> i8 {
        match self {
            Contact::Stick => 0,
            Contact::Slip(d) => d,
            Contact::Free => 2,
        }
    }
}

#[derive(Debug, Error, Clone, PartialEq)]
pub enum ContactError {
    #[error(
        "contact selection did not converge at interfaces {first}..{last} (non-finite forces?)"
    )]
    NoConvergence { first: usize, last: usize },
}

/// What an event-driven integrator gives the stick/slip switch ([`switch_contacts`]).
pub(crate) trait Contacts {
    /// The interfaces' states now, and the buffer for those before the switch.
    fn states(&mut self) -> (&mut [Contact], &mut [Contact]);
    /// `s_k = v(body above) − v(body below)` of interface `k`, m/s.
    fn relative_velocity(&self, k: usize) -> f64;
    /// Friction force of interface `k`, N (on the body above).
    fn force(&self, k: usize) -> f64;
    /// Every group of bodies joined by the interfaces that just stopped takes one
    /// momentum-weighted velocity.
    fn merge_stopped(&mut self);
    /// The Coulomb-consistent mode at the current state, ground acceleration `ga` (m/s²).
    fn select(&mut self, ga: f64) -> Result<(), super::SimError>;
}

/// After a contact selection: `held[k]` stays true only while interface `k` is stuck. Over a
/// run, whether it stuck at every selection (`Response::held`, `BuildingResponse::held`).
pub(crate) fn keep_held(held: &mut [bool], contacts: &[Contact]) {
    for (h, c) in held.iter_mut().zip(contacts) {
        *h &= *c == Contact::Stick;
    }
}

/// The stick/slip switch of both exact integrators, at an event that stopped interface
/// `stopped` or broke the interfaces `broke` loose: every slipping interface whose relative
/// velocity has reached or crossed zero sticks momentarily (its group merged), and so does every
/// one no further from zero than the stopped interface (its root's residue: interfaces that stop
/// together, such as identical stacks, stop at one event); the new mode is selected, and a break
/// that the selection left unchanged (the forces pinned at their limits with a relative
/// acceleration below round-off, where the event proved the demand exceeds them) slips each of
/// `broke` against its force. `broke` holds the interface whose limit the event reached and
/// those of other stacks whose limit it reached at the same instant (bounds tied within the
/// integrator's tolerance): they break together. Returns the number of interfaces whose state
/// changed.
pub(crate) fn switch_contacts(
    c: &mut impl Contacts,
    stopped: Option<usize>,
    broke: &[usize],
    ga: f64,
) -> Result<u64, super::SimError> {
    let n = {
        let (now, before) = c.states();
        before.copy_from_slice(now);
        now.len()
    };
    // The stopped interface's relative velocity at its root, if it is still on the slipping
    // side (a few ulps).
    let residue = stopped.map_or(0.0, |k| match c.states().0[k] {
        Contact::Slip(dir) => (f64::from(dir) * c.relative_velocity(k)).max(0.0),
        _ => 0.0,
    });
    let mut any = false;
    for k in 0..n {
        let Contact::Slip(dir) = c.states().0[k] else {
            continue;
        };
        let s = f64::from(dir) * c.relative_velocity(k);
        if s <= residue || stopped == Some(k) {
            c.states().0[k] = Contact::Stick;
            any = true;
        }
    }
    if any {
        c.merge_stopped();
    }
    c.select(ga)?;
    if !broke.is_empty() {
        let (now, before) = c.states();
        if now == before {
            for &k in broke {
                let f = c.force(k);
                c.states().0[k] = Contact::Slip(if f > 0.0 { -1 } else { 1 });
            }
            c.select(ga)?;
        }
    }
    let (now, before) = c.states();
    Ok(now
        .iter()
        .zip(before.iter())
        .filter(|(a, b)| a != b)
        .count() as u64)
}

/// Reusable workspace for [`ContactSelector::select`]; allocation happens once, in `new`.
#[derive(Debug, Clone)]
pub struct ContactSelector {
    lo: Vec<f64>,
    hi: Vec<f64>,
    f: Vec<f64>,
    grad: Vec<f64>,
    dir: Vec<f64>,
    active: Vec<i8>,
    diag: Vec<f64>,
    off: Vec<f64>,
    rhs: Vec<f64>,
    released: Vec<bool>,
    /// The interfaces of the segment being solved, ascending (a tree's; a chain's are
    /// `i0..i1`).
    seg: Vec<usize>,
    /// Dense workspace of a tree segment's Newton step, and the bodies' accelerations.
    dense: Vec<f64>,
    accel: Vec<f64>,
}

/// How the bodies hang together: body 0 at the bottom, interface `i` (0-based) under body
/// `i + 1` and above body `lower(i)`.
#[derive(Debug, Clone, Copy)]
enum Shape<'a> {
    /// `lower(i) = i`: a stack on a structure.
    Chain,
    /// `lower(i) = below[i] < i + 1`: several stacks on one floor (body 0).
    Tree(&'a [usize]),
}

impl Shape<'_> {
    #[inline]
    fn lower(self, i: usize) -> usize {
        match self {
            Shape::Chain => i,
            Shape::Tree(b) => b[i],
        }
    }
}

impl ContactSelector {
    pub fn new(blocks: usize) -> Self {
        let z = vec![0.0; blocks];
        Self {
            lo: z.clone(),
            hi: z.clone(),
            f: z.clone(),
            grad: z.clone(),
            dir: z.clone(),
            active: vec![0; blocks],
            diag: z.clone(),
            off: z.clone(),
            rhs: z,
            released: vec![false; blocks],
            seg: Vec::with_capacity(blocks),
            dense: Vec::new(),
            accel: vec![0.0; blocks + 1],
        }
    }

    /// Chooses the contact state and friction force of every interface of a stack.
    ///
    /// * `masses`: `[m_p, m_1, …, m_n]`, kg.
    /// * `external`: force on each body from everything but interface friction, N.
    /// * `limit_static`, `limit_kinetic`: `μ_s,i·N_i`, `μ_k,i·N_i` per interface, N.
    /// * `contacts`: on entry, `Slip(d)` for interfaces whose relative velocity is nonzero with
    ///   sign `d`, `Free` where `μ_s = 0`, anything else (`Stick`) where the relative velocity is
    ///   zero. On return, the chosen state of every interface.
    /// * `force`: on return `f_i`, the force body `i−1` exerts on body `i`, N.
    pub fn select(
        &mut self,
        masses: &[f64],
        external: &[f64],
        limit_static: &[f64],
        limit_kinetic: &[f64],
        contacts: &mut [Contact],
        force: &mut [f64],
    ) -> Result<(), ContactError> {
        self.select_shaped(
            Shape::Chain,
            masses,
            external,
            limit_static,
            limit_kinetic,
            contacts,
            force,
        )
    }

    /// [`ContactSelector::select`] for a tree: body 0 (a floor) carries several stacks.
    /// Interface `i` lies under body `i + 1` and above body `below[i]` (`< i + 1`); the rule is
    /// the same (the module doc), solved over every stack of the floor together.
    ///
    /// Stacks standing on the floor that are identical at this instant (the same masses,
    /// forces, limits and contact states, bit for bit) get the same choice, bit for bit: the
    /// problem is invariant under swapping them and strictly convex, so its minimiser gives
    /// them the same forces, and they are solved as one stack of their summed masses, forces
    /// and limits (the quotient of the problem by that symmetry), each taking its share. Solved
    /// one by one, round-off in the coupled solve and the order in which the active-set and
    /// release steps visit them would tell them apart, and the integrator would then break them
    /// loose and stick them one at a time.
    #[allow(clippy::too_many_arguments)]
    pub fn select_tree(
        &mut self,
        below: &[usize],
        masses: &[f64],
        external: &[f64],
        limit_static: &[f64],
        limit_kinetic: &[f64],
        contacts: &mut [Contact],
        force: &mut [f64],
    ) -> Result<(), ContactError> {
        let shape = if below.iter().enumerate().all(|(i, &b)| b == i) {
            Shape::Chain
        } else {
            Shape::Tree(below)
        };
        if let Shape::Tree(_) = shape {
            let lim = Limits {
                external,
                limit_static,
                limit_kinetic,
            };
            if let Some(classes) = identical_stacks(below, masses, &lim, contacts) {
                return self.select_quotient(&classes, masses, &lim, contacts, force);
            }
        }
        self.select_shaped(
            shape,
            masses,
            external,
            limit_static,
            limit_kinetic,
            contacts,
            force,
        )
    }

    /// [`ContactSelector::select_tree`] on the quotient of the floor's problem by its identical
    /// stacks: each class of identical stacks (`classes`: per class its stacks, each a range of
    /// interfaces, the first standing for all) becomes one stack whose masses, external forces
    /// and limits are the class's sums; its forces are shared out equally, the states copied,
    /// and a slipping interface takes its own kinetic force exactly.
    fn select_quotient(
        &mut self,
        classes: &[Vec<std::ops::Range<usize>>],
        masses: &[f64],
        lim: &Limits,
        contacts: &mut [Contact],
        force: &mut [f64],
    ) -> Result<(), ContactError> {
        let mut below_q = Vec::new();
        let mut masses_q = vec![masses[0]];
        let mut external_q = vec![lim.external[0]];
        let (mut ls_q, mut lk_q, mut contacts_q) = (Vec::new(), Vec::new(), Vec::new());
        for class in classes {
            let w = class.len() as f64;
            for (o, i) in class[0].clone().enumerate() {
                below_q.push(if o == 0 { 0 } else { below_q.len() });
                masses_q.push(w * masses[i + 1]);
                external_q.push(w * lim.external[i + 1]);
                ls_q.push(w * lim.limit_static[i]);
                lk_q.push(w * lim.limit_kinetic[i]);
                contacts_q.push(contacts[i]);
            }
        }
        let mut force_q = vec![0.0; contacts_q.len()];
        self.select_tree(
            &below_q,
            &masses_q,
            &external_q,
            &ls_q,
            &lk_q,
            &mut contacts_q,
            &mut force_q,
        )?;
        let mut q = 0;
        for class in classes {
            let w = class.len() as f64;
            for o in 0..class[0].len() {
                for stack in class {
                    let i = stack.start + o;
                    contacts[i] = contacts_q[q];
                    force[i] = match contacts_q[q] {
                        Contact::Slip(d) => -lim.limit_kinetic[i] * f64::from(d),
                        Contact::Free => 0.0,
                        Contact::Stick => force_q[q] / w,
                    };
                }
                q += 1;
            }
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn select_shaped(
        &mut self,
        shape: Shape,
        masses: &[f64],
        external: &[f64],
        limit_static: &[f64],
        limit_kinetic: &[f64],
        contacts: &mut [Contact],
        force: &mut [f64],
    ) -> Result<(), ContactError> {
        let n = contacts.len();
        for i in 0..n {
            force[i] = match contacts[i] {
                Contact::Slip(d) => -limit_kinetic[i] * f64::from(d),
                _ => 0.0,
            };
        }
        let lim = Limits {
            external,
            limit_static,
            limit_kinetic,
        };
        match shape {
            Shape::Chain => {
                // Segments: maximal runs of zero-velocity interfaces i0..i1 (interface index i
                // sits between bodies i and i+1).
                let mut i = 0;
                while i < n {
                    if contacts[i] != Contact::Stick {
                        i += 1;
                        continue;
                    }
                    let i0 = i;
                    while i < n && contacts[i] == Contact::Stick {
                        i += 1;
                    }
                    self.seg.clear();
                    self.seg.extend(i0..i);
                    self.solve_segment(shape, masses, &lim, contacts, force)?;
                }
            }
            Shape::Tree(below) => {
                // Segments: the connected sets of zero-velocity interfaces (joined through a
                // shared body), each found from its lowest interface.
                let mut done = vec![false; n];
                for start in 0..n {
                    if done[start] || contacts[start] != Contact::Stick {
                        continue;
                    }
                    self.seg.clear();
                    self.seg.push(start);
                    done[start] = true;
                    for i in start + 1..n {
                        if done[i] || contacts[i] != Contact::Stick {
                            continue;
                        }
                        let b = below[i];
                        let joined = self.seg.iter().any(|&j| j + 1 == b || below[j] == b);
                        if joined {
                            self.seg.push(i);
                            done[i] = true;
                        }
                    }
                    self.solve_segment(shape, masses, &lim, contacts, force)?;
                }
            }
        }
        Ok(())
    }

    /// The interfaces in `self.seg` are all at zero relative velocity; with the bodies they
    /// join they form the segment. Forces of the interfaces bounding it are already in `force`.
    fn solve_segment(
        &mut self,
        shape: Shape,
        masses: &[f64],
        lim: &Limits,
        contacts: &mut [Contact],
        force: &mut [f64],
    ) -> Result<(), ContactError> {
        let p = self.seg.len();
        let (first, last) = (self.seg[0] + 1, self.seg[p - 1] + 1);
        let in_seg = |seg: &[usize], i: usize| match shape {
            Shape::Chain => i >= seg[0] && i <= seg[seg.len() - 1],
            Shape::Tree(_) => seg.contains(&i),
        };
        // Known force on body j of the segment: external plus bounding kinetic friction.
        let known = |seg: &[usize], j: usize, force: &[f64]| -> f64 {
            let mut e = lim.external[j];
            match shape {
                Shape::Chain => {
                    if j == seg[0] && j > 0 {
                        e += force[j - 1];
                    }
                    if j == seg[seg.len() - 1] + 1 && j < force.len() {
                        e -= force[j];
                    }
                }
                Shape::Tree(below) => {
                    if j > 0 && !in_seg(seg, j - 1) {
                        e += force[j - 1];
                    }
                    for (i, &b) in below.iter().enumerate() {
                        if b == j && !in_seg(seg, i) {
                            e -= force[i];
                        }
                    }
                }
            }
            e
        };
        let mut scale = 0.0f64;
        for k in 0..p {
            let i = self.seg[k];
            for j in [shape.lower(i), i + 1] {
                scale = scale.max(known(&self.seg, j, force).abs());
            }
        }
        for k in 0..p {
            let i = self.seg[k];
            self.released[k] = false;
            self.lo[k] = -lim.limit_static[i];
            self.hi[k] = lim.limit_static[i];
            scale = scale.max(lim.limit_static[i]);
        }
        let seg = std::mem::take(&mut self.seg);
        let known_now = |j: usize| known(&seg, j, force);
        let mut rounds = 0;
        loop {
            self.active_set(shape, masses, &seg, known_now, scale)
                .ok_or(ContactError::NoConvergence { first, last })?;
            // Release every force pinned at a static bound while its relative acceleration
            // pushes beyond it; reopen a released one whose slip the others have reversed
            // (progressive release; see the module doc).
            let mut changed = false;
            for k in 0..p {
                let i = seg[k];
                let tol = release_tolerance(shape, masses, lim, i);
                let push = f64::from(self.active[k]) * self.grad[k];
                if self.released[k] {
                    if push > tol {
                        self.lo[k] = -lim.limit_static[i];
                        self.hi[k] = lim.limit_static[i];
                        self.released[k] = false;
                        changed = true;
                    }
                } else if self.active[k] != 0 && push < -tol {
                    let fk = f64::from(self.active[k]) * lim.limit_kinetic[i];
                    self.lo[k] = fk;
                    self.hi[k] = fk;
                    self.released[k] = true;
                    changed = true;
                }
            }
            if !changed {
                break;
            }
            rounds += 1;
            if rounds > 4 * p + 4 {
                // Release and reopening cycle: fall back to the kinetic solution, which is
                // always Coulomb-consistent (stuck forces within μ_k·N ≤ μ_s·N).
                for k in 0..p {
                    self.lo[k] = -lim.limit_kinetic[seg[k]];
                    self.hi[k] = lim.limit_kinetic[seg[k]];
                }
                self.active_set(shape, masses, &seg, known_now, scale)
                    .ok_or(ContactError::NoConvergence { first, last })?;
                for k in 0..p {
                    let tol = release_tolerance(shape, masses, lim, seg[k]);
                    self.released[k] =
                        self.active[k] != 0 && f64::from(self.active[k]) * self.grad[k] < -tol;
                }
                break;
            }
        }
        for k in 0..p {
            let i = seg[k];
            force[i] = self.f[k];
            contacts[i] = if self.released[k] {
                // Force +μ_k·N (lower body drags the upper forward) means the upper body lags:
                // relative velocity becomes negative.
                Contact::Slip(if self.f[k] > 0.0 { -1 } else { 1 })
            } else {
                Contact::Stick
            };
        }
        self.seg = seg;
        Ok(())
    }

    /// Relative accelerations `ṡ_k = ∂Φ/∂f_k` of the segment at the current forces.
    fn gradient(
        &mut self,
        shape: Shape,
        masses: &[f64],
        seg: &[usize],
        known: &impl Fn(usize) -> f64,
    ) {
        let p = seg.len();
        match shape {
            Shape::Chain => {
                let i0 = seg[0];
                let accel = |j: usize, f: &[f64]| -> f64 {
                    // body j = i0 + jj; interfaces below/above are k = jj-1 and k = jj.
                    let jj = j - i0;
                    let below = if jj > 0 { f[jj - 1] } else { 0.0 };
                    let above = if jj < p { f[jj] } else { 0.0 };
                    (known(j) + below - above) / masses[j]
                };
                let mut prev = accel(i0, &self.f);
                for k in 0..p {
                    let next = accel(i0 + k + 1, &self.f);
                    self.grad[k] = next - prev;
                    prev = next;
                }
            }
            Shape::Tree(below) => {
                // Every body the segment touches: net force over mass.
                let bodies = self.accel.len();
                for j in 0..bodies {
                    self.accel[j] = f64::NAN;
                }
                for k in 0..p {
                    for j in [below[seg[k]], seg[k] + 1] {
                        if !self.accel[j].is_nan() {
                            continue;
                        }
                        let mut e = known(j);
                        for (kk, &i) in seg.iter().enumerate() {
                            if i + 1 == j {
                                e += self.f[kk];
                            }
                            if below[i] == j {
                                e -= self.f[kk];
                            }
                        }
                        self.accel[j] = e / masses[j];
                    }
                }
                for k in 0..p {
                    let i = seg[k];
                    self.grad[k] = self.accel[i + 1] - self.accel[below[i]];
                }
            }
        }
    }

    /// The Newton direction on the free forces, `H_FF·d_F = −grad_F`, `d_W = 0`, into
    /// `self.dir`. `H` is the Hessian of the dual: `∂ṡ_k/∂f_l`.
    fn newton(&mut self, shape: Shape, masses: &[f64], seg: &[usize]) {
        let p = seg.len();
        match shape {
            Shape::Chain => {
                let i0 = seg[0];
                for k in 0..p {
                    let m_lo = masses[i0 + k];
                    let m_hi = masses[i0 + k + 1];
                    if self.active[k] != 0 {
                        self.diag[k] = 1.0;
                        self.rhs[k] = 0.0;
                    } else {
                        self.diag[k] = 1.0 / m_lo + 1.0 / m_hi;
                        self.rhs[k] = -self.grad[k];
                    }
                    // Coupling between k and k+1 is −1/m of the body between them.
                    self.off[k] = if k + 1 < p && self.active[k] == 0 && self.active[k + 1] == 0 {
                        -1.0 / m_hi
                    } else {
                        0.0
                    };
                }
                thomas(
                    &mut self.diag[..p],
                    &self.off[..p],
                    &mut self.rhs[..p],
                    &mut self.dir[..p],
                );
            }
            Shape::Tree(below) => {
                // H_kl = Σ_bodies D_bk·D_bl/m_b, D_bk = +1 for the body above interface k, −1
                // for the body below it.
                self.dense.clear();
                self.dense.resize(p * p, 0.0);
                for k in 0..p {
                    let (ik, jk) = (seg[k], below[seg[k]]);
                    for l in 0..p {
                        let (il, jl) = (seg[l], below[seg[l]]);
                        let mut h = 0.0;
                        for (b, sb) in [(ik + 1, 1.0), (jk, -1.0)] {
                            for (c, sc) in [(il + 1, 1.0), (jl, -1.0)] {
                                if b == c {
                                    h += sb * sc / masses[b];
                                }
                            }
                        }
                        let free = self.active[k] == 0 && self.active[l] == 0;
                        self.dense[k * p + l] = if k == l && !free {
                            1.0
                        } else if free {
                            h
                        } else {
                            0.0
                        };
                    }
                    self.rhs[k] = if self.active[k] == 0 {
                        -self.grad[k]
                    } else {
                        0.0
                    };
                }
                crate::numeric::cholesky_solve(
                    &mut self.dense,
                    &mut self.rhs[..p],
                    p,
                    f64::MIN_POSITIVE,
                );
                self.dir[..p].copy_from_slice(&self.rhs[..p]);
            }
        }
    }

    /// Primal active-set method for the box-constrained QP of one segment. Leaves the optimum in
    /// `self.f`, the bound each force is pinned at in `self.active` (−1, 0, +1) and the relative
    /// accelerations in `self.grad`. `None` if it fails to terminate (non-finite input).
    fn active_set(
        &mut self,
        shape: Shape,
        masses: &[f64],
        seg: &[usize],
        known: impl Fn(usize) -> f64,
        scale: f64,
    ) -> Option<()> {
        let p = seg.len();
        for k in 0..p {
            self.f[k] = 0.0f64.clamp(self.lo[k], self.hi[k]);
            self.active[k] = if self.lo[k] == self.hi[k] {
                if self.lo[k] > 0.0 { 1 } else { -1 }
            } else {
                0
            };
        }
        let max_iter = 50 * (p + 2);
        for _ in 0..max_iter {
            self.gradient(shape, masses, seg, &known);
            self.newton(shape, masses, seg);
            let mut step = 1.0;
            let mut block = None;
            for k in 0..p {
                if self.active[k] != 0 {
                    continue;
                }
                let d = self.dir[k];
                let room = if d > 0.0 {
                    (self.hi[k] - self.f[k]) / d
                } else if d < 0.0 {
                    (self.lo[k] - self.f[k]) / d
                } else {
                    f64::INFINITY
                };
                if room < step {
                    step = room;
                    block = Some(k);
                }
            }
            if !step.is_finite() {
                return None;
            }
            for k in 0..p {
                if self.active[k] == 0 {
                    self.f[k] += step * self.dir[k];
                }
            }
            if let Some(k) = block {
                let upper = self.dir[k] > 0.0;
                self.f[k] = if upper { self.hi[k] } else { self.lo[k] };
                self.active[k] = if upper { 1 } else { -1 };
                continue;
            }
            // Subspace optimum: check the multipliers of the pinned forces.
            self.gradient(shape, masses, seg, &known);
            let mut worst = None;
            let mut worst_val = 0.0;
            for k in 0..p {
                if self.active[k] == 0 || self.lo[k] == self.hi[k] {
                    continue;
                }
                // At the upper bound optimality needs grad ≤ 0, at the lower grad ≥ 0.
                let wrong = f64::from(self.active[k]) * self.grad[k];
                let i = seg[k];
                let tol = 1e-15 * scale * (1.0 / masses[shape.lower(i)] + 1.0 / masses[i + 1]);
                if wrong > tol && wrong > worst_val {
                    worst_val = wrong;
                    worst = Some(k);
                }
            }
            match worst {
                None => return Some(()),
                Some(k) => self.active[k] = 0,
            }
        }
        None
    }
}

/// The stacks of a floor (`below`: a tree whose interfaces each stand on the floor, body 0, or
/// continue the chain below them) in classes of identical ones, in order of their first stacks,
/// each stack a range of interfaces; `None` when no two are identical (or the tree has a body
/// carrying two stacks).
fn identical_stacks(
    below: &[usize],
    masses: &[f64],
    lim: &Limits,
    contacts: &[Contact],
) -> Option<Vec<Vec<std::ops::Range<usize>>>> {
    let n = below.len();
    let mut stacks = Vec::new();
    let mut i = 0;
    while i < n {
        if below[i] != 0 {
            return None;
        }
        let start = i;
        i += 1;
        while i < n && below[i] == i {
            i += 1;
        }
        stacks.push(start..i);
    }
    let same = |a: &std::ops::Range<usize>, b: &std::ops::Range<usize>| {
        let bits = |x: f64, y: f64| x.to_bits() == y.to_bits();
        a.len() == b.len()
            && a.clone().zip(b.clone()).all(|(i, j)| {
                bits(masses[i + 1], masses[j + 1])
                    && bits(lim.external[i + 1], lim.external[j + 1])
                    && bits(lim.limit_static[i], lim.limit_static[j])
                    && bits(lim.limit_kinetic[i], lim.limit_kinetic[j])
                    && contacts[i] == contacts[j]
            })
    };
    let mut classes: Vec<Vec<std::ops::Range<usize>>> = Vec::new();
    for stack in stacks {
        match classes.iter_mut().find(|c| same(&c[0], &stack)) {
            Some(c) => c.push(stack),
            None => classes.push(vec![stack]),
        }
    }
    (classes.len() < below.iter().filter(|&&b| b == 0).count()).then_some(classes)
}

/// The forces a selection is given.
struct Limits<'a> {
    external: &'a [f64],
    limit_static: &'a [f64],
    limit_kinetic: &'a [f64],
}

/// Relative acceleration below which interface `i` (0-based) pinned at its bound counts as not
/// pushing: round-off of the forces acting on its two bodies.
fn release_tolerance(shape: Shape, masses: &[f64], lim: &Limits, i: usize) -> f64 {
    let j = shape.lower(i);
    let force = lim.limit_static[i] + lim.external[j].abs() + lim.external[i + 1].abs();
    1e-11 * force * (1.0 / masses[j] + 1.0 / masses[i + 1])
}

/// Solves a symmetric tridiagonal system in place: `diag` on the diagonal, `off[k]` coupling
/// `k` and `k+1`; the solution goes to `x`. `diag` and `rhs` are overwritten.
fn thomas(diag: &mut [f64], off: &[f64], rhs: &mut [f64], x: &mut [f64]) {
    let p = diag.len();
    for k in 1..p {
        let w = off[k - 1] / diag[k - 1];
        diag[k] -= w * off[k - 1];
        rhs[k] -= w * rhs[k - 1];
    }
    for k in (0..p).rev() {
        let upper = if k + 1 < p { off[k] * x[k + 1] } else { 0.0 };
        x[k] = (rhs[k] - upper) / diag[k];
    }
}
