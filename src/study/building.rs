//! A study over buildings (docs/model.md, "A study over buildings"): the config's `building:`
//! section and `grid.stack_floor`, checked, and the [`Frame`] a case of such a study stands in.
//!
//! ```yaml
//! building:
//!   storeys: [1, 3, 6]             # one value or a list (a grid axis, `storeys`)
//!   floor_masses: [1, 1, 1]        # relative, floor 1 first (only with one `storeys` value)
//!   storey_stiffnesses: [3, 2, 1]  # relative, storey 1 first (idem) [default: all 1]
//!   storey_heights_m: 3.0          # m: one value (every storey) or a list, storey 1 first
//!                                  # (a list only with one `storeys` value) [default: 3.0]
//! grid:
//!   period_s: [0.3, 0.6]           # the bare building's first-mode period
//!   stack_floor: [1, roof, all]    # a floor number, `roof`, `mid`, `all`, or a list (an axis)
//! ```
//!
//! The building's damping is the grid's (`damping`, `damping_basis`: modal, `ζ` in every mode
//! of the basis); its period the grid's `period_s`; its storeys elastic.

use super::yaml::{checked_value, shown};
use crate::case::Case;
use crate::dynamics::G;
use crate::dynamics::building::model::modes;
use crate::fit::BuildingFeatures;
use crate::grid::{BuildingAxes, StackFloor};
use crate::limits::{MAX_AXIS_VALUES, MAX_STOREYS, excerpt};
use crate::store::fit::FrameSpec;
use serde::{Deserialize, Serialize};
use std::fmt;

/// One value or a list of them. Read by `one_or_list`, which says what one value must be.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum OneOrList<T> {
    One(T),
    List(Vec<T>),
}

/// One value or a list of them, each read by `one`; anything else refused as not `what`, in
/// words the parser places after the key and line.
fn one_or_list<T>(
    v: &serde_yaml::Value,
    what: &str,
    one: impl Fn(&serde_yaml::Value) -> Option<T>,
) -> Result<OneOrList<T>, String> {
    let bad = |x: &serde_yaml::Value| format!("expected {what}, got {}", shown(x));
    match v {
        serde_yaml::Value::Sequence(items) => (items.iter())
            .map(|x| one(x).ok_or_else(|| bad(x)))
            .collect::<Result<_, _>>()
            .map(OneOrList::List),
        x => one(x).map(OneOrList::One).ok_or_else(|| bad(x)),
    }
}

/// A key read by [`one_or_list`]; `null` is no value.
fn optional_one_or_list<'de, D, T>(
    d: D,
    what: &str,
    one: impl Fn(&serde_yaml::Value) -> Option<T>,
) -> Result<Option<OneOrList<T>>, D::Error>
where
    D: serde::Deserializer<'de>,
{
    checked_value(d, |v| match v {
        serde_yaml::Value::Null => Ok(None),
        v => one_or_list(&v, what, one).map(Some),
    })
}

/// A whole number of storeys (0 and too many are refused with the building's limits).
fn storey_count(v: &serde_yaml::Value) -> Option<usize> {
    v.as_u64().and_then(|n| usize::try_from(n).ok())
}

/// `building.storeys` of a study: a storey count or a list of them.
fn storeys<'de, D: serde::Deserializer<'de>>(d: D) -> Result<OneOrList<usize>, D::Error> {
    checked_value(d, |v| {
        one_or_list(
            &v,
            "a whole number of storeys ≥ 1 or a list of them",
            storey_count,
        )
    })
}

/// `building.storeys` of a case file: one storey count.
pub fn one_storey_count<'de, D: serde::Deserializer<'de>>(d: D) -> Result<usize, D::Error> {
    checked_value(d, |v| {
        storey_count(&v)
            .ok_or_else(|| format!("expected a whole number of storeys ≥ 1, got {}", shown(&v)))
    })
}

/// `building.storey_heights_m`: a height, m, for every storey, or a list of them.
pub fn storey_heights<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Option<OneOrList<f64>>, D::Error> {
    optional_one_or_list(
        d,
        "a storey height in m or a list of them, storey 1 first",
        serde_yaml::Value::as_f64,
    )
}

/// `grid.stack_floor`: a floor or a list of them.
pub fn stack_floors<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Option<OneOrList<FloorKey>>, D::Error> {
    let floor = |v: &serde_yaml::Value| match v {
        serde_yaml::Value::String(s) => Some(FloorKey::Name(s.clone())),
        _ => (v.as_u64())
            .and_then(|j| usize::try_from(j).ok())
            .map(FloorKey::Index),
    };
    optional_one_or_list(
        d,
        "a floor number, `roof`, `mid` or `all`, or a list of them",
        floor,
    )
}

impl<T: Clone> OneOrList<T> {
    pub fn to_vec(&self) -> Vec<T> {
        match self {
            OneOrList::One(v) => vec![v.clone()],
            OneOrList::List(v) => v.clone(),
        }
    }
}

/// A floor as the config writes it: a number, `roof`, `mid` or `all` (read by [`stack_floors`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum FloorKey {
    Index(usize),
    Name(String),
}

/// The `building:` section of a study: the case file's building keys, `storeys` possibly a
/// list. The keys a study sets elsewhere (`period`) or does not yet run (`structure` other than
/// `elastic`, the yield keys) are read so that they can be refused by name.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BuildingSection {
    /// Storey counts `N`: one, or a list (the `storeys` axis).
    #[serde(deserialize_with = "storeys")]
    pub storeys: OneOrList<usize>,
    /// Relative floor masses, floor 1 first [default: all 1].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floor_masses: Option<Vec<f64>>,
    /// Relative storey stiffnesses, storey 1 first [default: all 1].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub storey_stiffnesses: Option<Vec<f64>>,
    /// Storey heights, m: one value for every storey or a list, storey 1 first [default:
    /// [`DEFAULT_STOREY_HEIGHT_M`]]; they turn drifts into drift ratios.
    #[serde(
        default,
        deserialize_with = "storey_heights",
        skip_serializing_if = "Option::is_none"
    )]
    pub storey_heights_m: Option<OneOrList<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub period: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub structure: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub yield_strength_ratios: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub post_yield_ratio: Option<f64>,
}

pub use crate::dynamics::building::model::{DEFAULT_STOREY_HEIGHT_M, STOREY_HEIGHT_RANGE_M};

/// The building a case of a building study stands in: the bare building's relative floor
/// masses and storey stiffnesses (its first-mode period is the case's `T_p`), its storey
/// heights and the floors carrying the case's stack.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    pub floor_masses: Vec<f64>,
    pub storey_stiffnesses: Vec<f64>,
    /// Storey heights, m, storey 1 first.
    pub storey_heights_m: Vec<f64>,
    pub stack_floor: StackFloor,
}

impl Frame {
    /// The one-storey study's structure as a frame: one floor of relative mass 1, one storey of
    /// [`DEFAULT_STOREY_HEIGHT_M`], the stack on it; the frame `building: {storeys: [1]}` gives,
    /// whose results are the one-storey study's to the bit (docs/model.md, "Identity").
    pub fn one_storey() -> Self {
        Frame {
            floor_masses: vec![1.0],
            storey_stiffnesses: vec![1.0],
            storey_heights_m: vec![DEFAULT_STOREY_HEIGHT_M],
            stack_floor: StackFloor::Roof,
        }
    }

    pub fn storeys(&self) -> usize {
        self.floor_masses.len()
    }

    /// The frame as `fit.yaml` stores it.
    pub fn spec(&self) -> FrameSpec {
        FrameSpec {
            storeys: self.storeys(),
            stack_floor: self.stack_floor.to_string(),
            floor_masses: self.floor_masses.clone(),
            storey_stiffnesses: self.storey_stiffnesses.clone(),
            storey_heights_m: self.storey_heights_m.clone(),
            z_stack: self.stack_height_ratio(),
        }
    }

    /// The frame `fit.yaml` stored (`None` if its `stack_floor` is not one).
    pub fn of_spec(spec: &FrameSpec) -> Option<Frame> {
        Some(Frame {
            floor_masses: spec.floor_masses.clone(),
            storey_stiffnesses: spec.storey_stiffnesses.clone(),
            storey_heights_m: spec.storey_heights_m.clone(),
            stack_floor: spec.stack_floor.parse().ok()?,
        })
    }

    /// A base shear `v_n` (N, the floor masses taken as kg) over the bare building's weight
    /// `g·Σm_j`.
    pub fn base_shear_ratio(&self, v_n: f64) -> f64 {
        v_n / (G * self.floor_masses.iter().sum::<f64>())
    }

    /// The floors carrying a stack, 1-based, lowest first.
    pub fn floors(&self) -> Vec<usize> {
        self.stack_floor.floors(self.storeys())
    }

    /// The relative height `z = h/H` of the stack's floor, `h` its height above the ground and
    /// `H` the roof's (from `storey_heights_m`); with a stack on every floor, their mean
    /// weighted by the stacks' masses (each stack's mass is `α` times its floor's): the height
    /// of the stacks' centre of mass over `H`. 1 on one storey.
    pub fn stack_height_ratio(&self) -> f64 {
        let height = |f: usize| self.storey_heights_m[..f].iter().sum::<f64>();
        let roof = height(self.storeys());
        let floors = self.floors();
        let weight = |f: usize| self.floor_masses[f - 1];
        let total: f64 = floors.iter().map(|&f| weight(f)).sum();
        (floors.iter())
            .map(|&f| weight(f) * height(f) / roof)
            .sum::<f64>()
            / total
    }

    /// `Γ_1·φ_1,N` of the bare building: the roof's displacement per unit displacement of the
    /// first mode's equivalent SDOF (Chopra, *Dynamics of Structures*, the modal expansion of
    /// the effective earthquake forces: `u_N = Γ_1·φ_1,N·D_1`), `Γ_1 = φ_1ᵀ·M·1 / φ_1ᵀ·M·φ_1`.
    /// Independent of the mode's scale and sign and of the stiffnesses' scale; 1 on one storey
    /// (exact: `m·φ²` with `φ = 1/sqrt(m)`, given without round-off).
    pub fn roof_participation(&self) -> f64 {
        let n = self.storeys();
        if n == 1 {
            return 1.0;
        }
        let (_, phi) = modes(&self.floor_masses, &self.storey_stiffnesses);
        let m_phi_1: f64 = (0..n).map(|j| self.floor_masses[j] * phi[(j, 0)]).sum();
        let m_phi_phi: f64 = (0..n)
            .map(|j| self.floor_masses[j] * phi[(j, 0)] * phi[(j, 0)])
            .sum();
        m_phi_1 / m_phi_phi * phi[(n - 1, 0)]
    }

    /// `T_1,rigid`, s: the first-mode period of the building whose bare first-mode period is
    /// `case.period_s` with the case's whole stack (`α = Σα_i` of each loaded floor's mass)
    /// rigidly attached to every floor the frame names; on one storey `T_p·sqrt(1+α)`
    /// ([`Case::t_rigid_s`], the same arithmetic as the one-storey study).
    pub fn t_rigid_s(&self, case: &Case) -> f64 {
        if self.storeys() == 1 {
            return case.t_rigid_s();
        }
        self.t1_attached_s(case, 1.0)
    }

    /// The first-mode period of the building carrying `fraction` of `case`'s stack rigidly
    /// attached to each loaded floor, s: `T_1` at 0, `T_1,rigid` at 1 (the same arithmetic as
    /// [`Self::t_rigid_s`], bit for bit), shorter than `T_1` below 0 (docs/model.md, "The
    /// attached fraction").
    pub fn t1_attached_s(&self, case: &Case, fraction: f64) -> f64 {
        let alpha = fraction * case.alpha_total();
        if self.storeys() == 1 {
            return case.period_s * (1.0 + alpha).sqrt();
        }
        let mut loaded = self.floor_masses.clone();
        for f in self.floors() {
            loaded[f - 1] *= 1.0 + alpha;
        }
        let bare = modes(&self.floor_masses, &self.storey_stiffnesses).0[0];
        let rigid = modes(&loaded, &self.storey_stiffnesses).0[0];
        case.period_s * (bare / rigid).sqrt()
    }

    /// The building's height, m.
    pub fn height_m(&self) -> f64 {
        self.storey_heights_m.iter().sum()
    }

    /// Floor `floor`'s height over the roof's, `z/h` (floor 1 the lowest).
    pub fn height_ratio(&self, floor: usize) -> f64 {
        self.storey_heights_m[..floor].iter().sum::<f64>() / self.height_m()
    }

    /// An overturning moment at the base (N·m) over the bare building's weight times its
    /// height.
    pub fn overturning_ratio(&self, m_n_m: f64) -> f64 {
        self.base_shear_ratio(m_n_m) / self.height_m()
    }
}

/// For each of a study's frames (stored order), the first frame that is the same building (its
/// own index when none before is): the same storeys and loaded floors, so the same masses,
/// stiffnesses and stacks. On one storey floor 1, the roof and every floor are one building,
/// and on `N` storeys floor `N` is the roof. Such frames have the same results to the bit, so
/// `tnew` and `ida` compute the first only.
pub fn first_of_building(frames: &[Frame]) -> Vec<usize> {
    let same = |a: &Frame, b: &Frame| a.storeys() == b.storeys() && a.floors() == b.floors();
    (0..frames.len())
        .map(|f| (0..f).find(|&g| same(&frames[g], &frames[f])).unwrap_or(f))
        .collect()
}

/// The frames that are the first of their building ([`first_of_building`]), in order: those the
/// sweep runs.
pub fn distinct_frames(frames: &[Frame]) -> Vec<usize> {
    (first_of_building(frames).into_iter().enumerate())
        .filter(|&(f, first)| f == first)
        .map(|(f, _)| f)
        .collect()
}

/// Which of a study's frames repeat an earlier one's building ([`first_of_building`]): the fit
/// and the report count such a frame's cases once.
pub fn repeats(frames: &[Frame]) -> Vec<bool> {
    (first_of_building(frames).into_iter().enumerate())
        .map(|(f, first)| first != f)
        .collect()
}

/// The fit's features of a study of `frames` (`blocks` blocks): `N` and `z_stack` after the
/// one-storey ones, each only where it varies over the frames (docs/fit.md, "A study over
/// buildings"); `None` for a study of one frame, fitted with the one-storey features.
pub fn fit_features(blocks: usize, frames: &[Frame]) -> Option<BuildingFeatures> {
    let varies = |v: Vec<f64>| v.iter().any(|x| *x != v[0]);
    (frames.len() > 1).then(|| BuildingFeatures {
        blocks,
        storeys: varies(frames.iter().map(|f| f.storeys() as f64).collect()),
        height: varies(frames.iter().map(Frame::stack_height_ratio).collect()),
    })
}

/// `3 storeys, stack on floor 2` (or `on the roof`, `at mid-height (floor 2)`, `on every floor`).
impl fmt::Display for Frame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.storeys();
        let s = if n == 1 { "" } else { "s" };
        match self.stack_floor {
            StackFloor::Floor(j) => write!(f, "{n} storey{s}, stack on floor {j}"),
            StackFloor::Roof => write!(f, "{n} storey{s}, stack on the roof"),
            StackFloor::Mid => write!(
                f,
                "{n} storey{s}, stack at mid-height (floor {})",
                n.div_ceil(2)
            ),
            StackFloor::All => write!(f, "{n} storey{s}, a stack on every floor"),
        }
    }
}

impl BuildingSection {
    /// Checks the section and `grid.stack_floor` against it (`None`: the roof) and gives the
    /// building axes; `Err((key, why))`. The relative masses and stiffnesses are checked by
    /// [`Self::frame`]'s building when the physics builds it, and here by building each.
    pub fn axes(
        &self,
        stack_floor: Option<&OneOrList<FloorKey>>,
    ) -> Result<BuildingAxes, (String, String)> {
        let err = |k: &str, w: String| Err((k.to_string(), w));
        if self.period.is_some() {
            return err(
                "building.period",
                "a study's periods are `grid.period_s` (the bare building's first-mode period); \
                 remove `building.period`"
                    .into(),
            );
        }
        let yielding = self.yield_strength_ratios.is_some() || self.post_yield_ratio.is_some();
        if yielding || self.structure.as_ref().is_some_and(|s| s != "elastic") {
            return err(
                "building.structure",
                "a building study's sweep is elastic; yielding storeys (structure, \
                 yield_strength_ratios, post_yield_ratio) are not yet supported in a study"
                    .into(),
            );
        }
        let storeys = self.storeys.to_vec();
        if storeys.is_empty() || storeys.len() > MAX_AXIS_VALUES {
            return err(
                "building.storeys",
                format!("needs 1 to {MAX_AXIS_VALUES} values"),
            );
        }
        if let Some(n) = storeys.iter().find(|n| !(1..=MAX_STOREYS).contains(*n)) {
            return err(
                "building.storeys",
                format!("{n}: a building has 1 … {MAX_STOREYS} storeys"),
            );
        }
        if storeys.windows(2).any(|w| w[1] <= w[0]) {
            return err(
                "building.storeys",
                "values must be strictly increasing".into(),
            );
        }
        for (key, v) in [
            ("building.floor_masses", &self.floor_masses),
            ("building.storey_stiffnesses", &self.storey_stiffnesses),
        ] {
            if let Some(v) = v
                && (storeys.len() != 1 || v.len() != storeys[0])
            {
                return err(
                    key,
                    format!(
                        "lists {} values; it needs one per storey, and so one `building.storeys` \
                         value (omit it for uniform storeys)",
                        v.len()
                    ),
                );
            }
        }
        if let Some(h) = &self.storey_heights_m {
            let key = "building.storey_heights_m";
            let (lo, hi) = STOREY_HEIGHT_RANGE_M;
            if let OneOrList::List(v) = h
                && (storeys.len() != 1 || v.len() != storeys[0])
            {
                return err(
                    key,
                    format!(
                        "lists {} values; a list needs one per storey, and so one \
                         `building.storeys` value (or give one height for every storey)",
                        v.len()
                    ),
                );
            }
            if let Some(x) = h.to_vec().iter().find(|x| !(lo..=hi).contains(*x)) {
                return err(
                    key,
                    format!("{x:?}: a storey height must be within {lo} … {hi} m"),
                );
            }
        }
        let lowest = storeys[0];
        let keys = stack_floor.map_or(vec![FloorKey::Name("roof".into())], OneOrList::to_vec);
        if keys.is_empty() {
            return err("grid.stack_floor", "needs at least one value".into());
        }
        let mut floors = Vec::with_capacity(keys.len());
        for k in keys {
            let f = match k {
                FloorKey::Index(j) if (1..=lowest).contains(&j) => StackFloor::Floor(j),
                FloorKey::Index(j) => {
                    return err(
                        "grid.stack_floor",
                        format!(
                            "floor {j} is not a floor of every building: floors are 1 … {lowest} \
                             in the lowest (`building.storeys`); use `roof` for the top floor"
                        ),
                    );
                }
                FloorKey::Name(s) if s == "roof" => StackFloor::Roof,
                FloorKey::Name(s) if s == "mid" => StackFloor::Mid,
                FloorKey::Name(s) if s == "all" => StackFloor::All,
                FloorKey::Name(s) => {
                    return err(
                        "grid.stack_floor",
                        format!(
                            "`{}`: a floor number, `roof`, `mid` or `all` (or a list of them)",
                            excerpt(&s)
                        ),
                    );
                }
            };
            if floors.contains(&f) {
                return err("grid.stack_floor", format!("`{f}` is listed twice"));
            }
            floors.push(f);
        }
        Ok(BuildingAxes {
            storeys,
            stack_floor: floors,
        })
    }

    /// The frame of `storeys` storeys with the stack on `stack_floor`.
    pub fn frame(&self, storeys: usize, stack_floor: StackFloor) -> Frame {
        Frame {
            floor_masses: (self.floor_masses.clone()).unwrap_or_else(|| vec![1.0; storeys]),
            storey_stiffnesses: (self.storey_stiffnesses.clone())
                .unwrap_or_else(|| vec![1.0; storeys]),
            storey_heights_m: match &self.storey_heights_m {
                None => vec![DEFAULT_STOREY_HEIGHT_M; storeys],
                Some(OneOrList::One(h)) => vec![*h; storeys],
                Some(OneOrList::List(v)) => v.clone(),
            },
            stack_floor,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(n: usize, stack_floor: StackFloor) -> Frame {
        Frame {
            floor_masses: vec![1.0; n],
            storey_stiffnesses: vec![1.0; n],
            storey_heights_m: vec![DEFAULT_STOREY_HEIGHT_M; n],
            stack_floor,
        }
    }

    #[test]
    fn participation_and_rigid_period_against_closed_forms() {
        // Two equal storeys: the first mode is (1, g), g the golden ratio, so
        // Γ_1·φ_1,2 = g·(1 + g)/(1 + g²), by hand.
        let g = (1.0 + 5f64.sqrt()) / 2.0;
        let two = frame(2, StackFloor::Roof);
        let want = g * (1.0 + g) / (1.0 + g * g);
        assert!((two.roof_participation() - want).abs() < 1e-14, "{want}");
        assert_eq!(frame(1, StackFloor::Roof).roof_participation(), 1.0);
        // N uniform storeys: φ_j = sin((2r − 1)πj/(2N + 1)) for mode r, so with r = 1
        // Γ_1·φ_1,N = φ_N·Σφ_j/Σφ_j².
        for n in [3, 10, 40] {
            let phi: Vec<f64> = (1..=n)
                .map(|j| (std::f64::consts::PI * j as f64 / (2 * n + 1) as f64).sin())
                .collect();
            let sum: f64 = phi.iter().sum();
            let want = phi[n - 1] * sum / phi.iter().map(|p| p * p).sum::<f64>();
            let got = frame(n, StackFloor::Roof).roof_participation();
            assert!((got - want).abs() < 1e-12, "{n}: {got} vs {want}");
        }

        // α on floor 1 of two unit storeys (k = 1): m_1 = 1 + α, m_2 = 1 and
        // m_1·m_2·ω⁴ − k(m_1 + 2m_2)·ω² + k² = 0, the smaller root.
        let case = Case {
            period_s: 0.8,
            alpha: vec![0.3, 0.5],
            mu: vec![0.2, 0.1],
        };
        let w2 = |m1: f64, m2: f64| {
            let b = m1 + 2.0 * m2;
            (b - (b * b - 4.0 * m1 * m2).sqrt()) / (2.0 * m1 * m2)
        };
        let want = 0.8 * (w2(1.0, 1.0) / w2(1.8, 1.0)).sqrt();
        let got = frame(2, StackFloor::Floor(1)).t_rigid_s(&case);
        assert!((got - want).abs() < 1e-13, "{got} vs {want}");
        let want = 0.8 * (w2(1.0, 1.0) / w2(1.0, 1.8)).sqrt();
        assert!((two.t_rigid_s(&case) - want).abs() < 1e-13);
        // Every floor loaded alike scales M: T·sqrt(1+α), in any building.
        let all = Frame {
            floor_masses: vec![1.0, 2.0, 0.5, 1.5],
            storey_stiffnesses: vec![4.0, 3.0, 2.0, 1.0],
            storey_heights_m: vec![4.0, 3.0, 3.0, 3.0],
            stack_floor: StackFloor::All,
        };
        let got = all.t_rigid_s(&case);
        assert!((got - case.t_rigid_s()).abs() < 1e-13 * got, "{got}");
        assert_eq!(frame(1, StackFloor::All).t_rigid_s(&case), case.t_rigid_s());
    }

    #[test]
    fn stack_height_ratio_by_hand() {
        assert_eq!(frame(1, StackFloor::All).stack_height_ratio(), 1.0);
        assert_eq!(frame(4, StackFloor::Roof).stack_height_ratio(), 1.0);
        assert_eq!(frame(4, StackFloor::Floor(1)).stack_height_ratio(), 0.25);
        // Uniform masses: the mean of 1/3, 2/3, 1; masses 3, 1, 1: (3/3 + 2/3 + 1)/5.
        assert!((frame(3, StackFloor::All).stack_height_ratio() - 2.0 / 3.0).abs() < 1e-15);
        let heavy = Frame {
            floor_masses: vec![3.0, 1.0, 1.0],
            storey_stiffnesses: vec![1.0; 3],
            storey_heights_m: vec![3.0; 3],
            stack_floor: StackFloor::All,
        };
        assert!((heavy.stack_height_ratio() - (1.0 + 2.0 / 3.0 + 1.0) / 5.0).abs() < 1e-15);
        // A 4.5 m first storey under two of 3 m: floor 1 at 4.5/10.5.
        let tall = Frame {
            storey_heights_m: vec![4.5, 3.0, 3.0],
            stack_floor: StackFloor::Floor(1),
            ..heavy
        };
        assert!((tall.stack_height_ratio() - 4.5 / 10.5).abs() < 1e-15);
    }
}
