//! The exact event-driven integrator (default).
//!
//! Within a stick/slip mode the bodies form clusters (runs of stuck interfaces). The cluster that
//! holds the structure is a linear SDOF of its total mass under `−M·a_g(t)` plus the constant
//! friction of the interface above it; every other cluster is a free mass under `−M·a_g(t)` plus
//! constant friction. With `a_g` linear over a sample interval both have closed forms
//! ([`super::closed_form::Wave`]), so a sample interval is crossed in one evaluation unless a switch
//! occurs inside it:
//! * a slipping interface's relative velocity reaches zero;
//! * a stuck interface inside the structure's cluster needs more than its static friction
//!   (stuck interfaces in free clusters carry constant forces and cannot switch within a mode).
//!
//! Each switching function is located by a certified search (a bound on its second derivative
//! rules out roots between evaluations, so no zero crossing is missed however short) and refined
//! by bracketed root finding to a few ulps of time. At a switch the new mode comes from
//! [`ContactSelector`]. The peaks of the structure's displacement and absolute acceleration are
//! found by the same kind of bound-and-refine search, so they are exact, not sampled. Energy terms
//! are integrated in closed form piece by piece.
//!
//! Bounds come from the oscillation's amplitude (each `τ`-derivative scales it by `ω_n`), the
//! end values and slopes (a cubic Hermite bound), and a monotonicity certificate, so most pieces
//! need no search at all; a whole sample interval with every interface stuck on which the
//! acceleration provably stays inside its break bounds and no peak can grow only settles its
//! energy and state.
//!
//! A friction force counts as exceeding its static limit only beyond `1e-10` of that limit, so a
//! demand that sits exactly at the limit (ground acceleration equal to `μ·g`) sticks instead of
//! chattering. More than `max_switches_per_step` switches within one sample interval stop the run
//! with [`SimError::Zeno`].
//!
//! Long periods: the structure's cluster is written as particular plus homogeneous solution,
//! whose terms grow like `a_g/ω²` and `ȧ_g/ω³` and cancel when `ω·dt` is small (the energy
//! error of that form grows like `(T_rigid/dt)²`: 5e-3 at `T_rigid = 201 s`, `dt = 0.0005 s`).
//! Below `ω_n·dt = SDOF_FORM_OMEGA_STEP` each piece's end state, energy integrals and peak
//! displacement come from the φ-function step instead ([`sdof::piece`], [`sdof::Step`];
//! `docs/model.md`, "Long periods"), exact to round-off at any `T_rigid/dt` (energy 2e-13 there,
//! peak within 1e-10 of a fine-step reference up to `T_rigid = 1e6 s`); the wave still locates
//! the events, whose switching functions it keeps to round-off of the accelerations.

// Parallel per-body and per-interface arrays read best with index loops.
#![allow(clippy::needless_range_loop)]

use super::closed_form::{
    Basis, Osc, PieceIntegrals, Wave, integral_of_square_decay, integral_of_square_with,
};
use super::contact::{Contact, ContactSelector, Contacts, keep_held, switch_contacts};
use super::model::{G, System};
use super::response::{Energy, History, Response};
use super::rocking::{self, RockingOnset};
use super::search::{self, Node, Smooth};
use super::{Ground, SimError};
use crate::sdof::{self, Piece, decay_piece};

/// Relative tolerance on the static friction limit before a stuck interface breaks away.
pub const BREAK_TOLERANCE: f64 = 1e-10;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExactOptions {
    /// Keep the full time history (one row per record sample).
    pub history: bool,
    /// Switches allowed within one sample interval before the run is refused as Zeno.
    pub max_switches_per_step: usize,
    /// Integrate the input and damping energies and check the balance. Off, `energy.input`,
    /// `energy.damping` and `energy_balance_error_max` are NaN (friction, kinetic and strain
    /// energy are still exact); the sweep, which stores only friction energy, turns it off.
    pub energy_balance: bool,
    /// Search the peak absolute velocities (docs/model.md, "Absolute velocities"). Off, they
    /// are NaN; the study's stages, which do not store them, turn it off.
    pub abs_velocity: bool,
    /// Search every floor's peak displacement. Off, a building's floors below the roof have NaN
    /// (the roof's is searched: one storey is unaffected); the study's stages, which store only
    /// the roof's, turn it off.
    pub floor_displacements: bool,
}

impl Default for ExactOptions {
    fn default() -> Self {
        Self {
            history: false,
            max_switches_per_step: 1000,
            energy_balance: true,
            abs_velocity: true,
            floor_displacements: true,
        }
    }
}

/// Runs the exact integrator over the whole record. A yielding structure
/// ([`System::with_yielding`]) runs a separate instance of the integrator; the linear one is
/// compiled without any of its branches.
pub fn simulate_exact(
    sys: &System,
    ground: &Ground,
    opts: &ExactOptions,
) -> Result<Response, SimError> {
    simulate_exact_watched(sys, ground, opts, &super::Unwatched)
}

/// [`simulate_exact`] under `watch` ([`super::Watch`]).
pub fn simulate_exact_watched(
    sys: &System,
    ground: &Ground,
    opts: &ExactOptions,
    watch: &dyn super::Watch,
) -> Result<Response, SimError> {
    ground.validate()?;
    let (dt, accel) = (ground.dt_s, ground.accel_mps2);
    let r = match (sys.hysteresis().is_some(), long_periods(sys, dt)) {
        (true, true) => ExactRun::<true, true>::new(sys, dt, *opts).run(accel, watch)?,
        (true, false) => ExactRun::<true, false>::new(sys, dt, *opts).run(accel, watch)?,
        (false, true) => ExactRun::<false, true>::new(sys, dt, *opts).run(accel, watch)?,
        (false, false) => ExactRun::<false, false>::new(sys, dt, *opts).run(accel, watch)?,
    };
    r.check_finite()?;
    Ok(r)
}

/// Whether some structure cluster of `sys` takes [`sdof::piece`] at `dt`: the slowest are those
/// of the whole stack, on the elastic and on the post-yield branch (`ω_n·dt` falls with `ω_n`).
/// As a constant of [`ExactRun`] it leaves every other run's code as it was.
fn long_periods(sys: &System, dt: f64) -> bool {
    let mass: f64 = sys.masses().iter().sum();
    let slowest = |k: f64| StructureCluster::new(mass, k, sys.damping(), dt).sdof_form;
    slowest(sys.stiffness()) || (sys.hysteresis().is_some() && slowest(Spring::new(sys).k_post))
}

/// Coefficients of the structure's cluster (the structure and the bodies stuck to it, up to a top
/// body). With a post-yield stiffness of zero (`omega2 = 0`) the free motion is `1` and
/// `e^{−(c/M)τ}`: `osc` is then `{ decay: c/M, omega: 0 }`, whose wave `c·e^{−aτ}` is that
/// exponential.
#[derive(Debug, Clone, Copy)]
struct StructureCluster {
    mass: f64,
    osc: Osc,
    omega2: f64,
    /// `ω_n` of the cluster ([`Osc::natural`]), rad/s.
    natural: f64,
    basis_dt: Basis,
    /// The energy integrals over a whole sample interval.
    integrals_dt: PieceIntegrals,
    /// Whether `ω_n·dt < SDOF_FORM_OMEGA_STEP`: the state and integrals of a piece then come
    /// from [`sdof::piece`] ([`ExactRun::stable_piece`]).
    sdof_form: bool,
}

/// Below this `ω_n·dt` the particular-plus-homogeneous wave of the structure cluster loses more
/// than `1/(ω_n·dt)² ≈ 4e4` ulps of the state to cancellation per piece (its terms grow like
/// `p₀/ω²` and `ȧ_g/ω³`), so the piece's end state and energy integrals come from the
/// φ-function form ([`sdof::piece`]). Above it the wave is kept: it is cheaper, as accurate, and
/// the study's grid (`ω_n·dt ≥ 0.009`) runs bit for bit as before (`docs/model.md`,
/// "Long periods").
const SDOF_FORM_OMEGA_STEP: f64 = 5e-3;

impl StructureCluster {
    /// The cluster of mass `mass` (kg) on a spring of stiffness `stiffness` (N/m, `≥ 0`) and
    /// the damper `damping` (N·s/m), with its sample-interval basis for `dt` (s).
    fn new(mass: f64, stiffness: f64, damping: f64, dt: f64) -> Self {
        let omega2 = stiffness / mass;
        let osc = if omega2 == 0.0 {
            Osc {
                decay: damping / mass,
                omega: 0.0,
            }
        } else {
            let decay = damping / (2.0 * mass);
            Osc {
                decay,
                omega: (omega2 - decay * decay).sqrt(),
            }
        };
        let basis_dt = Basis::at(osc, dt);
        StructureCluster {
            mass,
            osc,
            omega2,
            natural: osc.natural(),
            basis_dt,
            integrals_dt: PieceIntegrals::new(osc, &basis_dt),
            sdof_form: omega2 > 0.0 && omega2.sqrt() * dt < SDOF_FORM_OMEGA_STEP,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum EventKind {
    /// Slipping interface (0-based) whose relative velocity reaches zero.
    SlipStop(usize),
    /// Stuck interface (0-based) whose required force leaves the static limit.
    Break(usize),
    /// The structure's displacement reaches the end of its elastic range on side ±1.
    Yield(i8),
    /// The structure's velocity reverses in a plastic branch.
    Unload,
}

/// Branch of a yielding structure's restoring force `F = k_b·u + f_off`.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Branch {
    /// `k_b = k`, within `lo ≤ u ≤ hi` (m).
    Elastic { offset: f64, lo: f64, hi: f64 },
    /// On the bounding line of side `dir`: `k_b = r·k`, `f_off = dir·(1 − r)·F_y`; lasts while
    /// `dir·u̇ ≥ 0`.
    Plastic(i8),
}

/// The yielding structure's spring and its current branch (docs/model.md, "Yielding
/// structure"); all zero for the linear structure, which never reads it.
#[derive(Debug, Clone, Copy)]
struct Spring {
    /// Elastic stiffness `k` and post-yield stiffness `r·k`, N/m.
    k: f64,
    k_post: f64,
    /// `(1 − r)·F_y`, N.
    intercept: f64,
    /// Yield displacement `u_y`, m.
    u_y: f64,
    branch: Branch,
}

impl Spring {
    fn new(sys: &System) -> Self {
        let Some(h) = sys.hysteresis() else {
            return Self {
                k: 0.0,
                k_post: 0.0,
                intercept: 0.0,
                u_y: 0.0,
                branch: Branch::Elastic {
                    offset: 0.0,
                    lo: f64::NEG_INFINITY,
                    hi: f64::INFINITY,
                },
            };
        };
        Self {
            k: h.stiffness,
            k_post: h.post_yield_ratio * h.stiffness,
            intercept: h.intercept_n(),
            u_y: h.yield_displacement_m,
            branch: Branch::Elastic {
                offset: 0.0,
                lo: -h.yield_displacement_m,
                hi: h.yield_displacement_m,
            },
        }
    }

    fn plastic(&self) -> bool {
        matches!(self.branch, Branch::Plastic(_))
    }

    /// `(k_b, f_off)` of the current branch, N/m and N.
    #[inline]
    fn line(&self) -> (f64, f64) {
        match self.branch {
            Branch::Elastic { offset, .. } => (self.k, offset),
            Branch::Plastic(dir) => (self.k_post, f64::from(dir) * self.intercept),
        }
    }

    /// Restoring force at `u` (m) on the current branch, N.
    #[inline]
    fn force(&self, u: f64) -> f64 {
        let (kb, off) = self.line();
        kb * u + off
    }

    /// Leaves the plastic branch at `u` (m): the new elastic line passes through the bounding
    /// line's point at `u`, and the elastic range ends exactly at `u` on the side just left, so
    /// the yield event of that side starts at zero.
    fn unload(&mut self, u: f64) {
        let Branch::Plastic(dir) = self.branch else {
            return;
        };
        let f = self.k_post * u + f64::from(dir) * self.intercept;
        let offset = f - self.k * u;
        let width = 2.0 * self.u_y;
        self.branch = if dir > 0 {
            Branch::Elastic {
                offset,
                lo: u - width,
                hi: u,
            }
        } else {
            Branch::Elastic {
                offset,
                lo: u,
                hi: u + width,
            }
        };
    }
}

/// A function of the piece's local time with its derivative and the oscillation amplitudes of
/// its first four derivatives ([`Osc::amplitudes`]), from which every bound below is formed.
#[derive(Debug, Clone, Copy)]
struct Tracked {
    f: Wave,
    d1: Wave,
    amps: [f64; 5],
}

impl Tracked {
    const ZERO: Tracked = Tracked {
        f: Wave::ZERO,
        d1: Wave::ZERO,
        amps: [0.0; 5],
    };

    /// `s·f + v`: the amplitudes scale by `|s|`.
    fn affine(&self, s: f64, v: f64) -> Self {
        Self {
            f: self.f.scale(s).plus_constant(v),
            d1: self.d1.scale(s),
            amps: self.amps.map(|a| a * s.abs()),
        }
    }

    fn new(f: Wave, osc: Osc, natural: f64) -> Self {
        Self {
            f,
            d1: f.deriv(osc),
            amps: Osc::amplitudes(natural, f.amplitude()),
        }
    }

    /// This function over a piece whose free motion is `osc`, for the certified searches.
    fn over(&self, osc: Osc) -> OverPiece<'_> {
        OverPiece { g: self, osc }
    }

    /// The node at `b`.
    fn node(&self, osc: Osc, b: Basis) -> Node<Basis> {
        let (f, df) = self.over(osc).eval(&b);
        Node { at: b, f, df }
    }

    /// The node at the start of a piece, from the wave itself (`eval` at τ = 0, bit for bit,
    /// without the arithmetic).
    fn start(&self) -> Node<Basis> {
        Node {
            at: Basis::ZERO,
            f: self.f.p[0] + self.f.c,
            df: self.d1.p[0] + self.d1.c,
        }
    }
}

/// A [`Tracked`] function over one piece: what [`search`] needs of it.
#[derive(Clone, Copy)]
struct OverPiece<'a> {
    g: &'a Tracked,
    osc: Osc,
}

impl Smooth for OverPiece<'_> {
    type At = Basis;

    fn at(&self, tau: f64) -> Basis {
        Basis::at(self.osc, tau)
    }

    fn tau(at: &Basis) -> f64 {
        at.tau
    }

    fn eval(&self, b: &Basis) -> (f64, f64) {
        let (f, d1) = (&self.g.f, &self.g.d1);
        if b.tau == 0.0 {
            return (f.p[0] + f.c, d1.p[0] + d1.c);
        }
        (f.eval(b), d1.eval(b))
    }

    fn value(&self, b: &Basis) -> f64 {
        let f = &self.g.f;
        if b.tau == 0.0 {
            return f.p[0] + f.c;
        }
        f.eval(b)
    }

    fn slope(&self, b: &Basis) -> f64 {
        self.g.d1.eval(b)
    }

    fn second(&self, b: &Basis) -> f64 {
        let d2 = self.g.d1.deriv(self.osc);
        if b.tau == 0.0 {
            return d2.p[0] + d2.c;
        }
        d2.eval(b)
    }

    /// Bound of `|f⁽ᵏ⁾|` over `[b.tau, t1]`.
    #[inline]
    fn bound(&self, k: usize, b: &Basis, t1: f64) -> f64 {
        self.g.f.deriv_abs_bound(k, t1, b.exp, self.g.amps[k])
    }
}

/// The tightest bounds on the structure cluster's absolute acceleration above and below
/// (m/s²), each with the interface whose static limit sets it.
type BreakBounds = (Option<(f64, usize)>, Option<(f64, usize)>);

/// The interval `[lower, upper]` the structure cluster's acceleration must stay in, m/s²
/// (unbounded where no interface sets a side).
fn accel_limits((upper, lower): BreakBounds) -> (f64, f64) {
    (
        lower.map_or(f64::NEG_INFINITY, |(value, _)| value),
        upper.map_or(f64::INFINITY, |(value, _)| value),
    )
}

/// A switching function `g ≥ 0` while the mode holds.
#[derive(Debug, Clone, Copy)]
struct Event {
    kind: EventKind,
    g: Tracked,
}

/// One run of the integrator; `YIELDS` is whether the structure yields (its spring and plastic
/// clusters are read only then), `LONG_PERIODS` whether some cluster takes [`sdof::piece`]
/// ([`long_periods`]).
struct ExactRun<'s, const YIELDS: bool, const LONG_PERIODS: bool> {
    sys: &'s System,
    dt: f64,
    opts: ExactOptions,
    n: usize,
    /// The structure's cluster on the elastic stiffness, by top body.
    structure_elastic: Vec<StructureCluster>,
    /// The structure's cluster on the post-yield stiffness, by top body (empty unless `YIELDS`).
    structure_plastic: Vec<StructureCluster>,
    spring: Spring,
    /// `∫F_s du` so far, J (only with `YIELDS`; the linear structure's is `½k·u²`).
    spring_work: f64,
    /// `mass_prefix[j] = Σ_{i<j} m_i`.
    mass_prefix: Vec<f64>,
    lim_s: Vec<f64>,
    lim_k: Vec<f64>,
    x: Vec<f64>,
    v: Vec<f64>,
    contacts: Vec<Contact>,
    before: Vec<Contact>,
    force: Vec<f64>,
    external: Vec<f64>,
    selector: ContactSelector,
    cluster_of: Vec<usize>,
    bottom: Vec<usize>,
    top: Vec<usize>,
    disp: Vec<Wave>,
    vel: Vec<Wave>,
    /// The structure's displacement and its cluster's absolute acceleration over the piece.
    u0: Tracked,
    a0: Tracked,
    /// [`ExactRun::break_bounds`] of the current mode; `None` after a new mode is selected.
    bounds: Option<BreakBounds>,
    /// Constant absolute acceleration of each free cluster, m/s².
    accel_free: Vec<f64>,
    /// The ground's velocity at the piece's start, m/s: the record integrated exactly (it is
    /// linear between samples).
    vg: f64,
    events: Vec<Event>,
    slip_start: Vec<f64>,
    out: Response,
    energy: Energy,
}

impl<'s, const YIELDS: bool, const LONG_PERIODS: bool> ExactRun<'s, YIELDS, LONG_PERIODS> {
    fn new(sys: &'s System, dt: f64, opts: ExactOptions) -> Self {
        let n = sys.blocks();
        let m = sys.masses();
        let mut mass_prefix = vec![0.0; n + 2];
        for j in 0..=n {
            mass_prefix[j + 1] = mass_prefix[j] + m[j];
        }
        let k = sys.stiffness();
        let c = sys.damping();
        let structure_elastic = (0..=n)
            .map(|top| StructureCluster::new(mass_prefix[top + 1], k, c, dt))
            .collect();
        let spring = Spring::new(sys);
        let structure_plastic = if YIELDS {
            (0..=n)
                .map(|top| StructureCluster::new(mass_prefix[top + 1], spring.k_post, c, dt))
                .collect()
        } else {
            Vec::new()
        };
        let lim_s = (1..=n).map(|i| sys.static_limit(i)).collect();
        let lim_k = (1..=n).map(|i| sys.kinetic_limit(i)).collect();
        let contacts: Vec<Contact> = sys
            .mu_static()
            .iter()
            .map(|&mu| {
                if mu == 0.0 {
                    Contact::Free
                } else {
                    Contact::Stick
                }
            })
            .collect();
        let out = Response {
            peak_abs_accel_mps2: vec![0.0; n + 1],
            peak_abs_velocity_mps: vec![0.0; n + 1],
            peak_slip_m: vec![0.0; n],
            residual_slip_m: vec![0.0; n],
            slip_time_s: vec![0.0; n],
            held: vec![true; n],
            ..Response::default()
        };
        Self {
            sys,
            dt,
            opts,
            n,
            structure_elastic,
            structure_plastic,
            spring,
            spring_work: 0.0,
            mass_prefix,
            lim_s,
            lim_k,
            x: vec![0.0; n + 1],
            v: vec![0.0; n + 1],
            before: contacts.clone(),
            contacts,
            force: vec![0.0; n],
            external: vec![0.0; n + 1],
            selector: ContactSelector::new(n),
            cluster_of: vec![0; n + 1],
            bottom: vec![0; n + 1],
            top: vec![0; n + 1],
            disp: vec![Wave::ZERO; n + 1],
            vel: vec![Wave::ZERO; n + 1],
            u0: Tracked::ZERO,
            a0: Tracked::ZERO,
            bounds: None,
            accel_free: vec![0.0; n + 1],
            vg: 0.0,
            events: Vec::with_capacity(2 * n),
            slip_start: vec![0.0; n],
            out,
            energy: Energy {
                friction_per_interface: vec![0.0; n],
                ..Energy::default()
            },
        }
    }

    fn run(mut self, accel: &[f64], watch: &dyn super::Watch) -> Result<Response, SimError> {
        let steps = accel.len() - 1;
        let mut history = self
            .opts
            .history
            .then(|| History::with_capacity(steps + 1, self.n + 1));
        self.select(accel[0])?;
        self.build(accel[0], (accel[1] - accel[0]) / self.dt);
        if let Some(h) = history.as_mut() {
            self.record(h, 0.0, accel[0]);
        }
        let mut input_peak = 0.0f64;
        // The ground's velocity at the sample, m/s (at rest at the record's start).
        let mut vg_k = 0.0;
        for k in 0..steps {
            super::watched(watch, k, steps)?;
            let t0 = k as f64 * self.dt;
            let slope = (accel[k + 1] - accel[k]) / self.dt;
            let mut tau = 0.0;
            let mut switches_here = 0;
            loop {
                let ga = accel[k] + slope * tau;
                self.vg = vg_k + tau * (accel[k] + 0.5 * slope * tau);
                if tau == 0.0 && self.quiet_interval(ga, slope) {
                    break;
                }
                self.build(ga, slope);
                let h = self.dt - tau;
                let osc = self.osc();
                let basis_h = if tau == 0.0 {
                    self.structure_cluster().basis_dt
                } else {
                    Basis::at(osc, h)
                };
                // Both break events at once: A₀ certified inside its bounds over the piece.
                let breaks_clear = self.breaks_clear(&basis_h);
                // Both yield events at once: u certified inside the elastic range.
                let yields_clear = YIELDS && self.yields_clear(&basis_h);
                let mut first: Option<(f64, usize)> = None;
                for (e, ev) in self.events.iter().enumerate() {
                    if breaks_clear && matches!(ev.kind, EventKind::Break(_))
                        || yields_clear && matches!(ev.kind, EventKind::Yield(_))
                    {
                        continue;
                    }
                    let limit = first.map_or(h, |f| f.0);
                    let b_end = if limit == h {
                        basis_h
                    } else {
                        Basis::at(osc, limit)
                    };
                    let g = ev.g.over(osc);
                    let found =
                        search::first_violation(&g, &ev.g.start(), &ev.g.node(osc, b_end), self.dt)
                            .map_err(|source| SimError::Search { time_s: t0, source })?;
                    if let Some(t) = found
                        && first.is_none_or(|f| t < f.0)
                    {
                        first = Some((t, e));
                    }
                }
                let end = first.map_or(h, |f| f.0);
                let basis_end = if first.is_none() {
                    basis_h
                } else {
                    Basis::at(osc, end)
                };
                self.advance(t0 + tau, ga, slope, &basis_end)
                    .map_err(|source| SimError::Search { time_s: t0, source })?;
                if let Some((_, e)) = first {
                    tau += end;
                    let kind = self.events[e].kind;
                    self.switch(kind, accel[k] + slope * tau)?;
                    switches_here += 1;
                    if switches_here > self.opts.max_switches_per_step {
                        return Err(SimError::Zeno {
                            time_s: t0,
                            limit: self.opts.max_switches_per_step,
                        });
                    }
                } else {
                    break;
                }
            }
            vg_k += 0.5 * self.dt * (accel[k] + accel[k + 1]);
            let t1 = (k + 1) as f64 * self.dt;
            if self.opts.energy_balance {
                let (kinetic, mut strain) = Energy::state_terms(
                    self.sys.masses(),
                    &self.v,
                    self.sys.stiffness(),
                    self.x[0],
                );
                if YIELDS {
                    // Recoverable plus hysteretic: all the spring's work so far.
                    strain = self.spring_work;
                }
                input_peak = input_peak.max(self.energy.input.abs());
                if input_peak > 0.0 {
                    let err = self.energy.residual_with(kinetic, strain).abs() / input_peak;
                    self.out.energy_balance_error_max = self.out.energy_balance_error_max.max(err);
                }
            }
            if let Some(h) = history.as_mut() {
                let slope_next = if k + 2 <= steps {
                    (accel[k + 2] - accel[k + 1]) / self.dt
                } else {
                    0.0
                };
                self.build(accel[k + 1], slope_next);
                self.record(h, t1, accel[k + 1]);
            }
        }
        self.finish(history)
    }

    /// The structure's cluster on its current branch.
    #[inline]
    fn structure_cluster(&self) -> &StructureCluster {
        if YIELDS && self.spring.plastic() {
            &self.structure_plastic[self.top[0]]
        } else {
            &self.structure_elastic[self.top[0]]
        }
    }

    fn osc(&self) -> Osc {
        self.structure_cluster().osc
    }

    /// The structure's restoring force at its current displacement, N.
    fn restoring_force(&self) -> f64 {
        if YIELDS {
            self.spring.force(self.x[0])
        } else {
            self.sys.stiffness() * self.x[0]
        }
    }

    /// Clusters, their closed-form motion from the current state, and the switching functions.
    fn build(&mut self, ga: f64, slope: f64) {
        let n = self.n;
        let mut nc = 0;
        for j in 0..=n {
            if j == 0 || self.contacts[j - 1] != Contact::Stick {
                self.bottom[nc] = j;
                nc += 1;
            }
            self.cluster_of[j] = nc - 1;
            self.top[nc - 1] = j;
        }
        let top = self.top[0];
        let cluster = *self.structure_cluster();
        let f_above = if top < n { self.force[top] } else { 0.0 };
        let osc = cluster.osc;
        self.disp[0] = self.structure_wave(&cluster, f_above, ga, slope);
        self.vel[0] = self.disp[0].deriv(osc);
        self.u0 = Tracked {
            f: self.disp[0],
            d1: self.vel[0],
            amps: Osc::amplitudes(cluster.natural, self.disp[0].amplitude()),
        };
        self.a0 = Tracked::new(self.accel0_wave(), osc, cluster.natural);
        for cidx in 1..nc {
            let (bj, ej) = (self.bottom[cidx], self.top[cidx]);
            let mass = self.mass_prefix[ej + 1] - self.mass_prefix[bj];
            let above = if ej < n { self.force[ej] } else { 0.0 };
            let acc_abs = (self.force[bj - 1] - above) / mass;
            self.accel_free[cidx] = acc_abs;
            self.disp[cidx] = Wave {
                p: [self.x[bj], self.v[bj], 0.5 * (acc_abs - ga), -slope / 6.0],
                c: 0.0,
                d: 0.0,
            };
            self.vel[cidx] = self.disp[cidx].deriv(osc);
        }
        self.events.clear();
        let (upper, lower) = self.mode_bounds(top, f_above);
        // g = bound − A₀ above, A₀ − bound below.
        for (bound, sign) in [(upper, -1.0), (lower, 1.0)] {
            if let Some((value, i)) = bound {
                self.events.push(Event {
                    kind: EventKind::Break(i),
                    g: self.a0.affine(sign, -sign * value),
                });
            }
        }
        for i in 0..n {
            let Contact::Slip(dir) = self.contacts[i] else {
                continue;
            };
            let sgn = f64::from(dir);
            let (lower, upper) = (self.cluster_of[i], self.cluster_of[i + 1]);
            let mut g = self.vel[upper].combine(sgn, &self.vel[lower], -sgn);
            // Anchor the value at τ = 0 to the state (exactly 0 for a fresh slip).
            let g0_state = sgn * (self.v[i + 1] - self.v[i]);
            g.p[0] += g0_state - (g.p[0] + g.c);
            self.events.push(Event {
                kind: EventKind::SlipStop(i),
                g: Tracked::new(g, osc, cluster.natural),
            });
        }
        if YIELDS {
            self.push_structure_events(osc, cluster.natural);
        }
    }

    /// The yielding structure's switching functions: in the elastic branch `hi − u ≥ 0` and
    /// `u − lo ≥ 0`; in a plastic branch `dir·u̇ ≥ 0`. Their values at `τ = 0` are set from the
    /// state (as the slip events' are), exactly: right after an unloading the yield function of
    /// the side just left starts at exactly 0, and its slope from the state's velocity, whose
    /// sign the event made certain (the wave's own slope there can differ by round-off and
    /// would yield again at once).
    fn push_structure_events(&mut self, osc: Osc, natural: f64) {
        let (x0, v0) = (self.x[0], self.v[0]);
        match self.spring.branch {
            Branch::Elastic { lo, hi, .. } => {
                for (dir, sign, value) in [(1, -1.0, hi - x0), (-1, 1.0, x0 - lo)] {
                    let mut g = self.u0.affine(sign, 0.0);
                    g.f.p[0] = value - g.f.c;
                    g.d1.p[0] = sign * v0 - g.d1.c;
                    self.events.push(Event {
                        kind: EventKind::Yield(dir),
                        g,
                    });
                }
            }
            Branch::Plastic(dir) => {
                let sgn = f64::from(dir);
                let mut g = Tracked::new(self.vel[0].scale(sgn), osc, natural);
                g.f.p[0] = sgn * v0 - g.f.c;
                self.events.push(Event {
                    kind: EventKind::Unload,
                    g,
                });
            }
        }
    }

    /// The structure cluster's displacement over a piece from the current state:
    /// `ü + 2aü + ω²u = p0 + p1·τ` (Nigam–Jennings, the constant friction from above added; for
    /// a yielding structure, the branch's constant force `f_off` too). On a branch without
    /// stiffness (`r = 0`): `ü + a·u̇ = p0 + p1·τ`, `a = c/M`, whose velocity is
    /// `A + Bτ + (v₀ − A)·e^{−aτ}` with `B = p1/a`, `A = (p0 − B)/a`; without damping either,
    /// a cubic.
    fn structure_wave(
        &self,
        cluster: &StructureCluster,
        f_above: f64,
        ga: f64,
        slope: f64,
    ) -> Wave {
        let p0 = if YIELDS {
            self.plastic_load(cluster, f_above, ga)
        } else {
            -f_above / cluster.mass - ga
        };
        let p1 = -slope;
        if YIELDS && cluster.omega2 == 0.0 {
            let (x0, v0) = (self.x[0], self.v[0]);
            let a = cluster.osc.decay;
            if a == 0.0 {
                return Wave {
                    p: [x0, v0, 0.5 * p0, p1 / 6.0],
                    c: 0.0,
                    d: 0.0,
                };
            }
            let big_b = p1 / a;
            let big_a = (p0 - big_b) / a;
            let c = -(v0 - big_a) / a;
            return Wave {
                p: [x0 - c, big_a, 0.5 * big_b, 0.0],
                c,
                d: 0.0,
            };
        }
        let b = p1 / cluster.omega2;
        let a = (p0 - 2.0 * cluster.osc.decay * b) / cluster.omega2;
        let c = self.x[0] - a;
        let d = (self.v[0] - b + cluster.osc.decay * c) / cluster.osc.omega;
        Wave {
            p: [a, b, 0.0, 0.0],
            c,
            d,
        }
    }

    /// `p₀` of [`ExactRun::structure_wave`] for a yielding structure: `−(f_above + f_off)/M − a_g`,
    /// m/s².
    fn plastic_load(&self, cluster: &StructureCluster, f_above: f64, ga: f64) -> f64 {
        -(f_above + self.spring.line().1) / cluster.mass - ga
    }

    /// The structure cluster's piece ending at `b` in a cancellation-free φ-function form, or
    /// `None` where its wave is accurate: on a branch without stiffness (`r = 0`) with `a·h ≤ 1`,
    /// [`decay_piece`] (beyond, the wave's terms of order `p₀/a²` no longer exceed its values);
    /// at long periods (`ω_n·dt` below `SDOF_FORM_OMEGA_STEP`), [`sdof::piece`].
    fn stable_piece(&self, ga: f64, slope: f64, b: &Basis) -> Option<Piece> {
        let cluster = self.structure_cluster();
        if LONG_PERIODS && cluster.sdof_form {
            return Some(self.sdof_piece(cluster, ga, slope, b));
        }
        if !YIELDS || cluster.omega2 != 0.0 || cluster.osc.decay * b.tau > 1.0 {
            return None;
        }
        Some(decay_piece(
            cluster.osc.decay,
            (self.plastic_load(cluster, self.f_above(), ga), -slope),
            (self.x[0], self.v[0]),
            b.tau,
            self.opts.energy_balance,
        ))
    }

    /// The [`sdof::piece`] branch of [`ExactRun::stable_piece`], kept out of line: the study's grid
    /// never takes it.
    #[cold]
    #[inline(never)]
    fn sdof_piece(&self, cluster: &StructureCluster, ga: f64, slope: f64, b: &Basis) -> Piece {
        let (omega_n, zeta, p0) = self.sdof_params(cluster, ga);
        sdof::piece(
            omega_n,
            zeta,
            (p0, -slope),
            (self.x[0], self.v[0]),
            b.tau,
            self.opts.energy_balance,
        )
    }

    /// `(max |u|, τ)` over the piece `[0, h]` by [`sdof::Step`], for a cluster that takes
    /// [`sdof::piece`] (the wave's values lose digits there): the piece's end and every zero of
    /// the exact `u̇` inside it, each found by Newton steps (`ü = p₀ + p₁τ − 2ζω_nu̇ − ω_n²u`)
    /// from a root of the velocity's Taylor polynomial `v₀ + ü₀τ + u⃛₀τ²/2`, whose error is of
    /// relative order `(ω_n·h)² < 2.5e-5`. The start is the previous piece's end.
    #[cold]
    #[inline(never)]
    fn sdof_peak(&self, ga: f64, slope: f64, h: f64) -> (f64, f64) {
        let (omega_n, zeta, p0) = self.sdof_params(self.structure_cluster(), ga);
        let (x0, v0, p1) = (self.x[0], self.v[0], -slope);
        let at = |t: f64| sdof::Step::new(omega_n, zeta, t).step(x0, v0, -p0, -(p0 + p1 * t));
        let mut best = (at(h).0.abs(), h);
        // v₀ + ü₀τ + (u⃛₀/2)τ² = 0 (Taylor to second order) without cancellation.
        let acc0 = p0 - 2.0 * zeta * omega_n * v0 - omega_n * omega_n * x0;
        let jerk0 = p1 - 2.0 * zeta * omega_n * acc0 - omega_n * omega_n * v0;
        let (qa, qb, qc) = (0.5 * jerk0, acc0, v0);
        let mut starts = [f64::NAN; 2];
        if qa == 0.0 {
            starts[0] = -qc / qb;
        } else {
            let disc = qb * qb - 4.0 * qa * qc;
            if disc >= 0.0 {
                let q = -0.5 * (qb + qb.signum() * disc.sqrt());
                starts = [q / qa, qc / q];
            }
        }
        for mut t in starts {
            if !(t > -0.01 * h && t < 1.01 * h) {
                continue;
            }
            for _ in 0..4 {
                let (u, v) = at(t);
                let acc = p0 + p1 * t - 2.0 * zeta * omega_n * v - omega_n * omega_n * u;
                let next = t - v / acc;
                if !next.is_finite() || next == t {
                    break;
                }
                t = next;
            }
            if t > 0.0 && t < h {
                let u = at(t).0.abs();
                if u > best.0 {
                    best = (u, t);
                }
            }
        }
        best
    }

    /// `(ω_n, ζ, p₀)` of the structure cluster's equation `ü + 2ζω_nu̇ + ω_n²u = p₀ + p₁τ`
    /// (the load of [`ExactRun::structure_wave`]).
    fn sdof_params(&self, cluster: &StructureCluster, ga: f64) -> (f64, f64, f64) {
        let p0 = if YIELDS {
            self.plastic_load(cluster, self.f_above(), ga)
        } else {
            -self.f_above() / cluster.mass - ga
        };
        let omega_n = cluster.omega2.sqrt();
        (omega_n, cluster.osc.decay / omega_n, p0)
    }

    /// The friction force on the structure cluster's top body from the body above, N (0 when the
    /// whole stack is in the cluster).
    fn f_above(&self) -> f64 {
        let top = self.top[0];
        if top < self.n { self.force[top] } else { 0.0 }
    }

    /// A whole sample interval on which, with every interface stuck, nothing can happen: the
    /// acceleration stays inside its break bounds and neither the displacement nor the
    /// acceleration can exceed its peak so far, each certified by the curvature bound on the
    /// values at the two ends. Then the piece needs only its energy and new state
    /// ([`ExactRun::settle`]), the same as the general path would give, and this returns `true`;
    /// otherwise it changes nothing and returns `false`.
    fn quiet_interval(&mut self, ga: f64, slope: f64) -> bool {
        let n = self.n;
        // The cluster arrays are those of the current mode (built at the last piece). A rocking
        // check still looking for its onset is made on every piece: the peaks so far, which
        // clear a quiet interval, need not bound its criterion.
        if self.top[0] != n
            || (YIELDS && self.spring.plastic())
            || (self.sys.rocking().is_some() && self.out.rocking_onset.is_none())
        {
            return false;
        }
        let cluster = self.structure_elastic[n];
        let (h, b) = (self.dt, cluster.basis_dt);
        let u = self.structure_wave(&cluster, 0.0, ga, slope);
        let (u_lo, u_hi) = (u.p[0] + u.c, u.eval(&b));
        let amp2 = cluster.natural * cluster.natural * u.amplitude();
        let curv_u = u.deriv_abs_bound(2, h, 1.0, amp2) * h * h / 8.0;
        if u_lo.abs().max(u_hi.abs()) + curv_u > self.out.peak_displacement_m {
            return false;
        }
        if YIELDS
            && let Branch::Elastic { lo, hi, .. } = self.spring.branch
            && (u_lo.min(u_hi) - curv_u < lo || u_lo.max(u_hi) + curv_u > hi)
        {
            return false;
        }
        let vel = u.deriv(cluster.osc);
        let (c_m, k_m) = (
            self.sys.damping() / cluster.mass,
            self.sys.stiffness() / cluster.mass,
        );
        let mut acc = vel.combine(-c_m, &u, -k_m);
        if YIELDS {
            acc = acc.plus_constant(-self.spring.line().1 / cluster.mass);
        }
        let (a_lo, a_hi) = (acc.p[0] + acc.c, acc.eval(&b));
        let amp_acc2 = cluster.natural * cluster.natural * acc.amplitude();
        let curv_a = acc.deriv_abs_bound(2, h, 1.0, amp_acc2) * h * h / 8.0;
        let floor = self
            .out
            .peak_abs_accel_mps2
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        if a_lo.abs().max(a_hi.abs()) + curv_a > floor {
            return false;
        }
        if self.opts.abs_velocity {
            let v_abs = self.abs_velocity_wave(&vel, ga, slope);
            let (v_lo, v_hi) = (v_abs.p[0] + v_abs.c, v_abs.eval(&b));
            let amp_v2 = cluster.natural * cluster.natural * v_abs.amplitude();
            let curv_v = v_abs.deriv_abs_bound(2, h, 1.0, amp_v2) * h * h / 8.0;
            let floor_v =
                (self.out.peak_abs_velocity_mps.iter().copied()).fold(f64::INFINITY, f64::min);
            if v_lo.abs().max(v_hi.abs()) + curv_v > floor_v {
                return false;
            }
        }
        let (lo, hi) = accel_limits(self.mode_bounds(n, 0.0));
        if a_lo.min(a_hi) - curv_a < lo || a_lo.max(a_hi) + curv_a > hi {
            return false;
        }
        self.disp[0] = u;
        self.vel[0] = vel;
        self.settle(ga, slope, &b);
        true
    }

    /// [`ExactRun::break_bounds`] of the current mode, computed once per mode.
    fn mode_bounds(&mut self, top: usize, f_above: f64) -> BreakBounds {
        if self.bounds.is_none() {
            self.bounds = Some(self.break_bounds(top, f_above));
        }
        self.bounds.unwrap_or_default()
    }

    /// Every interface inside the structure's cluster (top body `top`, friction `f_above` from
    /// above) carries `m_above·A₀(τ) + f_above`, so its static limit bounds A₀ to an interval; the
    /// tightest bounds above and below, with their interfaces, are the only ones that can be
    /// reached first. Bounds equal to within a tenth of the break tolerance (equal μ up to
    /// round-off) count as a tie, won by the lowest interface: a stack that moves as one slips at
    /// its base. Constant within a mode.
    fn break_bounds(&self, top: usize, f_above: f64) -> BreakBounds {
        let tie = 0.1 * BREAK_TOLERANCE;
        let (mut upper, mut lower): BreakBounds = (None, None);
        for i in 0..top {
            let m_above = self.mass_prefix[top + 1] - self.mass_prefix[i + 1];
            let room = self.lim_s[i] * (1.0 + BREAK_TOLERANCE);
            let (hi, lo) = ((room - f_above) / m_above, (-room - f_above) / m_above);
            if upper.is_none_or(|(h, _)| hi < h - tie * h.abs()) {
                upper = Some((hi, i));
            }
            if lower.is_none_or(|(l, _)| lo > l + tie * l.abs()) {
                lower = Some((lo, i));
            }
        }
        (upper, lower)
    }

    /// Whether the structure cluster's acceleration stays inside its break bounds over the piece
    /// ending at `b` (the same test the two break events' searches start with, done once);
    /// when not, the searches run.
    fn breaks_clear(&self, b: &Basis) -> bool {
        let bounds = self.bounds.unwrap_or_default();
        if bounds == (None, None) {
            return true;
        }
        let (lo, hi) = accel_limits(bounds);
        let osc = self.osc();
        let (n0, n1) = (self.a0.node(osc, Basis::ZERO), self.a0.node(osc, *b));
        search::range_within(&self.a0.over(osc), &n0, &n1, lo, hi)
    }

    /// Whether a yielding structure in its elastic branch stays inside its elastic range over
    /// the piece ending at `b` (the test both yield events' searches start with, done once).
    fn yields_clear(&self, b: &Basis) -> bool {
        let Branch::Elastic { lo, hi, .. } = self.spring.branch else {
            return false;
        };
        let osc = self.osc();
        let (mut n0, n1) = (self.u0.node(osc, Basis::ZERO), self.u0.node(osc, *b));
        // The state, not the wave, at τ = 0: the events are anchored to it.
        n0.f = self.x[0];
        search::range_within(&self.u0.over(osc), &n0, &n1, lo, hi)
    }

    /// Absolute acceleration of the structure's cluster: `(F − c·u̇ − k·u)/M`, or with a
    /// yielding structure `(F − c·u̇ − k_b·u − f_off)/M`.
    fn accel0_wave(&self) -> Wave {
        let top = self.top[0];
        let mass = self.structure_elastic[top].mass;
        let f_above = if top < self.n { self.force[top] } else { 0.0 };
        if YIELDS {
            let (kb, off) = self.spring.line();
            return self.vel[0]
                .combine(-self.sys.damping() / mass, &self.disp[0], -kb / mass)
                .plus_constant(-(f_above + off) / mass);
        }
        self.vel[0]
            .combine(
                -self.sys.damping() / mass,
                &self.disp[0],
                -self.sys.stiffness() / mass,
            )
            .plus_constant(-f_above / mass)
    }

    /// `vel + v_g`: a velocity wave relative to the ground made absolute by the ground's
    /// velocity over the piece, `v_g + a_g·τ + ȧ_g·τ²/2` (`ga`, `slope` at the piece's start).
    fn abs_velocity_wave(&self, vel: &Wave, ga: f64, slope: f64) -> Wave {
        let mut w = *vel;
        w.p[0] += self.vg;
        w.p[1] += ga;
        w.p[2] += 0.5 * slope;
        w
    }

    /// Moves the state to the end of the current piece, accumulating peaks and energy over it.
    fn advance(
        &mut self,
        t_start: f64,
        ga: f64,
        slope: f64,
        b: &Basis,
    ) -> Result<(), search::SearchError> {
        let osc = self.osc();
        let top = self.top[0];
        let b0 = Basis::ZERO;
        // Peaks of the structure's displacement and its cluster's absolute acceleration.
        let (best, at) = if LONG_PERIODS && self.structure_cluster().sdof_form {
            self.sdof_peak(ga, slope, b.tau)
        } else {
            let (n0, n1) = (self.u0.node(osc, b0), self.u0.node(osc, *b));
            search::peak_abs(
                &self.u0.over(osc),
                &n0,
                &n1,
                self.out.peak_displacement_m,
                self.dt,
            )?
        };
        if best > self.out.peak_displacement_m {
            self.out.peak_displacement_m = best;
            self.out.peak_displacement_time_s = t_start + at;
        }
        // Bodies of the structure's cluster share its acceleration: search above the smallest
        // of their peaks; a result above it is this piece's maximum.
        let floor = self.out.peak_abs_accel_mps2[..=top]
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        let (n0, n1) = (self.a0.node(osc, b0), self.a0.node(osc, *b));
        let (best_acc, _) = search::peak_abs(&self.a0.over(osc), &n0, &n1, floor, self.dt)?;
        if best_acc > floor {
            for p in &mut self.out.peak_abs_accel_mps2[..=top] {
                *p = p.max(best_acc);
            }
        }
        for j in top + 1..=self.n {
            let a = self.accel_free[self.cluster_of[j]].abs();
            let p = &mut self.out.peak_abs_accel_mps2[j];
            *p = p.max(a);
        }
        if self.opts.abs_velocity {
            self.abs_velocity_peaks(ga, slope, b)?;
        }
        self.rocking(t_start, b)?;
        self.settle(ga, slope, b);
        Ok(())
    }

    /// Raises the peak absolute velocities over the piece ending at `b`: the structure's
    /// cluster's wave plus the ground's quadratic, searched like the acceleration; a free
    /// cluster's is linear (its absolute acceleration is constant), so its ends bound it.
    fn abs_velocity_peaks(
        &mut self,
        ga: f64,
        slope: f64,
        b: &Basis,
    ) -> Result<(), search::SearchError> {
        let (osc, top) = (self.osc(), self.top[0]);
        let floor = self.out.peak_abs_velocity_mps[..=top]
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        let v_abs = self.abs_velocity_wave(&self.vel[0], ga, slope);
        let v_abs = Tracked::new(v_abs, osc, self.structure_cluster().natural);
        let mut n0 = v_abs.start();
        n0.f = self.v[0] + self.vg;
        let n1 = v_abs.node(osc, *b);
        let (best_v, _) = search::peak_abs(&v_abs.over(osc), &n0, &n1, floor, self.dt)?;
        if best_v > floor {
            for p in &mut self.out.peak_abs_velocity_mps[..=top] {
                *p = p.max(best_v);
            }
        }
        for j in top + 1..=self.n {
            let v0 = self.v[j] + self.vg;
            let v1 = v0 + self.accel_free[self.cluster_of[j]] * b.tau;
            let p = &mut self.out.peak_abs_velocity_mps[j];
            *p = p.max(v0.abs()).max(v1.abs());
        }
        Ok(())
    }

    /// The first rocking onset in the piece ending at `b` (starting at `t_start`, s), while
    /// none is known: per interface `i`, `g = g_n ∓ Σ_j w_ij·a_j ≥ 0` (docs/model.md, "Rocking:
    /// when a case leaves the model"), the blocks of the structure's cluster moving with its
    /// acceleration wave, the others with their clusters' constant ones.
    fn rocking(&mut self, t_start: f64, b: &Basis) -> Result<(), search::SearchError> {
        let Some(rocking) = self.sys.rocking() else {
            return Ok(());
        };
        if self.out.rocking_onset.is_some() {
            return Ok(());
        }
        let (osc, top) = (self.osc(), self.top[0]);
        let mut found = None;
        for i in 0..rocking.blocks() {
            // Block j is body j + 1.
            let (on_wave, constant) = rocking.split(i, |j| {
                (j + 1 > top).then(|| self.accel_free[self.cluster_of[j + 1]])
            });
            for sign in [1.0, -1.0] {
                let g = self.a0.affine(-sign * on_wave, G - sign * constant);
                let at =
                    search::first_violation(&g.over(osc), &g.start(), &g.node(osc, *b), self.dt)?;
                found = rocking::earlier(
                    found,
                    at.map(|t| RockingOnset {
                        block: i + 1,
                        time_s: t_start + t,
                    }),
                );
            }
        }
        self.out.rocking_onset = found;
        Ok(())
    }

    /// The energy terms over the piece ending at `b` and the new state of every body (the
    /// clusters' waves are those of the piece).
    fn settle(&mut self, ga: f64, slope: f64, b: &Basis) {
        let osc = self.osc();
        let end = b.tau;
        // Energy: input −Σ M_c∫a_g·v_c, damping ∫c·u̇².
        let nc = self.cluster_of[self.n] + 1;
        // A plastic piece without stiffness, or a long period: the structure cluster's state and
        // integrals from a cancellation-free form.
        let stable = self.stable_piece(ga, slope, b);
        if self.opts.energy_balance {
            let cluster = *self.structure_cluster();
            let pi = if *b == cluster.basis_dt {
                cluster.integrals_dt
            } else {
                PieceIntegrals::new(osc, b)
            };
            let mut input = 0.0;
            for cidx in 0..nc {
                let mass =
                    self.mass_prefix[self.top[cidx] + 1] - self.mass_prefix[self.bottom[cidx]];
                let int_av = match stable {
                    Some(d) if cidx == 0 => ga * (d.u - self.x[0]) + slope * (end * d.u - d.int_u),
                    _ => {
                        let w = &self.disp[cidx];
                        let x0 = w.p[0] + w.c;
                        let x1 = w.eval(b);
                        ga * (x1 - x0) + slope * (end * x1 - w.integral_with(b, &pi))
                    }
                };
                input -= mass * int_av;
            }
            self.energy.input += input;
            self.energy.damping += self.sys.damping()
                * match stable {
                    Some(d) => d.int_v2,
                    None if YIELDS && cluster.omega2 == 0.0 => {
                        integral_of_square_decay(&self.vel[0], osc.decay, end)
                    }
                    None => integral_of_square_with(&self.vel[0], b, &pi),
                };
        }
        if YIELDS {
            // ∫F_s du over the piece, F_s = k_b·u + f_off on one branch.
            let (kb, off) = self.spring.line();
            let u0 = self.x[0];
            let u1 = stable.map_or_else(|| self.disp[0].eval(b), |d| d.u);
            self.spring_work += (u1 - u0) * (0.5 * kb * (u1 + u0) + off);
        }
        // New state of every body; offsets within a cluster are constant.
        for i in 0..self.n {
            self.slip_start[i] = self.x[i + 1] - self.x[i];
        }
        for cidx in 0..nc {
            let bj = self.bottom[cidx];
            let (xb, vb) = match stable {
                Some(d) if cidx == 0 => (d.u, d.v),
                _ => (self.disp[cidx].eval(b), self.vel[cidx].eval(b)),
            };
            for j in (bj..=self.top[cidx]).rev() {
                self.x[j] = xb + (self.x[j] - self.x[bj]);
                self.v[j] = vb;
            }
        }
        for i in 0..self.n {
            let slip = self.x[i + 1] - self.x[i];
            if let Contact::Slip(_) = self.contacts[i] {
                self.out.slip_time_s[i] += end;
                // The relative velocity keeps its sign within a mode: work is μ_k·N·|Δslip|.
                let w = self.lim_k[i] * (slip - self.slip_start[i]).abs();
                self.energy.friction_per_interface[i] += w;
                self.energy.friction += w;
            }
            let p = &mut self.out.peak_slip_m[i];
            *p = p.max(slip.abs());
        }
    }

    /// Applies a switch at the current state and chooses the next mode. A yield or an
    /// unloading changes only the structure's branch: its force is continuous there, so the
    /// contact forces and the stick/slip mode stay as they are.
    fn switch(&mut self, kind: EventKind, ga: f64) -> Result<(), SimError> {
        match kind {
            EventKind::Yield(dir) => {
                self.spring.branch = Branch::Plastic(dir);
                self.out.yield_events += 1;
            }
            EventKind::Unload => {
                if let Branch::Plastic(dir) = self.spring.branch
                    && f64::from(dir) * self.v[0] > 0.0
                {
                    // The event certified the reversal on the wave; the state's velocity (of
                    // the cancellation-free form when r = 0) is zero up to a round-off residue,
                    // here of the old sign, which would yield again at once: it is zero.
                    self.v[..=self.top[0]].fill(0.0);
                }
                self.spring.unload(self.x[0]);
                self.out.yield_events += 1;
            }
            EventKind::SlipStop(i) => self.out.switches += switch_contacts(self, Some(i), &[], ga)?,
            EventKind::Break(i) => self.out.switches += switch_contacts(self, None, &[i], ga)?,
        }
        Ok(())
    }

    fn fill_state_energy(&self, e: &mut Energy) {
        e.set_state(self.sys.masses(), &self.v, self.sys.stiffness(), self.x[0]);
        if YIELDS {
            let f = self.spring.force(self.x[0]);
            e.strain = f * f / (2.0 * self.spring.k);
            e.hysteretic = self.spring_work - e.strain;
        }
    }

    /// Appends the current state as a history row (mode of the piece ending here).
    fn record(&self, h: &mut History, t: f64, ga: f64) {
        h.time_s.push(t);
        h.ground_accel_mps2.push(ga);
        h.displacement_m.extend_from_slice(&self.x);
        h.velocity_mps.extend_from_slice(&self.v);
        let top = self.top[0];
        let mass = self.structure_elastic[top].mass;
        let f_above = if top < self.n { self.force[top] } else { 0.0 };
        let a0 = (-f_above - self.sys.damping() * self.v[0] - self.restoring_force()) / mass;
        for j in 0..=self.n {
            h.abs_accel_mps2.push(if j <= top {
                a0
            } else {
                self.accel_free[self.cluster_of[j]]
            });
        }
        h.contact.extend(self.contacts.iter().map(|c| c.code()));
    }

    fn finish(mut self, history: Option<History>) -> Result<Response, SimError> {
        let mut e = std::mem::take(&mut self.energy);
        self.fill_state_energy(&mut e);
        let mut e = e.per_kg(self.sys.mass_kg());
        if !self.opts.energy_balance {
            e.input = f64::NAN;
            e.damping = f64::NAN;
            self.out.energy_balance_error_max = f64::NAN;
        }
        if !self.opts.abs_velocity {
            self.out.peak_abs_velocity_mps.fill(f64::NAN);
        }
        for i in 0..self.n {
            self.out.residual_slip_m[i] = self.x[i + 1] - self.x[i];
        }
        self.out.residual_displacement_m = self.x[0];
        if YIELDS {
            self.out.ductility = Some(self.out.peak_displacement_m / self.spring.u_y);
        }
        self.out.energy = e;
        self.out.history = history;
        Ok(self.out)
    }
}

impl<const YIELDS: bool, const LONG_PERIODS: bool> Contacts for ExactRun<'_, YIELDS, LONG_PERIODS> {
    fn states(&mut self) -> (&mut [Contact], &mut [Contact]) {
        (&mut self.contacts, &mut self.before)
    }

    fn relative_velocity(&self, i: usize) -> f64 {
        self.v[i + 1] - self.v[i]
    }

    fn force(&self, i: usize) -> f64 {
        self.force[i]
    }

    /// External forces at the current state and the Coulomb-consistent mode.
    fn select(&mut self, ga: f64) -> Result<(), SimError> {
        self.bounds = None;
        let m = self.sys.masses();
        for j in 0..=self.n {
            self.external[j] = -m[j] * ga;
        }
        self.external[0] -= self.sys.damping() * self.v[0] + self.restoring_force();
        self.selector.select(
            m,
            &self.external,
            &self.lim_s,
            &self.lim_k,
            &mut self.contacts,
            &mut self.force,
        )?;
        keep_held(&mut self.out.held, &self.contacts);
        Ok(())
    }

    /// Gives every run of bodies joined by stuck interfaces one momentum-weighted velocity; the
    /// kinetic energy this removes (round-off small after an exact root) is friction work of the
    /// lowest interface that just stopped in the run.
    fn merge_stopped(&mut self) {
        let m = self.sys.masses();
        let mut j0 = 0;
        while j0 <= self.n {
            let mut j1 = j0;
            while j1 < self.n && self.contacts[j1] == Contact::Stick {
                j1 += 1;
            }
            let first_stopped = (j0..j1).find(|&i| self.before[i] != Contact::Stick);
            if let Some(i) = first_stopped {
                let mass = self.mass_prefix[j1 + 1] - self.mass_prefix[j0];
                let momentum: f64 = (j0..=j1).map(|j| m[j] * self.v[j]).sum();
                let vm = momentum / mass;
                let loss: f64 = (j0..=j1)
                    .map(|j| 0.5 * m[j] * (self.v[j] - vm) * (self.v[j] - vm))
                    .sum();
                self.energy.friction_per_interface[i] += loss;
                self.energy.friction += loss;
                for j in j0..=j1 {
                    self.v[j] = vm;
                }
            }
            j0 = j1 + 1;
        }
    }
}
