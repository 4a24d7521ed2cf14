//! A building case of `slidestack simulate` (docs/model.md, "A multi-storey building"): the
//! case file's `building:` and `stacks:` keys, checked and resolved into a [`Building`], the run
//! (the one-storey integrator where the building is one storey with at most one stack, the
//! modal one otherwise), and the [`BuildingSummary`] `--json` prints.

use crate::dynamics::building::{
    Building, BuildingResponse, BuildingSpec, StackSpec, StoreyYielding,
    simulate_building_rk4_watched, simulate_building_watched,
};
use crate::dynamics::{
    DampingBasis, Energy, ExactOptions, G, Ground, History, RockingOnset, Watch,
    simulate_exact_watched, simulate_rk4_watched,
};
use crate::limits::MAX_STOREYS;
use crate::one_case::{Integrator, StructureKind};
use crate::render::chart::{Axis, Figure, PALETTE, Panel, Series, Stroke};
use crate::store::HistoryLayout;
use crate::study::building::{DEFAULT_STOREY_HEIGHT_M, OneOrList, STOREY_HEIGHT_RANGE_M};
use serde::{Deserialize, Serialize};

/// The `building:` key of a case file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BuildingSettings {
    /// Storeys `N`.
    #[serde(deserialize_with = "crate::study::building::one_storey_count")]
    pub storeys: usize,
    /// First-mode period of the bare building, s.
    pub period: f64,
    /// Relative floor masses, floor 1 first [default: all 1].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floor_masses: Option<Vec<f64>>,
    /// Relative storey stiffnesses, storey 1 first [default: all 1].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub storey_stiffnesses: Option<Vec<f64>>,
    /// Every storey's restoring force [default: elastic].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub structure: Option<StructureKind>,
    /// `C_y,i` per storey (epp, bilinear): `F_y,i = C_y,i·g·Σ_{j≥i} m_j`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub yield_strength_ratios: Option<Vec<f64>>,
    /// `r` of every storey (bilinear).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub post_yield_ratio: Option<f64>,
    /// Storey heights, m: one value for every storey or a list, storey 1 first [default:
    /// [`DEFAULT_STOREY_HEIGHT_M`]]; they give the drift ratios.
    #[serde(
        default,
        deserialize_with = "crate::study::building::storey_heights",
        skip_serializing_if = "Option::is_none"
    )]
    pub storey_heights_m: Option<OneOrList<f64>>,
}

impl BuildingSettings {
    /// The storey heights, m, storey 1 first; `Err` names the key.
    pub fn storey_heights(&self) -> Result<Vec<f64>, String> {
        let n = self.storeys;
        let h = match &self.storey_heights_m {
            None => vec![DEFAULT_STOREY_HEIGHT_M; n],
            Some(OneOrList::One(h)) => vec![*h; n],
            Some(OneOrList::List(v)) if v.len() == n => v.clone(),
            Some(OneOrList::List(v)) => {
                return Err(format!(
                    "building.storey_heights_m lists {} values but the building has {n} storeys",
                    v.len()
                ));
            }
        };
        let (lo, hi) = STOREY_HEIGHT_RANGE_M;
        match h.iter().position(|x| !(lo..=hi).contains(x)) {
            Some(i) => Err(format!(
                "building.storey_heights_m[{i}] must be within {lo} … {hi} m, got {:?}",
                h[i]
            )),
            None => Ok(h),
        }
    }
}

/// The floor a stack stands on: `1 … N`, or `roof` (floor `N`).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Floor {
    Index(usize),
    Name(String),
}

impl<'de> Deserialize<'de> for Floor {
    /// A whole number or a word; anything else refused in words
    /// ([`crate::study::yaml::checked_value`]). A number or word that is no floor of the
    /// building is refused with the building.
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use crate::study::yaml::{checked_value, shown};
        checked_value(d, |v| {
            match &v {
                serde_yaml::Value::String(s) => Some(Floor::Name(s.clone())),
                _ => (v.as_u64())
                    .and_then(|j| usize::try_from(j).ok())
                    .map(Floor::Index),
            }
            .ok_or_else(|| {
                format!(
                    "expected a floor number (1 the lowest) or `roof`, got {}",
                    shown(&v)
                )
            })
        })
    }
}

/// One entry of the `stacks:` key.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StackSettings {
    pub floor: Floor,
    /// Block masses over the floor's mass, bottom block first.
    pub alpha: Vec<f64>,
    /// Kinetic friction, interface 1 (floor–block 1) first.
    pub mu: Vec<f64>,
    /// Static friction [default: equal to `mu`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu_static: Option<Vec<f64>>,
    /// Width over height of each block, bottom first: asks for the rocking check
    /// (docs/model.md, "Rocking: when a case leaves the model") [default: not checked].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aspect: Option<Vec<f64>>,
}

/// Resolves the building keys; `Err` names the key (the caller adds the file).
pub fn building_spec(
    b: &BuildingSettings,
    stacks: &[StackSettings],
    damping: f64,
    basis: DampingBasis,
) -> Result<BuildingSpec, String> {
    let n = b.storeys;
    if !(1..=MAX_STOREYS).contains(&n) {
        return Err(format!(
            "building.storeys must be 1 … {MAX_STOREYS}, got {n}"
        ));
    }
    let storey_heights_m = b.storey_heights()?;
    let yielding = match (
        b.structure.unwrap_or(StructureKind::Elastic),
        &b.yield_strength_ratios,
        b.post_yield_ratio,
    ) {
        (StructureKind::Elastic, None, None) => None,
        (StructureKind::Elastic, _, _) => {
            return Err(
                "building.yield_strength_ratios and building.post_yield_ratio apply \
                 only to building.structure epp or bilinear"
                    .into(),
            );
        }
        (s, None, _) => {
            return Err(format!(
                "building.structure {} needs building.yield_strength_ratios (C_y per storey)",
                s.name()
            ));
        }
        (StructureKind::Epp, Some(c), None) => Some(StoreyYielding {
            strength_ratios: c.clone(),
            post_yield_ratio: 0.0,
        }),
        (StructureKind::Epp, Some(_), Some(r)) => {
            return Err(format!(
                "building.structure epp has no post-yield stiffness (r = 0), got \
                 building.post_yield_ratio {r}; use bilinear"
            ));
        }
        (StructureKind::Bilinear, Some(_), None) => {
            return Err(
                "building.structure bilinear needs building.post_yield_ratio (r, \
                 0 ≤ r < 1)"
                    .into(),
            );
        }
        (StructureKind::Bilinear, Some(c), Some(r)) => Some(StoreyYielding {
            strength_ratios: c.clone(),
            post_yield_ratio: r,
        }),
    };
    for (key, values) in [
        ("floor_masses", &b.floor_masses),
        ("storey_stiffnesses", &b.storey_stiffnesses),
        ("yield_strength_ratios", &b.yield_strength_ratios),
    ] {
        if let Some(v) = values
            && v.len() != n
        {
            return Err(format!(
                "building.{key} lists {} values but the building has {n} storeys",
                v.len()
            ));
        }
    }
    let stacks = stacks
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let floor = match &s.floor {
                Floor::Index(f) => *f,
                Floor::Name(name) if name == "roof" => n,
                Floor::Name(other) => {
                    return Err(format!(
                        "stacks[{i}].floor must be a floor number 1 … {n} or `roof`, got \
                         `{}`",
                        crate::limits::excerpt(other)
                    ));
                }
            };
            Ok(StackSpec {
                floor,
                alpha: s.alpha.clone(),
                mu: s.mu.clone(),
                mu_static: s.mu_static.clone(),
                aspect: s.aspect.clone(),
            })
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok(BuildingSpec {
        period_s: b.period,
        floor_masses: b.floor_masses.clone().unwrap_or_else(|| vec![1.0; n]),
        storey_stiffnesses: b.storey_stiffnesses.clone().unwrap_or_else(|| vec![1.0; n]),
        damping_ratio: damping,
        damping_basis: basis,
        storey_heights_m,
        yielding,
        stacks,
    })
}

/// Runs the building on `accel_mps2` (m/s², step `dt_s`): the one-storey integrators where the
/// building is one storey with at most one stack ([`Building::one_storey`]: today's case, bit
/// for bit), the building's otherwise.
pub fn run_building(
    b: &Building,
    dt_s: f64,
    accel_mps2: &[f64],
    integrator: Integrator,
    rk4_substeps: usize,
    history: bool,
    watch: &dyn Watch,
) -> Result<BuildingResponse, crate::dynamics::SimError> {
    let ground = Ground { dt_s, accel_mps2 };
    let opts = ExactOptions {
        history,
        ..ExactOptions::default()
    };
    if let Some(sys) = b.one_storey() {
        let r = match integrator {
            Integrator::Exact => simulate_exact_watched(&sys, &ground, &opts, watch)?,
            Integrator::Rk4 => simulate_rk4_watched(&sys, &ground, rk4_substeps, history, watch)?,
        };
        return Ok(BuildingResponse::from_one_storey(r));
    }
    match integrator {
        Integrator::Exact => simulate_building_watched(b, &ground, &opts, watch),
        Integrator::Rk4 => simulate_building_rk4_watched(b, &ground, rk4_substeps, history, watch),
    }
}

/// The history file's layout of a building.
pub fn history_layout(b: &Building) -> HistoryLayout {
    let blocks: Vec<usize> = b.stacks().iter().map(|s| s.blocks).collect();
    HistoryLayout::building(b.storeys(), &blocks)
}

/// The building as the case states it, echoed in the summary.
#[derive(Debug, Clone, Serialize)]
pub struct BuildingEcho {
    pub storeys: usize,
    pub period_s: f64,
    pub floor_masses: Vec<f64>,
    pub storey_stiffnesses: Vec<f64>,
    pub structure: StructureKind,
    pub yield_strength_ratios: Option<Vec<f64>>,
    pub post_yield_ratio: Option<f64>,
    /// Storey stiffnesses `k_i`, N/m per kg of the floors' relative masses.
    pub stiffness_n_per_m: Vec<f64>,
    /// `F_y,i/k_i`, m; null when elastic.
    pub yield_drift_m: Option<Vec<f64>>,
    /// Storey heights, m, storey 1 first.
    pub storey_heights_m: Vec<f64>,
}

/// One stack: as stated, and its response.
#[derive(Debug, Clone, Serialize)]
pub struct StackSummary {
    pub floor: usize,
    pub alpha: Vec<f64>,
    pub mu: Vec<f64>,
    pub mu_static: Vec<f64>,
    /// Interface 1 first, m.
    pub peak_slip_m: Vec<f64>,
    /// Signed, m.
    pub residual_slip_m: Vec<f64>,
    /// Blocks bottom-up, g.
    pub peak_abs_accel_g: Vec<f64>,
    /// Blocks bottom-up, m/s: relative to the ground plus the ground's.
    pub peak_abs_velocity_mps: Vec<f64>,
    /// Width over height per block, as given (absent: rocking not checked).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub aspect: Option<Vec<f64>>,
    /// With `aspect`: `null`, or the block (1 = bottom) whose base the stack would first rock on,
    /// and when (docs/model.md, "Rocking: when a case leaves the model").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rocking_onset: Option<Option<RockingOnset>>,
}

/// What one building simulation gives: the `simulate --json` contract for a case with
/// `building` (docs/building.md, "A multi-storey building").
#[derive(Debug, Clone, Serialize)]
pub struct BuildingSummary {
    pub record: String,
    pub dt_s: f64,
    pub npts: usize,
    pub scale: f64,
    pub damping: f64,
    pub damping_basis: DampingBasis,
    pub integrator: Integrator,
    pub rk4_substeps: Option<usize>,
    pub building: BuildingEcho,
    /// Periods of the bare building's modes, first first, s.
    pub modes_s: Vec<f64>,
    /// Floor 1 first.
    pub floor_peak_displacement_m: Vec<f64>,
    pub floor_peak_abs_accel_g: Vec<f64>,
    /// Relative to the ground plus the ground's, m/s (pelicun's PFV).
    pub floor_peak_abs_velocity_mps: Vec<f64>,
    /// Storey 1 first: `δ_i = u_i − u_{i−1}`.
    pub storey_peak_drift_m: Vec<f64>,
    /// `max|δ_i|/h_i`, storey 1 first.
    pub storey_peak_drift_ratio: Vec<f64>,
    /// Peak base shear `F_1 + 1ᵀ·C·u̇` over the bare building's weight (docs/model.md, "Base
    /// shear, drift ratio, floor acceleration"); null where the one-storey integrator ran.
    pub peak_base_shear_ratio: Option<f64>,
    /// `max|δ_i|/(F_y,i/k_i)`; null when elastic.
    pub storey_ductility: Option<Vec<f64>>,
    pub storey_residual_drift_m: Vec<f64>,
    pub stacks: Vec<StackSummary>,
    pub switches: u64,
    pub yield_events: u64,
    /// J per kg of the bare building's total mass.
    pub energy: Energy,
    pub energy_balance_error: f64,
    pub energy_balance_error_max: f64,
    /// Each floor's response spectra (`floor_spectra:` asked for them).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub floor_spectra: Option<super::floor_spectra::FloorSpectra>,
}

/// The summary of a run of `b`.
#[allow(clippy::too_many_arguments)]
pub fn building_summary(
    b: &Building,
    settings: &BuildingSettings,
    record: (&str, f64, usize, f64),
    damping: (f64, DampingBasis),
    integrator: (Integrator, usize),
    r: &BuildingResponse,
) -> BuildingSummary {
    let spec = b.spec();
    let n = b.storeys();
    let stacks = b
        .stacks()
        .iter()
        .zip(&spec.stacks)
        .enumerate()
        .map(|(si, (s, st))| {
            let range = s.first..s.first + s.blocks;
            StackSummary {
                floor: st.floor,
                alpha: st.alpha.clone(),
                mu: st.mu.clone(),
                mu_static: st.mu_static.clone().unwrap_or_else(|| st.mu.clone()),
                peak_slip_m: r.peak_slip_m[range.clone()].to_vec(),
                residual_slip_m: r.residual_slip_m[range.clone()].to_vec(),
                peak_abs_accel_g: r.block_peak_abs_accel_mps2[range.clone()]
                    .iter()
                    .map(|a| a / G)
                    .collect(),
                peak_abs_velocity_mps: r.block_peak_abs_velocity_mps[range].to_vec(),
                aspect: st.aspect.clone(),
                rocking_onset: st.aspect.as_ref().map(|_| r.rocking_onset[si]),
            }
        })
        .collect();
    let e = &r.energy;
    let heights = settings
        .storey_heights()
        .expect("checked when the building was resolved");
    let weight_n = G * spec.floor_masses.iter().sum::<f64>();
    BuildingSummary {
        record: record.0.to_string(),
        dt_s: record.1,
        npts: record.2,
        scale: record.3,
        damping: damping.0,
        damping_basis: damping.1,
        integrator: integrator.0,
        rk4_substeps: (integrator.0 == Integrator::Rk4).then_some(integrator.1),
        building: BuildingEcho {
            storeys: n,
            period_s: spec.period_s,
            floor_masses: spec.floor_masses.clone(),
            storey_stiffnesses: spec.storey_stiffnesses.clone(),
            structure: settings.structure.unwrap_or(StructureKind::Elastic),
            yield_strength_ratios: spec.yielding.as_ref().map(|y| y.strength_ratios.clone()),
            post_yield_ratio: spec.yielding.as_ref().map(|y| y.post_yield_ratio),
            stiffness_n_per_m: b.stiffness().to_vec(),
            yield_drift_m: b
                .springs()
                .map(|s| s.iter().map(|sp| sp.yield_drift_m).collect()),
            storey_heights_m: heights.clone(),
        },
        modes_s: b.periods_s().to_vec(),
        floor_peak_displacement_m: r.floor_peak_displacement_m.clone(),
        floor_peak_abs_accel_g: r.floor_peak_abs_accel_mps2.iter().map(|a| a / G).collect(),
        floor_peak_abs_velocity_mps: r.floor_peak_abs_velocity_mps.clone(),
        storey_peak_drift_m: r.storey_peak_drift_m.clone(),
        storey_peak_drift_ratio: (r.storey_peak_drift_m.iter().zip(&heights))
            .map(|(d, h)| d / h)
            .collect(),
        peak_base_shear_ratio: (!r.peak_base_shear_n.is_nan())
            .then(|| r.peak_base_shear_n / weight_n),
        storey_ductility: r.storey_ductility.clone(),
        storey_residual_drift_m: r.storey_residual_drift_m.clone(),
        stacks,
        switches: r.switches,
        yield_events: r.yield_events,
        energy: e.clone(),
        energy_balance_error: e.balance_error(),
        energy_balance_error_max: r.energy_balance_error_max,
        floor_spectra: None,
    }
}

/// The worked example's figure: peak floor displacement and storey drift over the height with
/// the stacks sliding and with them rigidly attached, and the roof's displacement and every
/// stack's slip on its floor over time (the latter two when both responses carry histories).
pub fn building_figure(
    b: &Building,
    sliding: &BuildingResponse,
    attached: &BuildingResponse,
    title: &str,
) -> Figure {
    let n = b.storeys();
    let level: Vec<f64> = (1..=n).map(|j| j as f64).collect();
    let profile =
        |values: &[f64], scale: f64| -> Vec<f64> { values.iter().map(|v| v * scale).collect() };
    // The legend is the figure's: only the first panel names the two systems.
    let pair = |a: &[f64], s: &[f64], named: bool| {
        let name = |n: &str| if named { n.to_string() } else { String::new() };
        vec![
            Series::line(name("stacks sliding"), profile(s, 100.0), level.clone())
                .colour(PALETTE[0])
                .stroke(Stroke::Solid, 2),
            Series::line(
                name("stacks rigidly attached"),
                profile(a, 100.0),
                level.clone(),
            )
            .colour(PALETTE[1])
            .stroke(Stroke::Dashed, 2),
        ]
    };
    let mut panels = vec![
        Panel::xy(
            "peak floor displacement",
            Axis::new("peak |u_j| (cm)"),
            Axis::new("floor").range(0.5, n as f64 + 0.5),
            pair(
                &attached.floor_peak_displacement_m,
                &sliding.floor_peak_displacement_m,
                true,
            ),
        ),
        Panel::xy(
            "peak storey drift",
            Axis::new("peak |δ_i| (cm)"),
            Axis::new("storey").range(0.5, n as f64 + 0.5),
            pair(
                &attached.storey_peak_drift_m,
                &sliding.storey_peak_drift_m,
                false,
            ),
        ),
    ];
    if let (Some(hs), Some(ha)) = (&sliding.history, &attached.history) {
        let roof = |h: &History| -> Vec<f64> {
            h.displacement_of(n - 1)
                .into_iter()
                .map(|u| u * 100.0)
                .collect()
        };
        panels.push(Panel::xy(
            "roof displacement",
            Axis::new("time t (s)"),
            Axis::new("u_N (cm)"),
            vec![
                Series::line("", ha.time_s.clone(), roof(ha))
                    .colour(PALETTE[1])
                    .stroke(Stroke::Dashed, 1),
                Series::line("", hs.time_s.clone(), roof(hs))
                    .colour(PALETTE[0])
                    .stroke(Stroke::Solid, 1),
            ],
        ));
        let mut slips = Vec::new();
        for (si, s) in b.stacks().iter().enumerate() {
            let below = b.below(s.first);
            let top = hs.displacement_of(n + s.first);
            let base = hs.displacement_of(below);
            let slip: Vec<f64> = top
                .iter()
                .zip(&base)
                .map(|(t, f)| (t - f) * 100.0)
                .collect();
            slips.push(
                Series::line(
                    format!("stack {} (floor {}), interface 1", si + 1, s.floor + 1),
                    hs.time_s.clone(),
                    slip,
                )
                .colour(PALETTE[(si + 2) % PALETTE.len()])
                .stroke(Stroke::Solid, 1),
            );
        }
        panels.push(Panel::xy(
            "slip of each stack's bottom block on its floor",
            Axis::new("time t (s)"),
            Axis::new("slip (cm)"),
            slips,
        ));
    }
    Figure::grid(title, panels, 2)
}
