//! What a building simulation returns: per floor, per storey, per stack and the energy terms.

use super::super::response::{Energy, History, Response};
use super::super::rocking::RockingOnset;

/// The response of a building to one record (docs/model.md, "A multi-storey building"). Peaks
/// are exact over time (between samples and at switches, one-sided limits included).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BuildingResponse {
    /// Peak `|u_j|` of each floor relative to the ground, m, floor 1 first.
    pub floor_peak_displacement_m: Vec<f64>,
    /// Peak absolute acceleration of each floor, m/s².
    pub floor_peak_abs_accel_mps2: Vec<f64>,
    /// Peak absolute velocity of each floor (relative to the ground plus the ground's), m/s.
    pub floor_peak_abs_velocity_mps: Vec<f64>,
    /// Peak `|δ_i|`, `δ_i = u_i − u_{i−1}`, m, storey 1 first.
    pub storey_peak_drift_m: Vec<f64>,
    /// `max|δ_i| / (F_y,i/k_i)`; `None` when the storeys are elastic.
    pub storey_ductility: Option<Vec<f64>>,
    /// Signed `δ_i` at the record's end, m.
    pub storey_residual_drift_m: Vec<f64>,
    /// Peak `|V|`, N, of the base shear `V = F_1 + 1ᵀ·C·u̇` (the first storey's spring force
    /// and the dampers' forces on the ground; by equilibrium every body's mass times its
    /// absolute acceleration, summed: docs/model.md, "Base shear"). NaN where the integrator
    /// does not give it (the one-storey integrator's response, [`Self::from_one_storey`]).
    pub peak_base_shear_n: f64,
    /// Peak `|V_i|` of each storey's shear `V_i = F_i + Σ_{j≥i} (C·u̇)_j`, N, storey 1 (the base
    /// shear) first: by equilibrium, the mass times the absolute acceleration of every body on
    /// the floors above the cut, summed (docs/model.md, "Storey shears and the overturning
    /// moment"). NaN where the integrator does not give them.
    pub storey_peak_shear_n: Vec<f64>,
    /// Peak `|M|` of the overturning moment at the base, `M = Σ_i h_i·V_i` (`h_i` the storey
    /// heights), N·m. NaN where the integrator does not give it.
    pub peak_overturning_n_m: f64,
    /// The stacks' mass moving with its floor (every interface below it stuck), averaged over
    /// the record's duration, over the stacks' mass: 1 for a stack that never slides, near 0 for
    /// one that slips all the time (NaN without stacks, or where the integrator does not give
    /// it).
    pub stuck_mass_share: f64,
    /// Peak absolute acceleration of every block, m/s² (stacks in order, bottom-up).
    pub block_peak_abs_accel_mps2: Vec<f64>,
    /// Peak absolute velocity of every block, m/s (in the same order).
    pub block_peak_abs_velocity_mps: Vec<f64>,
    /// Peak `|slip|` of every interface relative to the body below, m.
    pub peak_slip_m: Vec<f64>,
    /// Signed slip at the record's end, m.
    pub residual_slip_m: Vec<f64>,
    /// Whether each interface stuck for the whole record: every contact selection left it
    /// stuck (never slipping, never free). Empty where the integrator does not track it (the
    /// RK4 reference).
    pub held: Vec<bool>,
    /// Stick/slip switches.
    pub switches: u64,
    /// Yield and unloading events of all storeys.
    pub yield_events: u64,
    /// Energy per kg of the bare building's mass.
    pub energy: Energy,
    /// Largest `|residual|/input` at the end of a sample interval (NaN without the balance).
    pub energy_balance_error_max: f64,
    /// Per stack, where and when it would first start to rock (its blocks' ratios given,
    /// [`super::StackSpec::aspect`]); `None` when it never does or is not checked.
    pub rocking_onset: Vec<Option<RockingOnset>>,
    /// Bodies: floors, then blocks; interfaces: every stack's, in order.
    pub history: Option<History>,
}

impl BuildingResponse {
    /// A response of `storeys` floors and `blocks` blocks in `stacks` stacks with every peak at
    /// zero, to be filled by an integrator.
    pub fn zeroed(storeys: usize, blocks: usize, stacks: usize) -> Self {
        Self {
            floor_peak_displacement_m: vec![0.0; storeys],
            floor_peak_abs_accel_mps2: vec![0.0; storeys],
            floor_peak_abs_velocity_mps: vec![0.0; storeys],
            storey_peak_drift_m: vec![0.0; storeys],
            storey_residual_drift_m: vec![0.0; storeys],
            peak_base_shear_n: 0.0,
            storey_peak_shear_n: vec![0.0; storeys],
            peak_overturning_n_m: 0.0,
            stuck_mass_share: f64::NAN,
            block_peak_abs_accel_mps2: vec![0.0; blocks],
            block_peak_abs_velocity_mps: vec![0.0; blocks],
            peak_slip_m: vec![0.0; blocks],
            residual_slip_m: vec![0.0; blocks],
            rocking_onset: vec![None; stacks],
            ..Self::default()
        }
    }

    /// The one-storey integrator's response in a building's terms (floor 1 = the structure,
    /// one stack), for [`super::Building::one_storey`].
    pub fn from_one_storey(r: Response) -> Self {
        let blocks = r.peak_slip_m.len();
        Self {
            floor_peak_displacement_m: vec![r.peak_displacement_m],
            floor_peak_abs_accel_mps2: vec![r.peak_abs_accel_mps2[0]],
            floor_peak_abs_velocity_mps: vec![r.peak_abs_velocity_mps[0]],
            storey_peak_drift_m: vec![r.peak_displacement_m],
            storey_ductility: r.ductility.map(|d| vec![d]),
            storey_residual_drift_m: vec![r.residual_displacement_m],
            peak_base_shear_n: f64::NAN,
            storey_peak_shear_n: vec![f64::NAN],
            peak_overturning_n_m: f64::NAN,
            stuck_mass_share: f64::NAN,
            block_peak_abs_accel_mps2: r.peak_abs_accel_mps2[1..=blocks].to_vec(),
            block_peak_abs_velocity_mps: r.peak_abs_velocity_mps[1..=blocks].to_vec(),
            peak_slip_m: r.peak_slip_m,
            residual_slip_m: r.residual_slip_m,
            held: r.held,
            switches: r.switches,
            yield_events: r.yield_events,
            energy: r.energy,
            energy_balance_error_max: r.energy_balance_error_max,
            rocking_onset: if blocks > 0 {
                vec![r.rocking_onset]
            } else {
                Vec::new()
            },
            history: r.history,
        }
    }

    /// Refuses a response with a non-finite number.
    pub fn check_finite(&self) -> Result<(), super::super::SimError> {
        let lists = [
            &self.floor_peak_abs_accel_mps2,
            &self.storey_peak_drift_m,
            &self.storey_residual_drift_m,
            &self.block_peak_abs_accel_mps2,
            &self.peak_slip_m,
            &self.residual_slip_m,
        ];
        let e = &self.energy;
        let velocities = [
            &self.floor_peak_abs_velocity_mps,
            &self.block_peak_abs_velocity_mps,
        ];
        // NaN velocities and displacements below the roof: left out by the options.
        let roof_finite = (self.floor_peak_displacement_m.split_last())
            .is_none_or(|(roof, below)| roof.is_finite() && below.iter().all(|x| !x.is_infinite()));
        let finite = roof_finite
            && lists.iter().all(|l| l.iter().all(|x| x.is_finite()))
            && velocities
                .iter()
                .all(|l| l.iter().all(|x| !x.is_infinite()))
            && !self.peak_base_shear_n.is_infinite()
            && !self.peak_overturning_n_m.is_infinite()
            && self.storey_peak_shear_n.iter().all(|x| !x.is_infinite())
            && self
                .storey_ductility
                .as_ref()
                .is_none_or(|d| d.iter().all(|x| x.is_finite()))
            && [e.kinetic, e.strain, e.friction, e.hysteretic]
                .iter()
                .all(|x| x.is_finite());
        if finite {
            Ok(())
        } else {
            Err(super::super::SimError::Diverged)
        }
    }
}
