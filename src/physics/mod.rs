//! The physics: the scene, the stick/slip modes of the stack and the
//! integrators. Knows nothing of FMI or of record files.
//!
//! - [`params`]: the scene and solver settings, their ranges and validation.
//! - [`system`]: masses, stiffness, damping and normal forces.
//! - [`mode`]: stick/slip modes, their reduced dynamics, and the resolution
//!   of a consistent mode at an instant.
//! - [`engine`]: the exact default (and the stepping loop the step-end RK4
//!   baseline of [`crate::baselines`] shares); peaks and energies.
//! - [`hermite`]: peaks between steps from the cubic Hermite interpolant.
//! - [`snapshot`]: the byte format of saved states.
//! - [`sdof`]: the exact linear oscillator (Nigam–Jennings), an oracle.

pub mod engine;
pub mod hermite;
pub mod mode;
pub mod params;
pub mod sdof;
pub mod snapshot;
pub mod system;
