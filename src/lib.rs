//! StackedLiveLoad: a linear SDOF structure carrying a stack of up to eight
//! rigid blocks, each free to stick or slide with Coulomb friction on the
//! body below, under ground acceleration (see `shared/MODEL.md`).
//!
//! - [`params`]: the scene and solver settings, validated.
//! - [`system`]: masses, stiffness, damping and normal forces.
//! - [`mode`]: stick/slip modes, their reduced dynamics, and the resolution
//!   of a consistent mode at an instant.
//! - [`engine`]: RK4 with located events, peaks and energies.
//! - [`record`]: ground-motion files and driving a simulation through one.
//! - [`limits`]: the bounds that keep an instance safe inside its host process.
//! - [`regularized`]: tanh-regularized friction with plain RK4, a baseline.
//! - [`ports`]: outputs and their derivatives as a coupling master sees them.
//! - [`solver`]: the FMU's three solver choices behind one type.
//! - [`batch`]: `sllRunBatch`, many parameter sets over one record in one
//!   call (beside the FMI API, for parametric studies).
//! - [`sdof`]: the exact linear oscillator (Nigam–Jennings), an oracle.
//! - [`synthetic`]: the embedded default ground motion.

#![warn(missing_docs)]

pub mod batch;
pub mod engine;
pub mod fmi;
pub mod hermite;
pub mod limits;
pub mod mode;
pub mod params;
pub mod record;
pub mod regularized;
pub mod sdof;
pub mod snapshot;
pub mod solver;
pub mod synthetic;
pub mod system;

pub use engine::{Excitation, Outputs, SimError, Simulator, Stats};
pub use params::{Method, ParamError, Params, Settings, MAX_BLOCKS};
pub use record::{GroundMotion, RecordError};
