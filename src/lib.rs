//! StackedLiveLoad: a linear SDOF structure carrying a stack of up to eight
//! rigid blocks, each free to stick or slide with Coulomb friction on the
//! body below, under ground acceleration (see `shared/MODEL.md`), exported
//! as an FMI 2.0 and an FMI 3.0 Co-Simulation FMU (one library for both).
//!
//! Rooms, each using only the ones listed before it (but for `physics`
//! reaching [`baselines`] through the step-end branch of its stepping
//! loop):
//! - [`physics`]: the scene, stick/slip modes, the exact default.
//! - [`baselines`]: the RK4 baselines the charts compare against (the
//!   paper's step-end RK4, tanh-regularized friction), apart from the
//!   default and never entered by it.
//! - [`solver`]: the FMU's `solver` choice between the exact engine and a
//!   baseline, and the `Stepper` trait that drives either.
//! - [`ground`]: ground-motion records and driving a simulation through one.
//! - [`fmi`]: the FMU (instance state machine, variables, C API).
//! - [`batch`]: `sllRunBatch`, many parameter sets over one record in one
//!   call, beside the FMI API (for parametric studies).
//!
//! [`limits`] holds the bounds that keep an instance safe inside its host
//! process; all rooms read them. [`isa`] compiles the engine's hottest
//! functions for AVX2 and AVX-512 too and picks the copy at each call (the
//! same results bit for bit).

#![warn(missing_docs)]

pub mod baselines;
pub mod batch;
pub mod fmi;
pub mod ground;
pub mod isa;
pub mod limits;
pub mod physics;
pub mod solver;

pub use ground::record::{GroundMotion, RecordError};
pub use physics::engine::{Excitation, Outputs, SimError, Simulator, Stats};
pub use physics::params::{Method, ParamError, Params, Settings, Support, MAX_BLOCKS};
