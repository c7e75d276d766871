//! The RK4 baselines: what the accuracy-speed chart and the stability map
//! compare the exact default against, kept apart from it and never entered
//! by it. Not recommended modes.
//!
//! - [`regularized`]: tanh-regularized friction with plain RK4, its own
//!   simulator (`solver = 3`).
//! - `step_end`: the paper's RK4 with mode switches at step ends only
//!   (`solver = 2`), steps of the engine's [`Simulator`] taken by the
//!   `Method::StepEnd` branch of its stepping loop.
//!
//! [`Simulator`]: crate::physics::engine::Simulator

pub mod regularized;
mod step_end;
