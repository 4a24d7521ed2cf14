//! The exact event-driven integrator of a building (docs/model.md, "A multi-storey building"),
//! the multi-storey form of [`super::super::exact`].
//!
//! Within a mode (every interface stuck or slipping, every storey on one branch) the floors with
//! the blocks stuck to them form one linear system, moved exactly by `modal`; every
//! other run of stuck blocks is a free mass under constant friction (a cubic). A sample interval
//! is crossed in one piece unless a switch occurs inside it:
//! * a slipping interface's relative velocity reaches zero;
//! * a floor's absolute acceleration leaves the interval in which the static friction of every
//!   interface stuck to it can carry the blocks above (the tightest bound over the floor's
//!   stacks, ties to the first stack and the lowest interface; the stacks whose bound ties it
//!   break loose together, `Integrator::broken_together`);
//! * a storey's drift reaches the end of its elastic range (yield), or its drift rate reverses
//!   on a bounding line (unloading).
//!
//! Each is located by the certified search of `dynamics::search` and refined to a few ulps
//! of time; the new mode is chosen floor by floor ([`ContactSelector::select_tree`]: at an
//! instant the spring and damper forces are known, so the floors' contact problems are
//! independent), by the same rule as for one storey. The peaks of every floor's displacement
//! and absolute acceleration and of every storey's drift are found by the same kind of search.
//! Energy terms are exact per piece, the damping integral `∫u̇ᵀ·C·u̇` by 8-point Gauss–Legendre
//! on panels no longer than `1/max|λ|` (error below `1e-16` of the integral).

// Parallel per-body and per-interface arrays read best with index loops.
#![allow(clippy::needless_range_loop)]

use super::super::contact::{Contact, ContactSelector, Contacts, keep_held, switch_contacts};
use super::super::deferred::DeferredPeak;
use super::super::exact::{BREAK_TOLERANCE, ExactOptions};
use super::super::model::G;
use super::super::response::{Energy, History};
use super::super::rocking::{self, RockingOnset};
use super::super::search::{self, Node};
use super::super::{Ground, SimError, Unwatched, Watch, watched};
use super::modal::{
    ModalError, ModalFn, ModalPoint, Piece, RowsByMode, StateModes, cubic, cubic_slope, mode_terms,
};
use super::model::{Building, Stack, StoreySpring};
use super::response::BuildingResponse;
use crate::numeric::{Cx, GAUSS8};
use std::cell::RefCell;
use std::collections::HashMap;
use std::rc::Rc;

impl From<ModalError> for SimError {
    fn from(e: ModalError) -> Self {
        SimError::Modal(e.to_string())
    }
}

/// Runs the exact integrator of a building over the whole record.
pub fn simulate_building(
    building: &Building,
    ground: &Ground,
    opts: &ExactOptions,
) -> Result<BuildingResponse, SimError> {
    simulate_building_watched(building, ground, opts, &Unwatched)
}

/// [`simulate_building`] under `watch` ([`Watch`]).
pub fn simulate_building_watched(
    building: &Building,
    ground: &Ground,
    opts: &ExactOptions,
    watch: &dyn Watch,
) -> Result<BuildingResponse, SimError> {
    ground.validate()?;
    let r = Integrator::new(building, ground.dt_s, *opts).run(ground.accel_mps2, watch)?;
    r.check_finite()?;
    Ok(r)
}

/// Branch of a storey's restoring force `F = k_b·δ + f_off`.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Branch {
    /// `k_b = k`, within `lo ≤ δ ≤ hi` (m).
    Elastic { offset: f64, lo: f64, hi: f64 },
    /// On the bounding line of side `dir`: `k_b = r·k`, `f_off = dir·(1 − r)·F_y`.
    Plastic(i8),
}

/// The bases met by the runs on this thread, by the exact bits of everything a [`Mode`]
/// depends on: a sweep runs one building under many frictions and motions, and each meets the
/// same few contact and yield states. A basis is a function of its inputs alone, so a run gives
/// the same bits whether its bases come from here or are computed again.
#[derive(Default)]
struct BasisMemo {
    bases: HashMap<Vec<u64>, Rc<Mode>>,
    /// Their numbers (8 bytes each), counted against [`BASIS_MEMO_VALUES`].
    values: usize,
}

/// Numbers the memo of one thread holds before it starts again empty: 16 MiB, about 90
/// twenty-storey bases or a thousand six-storey ones (each about 8 numbers per row
/// coefficient: the rows, their magnitudes, the tables by mode and the basis itself).
const BASIS_MEMO_VALUES: usize = 2 << 20;

thread_local! {
    static BASES: RefCell<BasisMemo> = RefCell::new(BasisMemo::default());
}

impl BasisMemo {
    /// The basis of a state with floor masses `floor_mass` (kg, with their stuck blocks) and
    /// storey stiffnesses `k_t` (N/m) in `b` (its damping and storey heights) at step `dt`
    /// (s): from the memo, or built by `build` and kept.
    fn get_or_build(
        &mut self,
        dt: f64,
        floor_mass: &[f64],
        k_t: &[f64],
        b: &Building,
        build: impl FnOnce() -> Result<Mode, ModalError>,
    ) -> Result<Rc<Mode>, ModalError> {
        let key: Vec<u64> = std::iter::once(dt)
            .chain(floor_mass.iter().copied())
            .chain(k_t.iter().copied())
            .chain(b.damping().iter().copied())
            .chain(b.storey_heights_m().iter().copied())
            .map(f64::to_bits)
            .collect();
        if let Some(m) = self.bases.get(&key) {
            return Ok(Rc::clone(m));
        }
        let m = Rc::new(build()?);
        let values = 8 * m.rows.len();
        if self.values + values > BASIS_MEMO_VALUES {
            self.bases.clear();
            self.values = 0;
        }
        self.values += values;
        self.bases.insert(key, Rc::clone(&m));
        Ok(m)
    }
}

/// One storey's spring and its branch (an elastic storey is elastic over an unbounded range).
#[derive(Debug, Clone, Copy)]
struct Storey {
    spring: StoreySpring,
    branch: Branch,
}

impl Storey {
    fn line(&self) -> (f64, f64) {
        match self.branch {
            Branch::Elastic { offset, .. } => (self.spring.k, offset),
            Branch::Plastic(dir) => (self.spring.k_post, f64::from(dir) * self.spring.intercept_n),
        }
    }

    fn force(&self, drift: f64) -> f64 {
        let (kb, off) = self.line();
        kb * drift + off
    }

    /// Leaves the plastic branch at drift `d`: the new elastic line passes through the bounding
    /// line's point there, and the elastic range ends exactly at `d` on the side just left.
    fn unload(&mut self, d: f64) {
        let Branch::Plastic(dir) = self.branch else {
            return;
        };
        let f = self.spring.k_post * d + f64::from(dir) * self.spring.intercept_n;
        let offset = f - self.spring.k * d;
        let width = 2.0 * self.spring.yield_drift_m;
        self.branch = if dir > 0 {
            Branch::Elastic {
                offset,
                lo: d - width,
                hi: d,
            }
        } else {
            Branch::Elastic {
                offset,
                lo: d,
                hi: d + width,
            }
        };
    }
}

/// Linear functions of the floors' state whose modal rows are kept per mode.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Row {
    /// `u_j`.
    Disp,
    /// `u̇_j`.
    Vel,
    /// `δ_j = u_j − u_{j−1}`.
    Drift,
    /// `ü_j` without the load (`(A·z)_{N+j}`): with the load's constant, a floor's absolute
    /// acceleration.
    Accel,
    /// Storey `j`'s shear without the storey's force offset, `k_t,j·δ_j + Σ_{i≥j} (C·u̇)_i`
    /// (docs/model.md, "Storey shears and the overturning moment"); storey 1's is the base
    /// shear `k_t,1·δ_1 + 1ᵀ·C·u̇`.
    Shear,
    /// The overturning moment at the base without the storeys' force offsets, `Σ_j h_j·V_j`
    /// over the [`Row::Shear`] rows; one row, `j = 0`.
    Overturning,
    /// `δ̇_j`: only a yielding storey's unloading asks for it, so it comes last, and the passes
    /// over every row leave it out for elastic storeys ([`Mode::live_rows`]).
    DriftRate,
}

/// Rows of a building of `n` storeys: `N` of each kind, one overturning moment.
fn row_count(n: usize) -> usize {
    6 * n + 1
}

/// A mode's basis, its rows and what a whole sample interval needs of it.
struct Mode {
    modes: StateModes,
    /// [`row_count`] rows of `m` coefficients ([`Mode::index`]), and their magnitudes times the
    /// modes' weights.
    rows: Vec<Cx>,
    rows_abs: Vec<f64>,
    /// The same rows mode by mode, for the passes that evaluate every row at once.
    by_mode: RowsByMode,
    /// [`mode_terms`] at `dt`, per kept mode.
    terms_dt: Vec<[Cx; 4]>,
}

impl Mode {
    /// `k_t`: the storeys' branch stiffnesses (N/m); `damping_above`: `N × N` row-major,
    /// `[j][l] = Σ_{i≥j} C_il` (N·s/m), the dampers' share of storey `j`'s shear per unit
    /// velocity of floor `l`; `heights_m`: the storey heights ([`Row::Shear`],
    /// [`Row::Overturning`]).
    fn new(
        modes: StateModes,
        dt: f64,
        k_t: &[f64],
        damping_above: &[f64],
        heights_m: &[f64],
    ) -> Self {
        let (n, m) = (modes.n, modes.modes());
        let mut rows = vec![Cx(0.0, 0.0); row_count(n) * m];
        let at = |row: Row, j: usize, r: usize| Self::index_in(n, row, j) * m + r;
        for r in 0..m {
            let mut moment = Cx(0.0, 0.0);
            for j in 0..n {
                let u_prev = if j > 0 {
                    modes.row(j - 1)[r]
                } else {
                    Cx(0.0, 0.0)
                };
                let mut shear = modes.row(j)[r].sub(u_prev).scale(k_t[j]);
                for l in 0..n {
                    shear = shear.add(modes.row(n + l)[r].scale(damping_above[j * n + l]));
                }
                rows[at(Row::Shear, j, r)] = shear;
                moment = moment.add(shear.scale(heights_m[j]));
            }
            rows[at(Row::Overturning, 0, r)] = moment;
        }
        for j in 0..n {
            for r in 0..m {
                let u = modes.row(j)[r];
                let v = modes.row(n + j)[r];
                let (u_prev, v_prev) = if j > 0 {
                    (modes.row(j - 1)[r], modes.row(n + j - 1)[r])
                } else {
                    (Cx(0.0, 0.0), Cx(0.0, 0.0))
                };
                rows[at(Row::Disp, j, r)] = u;
                rows[at(Row::Vel, j, r)] = v;
                rows[at(Row::Drift, j, r)] = u.sub(u_prev);
                rows[at(Row::DriftRate, j, r)] = v.sub(v_prev);
                rows[at(Row::Accel, j, r)] = modes.lambda[r].mul(v);
            }
        }
        let rows_abs: Vec<f64> = rows
            .iter()
            .enumerate()
            .map(|(i, c)| modes.weight[i % m] * c.abs())
            .collect();
        let terms_dt = modes.lambda.iter().map(|&l| mode_terms(l, dt)).collect();
        let by_mode = RowsByMode::new(&rows, &rows_abs, m);
        Self {
            modes,
            rows,
            rows_abs,
            by_mode,
            terms_dt,
        }
    }

    /// Where row `(row, j)` is in the tables, and in the passes over all rows.
    fn index(&self, row: Row, j: usize) -> usize {
        Self::index_in(self.modes.n, row, j)
    }

    /// [`Self::index`] in a building of `n` storeys: the kinds in [`Row`]'s order, `N` rows
    /// each but the overturning moment's one.
    fn index_in(n: usize, row: Row, j: usize) -> usize {
        debug_assert!(j < n && (row != Row::Overturning || j == 0), "{row:?} {j}");
        match row {
            Row::DriftRate => (Row::Overturning as usize) * n + 1 + j,
            _ => row as usize * n + j,
        }
    }

    /// The rows the passes over every row evaluate, from the first: all of them where a storey
    /// can yield, else all but the [`Row::DriftRate`] rows, which no function reads.
    fn live_rows(&self, yielding: bool) -> usize {
        match yielding {
            true => row_count(self.modes.n),
            false => self.index(Row::DriftRate, 0),
        }
    }

    fn row(&self, row: Row, j: usize) -> &[Cx] {
        let m = self.modes.modes();
        let at = self.index(row, j) * m;
        &self.rows[at..at + m]
    }

    fn row_abs(&self, row: Row, j: usize) -> &[f64] {
        let m = self.modes.modes();
        let at = self.index(row, j) * m;
        &self.rows_abs[at..at + m]
    }
}

/// A function of one piece: `scale·row(τ) + poly(τ)` (no row: the polynomial alone), with its
/// exact value at the piece's start.
#[derive(Debug, Clone, Copy)]
struct Func {
    row: Option<(Row, usize)>,
    scale: f64,
    poly: [f64; 4],
    /// Value and slope at `τ = 0` from the state (the slope `None`: the modal one).
    f0: f64,
    df0: Option<f64>,
}

/// What a deferred peak search needs of its piece ([`DeferredPeak`]): the mode, the piece's
/// modal coefficients, its two ends, and the time of the sample interval it lies in (s, for an
/// error's message).
#[derive(Default)]
struct PieceCopy {
    mode: Option<Rc<Mode>>,
    piece: Piece,
    p_start: ModalPoint,
    p_end: ModalPoint,
    t0: f64,
}

/// A deferred peak's waiting piece: its copy (shared by the functions of that piece) and the
/// function.
type Waiting = (Rc<PieceCopy>, Func);

/// What a peak function is the peak of.
#[derive(Debug, Clone, Copy, PartialEq)]
enum PeakOf {
    /// Floor `j`'s displacement.
    Disp(usize),
    /// Storey `i`'s drift.
    Drift(usize),
    /// Floor `f`'s absolute acceleration (and its riders').
    Accel(usize),
    /// Storey `j`'s shear.
    Shear(usize),
    /// Floor `f`'s absolute velocity (and its riders').
    Velocity(usize),
    Overturning,
}

/// A floor's acceleration bound (m/s²) with the interface whose static limit sets it.
type Bound = Option<(f64, usize)>;

/// Bounds of a floor's acceleration equal to within this (relative) tie: equal `μ` up to
/// round-off. The tightest bound's event goes to the first of them, and they break together
/// ([`Integrator::broken_together`]).
const BREAK_TIE: f64 = 0.1 * BREAK_TOLERANCE;

#[derive(Debug, Clone, Copy, PartialEq)]
enum EventKind {
    /// Slipping interface whose relative velocity reaches zero.
    SlipStop(usize),
    /// Stuck interface whose demand leaves its static limit: the floor's acceleration above
    /// its upper bound (`+1`) or below its lower one (`−1`).
    Break(usize, i8),
    /// Storey `i` reaches the end of its elastic range on side ±1.
    Yield(usize, i8),
    /// Storey `i`'s drift rate reverses on a bounding line.
    Unload(usize),
}

#[derive(Debug, Clone, Copy)]
struct Event {
    kind: EventKind,
    g: Func,
}

/// A run of blocks stuck together above a slipping interface: a free mass.
#[derive(Debug, Clone, Copy, Default)]
struct FreeCluster {
    bottom: usize,
    top: usize,
    mass: f64,
    /// Absolute acceleration, m/s².
    accel: f64,
    /// Displacement of the bottom body relative to the ground over the piece.
    disp: [f64; 4],
}

/// Where a block is in the current mode.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Holder {
    /// Stuck to floor `j` (through every interface below it).
    Floor(usize),
    /// In free cluster `c`.
    Free(usize),
}

/// The blocks riding on a floor (`Holder::Floor`) whose stacks are `on_floor`, `stuck[s]` the
/// stuck blocks of stack `s`: each stack's stuck part, in block order.
fn riders<'a>(
    stacks: &'a [Stack],
    on_floor: &'a [usize],
    stuck: &'a [usize],
) -> impl Iterator<Item = usize> + 'a {
    (on_floor.iter()).flat_map(|&s| stacks[s].first..stacks[s].first + stuck[s])
}

/// A floor's part of the contact problem: its stacks' interfaces (global, in order) and for each
/// the local index of the body below (0 the floor).
struct FloorContacts {
    interfaces: Vec<usize>,
    below: Vec<usize>,
    selector: ContactSelector,
    masses: Vec<f64>,
    external: Vec<f64>,
    lim_s: Vec<f64>,
    lim_k: Vec<f64>,
    contacts: Vec<Contact>,
    force: Vec<f64>,
}

struct Integrator<'b> {
    b: &'b Building,
    dt: f64,
    opts: ExactOptions,
    n: usize,
    bodies: usize,
    storeys: Vec<Storey>,
    yielding: bool,
    /// `∫F_i dδ_i` so far per storey, J.
    spring_work: Vec<f64>,
    x: Vec<f64>,
    v: Vec<f64>,
    contacts: Vec<Contact>,
    before: Vec<Contact>,
    force: Vec<f64>,
    floors: Vec<FloorContacts>,
    /// Bases by mode key (stuck blocks per stack, branch per storey).
    cache: HashMap<Vec<u16>, Rc<Mode>>,
    key: Vec<u16>,
    mode: Option<Rc<Mode>>,
    /// Blocks stuck to their floor, per stack.
    stuck: Vec<usize>,
    /// The stacks standing on each floor, in their order.
    stacks_on: Vec<Vec<usize>>,
    /// Per floor: mass with its stuck blocks (kg) and the constant part of its absolute
    /// acceleration, `−(d_j + f_top,j)/M_j` (m/s²).
    floor_mass: Vec<f64>,
    accel_const: Vec<f64>,
    /// Per floor: the friction on it from the slipping interfaces above its stuck blocks (N);
    /// per storey: branch stiffness (N/m) and force offset (N).
    f_top: Vec<f64>,
    k_t: Vec<f64>,
    offsets: Vec<f64>,
    /// Scratch per floor.
    x_new: Vec<f64>,
    v_new: Vec<f64>,
    holder: Vec<Holder>,
    free: Vec<FreeCluster>,
    piece: Piece,
    p_start: ModalPoint,
    p_end: ModalPoint,
    p_quad: ModalPoint,
    /// Every row of the mode at `p_end` ([`Mode::index`]; the first [`Mode::live_rows`]), the
    /// modal part of each row's curvature bound over the piece (the same rows), and the floors'
    /// [`Row::Accel`] rows at `p_start`.
    end_rows: Vec<f64>,
    curvatures: Vec<f64>,
    start_accel: Vec<f64>,
    z: Vec<f64>,
    /// The modal state of `z`, and the modal loads of the mode's constant floor loads
    /// (`accel_const`).
    y_floors: Vec<Cx>,
    mode_load: Vec<Cx>,
    /// Whether the state is the last piece's at its end (`self.p_end`): set once a piece has
    /// been advanced over; a switch then leaves the mode unset, so the next piece starts afresh.
    at_piece_end: bool,
    events: Vec<Event>,
    /// Peak functions: floor displacements, storey drifts, floor accelerations, storey shears,
    /// floor absolute velocities, the overturning moment.
    peaks: Vec<(PeakOf, Func)>,
    /// Every stored peak ([`Integrator::deferred_slot`]) with its searches deferred, and the
    /// copies of the pieces waiting in them (the current piece's, once one waits).
    deferred: Vec<DeferredPeak<Waiting>>,
    copies: Vec<Rc<PieceCopy>>,
    copy: Option<Rc<PieceCopy>>,
    /// Scratch: the bodies sharing a floor's acceleration or velocity.
    sharing: Vec<usize>,
    /// The ground's velocity at the piece's start, m/s: the record integrated exactly (it is
    /// linear between samples).
    vg: f64,
    /// `N × N`, `[j][l] = Σ_{i≥j} C_il`, N·s/m: the dampers' share of storey `j`'s shear per
    /// unit velocity of floor `l` (row 0: `1ᵀ·C`, the base shear's).
    damping_above: Vec<f64>,
    /// Mass of the blocks not stuck to their floors in the current mode, kg, and its integral
    /// over time so far, kg·s (counted this way round, a stack that never slides has exactly
    /// 0, so its stuck share is exactly 1).
    loose_mass_kg: f64,
    loose_mass_time: f64,
    /// Sample intervals of the record.
    steps: usize,
    slip_start: Vec<f64>,
    out: BuildingResponse,
    energy: Energy,
}

impl<'b> Integrator<'b> {
    fn new(b: &'b Building, dt: f64, opts: ExactOptions) -> Self {
        let n = b.storeys();
        let nb = b.blocks();
        let storeys: Vec<Storey> = match b.springs() {
            Some(s) => s
                .iter()
                .map(|&spring| Storey {
                    spring,
                    branch: Branch::Elastic {
                        offset: 0.0,
                        lo: -spring.yield_drift_m,
                        hi: spring.yield_drift_m,
                    },
                })
                .collect(),
            None => b
                .stiffness()
                .iter()
                .map(|&k| Storey {
                    spring: StoreySpring {
                        k,
                        k_post: k,
                        yield_force_n: f64::INFINITY,
                        yield_drift_m: f64::INFINITY,
                        intercept_n: 0.0,
                    },
                    branch: Branch::Elastic {
                        offset: 0.0,
                        lo: f64::NEG_INFINITY,
                        hi: f64::INFINITY,
                    },
                })
                .collect(),
        };
        let contacts: Vec<Contact> = (0..nb)
            .map(|k| {
                if b.mu_static(k) == 0.0 {
                    Contact::Free
                } else {
                    Contact::Stick
                }
            })
            .collect();
        let floors = (0..n)
            .map(|f| {
                let interfaces: Vec<usize> = b
                    .stacks()
                    .iter()
                    .filter(|s| s.floor == f)
                    .flat_map(|s| s.first..s.first + s.blocks)
                    .collect();
                let local = |body: usize| {
                    if body == f {
                        0
                    } else {
                        1 + interfaces.iter().position(|&k| n + k == body).unwrap_or(0)
                    }
                };
                let below = interfaces.iter().map(|&k| local(b.below(k))).collect();
                let mut masses = vec![b.masses()[f]];
                masses.extend(interfaces.iter().map(|&k| b.masses()[n + k]));
                let p = interfaces.len();
                FloorContacts {
                    lim_s: interfaces.iter().map(|&k| b.static_limit(k)).collect(),
                    lim_k: interfaces.iter().map(|&k| b.kinetic_limit(k)).collect(),
                    below,
                    selector: ContactSelector::new(p),
                    external: vec![0.0; p + 1],
                    contacts: vec![Contact::Stick; p],
                    force: vec![0.0; p],
                    masses,
                    interfaces,
                }
            })
            .collect();
        let out = BuildingResponse {
            held: vec![true; nb],
            ..BuildingResponse::zeroed(n, nb, b.stacks().len())
        };
        Self {
            b,
            dt,
            opts,
            n,
            bodies: n + nb,
            yielding: b.springs().is_some(),
            storeys,
            spring_work: vec![0.0; n],
            x: vec![0.0; n + nb],
            v: vec![0.0; n + nb],
            before: contacts.clone(),
            contacts,
            force: vec![0.0; nb],
            floors,
            cache: HashMap::new(),
            key: Vec::new(),
            mode: None,
            stuck: vec![0; b.stacks().len()],
            stacks_on: (0..n)
                .map(|f| {
                    (0..b.stacks().len())
                        .filter(|&si| b.stacks()[si].floor == f)
                        .collect()
                })
                .collect(),
            floor_mass: vec![0.0; n],
            accel_const: vec![0.0; n],
            f_top: vec![0.0; n],
            k_t: vec![0.0; n],
            offsets: vec![0.0; n],
            x_new: vec![0.0; n],
            v_new: vec![0.0; n],
            holder: vec![Holder::Floor(0); nb],
            free: Vec::with_capacity(nb),
            piece: Piece::default(),
            p_start: ModalPoint::default(),
            p_end: ModalPoint {
                integrals: opts.energy_balance,
                ..ModalPoint::default()
            },
            p_quad: ModalPoint::default(),
            end_rows: vec![0.0; row_count(n)],
            curvatures: vec![0.0; row_count(n)],
            start_accel: vec![0.0; n],
            z: vec![0.0; 2 * n],
            y_floors: Vec::new(),
            mode_load: Vec::new(),
            at_piece_end: false,
            events: Vec::new(),
            peaks: Vec::new(),
            deferred: (0..3 * n + 1 + 2 * (n + nb))
                .map(|_| DeferredPeak::default())
                .collect(),
            copies: Vec::new(),
            copy: None,
            sharing: Vec::new(),
            vg: 0.0,
            damping_above: (0..n * n)
                .map(|jl| {
                    let (j, l) = (jl / n, jl % n);
                    (j..n).map(|i| b.damping()[i * n + l]).sum()
                })
                .collect(),
            loose_mass_kg: 0.0,
            loose_mass_time: 0.0,
            steps: 0,
            slip_start: vec![0.0; nb],
            out,
            energy: Energy {
                friction_per_interface: vec![0.0; nb],
                ..Energy::default()
            },
        }
    }

    fn run(mut self, accel: &[f64], watch: &dyn Watch) -> Result<BuildingResponse, SimError> {
        let steps = accel.len() - 1;
        self.steps = steps;
        let mut history = self
            .opts
            .history
            .then(|| History::with_layout(steps + 1, self.bodies, self.b.blocks()));
        self.select(accel[0])?;
        self.build(accel[0], (accel[1] - accel[0]) / self.dt)?;
        if let Some(h) = history.as_mut() {
            self.record(h, 0.0, accel[0]);
        }
        let mut input_peak = 0.0f64;
        // The ground's velocity at the sample, m/s (at rest at the record's start).
        let mut vg_k = 0.0;
        for k in 0..steps {
            watched(watch, k, steps)?;
            let t0 = k as f64 * self.dt;
            let slope = (accel[k + 1] - accel[k]) / self.dt;
            let mut tau = 0.0;
            let mut switches_here = 0;
            loop {
                let ga = accel[k] + slope * tau;
                self.vg = vg_k + tau * (accel[k] + 0.5 * slope * tau);
                self.build(ga, slope)?;
                let h = self.dt - tau;
                let mode = self.mode();
                self.end_at(&mode, h, tau == 0.0);
                let mut first: Option<(f64, usize)> = None;
                for e in 0..self.events.len() {
                    let g = &self.events[e].g;
                    if first.is_none() && self.clear(&mode, g, h, 0.0, f64::INFINITY) {
                        continue;
                    }
                    let f = self.func(&mode, g);
                    let n0 = self.node0(&mode, g);
                    let limit = first.map_or(h, |f| f.0);
                    let n1 = if limit == h {
                        Self::node_at(&mode, g, &self.p_end)
                    } else {
                        Node::of(&f, limit)
                    };
                    let found = search::first_violation(&f, &n0, &n1, self.dt)
                        .map_err(|source| SimError::Search { time_s: t0, source })?;
                    if let Some(t) = found
                        && first.is_none_or(|f| t < f.0)
                    {
                        first = Some((t, e));
                    }
                }
                let end = first.map_or(h, |f| f.0);
                if end != h {
                    self.end_at(&mode, end, false);
                }
                self.rocking(&mode, t0 + tau, end)
                    .map_err(|source| SimError::Search { time_s: t0, source })?;
                self.advance(&mode, t0, ga, slope, end)?;
                let Some((_, e)) = first else {
                    break;
                };
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
            }
            vg_k += 0.5 * self.dt * (accel[k] + accel[k + 1]);
            self.vg = vg_k;
            if self.opts.energy_balance {
                let (kinetic, strain) = self.state_energy();
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
                self.build(accel[k + 1], slope_next)?;
                self.record(h, (k + 1) as f64 * self.dt, accel[k + 1]);
            }
        }
        self.finish(history)
    }

    /// The first rocking onset of each checked stack in the piece `[0, end]` (starting at
    /// `t_start`, s; `self.p_end` at `end`), while none is known: per interface `i`,
    /// `g = g_n ∓ Σ_j w_ij·a_j ≥ 0` (docs/model.md, "Rocking: when a case leaves the model"),
    /// the blocks stuck to the floor moving with its acceleration, the others with their free
    /// clusters' constant ones.
    fn rocking(&mut self, mode: &Mode, t_start: f64, end: f64) -> Result<(), search::SearchError> {
        let b = self.b;
        for (si, s) in b.stacks().iter().enumerate() {
            let Some(rocking) = &s.rocking else {
                continue;
            };
            if self.out.rocking_onset[si].is_some() {
                continue;
            }
            let mut found = None;
            for i in 0..s.blocks {
                let (on_floor, constant) = rocking.split(i, |j| match self.holder[s.first + j] {
                    Holder::Floor(_) => None,
                    Holder::Free(c) => Some(self.free[c].accel),
                });
                for sign in [1.0, -1.0] {
                    let mut g = Func {
                        row: Some((Row::Accel, s.floor)),
                        scale: -sign * on_floor,
                        poly: [
                            G - sign * (constant + on_floor * self.accel_const[s.floor]),
                            0.0,
                            0.0,
                            0.0,
                        ],
                        f0: 0.0,
                        df0: None,
                    };
                    g.f0 = self.start_value(mode, &g);
                    if self.clear(mode, &g, end, 0.0, f64::INFINITY) {
                        continue;
                    }
                    let f = self.func(mode, &g);
                    let n0 = self.node0(mode, &g);
                    let n1 = Self::node_at(mode, &g, &self.p_end);
                    let at = search::first_violation(&f, &n0, &n1, self.dt)?;
                    found = rocking::earlier(
                        found,
                        at.map(|t| RockingOnset {
                            block: i + 1,
                            time_s: t_start + t,
                        }),
                    );
                }
            }
            self.out.rocking_onset[si] = found;
        }
        Ok(())
    }

    /// `p_end` at `tau` (with the mode's terms at `dt` where `whole`: the piece spans the sample
    /// interval) and every row there.
    fn end_at(&mut self, mode: &Mode, tau: f64, whole: bool) {
        if whole {
            self.p_end
                .at_terms(&mode.modes, &self.piece, tau, &mode.terms_dt);
        } else {
            self.p_end.at(&mode.modes, &self.piece, tau);
        }
        let live = mode.live_rows(self.yielding);
        mode.by_mode.dots(
            &mode.modes.weight,
            &self.p_end.y,
            0,
            &mut self.end_rows[..live],
        );
    }

    fn mode(&self) -> Rc<Mode> {
        Rc::clone(self.mode.as_ref().expect("built before use"))
    }

    fn func<'m>(&'m self, mode: &'m Mode, g: &Func) -> ModalFn<'m> {
        Self::func_of(mode, &self.piece, g)
    }

    /// `g` over `piece`.
    fn func_of<'m>(mode: &'m Mode, piece: &'m Piece, g: &Func) -> ModalFn<'m> {
        ModalFn {
            modes: &mode.modes,
            piece,
            c: g.row.map_or(&[][..], |(row, j)| mode.row(row, j)),
            c_abs: g.row.map_or(&[][..], |(row, j)| mode.row_abs(row, j)),
            scale: g.scale,
            poly: g.poly,
        }
    }

    /// `(f, f')` of `g` at a modal point.
    fn value_at(mode: &Mode, g: &Func, p: &ModalPoint) -> (f64, f64) {
        let t = p.tau;
        let q = &g.poly;
        let mut f = cubic(q, t);
        let mut df = cubic_slope(q, t);
        if let Some((row, j)) = g.row {
            let c = mode.row(row, j);
            f += g.scale * ModalPoint::dot(&mode.modes, c, &p.y);
            df += g.scale * ModalPoint::dot(&mode.modes, c, &p.dy);
        }
        (f, df)
    }

    /// `f` of `g` at `p_start`: [`Self::value_at`]'s value, a floor's [`Row::Accel`] row taken
    /// from the pass over the floors' accelerations.
    fn start_value(&self, mode: &Mode, g: &Func) -> f64 {
        let Some((Row::Accel, j)) = g.row else {
            return Self::value_at(mode, g, &self.p_start).0;
        };
        cubic(&g.poly, self.p_start.tau) + g.scale * self.start_accel[j]
    }

    fn node_at(mode: &Mode, g: &Func, p: &ModalPoint) -> Node<f64> {
        let (f, df) = Self::value_at(mode, g, p);
        Node { at: p.tau, f, df }
    }

    /// `(f(0), f(h), s)`: `g`'s end values over the piece `[0, h]` (`self.p_end` at `h`) and the
    /// curvature bound's reach between them, `s = max|g''|·h²/8`, so that `g` lies within
    /// `[min − s, max + s]` of its end values over the piece.
    #[inline]
    fn ends_and_reach(&self, mode: &Mode, g: &Func, h: f64) -> (f64, f64, f64) {
        let q = &g.poly;
        let mut f1 = cubic(q, h);
        let mut curv = 2.0 * q[2].abs() + 6.0 * h * q[3].abs();
        if let Some((row, j)) = g.row {
            let i = mode.index(row, j);
            f1 += g.scale * self.end_rows[i];
            curv += g.scale.abs() * self.curvatures[i] * (1.0 + 1e-12);
        }
        (g.f0, f1, curv * h * h / 8.0)
    }

    /// Whether `lower ≤ g ≤ upper` over the whole piece `[0, h]` (`self.p_end` at `h`) is
    /// certified by the curvature bound on the end values alone: the first test of
    /// [`search::range_within`], without the slopes, which most functions of most pieces pass.
    #[inline]
    fn clear(&self, mode: &Mode, g: &Func, h: f64, lower: f64, upper: f64) -> bool {
        let (f0, f1, slack) = self.ends_and_reach(mode, g, h);
        f0.min(f1) - slack >= lower && f0.max(f1) + slack <= upper
    }

    /// The start node: the state's exact value (and slope where the state gives it).
    fn node0(&self, mode: &Mode, g: &Func) -> Node<f64> {
        Self::node0_at(mode, g, &self.p_start)
    }

    /// [`Self::node0`] of a piece starting at `p_start`.
    fn node0_at(mode: &Mode, g: &Func, p_start: &ModalPoint) -> Node<f64> {
        let df = match g.df0 {
            Some(d) => d,
            None => Self::value_at(mode, g, p_start).1,
        };
        Node {
            at: 0.0,
            f: g.f0,
            df,
        }
    }

    /// A function anchored to its exact start value (and slope).
    fn anchored(&self, mode: &Mode, mut g: Func) -> Func {
        let (f, df) = Self::value_at(mode, &g, &self.p_start);
        g.poly[0] += g.f0 - f;
        if let Some(d) = g.df0 {
            g.poly[1] += d - df;
        }
        g
    }

    /// External forces on the floors (springs, dampers, ground) at the current state, N,
    /// without the blocks.
    fn floor_forces(&self, ga: f64, out: &mut [f64]) {
        let n = self.n;
        let c = self.b.damping();
        for j in 0..n {
            let damper: f64 = (0..n).map(|l| c[j * n + l] * self.v[l]).sum();
            let drift = self.x[j] - if j > 0 { self.x[j - 1] } else { 0.0 };
            let below = self.storeys[j].force(drift);
            let above = if j + 1 < n {
                self.storeys[j + 1].force(self.x[j + 1] - self.x[j])
            } else {
                0.0
            };
            out[j] = -self.b.masses()[j] * ga - damper - below + above;
        }
    }

    /// The piece from the current state: the mode (set up again after a switch), the floors'
    /// loads and modal coefficients, the free clusters' cubics, and the switching and peak
    /// functions.
    ///
    /// Within a mode the modal state is the state: while no switch has come since the last
    /// piece, which ended here (`self.p_end`), the piece starts from that piece's modal state and
    /// the floors' accelerations there, with no pass over the floors.
    fn build(&mut self, ga: f64, slope: f64) -> Result<(), SimError> {
        let carried = self.mode.is_some() && self.at_piece_end;
        if self.mode.is_none() {
            self.set_up_mode()?;
        }
        let mode = self.mode();
        let n = self.n;
        let accel_rows = mode.index(Row::Accel, 0);
        if !carried {
            for j in 0..n {
                self.z[j] = self.x[j];
                self.z[n + j] = self.v[j];
            }
            mode.modes.modal_state(&self.z, &mut self.y_floors);
        }
        let y0 = if carried {
            &self.p_end.y
        } else {
            &self.y_floors
        };
        mode.modes
            .piece_in_mode(y0, &self.mode_load, ga, -slope, &mut self.piece);
        self.p_start.start(&mode.modes, &self.piece);
        if carried {
            self.start_accel
                .copy_from_slice(&self.end_rows[accel_rows..accel_rows + n]);
        } else {
            mode.by_mode.dots(
                &mode.modes.weight,
                &self.p_start.y,
                accel_rows,
                &mut self.start_accel,
            );
        }
        let live = mode.live_rows(self.yielding);
        mode.by_mode
            .curvatures(&self.piece.mag, &mut self.curvatures[..live]);
        for c in &mut self.free {
            c.disp = [
                self.x[c.bottom],
                self.v[c.bottom],
                0.5 * (c.accel - ga),
                -slope / 6.0,
            ];
        }
        self.build_functions(&mode, ga, slope, carried);
        Ok(())
    }

    /// Which blocks ride on their floor and which form free clusters, each floor's mass and
    /// load constant, and the mode's basis (from the cache, or computed once).
    fn set_up_mode(&mut self) -> Result<(), SimError> {
        let (n, b) = (self.n, self.b);
        self.key.clear();
        self.loose_mass_kg = 0.0;
        self.floor_mass.copy_from_slice(&b.masses()[..n]);
        self.f_top.fill(0.0);
        self.free.clear();
        for (si, s) in b.stacks().iter().enumerate() {
            let mut e = 0;
            while e < s.blocks && self.contacts[s.first + e] == Contact::Stick {
                e += 1;
            }
            self.stuck[si] = e;
            self.key.push(e as u16);
            for q in e..s.blocks {
                self.loose_mass_kg += b.masses()[n + s.first + q];
            }
            for q in 0..e {
                self.floor_mass[s.floor] += b.masses()[n + s.first + q];
                self.holder[s.first + q] = Holder::Floor(s.floor);
            }
            if e < s.blocks {
                // The slipping (or free) interface above the stuck part pulls on the floor's
                // cluster with −f.
                self.f_top[s.floor] += self.force[s.first + e];
            }
            // Free clusters above: runs of stuck interfaces.
            let mut q = e;
            while q < s.blocks {
                let bottom = q;
                let mut top = q;
                while top + 1 < s.blocks && self.contacts[s.first + top + 1] == Contact::Stick {
                    top += 1;
                }
                let ci = self.free.len();
                let mass: f64 = (bottom..=top).map(|t| b.masses()[n + s.first + t]).sum();
                let above = if top + 1 < s.blocks {
                    self.force[s.first + top + 1]
                } else {
                    0.0
                };
                self.free.push(FreeCluster {
                    bottom: n + s.first + bottom,
                    top: n + s.first + top,
                    mass,
                    accel: (self.force[s.first + bottom] - above) / mass,
                    disp: [0.0; 4],
                });
                for t in bottom..=top {
                    self.holder[s.first + t] = Holder::Free(ci);
                }
                q = top + 1;
            }
        }
        for (i, s) in self.storeys.iter().enumerate() {
            let (kb, off) = s.line();
            self.k_t[i] = kb;
            self.offsets[i] = off;
            self.key
                .push(u16::from(matches!(s.branch, Branch::Plastic(_))));
        }
        // Constant part of each floor's absolute acceleration: −(d_j + f_top,j)/M_j with
        // d_j = off_j − off_{j+1}.
        for j in 0..n {
            let d = self.offsets[j] - if j + 1 < n { self.offsets[j + 1] } else { 0.0 };
            self.accel_const[j] = -(d + self.f_top[j]) / self.floor_mass[j];
        }
        let mode = match self.cache.get(&self.key) {
            Some(m) => Rc::clone(m),
            None => {
                let m = BASES.with_borrow_mut(|bases| {
                    bases.get_or_build(self.dt, &self.floor_mass, &self.k_t, b, || {
                        Ok(Mode::new(
                            StateModes::new(&self.floor_mass, &self.k_t, b.damping())?,
                            self.dt,
                            &self.k_t,
                            &self.damping_above,
                            b.storey_heights_m(),
                        ))
                    })
                })?;
                self.cache.insert(self.key.clone(), Rc::clone(&m));
                m
            }
        };
        mode.modes
            .modal_loads(&self.accel_const, &mut self.mode_load);
        self.mode = Some(mode);
        Ok(())
    }

    /// Velocity of a block's holder as a row or a polynomial: `(row, poly)`.
    fn velocity_of(&self, body: usize) -> (Option<(Row, usize)>, [f64; 4]) {
        if body < self.n {
            return (Some((Row::Vel, body)), [0.0; 4]);
        }
        match self.holder[body - self.n] {
            Holder::Floor(f) => (Some((Row::Vel, f)), [0.0; 4]),
            Holder::Free(c) => {
                let d = self.free[c].disp;
                (None, [d[1], 2.0 * d[2], 3.0 * d[3], 0.0])
            }
        }
    }

    /// `carried`: the piece continues the last one's modal state ([`Self::build`]), so the rows'
    /// values at its start are those at the last one's end.
    fn build_functions(&mut self, mode: &Mode, ga: f64, slope: f64, carried: bool) {
        let (n, b) = (self.n, self.b);
        let mut events = std::mem::take(&mut self.events);
        let mut peaks = std::mem::take(&mut self.peaks);
        events.clear();
        peaks.clear();
        // Break bounds per floor: the tightest over its stacks' stuck interfaces.
        for f in 0..n {
            let (mut upper, mut lower): (Bound, Bound) = (None, None);
            self.break_bounds(f, |_, k, hi, lo| {
                if upper.is_none_or(|(h, _)| hi < h - BREAK_TIE * h.abs()) {
                    upper = Some((hi, k));
                }
                if lower.is_none_or(|(l, _)| lo > l + BREAK_TIE * l.abs()) {
                    lower = Some((lo, k));
                }
            });
            for (bound, sign, side) in [(upper, -1.0, 1), (lower, 1.0, -1)] {
                if let Some((value, k)) = bound {
                    let mut g = Func {
                        row: Some((Row::Accel, f)),
                        scale: sign,
                        poly: [sign * (self.accel_const[f] - value), 0.0, 0.0, 0.0],
                        f0: 0.0,
                        df0: None,
                    };
                    g.f0 = self.start_value(mode, &g);
                    events.push(Event {
                        kind: EventKind::Break(k, side),
                        g,
                    });
                }
            }
        }
        // Slipping interfaces: the relative velocity keeps its sign.
        for k in 0..b.blocks() {
            let Contact::Slip(dir) = self.contacts[k] else {
                continue;
            };
            let sgn = f64::from(dir);
            let (upper, lower) = (n + k, b.below(k));
            let (row_u, poly_u) = self.velocity_of(upper);
            let (row_l, poly_l) = self.velocity_of(lower);
            debug_assert!(
                row_u.is_none(),
                "a block above a slipping interface is free"
            );
            let poly = std::array::from_fn(|i| sgn * (poly_u[i] - poly_l[i]));
            let g = Func {
                row: row_l.or(row_u),
                scale: if row_l.is_some() { -sgn } else { sgn },
                poly,
                f0: sgn * (self.v[upper] - self.v[lower]),
                df0: None,
            };
            events.push(Event {
                kind: EventKind::SlipStop(k),
                g: self.anchored(mode, g),
            });
        }
        // Storeys: yield from the elastic branch, unloading from a plastic one.
        if self.yielding {
            for i in 0..n {
                let (x_prev, v_prev) = if i > 0 {
                    (self.x[i - 1], self.v[i - 1])
                } else {
                    (0.0, 0.0)
                };
                let (drift, rate) = (self.x[i] - x_prev, self.v[i] - v_prev);
                match self.storeys[i].branch {
                    Branch::Elastic { lo, hi, .. } => {
                        for (dir, sign, value) in [(1, -1.0, hi - drift), (-1, 1.0, drift - lo)] {
                            let g = Func {
                                row: Some((Row::Drift, i)),
                                scale: sign,
                                poly: [if dir > 0 { hi } else { -lo }, 0.0, 0.0, 0.0],
                                f0: value,
                                df0: Some(sign * rate),
                            };
                            events.push(Event {
                                kind: EventKind::Yield(i, dir),
                                g: self.anchored(mode, g),
                            });
                        }
                    }
                    Branch::Plastic(dir) => {
                        let sgn = f64::from(dir);
                        let g = Func {
                            row: Some((Row::DriftRate, i)),
                            scale: sgn,
                            poly: [0.0; 4],
                            f0: sgn * rate,
                            df0: None,
                        };
                        events.push(Event {
                            kind: EventKind::Unload(i),
                            g: self.anchored(mode, g),
                        });
                    }
                }
            }
        }
        // Peak functions start at the state; inside the piece the modal values differ from it
        // by round-off only, so they need no anchoring.
        let lowest_disp = if self.opts.floor_displacements {
            0
        } else {
            n - 1
        };
        for j in lowest_disp..n {
            peaks.push((
                PeakOf::Disp(j),
                Func {
                    row: Some((Row::Disp, j)),
                    scale: 1.0,
                    poly: [0.0; 4],
                    f0: self.x[j],
                    df0: Some(self.v[j]),
                },
            ));
        }
        for i in 0..n {
            let (x_prev, v_prev) = if i > 0 {
                (self.x[i - 1], self.v[i - 1])
            } else {
                (0.0, 0.0)
            };
            peaks.push((
                PeakOf::Drift(i),
                Func {
                    row: Some((Row::Drift, i)),
                    scale: 1.0,
                    poly: [0.0; 4],
                    f0: self.x[i] - x_prev,
                    df0: Some(self.v[i] - v_prev),
                },
            ));
        }
        for f in 0..n {
            let mut g = Func {
                row: Some((Row::Accel, f)),
                scale: 1.0,
                poly: [self.accel_const[f], 0.0, 0.0, 0.0],
                f0: 0.0,
                df0: None,
            };
            g.f0 = self.start_value(mode, &g);
            peaks.push((PeakOf::Accel(f), g));
        }
        let heights = self.b.storey_heights_m();
        let (mut moment_offset, mut moment) = (0.0, 0.0);
        for j in 0..n {
            let shear = if carried {
                self.offsets[j] + self.end_rows[mode.index(Row::Shear, j)]
            } else {
                let damper: f64 = (self.damping_above[j * n..(j + 1) * n].iter())
                    .zip(&self.v[..n])
                    .map(|(c, v)| c * v)
                    .sum();
                let x_prev = if j > 0 { self.x[j - 1] } else { 0.0 };
                self.storeys[j].force(self.x[j] - x_prev) + damper
            };
            peaks.push((
                PeakOf::Shear(j),
                Func {
                    row: Some((Row::Shear, j)),
                    scale: 1.0,
                    poly: [self.offsets[j], 0.0, 0.0, 0.0],
                    f0: shear,
                    df0: None,
                },
            ));
            moment_offset += heights[j] * self.offsets[j];
            moment += heights[j] * shear;
        }
        peaks.push((
            PeakOf::Overturning,
            Func {
                row: Some((Row::Overturning, 0)),
                scale: 1.0,
                poly: [moment_offset, 0.0, 0.0, 0.0],
                f0: moment,
                df0: None,
            },
        ));
        // Absolute velocity: the floor's relative velocity plus the ground's quadratic.
        if self.opts.abs_velocity {
            for j in 0..n {
                peaks.push((
                    PeakOf::Velocity(j),
                    Func {
                        row: Some((Row::Vel, j)),
                        scale: 1.0,
                        poly: [self.vg, ga, 0.5 * slope, 0.0],
                        f0: self.v[j] + self.vg,
                        df0: None,
                    },
                ));
            }
        }
        self.events = events;
        self.peaks = peaks;
    }

    /// Calls `each(stack, interface, upper, lower)` for every interface stuck to floor `f`, in
    /// order (stacks, then bottom up): the interval of the floor's absolute acceleration (m/s²)
    /// within which its static limit carries the blocks above it, in the current mode.
    fn break_bounds(&self, f: usize, mut each: impl FnMut(usize, usize, f64, f64)) {
        let (n, b) = (self.n, self.b);
        for &si in &self.stacks_on[f] {
            let (s, e) = (&b.stacks()[si], self.stuck[si]);
            if e == 0 {
                continue;
            }
            let f_top = if e < s.blocks {
                self.force[s.first + e]
            } else {
                0.0
            };
            let mut m_above: f64 = (0..e).map(|q| b.masses()[n + s.first + q]).sum();
            for q in 0..e {
                let k = s.first + q;
                let room = b.static_limit(k) * (1.0 + BREAK_TOLERANCE);
                each(si, k, (room - f_top) / m_above, (-room - f_top) / m_above);
                m_above -= b.masses()[n + k];
            }
        }
    }

    /// The interfaces a break event of interface `k` on side `side` breaks loose: `k`, and in
    /// every other stack on its floor the lowest stuck interface whose bound on that side ties
    /// `k`'s (within [`BREAK_TIE`], the tolerance by which the event chose `k`): the floor's
    /// acceleration reaches their limits at the same instant. Identical stacks, or single blocks
    /// of one `μ` of any masses, tie; within one stack only the lowest breaks (the run above it
    /// then moves with it).
    fn broken_together(&self, k: usize, side: i8) -> Vec<usize> {
        let b = self.b;
        let Some(home) = b
            .stacks()
            .iter()
            .position(|s| (s.first..s.first + s.blocks).contains(&k))
        else {
            return vec![k];
        };
        let mut value = f64::NAN;
        self.break_bounds(b.stacks()[home].floor, |_, i, hi, lo| {
            if i == k {
                value = if side > 0 { hi } else { lo };
            }
        });
        let mut out = vec![k];
        let mut last = None;
        self.break_bounds(b.stacks()[home].floor, |si, i, hi, lo| {
            let v = if side > 0 { hi } else { lo };
            if si != home && last != Some(si) && (v - value).abs() <= BREAK_TIE * value.abs() {
                out.push(i);
                last = Some(si);
            }
        });
        out
    }

    /// Every floor's absolute acceleration at the current state in the current mode, m/s²:
    /// `(F_j + m_j·a_g − f_top,j)/M_j`, `F_j` the spring, damper and ground forces on the bare
    /// floor and `f_top,j` the friction from the slipping interfaces above its stuck blocks.
    fn floor_accels(&self, ga: f64) -> Vec<f64> {
        let mut out = vec![0.0; self.n];
        self.floor_forces(ga, &mut out);
        for (j, a) in out.iter_mut().enumerate() {
            *a += self.b.masses()[j] * ga;
        }
        for (si, s) in self.b.stacks().iter().enumerate() {
            let e = self.stuck[si];
            if e < s.blocks {
                out[s.floor] -= self.force[s.first + e];
            }
        }
        for (a, m) in out.iter_mut().zip(&self.floor_mass) {
            *a /= m;
        }
        out
    }

    /// Moves the state to the end of the current piece (`self.p_end`, at `end`), accumulating
    /// peaks and energy over it.
    fn advance(
        &mut self,
        mode: &Mode,
        t0: f64,
        ga: f64,
        slope: f64,
        end: f64,
    ) -> Result<(), SimError> {
        let (n, nb) = (self.n, self.b.blocks());
        self.loose_mass_time += self.loose_mass_kg * end;
        // Peaks: floor displacements, storey drifts, floor accelerations (with the blocks that
        // ride on each floor), storey shears, floor velocities (with their riders), the
        // overturning moment.
        self.copy = None;
        for idx in 0..self.peaks.len() {
            // Borrowed, not copied: a copy of the function stalls the loads that follow it.
            let (of, g) = (self.peaks[idx].0, &self.peaks[idx].1);
            let (f0, f1, slack) = self.ends_and_reach(mode, g, end);
            let ends = f0.abs().max(f1.abs());
            let bound = (f0.max(f1) + slack).max(slack - f0.min(f1));
            // A bound not below the peak known (or not a number: its search reports it) waits.
            let (PeakOf::Accel(f) | PeakOf::Velocity(f)) = of else {
                let d = self.deferred_slot(of, 0);
                if bound <= self.deferred[d].known() {
                    continue;
                }
                let g = *g;
                self.defer_peak(d, ends, bound, &g, t0)?;
                continue;
            };
            // The floor and the blocks riding on it share the value: the smallest of their
            // peaks known clears them all.
            let mut bodies = std::mem::take(&mut self.sharing);
            bodies.clear();
            bodies.push(f);
            bodies.extend(riders(self.b.stacks(), &self.stacks_on[f], &self.stuck).map(|q| n + q));
            let known = (bodies.iter())
                .map(|&body| self.deferred[self.deferred_slot(of, body)].known())
                .fold(f64::INFINITY, f64::min);
            if bound <= known {
                self.sharing = bodies;
                continue;
            }
            let g = *g;
            for &body in &bodies {
                self.defer_peak(self.deferred_slot(of, body), ends, bound, &g, t0)?;
            }
            self.sharing = bodies;
        }
        // A free cluster's absolute acceleration is constant, so its absolute velocity is linear
        // over the piece: its ends bound it.
        for c in &self.free {
            let v0 = self.v[c.bottom] + self.vg;
            let v1 = v0 + c.accel * end;
            for body in c.bottom..=c.top {
                let accel = self.deferred_slot(PeakOf::Accel(0), body);
                self.deferred[accel].met(c.accel.abs());
                let velocity = self.deferred_slot(PeakOf::Velocity(0), body);
                self.deferred[velocity].met(v0.abs().max(v1.abs()));
            }
        }
        // New floor state.
        let mut x_new = std::mem::take(&mut self.x_new);
        let mut v_new = std::mem::take(&mut self.v_new);
        for j in 0..n {
            x_new[j] = self.end_rows[mode.index(Row::Disp, j)];
            v_new[j] = self.end_rows[mode.index(Row::Vel, j)];
        }
        if self.opts.energy_balance {
            let mut input = 0.0;
            for j in 0..n {
                let int_u = ModalPoint::dot(&mode.modes, mode.row(Row::Disp, j), &self.p_end.iy);
                input -= self.floor_mass[j]
                    * (ga * (x_new[j] - self.x[j]) + slope * (end * x_new[j] - int_u));
            }
            for c in &self.free {
                let d = &c.disp;
                let x1 = d[0] + end * (d[1] + end * (d[2] + end * d[3]));
                let int_x =
                    end * (d[0] + end * (d[1] / 2.0 + end * (d[2] / 3.0 + end * d[3] / 4.0)));
                input -= c.mass * (ga * (x1 - d[0]) + slope * (end * x1 - int_x));
            }
            self.energy.input += input;
            self.energy.damping += self.damping_integral(mode, end);
        }
        if self.yielding {
            for i in 0..n {
                let d0 = self.x[i] - if i > 0 { self.x[i - 1] } else { 0.0 };
                let d1 = x_new[i] - if i > 0 { x_new[i - 1] } else { 0.0 };
                let (kb, off) = self.storeys[i].line();
                self.spring_work[i] += (d1 - d0) * (0.5 * kb * (d1 + d0) + off);
            }
        }
        for k in 0..nb {
            self.slip_start[k] = self.x[n + k] - self.x[self.b.below(k)];
        }
        // Blocks: those riding on a floor keep their offset to it; free clusters move by their
        // cubic.
        for q in 0..nb {
            let body = n + q;
            match self.holder[q] {
                Holder::Floor(f) => {
                    self.x[body] = x_new[f] + (self.x[body] - self.x[f]);
                    self.v[body] = v_new[f];
                }
                Holder::Free(_) => {}
            }
        }
        for c in &self.free {
            let d = &c.disp;
            let xb = d[0] + end * (d[1] + end * (d[2] + end * d[3]));
            let vb = d[1] + end * (2.0 * d[2] + 3.0 * end * d[3]);
            for body in (c.bottom..=c.top).rev() {
                self.x[body] = xb + (self.x[body] - self.x[c.bottom]);
                self.v[body] = vb;
            }
        }
        self.x[..n].copy_from_slice(&x_new);
        self.v[..n].copy_from_slice(&v_new);
        self.at_piece_end = true;
        self.x_new = x_new;
        self.v_new = v_new;
        for k in 0..nb {
            let slip = self.x[n + k] - self.x[self.b.below(k)];
            if let Contact::Slip(_) = self.contacts[k] {
                let w = self.b.kinetic_limit(k) * (slip - self.slip_start[k]).abs();
                self.energy.friction_per_interface[k] += w;
                self.energy.friction += w;
            }
            let p = &mut self.out.peak_slip_m[k];
            *p = p.max(slip.abs());
        }
        Ok(())
    }

    /// Where a peak is kept among [`Integrator::deferred`]: a floor's displacement, a storey's
    /// drift and shear, the overturning moment (`body` unused), then a body's absolute
    /// acceleration and velocity (`of` names the kind, `body` the floor or `N +` block).
    fn deferred_slot(&self, of: PeakOf, body: usize) -> usize {
        let (n, bodies) = (self.n, self.bodies);
        match of {
            PeakOf::Disp(j) => j,
            PeakOf::Drift(i) => n + i,
            PeakOf::Shear(j) => 2 * n + j,
            PeakOf::Overturning => 3 * n,
            PeakOf::Accel(_) => 3 * n + 1 + body,
            PeakOf::Velocity(_) => 3 * n + 1 + bodies + body,
        }
    }

    /// A piece of peak `d` with its larger end value `ends` and its bound over the piece: cleared
    /// by the peak known, or left waiting ([`DeferredPeak::defer`]), with the search that makes
    /// room.
    fn defer_peak(
        &mut self,
        d: usize,
        ends: f64,
        bound: f64,
        g: &Func,
        t0: f64,
    ) -> Result<(), SimError> {
        if bound <= self.deferred[d].known() {
            // Its end values too are below the peak known.
            return Ok(());
        }
        let copy = self.piece_copy(t0);
        if let Some(((copy, g), best)) = self.deferred[d].defer(ends, bound, (copy, *g)) {
            let peak = Self::search_copy(&copy, &g, best, self.dt)?;
            self.deferred[d].searched(peak);
        }
        Ok(())
    }

    /// The current piece's copy (in sample interval `t0`, s), made once per piece, in a buffer
    /// no waiting piece holds.
    fn piece_copy(&mut self, t0: f64) -> Rc<PieceCopy> {
        if let Some(c) = &self.copy {
            return Rc::clone(c);
        }
        let at = match self.copies.iter().position(|c| Rc::strong_count(c) == 1) {
            Some(at) => at,
            None => {
                self.copies.push(Rc::new(PieceCopy::default()));
                self.copies.len() - 1
            }
        };
        let c = Rc::get_mut(&mut self.copies[at]).expect("held by the pool alone");
        c.mode = self.mode.clone();
        c.piece.copy_coefficients(&self.piece);
        c.p_start.copy_values(&self.p_start);
        c.p_end.copy_values(&self.p_end);
        c.t0 = t0;
        let c = Rc::clone(&self.copies[at]);
        self.copy = Some(Rc::clone(&c));
        c
    }

    /// Peak `|g|` over a copied piece, from `best`.
    fn search_copy(copy: &PieceCopy, g: &Func, best: f64, dt: f64) -> Result<f64, SimError> {
        let mode = copy.mode.as_deref().expect("a copy has its mode");
        let f = Self::func_of(mode, &copy.piece, g);
        let n0 = Self::node0_at(mode, g, &copy.p_start);
        let n1 = Self::node_at(mode, g, &copy.p_end);
        search::peak_abs(&f, &n0, &n1, best, dt)
            .map(|(peak, _)| peak)
            .map_err(|source| SimError::Search {
                time_s: copy.t0,
                source,
            })
    }

    /// Searches the deferred peaks' waiting pieces that can still raise them, and stores them.
    fn settle_deferred_peaks(&mut self) -> Result<(), SimError> {
        for d in 0..self.deferred.len() {
            while let Some(((copy, g), best)) = self.deferred[d].next() {
                let peak = Self::search_copy(&copy, &g, best, self.dt)?;
                self.deferred[d].searched(peak);
            }
        }
        let mut out = std::mem::take(&mut self.out);
        let peak = |of: PeakOf, body: usize| self.deferred[self.deferred_slot(of, body)].peak();
        for j in 0..self.n {
            out.floor_peak_displacement_m[j] = peak(PeakOf::Disp(j), 0);
            out.storey_peak_drift_m[j] = peak(PeakOf::Drift(j), 0);
            out.storey_peak_shear_n[j] = peak(PeakOf::Shear(j), 0);
            out.floor_peak_abs_accel_mps2[j] = peak(PeakOf::Accel(j), j);
            out.floor_peak_abs_velocity_mps[j] = peak(PeakOf::Velocity(j), j);
        }
        for q in 0..self.b.blocks() {
            out.block_peak_abs_accel_mps2[q] = peak(PeakOf::Accel(0), self.n + q);
            out.block_peak_abs_velocity_mps[q] = peak(PeakOf::Velocity(0), self.n + q);
        }
        out.peak_overturning_n_m = peak(PeakOf::Overturning, 0);
        self.out = out;
        Ok(())
    }

    /// `∫₀^end u̇ᵀ·C·u̇ dτ` of the floors over the piece, J.
    fn damping_integral(&mut self, mode: &Mode, end: f64) -> f64 {
        let n = self.n;
        let c = self.b.damping();
        if end == 0.0 || c.iter().all(|&x| x == 0.0) {
            return 0.0;
        }
        let panels = (end * mode.modes.fastest()).ceil().max(1.0) as usize;
        let w = end / panels as f64;
        let mut total = 0.0;
        let mut vel = vec![0.0; n];
        for p in 0..panels {
            for &(node, weight) in &GAUSS8 {
                let t = (p as f64 + node) * w;
                self.p_quad.at(&mode.modes, &self.piece, t);
                for j in 0..n {
                    vel[j] = ModalPoint::dot(&mode.modes, mode.row(Row::Vel, j), &self.p_quad.y);
                }
                let mut q = 0.0;
                for a in 0..n {
                    let row: f64 = (0..n).map(|l| c[a * n + l] * vel[l]).sum();
                    q += vel[a] * row;
                }
                total += weight * w * q;
            }
        }
        total
    }

    /// Kinetic energy and all the storeys' spring work (recoverable plus hysteretic) now, J.
    fn state_energy(&self) -> (f64, f64) {
        let m = self.b.masses();
        let kinetic = 0.5
            * (0..self.bodies)
                .map(|j| m[j] * self.v[j] * self.v[j])
                .sum::<f64>();
        let strain = if self.yielding {
            self.spring_work.iter().sum()
        } else {
            (0..self.n)
                .map(|i| {
                    let d = self.x[i] - if i > 0 { self.x[i - 1] } else { 0.0 };
                    0.5 * self.storeys[i].spring.k * d * d
                })
                .sum()
        };
        (kinetic, strain)
    }

    /// Applies a switch at the current state and chooses the next mode.
    fn switch(&mut self, kind: EventKind, ga: f64) -> Result<(), SimError> {
        match kind {
            EventKind::Yield(i, dir) => {
                self.storeys[i].branch = Branch::Plastic(dir);
                self.out.yield_events += 1;
                self.mode = None;
            }
            EventKind::Unload(i) => {
                if let Branch::Plastic(dir) = self.storeys[i].branch {
                    let below = if i > 0 { self.v[i - 1] } else { 0.0 };
                    if f64::from(dir) * (self.v[i] - below) > 0.0 {
                        // A round-off residue of the old sign would yield again at once: the
                        // two floors (with what rides on them) take their common velocity.
                        self.equalise_storey(i);
                    }
                }
                let d = self.x[i] - if i > 0 { self.x[i - 1] } else { 0.0 };
                self.storeys[i].unload(d);
                self.out.yield_events += 1;
                self.mode = None;
            }
            EventKind::SlipStop(k) => self.out.switches += switch_contacts(self, Some(k), &[], ga)?,
            EventKind::Break(k, side) => {
                let broke = self.broken_together(k, side);
                self.out.switches += switch_contacts(self, None, &broke, ga)?
            }
        }
        Ok(())
    }

    /// Floors `i − 1` and `i` (the ground for `i = 0`) and every block stuck to them take one
    /// momentum-weighted velocity (the ground's, zero, for storey 1).
    fn equalise_storey(&mut self, i: usize) {
        let n = self.n;
        let members: Vec<usize> = (0..self.bodies)
            .filter(|&body| {
                let floor = if body < n {
                    Some(body)
                } else {
                    match self.holder[body - n] {
                        Holder::Floor(f) => Some(f),
                        Holder::Free(_) => None,
                    }
                };
                floor.is_some_and(|f| f == i || (i > 0 && f == i - 1))
            })
            .collect();
        let m = self.b.masses();
        let vm = if i == 0 {
            0.0
        } else {
            let mass: f64 = members.iter().map(|&j| m[j]).sum();
            members.iter().map(|&j| m[j] * self.v[j]).sum::<f64>() / mass
        };
        for j in members {
            self.v[j] = vm;
        }
    }

    /// Appends the current state as a history row (mode of the piece ending here).
    fn record(&self, h: &mut History, t: f64, ga: f64) {
        h.time_s.push(t);
        h.ground_accel_mps2.push(ga);
        h.displacement_m.extend_from_slice(&self.x);
        h.velocity_mps.extend_from_slice(&self.v);
        let floors = self.floor_accels(ga);
        h.abs_accel_mps2.extend_from_slice(&floors);
        for q in 0..self.b.blocks() {
            h.abs_accel_mps2.push(match self.holder[q] {
                Holder::Floor(f) => floors[f],
                Holder::Free(c) => self.free[c].accel,
            });
        }
        h.contact.extend(self.contacts.iter().map(|c| c.code()));
    }

    fn finish(mut self, history: Option<History>) -> Result<BuildingResponse, SimError> {
        self.settle_deferred_peaks()?;
        let n = self.n;
        let mut e = std::mem::take(&mut self.energy);
        let (kinetic, _) = self.state_energy();
        e.kinetic = kinetic;
        let drift = |i: usize, x: &[f64]| x[i] - if i > 0 { x[i - 1] } else { 0.0 };
        if self.yielding {
            e.strain = (0..n)
                .map(|i| {
                    let f = self.storeys[i].force(drift(i, &self.x));
                    f * f / (2.0 * self.storeys[i].spring.k)
                })
                .sum();
            e.hysteretic = self.spring_work.iter().sum::<f64>() - e.strain;
            self.out.storey_ductility = Some(
                (0..n)
                    .map(|i| self.out.storey_peak_drift_m[i] / self.storeys[i].spring.yield_drift_m)
                    .collect(),
            );
        } else {
            e.strain = (0..n)
                .map(|i| 0.5 * self.storeys[i].spring.k * drift(i, &self.x).powi(2))
                .sum();
        }
        let mut e = e.per_kg(self.b.bare_mass_kg());
        if !self.opts.energy_balance {
            e.input = f64::NAN;
            e.damping = f64::NAN;
            self.out.energy_balance_error_max = f64::NAN;
        }
        if !self.opts.abs_velocity {
            self.out.floor_peak_abs_velocity_mps.fill(f64::NAN);
            self.out.block_peak_abs_velocity_mps.fill(f64::NAN);
        }
        if !self.opts.floor_displacements {
            self.out.floor_peak_displacement_m[..n - 1].fill(f64::NAN);
        }
        for i in 0..n {
            self.out.storey_residual_drift_m[i] = drift(i, &self.x);
        }
        self.out.peak_base_shear_n = self.out.storey_peak_shear_n[0];
        let load_kg: f64 = self.b.masses()[n..].iter().sum();
        let duration_s = self.steps as f64 * self.dt;
        self.out.stuck_mass_share = if load_kg > 0.0 {
            1.0 - self.loose_mass_time / (duration_s * load_kg)
        } else {
            f64::NAN
        };
        for k in 0..self.b.blocks() {
            self.out.residual_slip_m[k] = self.x[n + k] - self.x[self.b.below(k)];
        }
        self.out.energy = e;
        self.out.history = history;
        Ok(self.out)
    }
}

impl Contacts for Integrator<'_> {
    fn states(&mut self) -> (&mut [Contact], &mut [Contact]) {
        (&mut self.contacts, &mut self.before)
    }

    fn relative_velocity(&self, k: usize) -> f64 {
        self.v[self.n + k] - self.v[self.b.below(k)]
    }

    fn force(&self, k: usize) -> f64 {
        self.force[k]
    }

    /// The Coulomb-consistent mode at the current state, floor by floor.
    fn select(&mut self, ga: f64) -> Result<(), SimError> {
        let mut ext = vec![0.0; self.n];
        self.floor_forces(ga, &mut ext);
        let n = self.n;
        for (f, fc) in self.floors.iter_mut().enumerate() {
            if fc.interfaces.is_empty() {
                continue;
            }
            fc.external[0] = ext[f];
            for (l, &k) in fc.interfaces.iter().enumerate() {
                fc.external[l + 1] = -self.b.masses()[n + k] * ga;
                fc.contacts[l] = self.contacts[k];
            }
            fc.selector.select_tree(
                &fc.below,
                &fc.masses,
                &fc.external,
                &fc.lim_s,
                &fc.lim_k,
                &mut fc.contacts,
                &mut fc.force,
            )?;
            for (l, &k) in fc.interfaces.iter().enumerate() {
                self.contacts[k] = fc.contacts[l];
                self.force[k] = fc.force[l];
            }
        }
        keep_held(&mut self.out.held, &self.contacts);
        self.mode = None;
        Ok(())
    }

    /// Every group of bodies joined by stuck interfaces that just stopped takes one
    /// momentum-weighted velocity; the kinetic energy this removes (round-off small after an
    /// exact root) is friction work of the lowest interface that just stopped in it.
    fn merge_stopped(&mut self) {
        let (n, nb) = (self.n, self.b.blocks());
        // Union-find over bodies through stuck interfaces.
        let mut parent: Vec<usize> = (0..self.bodies).collect();
        fn root(p: &mut [usize], mut a: usize) -> usize {
            while p[a] != a {
                p[a] = p[p[a]];
                a = p[a];
            }
            a
        }
        for k in 0..nb {
            if self.contacts[k] == Contact::Stick {
                let (a, c) = (root(&mut parent, n + k), root(&mut parent, self.b.below(k)));
                parent[a.max(c)] = a.min(c);
            }
        }
        let m = self.b.masses();
        let mut groups: HashMap<usize, Vec<usize>> = HashMap::new();
        for j in 0..self.bodies {
            let r = root(&mut parent, j);
            groups.entry(r).or_default().push(j);
        }
        let mut roots: Vec<usize> = groups.keys().copied().collect();
        roots.sort_unstable();
        for r in roots {
            let members = &groups[&r];
            let first_stopped = (0..nb).find(|&k| {
                self.before[k] != Contact::Stick
                    && self.contacts[k] == Contact::Stick
                    && members.contains(&(n + k))
            });
            let Some(k) = first_stopped else {
                continue;
            };
            let mass: f64 = members.iter().map(|&j| m[j]).sum();
            let vm = members.iter().map(|&j| m[j] * self.v[j]).sum::<f64>() / mass;
            let loss: f64 = members
                .iter()
                .map(|&j| 0.5 * m[j] * (self.v[j] - vm) * (self.v[j] - vm))
                .sum();
            self.energy.friction_per_interface[k] += loss;
            self.energy.friction += loss;
            for &j in members {
                self.v[j] = vm;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::building::{BuildingSpec, StackSpec, StoreyYielding};

    /// A record with a strong phase and a long free tail, m/s² at 0.01 s.
    fn record(scale: f64) -> Vec<f64> {
        (0..3000)
            .map(|k| {
                let t = k as f64 * 0.01;
                let envelope = (t / 3.0).min(1.0) * (-((t - 8.0).max(0.0)) / 3.0).exp();
                scale
                    * envelope
                    * ((2.1 * t).sin() + 0.7 * (5.3 * t + 1.0).sin() + 0.4 * (11.7 * t).sin())
            })
            .collect()
    }

    fn run(b: &Building, accel: &[f64], opts: ExactOptions, defer: bool) -> BuildingResponse {
        let mut it = Integrator::new(b, 0.01, opts);
        if !defer {
            it.deferred = (it.deferred.iter()).map(|_| DeferredPeak::new(0)).collect();
        }
        it.run(accel, &Unwatched).unwrap()
    }

    /// Deferred peak searches ([`DeferredPeak`]) against each failing piece searched at once:
    /// the same peaks to round-off (each piece's maximum is certified to `ε/8` of its value,
    /// from a start that differs between the two), every other output bit for bit (the peaks
    /// steer nothing).
    #[test]
    fn deferred_peaks_are_each_failing_piece_searched_at_once() {
        let mut three = BuildingSpec::uniform(3, 0.6);
        three.stacks = vec![
            StackSpec::new(3, &[0.5, 0.5], &[0.2, 0.1]),
            StackSpec::new(1, &[1.0], &[0.3]),
        ];
        let mut yielding = three.clone();
        yielding.yielding = Some(StoreyYielding {
            strength_ratios: vec![0.15, 0.12, 0.1],
            post_yield_ratio: 0.05,
        });
        let mut one = BuildingSpec::uniform(1, 1.0);
        one.stacks = vec![StackSpec::new(1, &[0.5, 0.5], &[0.2, 0.1])];
        let mut eight = BuildingSpec::uniform(8, 1.0);
        eight.stacks = vec![
            StackSpec::new(8, &[0.5, 0.5], &[0.2, 0.1]),
            StackSpec::new(4, &[1.0], &[0.15]),
        ];
        let opts = ExactOptions {
            abs_velocity: true,
            ..ExactOptions::default()
        };
        let roof_only = ExactOptions {
            floor_displacements: false,
            ..ExactOptions::default()
        };
        let mut compared = 0;
        for spec in [one, three, yielding, eight] {
            let b = Building::new(&spec).unwrap();
            for scale in [0.5, 2.0, 6.0] {
                let accel = record(scale);
                for o in [opts, roof_only] {
                    let (got, want) = (run(&b, &accel, o, true), run(&b, &accel, o, false));
                    let mut close = |a: &[f64], b: &[f64], what: &str| {
                        for (x, y) in a.iter().zip(b) {
                            let tol = 1e-13 * y.abs();
                            assert!(
                                (x - y).abs() <= tol || x.is_nan() && y.is_nan(),
                                "{what}: {x} against {y}"
                            );
                            compared += 1;
                        }
                    };
                    close(
                        &got.floor_peak_displacement_m,
                        &want.floor_peak_displacement_m,
                        "u",
                    );
                    close(&got.storey_peak_drift_m, &want.storey_peak_drift_m, "drift");
                    close(&got.storey_peak_shear_n, &want.storey_peak_shear_n, "shear");
                    close(
                        &[got.peak_overturning_n_m],
                        &[want.peak_overturning_n_m],
                        "moment",
                    );
                    close(
                        &[got.peak_base_shear_n],
                        &[want.peak_base_shear_n],
                        "base shear",
                    );
                    for (a, b, what) in [
                        (
                            &got.floor_peak_abs_accel_mps2,
                            &want.floor_peak_abs_accel_mps2,
                            "a",
                        ),
                        (
                            &got.floor_peak_abs_velocity_mps,
                            &want.floor_peak_abs_velocity_mps,
                            "v",
                        ),
                        (
                            &got.block_peak_abs_accel_mps2,
                            &want.block_peak_abs_accel_mps2,
                            "a_q",
                        ),
                        (
                            &got.block_peak_abs_velocity_mps,
                            &want.block_peak_abs_velocity_mps,
                            "v_q",
                        ),
                    ] {
                        close(a, b, what);
                    }
                    if let (Some(a), Some(b)) = (&got.storey_ductility, &want.storey_ductility) {
                        close(a, b, "ductility");
                    }
                    let bits = |r: &BuildingResponse| {
                        let mut v = Vec::new();
                        for x in [
                            &r.storey_residual_drift_m,
                            &r.peak_slip_m,
                            &r.residual_slip_m,
                        ] {
                            v.extend(x.iter().map(|x| x.to_bits()));
                        }
                        v.extend([r.stuck_mass_share.to_bits(), r.switches, r.yield_events]);
                        v
                    };
                    assert_eq!(bits(&got), bits(&want));
                }
            }
        }
        assert!(compared > 100, "{compared}");
    }
}
