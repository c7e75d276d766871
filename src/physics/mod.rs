//! The physics: the scene, the stick/slip modes of the stack and the
//! integrators. Knows nothing of FMI or of record files.
//!
//! - [`params`]: the scene and solver settings, their ranges and validation.
//! - [`system`]: masses, stiffness, damping and normal forces.
//! - [`mode`]: stick/slip modes, their reduced dynamics, and the resolution
//!   of a consistent mode at an instant.
//! - [`engine`]: the exact default and RK4 with located events; peaks and
//!   energies.
//! - [`hermite`]: peaks between steps from the cubic Hermite interpolant.
//! - [`regularized`]: tanh-regularized friction with plain RK4, a baseline.
//! - [`solver`]: the FMU's three solver choices behind one type.
//! - [`snapshot`]: the byte format of saved states.
//! - [`sdof`]: the exact linear oscillator (Nigam–Jennings), an oracle.

pub mod engine;
pub mod hermite;
pub mod mode;
pub mod params;
pub mod regularized;
pub mod sdof;
pub mod snapshot;
pub mod solver;
pub mod system;
