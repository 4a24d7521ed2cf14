//! A multi-storey shear building carrying stacks of sliding blocks on its floors
//! (docs/model.md, "A multi-storey building").
//!
//! * [`model`]: the building as stated and validated (floors, storeys, stacks, damping matrix).
//! * `modal`: the floors' exact motion within one contact and yield state.
//! * [`exact`]: the event-driven integrator ([`simulate_building`]).
//! * [`linear`]: the peaks of a building without stacks and with elastic storeys, from one modal
//!   basis ([`LinearBuilding`]; docs/model.md, "The linear building kernel").
//! * [`rk4`]: the paper's fixed-step RK4 as a reference ([`simulate_building_rk4`]).
//! * [`response`]: what it returns.

pub mod exact;
pub mod linear;
pub(crate) mod modal;
pub mod model;
pub mod response;
pub mod rk4;

pub use exact::{simulate_building, simulate_building_watched};
pub use linear::{LinearBuilding, LinearBuildingError, LinearOutput, LinearPeaks, Selection};
pub use modal::ModalError;
pub use model::{Building, BuildingError, BuildingSpec, DampingBasis, StackSpec, StoreyYielding};
pub use response::BuildingResponse;
pub use rk4::{simulate_building_rk4, simulate_building_rk4_watched};
