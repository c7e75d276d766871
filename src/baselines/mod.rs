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

/// RK4 step limit for the bare structure: stability needs `h ω_p < 2.83`
/// (undamped); we keep a margin.
pub const STABLE_H_OMEGA: f64 = 2.5;
/// Default accuracy bounds: `h ω_p <= 0.02` and `h <= 1.25 ms`. Measured
/// over periods 0.1–10 s on real, synthetic and spectrum-matched records, they
/// keep peaks within 1e-6 relative of the exact solution and the energy
/// residual below 1e-8 of the input (docs/accuracy-speed.md, "Accuracy"). The absolute bound
/// matters at long periods and for records rich in short periods (matched
/// records): the structure's free response absorbs every change of slope of
/// the forcing, and the per-step error then no longer falls with ω.
pub const ACCURATE_H_OMEGA: f64 = 0.02;
/// See [`ACCURATE_H_OMEGA`].
pub const ACCURATE_MAX_STEP: f64 = 0.00125;

/// The RK4 baselines' internal step for `maxStep` (0: automatic) and the
/// structure: `maxStep` within the stability bound, or the accuracy bounds
/// when automatic. On a prescribed support (`omega_p = 0`: no spring, no
/// stability bound) it is `maxStep`, or `ACCURATE_MAX_STEP` when automatic.
pub fn auto_step(max_step: f64, omega_p: f64) -> f64 {
    if max_step > 0.0 {
        max_step.min(STABLE_H_OMEGA / omega_p)
    } else {
        (ACCURATE_H_OMEGA / omega_p).min(ACCURATE_MAX_STEP)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::engine::Simulator;
    use crate::physics::params::{Method, Params, Settings};

    #[test]
    fn internal_step_respects_both_bounds() {
        // The exact default: substeps of omega h = MAP_H_OMEGA, or maxStep
        // where shorter; the RK4 baseline (solver 2): the automatic step,
        // maxStep bounded by the stability limit STABLE_H_OMEGA / omega.
        let p = Params::default();
        let omega = 2.0 * std::f64::consts::PI / p.tp;
        let auto = Simulator::new(&p, &Settings::default()).unwrap();
        assert_eq!(auto.max_internal_step(), 0.5 / omega);
        for (max_step, expected) in [(1e-4, 1e-4), (10.0, 0.5 / omega)] {
            let s = Settings {
                max_step,
                ..Settings::default()
            };
            let sim = Simulator::new(&p, &s).unwrap();
            assert_eq!(sim.max_internal_step(), expected);
        }
        let baseline = |max_step| Settings {
            method: Method::StepEnd,
            max_step,
        };
        let sim = Simulator::new(&p, &baseline(0.0)).unwrap();
        assert_eq!(
            sim.max_internal_step(),
            (ACCURATE_H_OMEGA / omega).min(ACCURATE_MAX_STEP)
        );
        let sim = Simulator::new(&p, &baseline(10.0)).unwrap();
        assert_eq!(sim.max_internal_step(), STABLE_H_OMEGA / omega);
    }
}
