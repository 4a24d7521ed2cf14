//! What a simulation returns: peaks, slips, switch counts, energy terms and, on request, the
//! full time history.

use serde::Serialize;

/// Energy terms per kg of structure mass, J/kg, in the relative-motion formulation: the input
/// energy is the work of the effective earthquake forces `−m_j·a_g` on the relative velocities.
/// `input = kinetic + strain + damping + friction + hysteretic` up to `residual`.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Energy {
    pub input: f64,
    pub kinetic: f64,
    /// Recoverable strain energy `F_s²/(2k)` (for the linear structure `½k·u²`).
    pub strain: f64,
    pub damping: f64,
    pub friction: f64,
    /// Friction dissipation per interface, interface 1 first.
    pub friction_per_interface: Vec<f64>,
    /// A yielding structure's hysteretic energy `∫F_s du − F_s²/(2k)` (docs/model.md,
    /// "Yielding structure"); 0 for the linear structure.
    pub hysteretic: f64,
}

impl Energy {
    /// `input − (kinetic + strain + damping + friction + hysteretic)`.
    pub fn residual(&self) -> f64 {
        self.residual_with(self.kinetic, self.strain + self.hysteretic)
    }

    /// Sets the kinetic (`½Σm_j·v_j²`) and strain (`½k·u₀²`) terms from a state: masses and
    /// relative velocities of all bodies, stiffness and structure displacement.
    pub fn set_state(&mut self, masses: &[f64], velocity: &[f64], stiffness: f64, u0: f64) {
        (self.kinetic, self.strain) = Self::state_terms(masses, velocity, stiffness, u0);
    }

    /// The kinetic and strain terms of [`Energy::set_state`].
    pub fn state_terms(masses: &[f64], velocity: &[f64], stiffness: f64, u0: f64) -> (f64, f64) {
        let kinetic = 0.5
            * masses
                .iter()
                .zip(velocity)
                .map(|(m, v)| m * v * v)
                .sum::<f64>();
        (kinetic, 0.5 * stiffness * u0 * u0)
    }

    /// [`Energy::residual`] with the kinetic and strain terms given instead of stored (`strain`
    /// standing for all the spring's work, `strain + hysteretic`).
    pub fn residual_with(&self, kinetic: f64, strain: f64) -> f64 {
        self.input - (kinetic + strain + self.damping + self.friction)
    }

    /// Every term divided by the structure mass, so in J per kg of it.
    pub fn per_kg(mut self, mass_kg: f64) -> Self {
        let s = 1.0 / mass_kg;
        for val in [
            &mut self.input,
            &mut self.kinetic,
            &mut self.strain,
            &mut self.damping,
            &mut self.friction,
            &mut self.hysteretic,
        ]
        .into_iter()
        .chain(self.friction_per_interface.iter_mut())
        {
            *val *= s;
        }
        self
    }

    /// `|residual| / input` (0 when no energy entered).
    pub fn balance_error(&self) -> f64 {
        let scale = self
            .input
            .abs()
            .max(self.kinetic + self.strain + self.damping + self.friction + self.hysteretic);
        if scale == 0.0 {
            0.0
        } else {
            self.residual().abs() / scale
        }
    }
}

/// Time history sampled at every record sample (and, for the RK4 integrator, every sample).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct History {
    /// Time of each row, s.
    pub time_s: Vec<f64>,
    /// Ground acceleration, m/s².
    pub ground_accel_mps2: Vec<f64>,
    /// Displacement relative to the ground, m: row-major `[time][body]`, structure first.
    pub displacement_m: Vec<f64>,
    /// Velocity relative to the ground, m/s, same layout.
    pub velocity_mps: Vec<f64>,
    /// Absolute acceleration, m/s², same layout.
    pub abs_accel_mps2: Vec<f64>,
    /// Interface state ([`crate::dynamics::Contact::code`]): row-major `[time][interface]`.
    pub contact: Vec<i8>,
    /// Number of bodies (structure plus blocks; for a building, floors plus blocks).
    pub bodies: usize,
    /// Number of interfaces.
    pub interfaces: usize,
}

impl History {
    /// A history of one storey: `bodies` (structure and blocks), one interface under each block.
    pub fn with_capacity(rows: usize, bodies: usize) -> Self {
        Self::with_layout(rows, bodies, bodies.saturating_sub(1))
    }

    pub fn with_layout(rows: usize, bodies: usize, interfaces: usize) -> Self {
        Self {
            time_s: Vec::with_capacity(rows),
            ground_accel_mps2: Vec::with_capacity(rows),
            displacement_m: Vec::with_capacity(rows * bodies),
            velocity_mps: Vec::with_capacity(rows * bodies),
            abs_accel_mps2: Vec::with_capacity(rows * bodies),
            contact: Vec::with_capacity(rows * interfaces),
            bodies,
            interfaces,
        }
    }

    pub fn rows(&self) -> usize {
        self.time_s.len()
    }

    /// Body `body`'s displacement relative to the ground at every row, m.
    pub fn displacement_of(&self, body: usize) -> Vec<f64> {
        self.displacement_m
            .iter()
            .skip(body)
            .step_by(self.bodies)
            .copied()
            .collect()
    }
}

/// Result of one simulation.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Response {
    /// Peak |structure displacement| relative to the ground, m, and when it occurs, s.
    pub peak_displacement_m: f64,
    pub peak_displacement_time_s: f64,
    /// Peak |absolute acceleration| of every body, m/s², structure first then blocks bottom-up.
    pub peak_abs_accel_mps2: Vec<f64>,
    /// Peak |absolute velocity| of every body, m/s, in the same order: the body's velocity
    /// relative to the ground plus the ground's (docs/model.md, "Absolute velocities").
    pub peak_abs_velocity_mps: Vec<f64>,
    /// Peak |relative displacement| across each interface, m, interface 1 first.
    pub peak_slip_m: Vec<f64>,
    /// Relative displacement across each interface at the end of the record, m.
    pub residual_slip_m: Vec<f64>,
    /// Total time each interface spent slipping, s.
    pub slip_time_s: Vec<f64>,
    /// Whether each interface stuck for the whole record: every contact selection left it
    /// stuck (never slipping, never free). Empty where the integrator does not track it (the
    /// RK4 reference).
    pub held: Vec<bool>,
    /// Number of interface state changes.
    pub switches: u64,
    /// Structure displacement relative to the ground at the end of the record, m (a yielding
    /// structure's residual drift once the record has let it come to rest: pad a record with
    /// zeros for that).
    pub residual_displacement_m: f64,
    /// Peak displacement over the yield displacement, `u_m/u_y` (Chopra, Section 7.2); `None`
    /// for the linear structure.
    pub ductility: Option<f64>,
    /// Number of yield and unloading events of a yielding structure.
    pub yield_events: u64,
    /// Energy terms at the end of the record, J per kg of structure mass.
    pub energy: Energy,
    /// Largest `|residual(t)| / max_{s≤t} input(s)` over the record samples.
    pub energy_balance_error_max: f64,
    /// Where and when the stack would first start to rock (the system's blocks' ratios
    /// given, [`super::System::with_aspect`]); `None` when it never does or is not checked.
    pub rocking_onset: Option<super::RockingOnset>,
    pub history: Option<History>,
}

impl Response {
    /// Refuses a response with a non-finite peak or energy term (a diverged integration) instead
    /// of reporting it. NaN energy terms and velocities the options left out are not checked.
    pub fn check_finite(&self) -> Result<(), super::SimError> {
        let e = &self.energy;
        let finite = self.peak_displacement_m.is_finite()
            && self.residual_displacement_m.is_finite()
            && self
                .peak_abs_accel_mps2
                .iter()
                .chain(&self.peak_slip_m)
                .chain(&self.residual_slip_m)
                .all(|v| v.is_finite())
            && self.peak_abs_velocity_mps.iter().all(|v| !v.is_infinite())
            && [e.kinetic, e.strain, e.friction, e.hysteretic]
                .iter()
                .all(|v| v.is_finite());
        if finite {
            Ok(())
        } else {
            Err(super::SimError::Diverged)
        }
    }
}
