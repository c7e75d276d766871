//! Checks of a deserialized saved state (`fmi2DeSerializeFMUstate`) beyond
//! what the engine checks of its own state: a blob changed anywhere must be
//! refused, never lead to a panic, a hang or a non-finite output.

use super::{Dynamic, Phase};
use crate::limits::MAX_PATH_BYTES;
use crate::physics::params::{check_scalar, MAX_BLOCKS};
use crate::physics::snapshot::SnapshotError;
use crate::physics::solver::{Solver, SolverKind, Stepper};

/// Every field of a deserialized state, beyond what the engine checks of its
/// own: times, parameters in range, a solver that is the one its parameters
/// build, finite inputs and outputs (docs/robustness.md, "Saved states").
pub(super) fn check_saved(d: &Dynamic) -> Result<(), SnapshotError> {
    if d.phase == Phase::Error {
        return Err("a saved state is never in the Error state".into());
    }
    let stop_ok = d
        .stop_time
        .is_none_or(|stop| stop.is_finite() && stop >= d.start_time);
    let tol = 1e-9 * d.time.abs().max(1.0);
    let time_ok = d.start_time.is_finite()
        && d.time.is_finite()
        && d.time >= d.start_time
        && d.stop_time.is_none_or(|stop| d.time <= stop + tol);
    if !(stop_ok && time_ok) {
        return Err(format!(
            "times of the saved state are not consistent: startTime {}, stopTime {:?}, time {}",
            d.start_time, d.stop_time, d.time
        ));
    }
    let v = &d.values;
    if v.record_file.len() > MAX_PATH_BYTES {
        return Err("the saved recordFile is longer than a path".into());
    }
    if SolverKind::from_code(v.solver).is_none() {
        return Err(format!("solver {} of the saved state is unknown", v.solver));
    }
    for (name, x) in [
        ("recordScale", v.record_scale),
        ("maxStep", v.max_step),
        ("frictionEps", v.friction_eps),
    ] {
        check_scalar(name, x).map_err(|e| format!("saved parameter {e}"))?;
    }
    if ![d.ag, d.fext, d.der_ag, d.der_fext]
        .iter()
        .all(|x| x.is_finite())
    {
        return Err("a saved input is not finite".into());
    }
    let Some(sim) = &d.sim else {
        if d.phase == Phase::StepComplete {
            return Err("a saved state ready to step has no simulator".into());
        }
        // Before initialization each value was checked as it was set; the
        // cross-field rules wait for fmi2ExitInitializationMode.
        let p = &v.params;
        if p.n_blocks > MAX_BLOCKS {
            return Err(format!(
                "nBlocks {} of the saved state is above 8",
                p.n_blocks
            ));
        }
        let scalars = [("mp", p.mp), ("Tp", p.tp), ("zeta", p.zeta), ("g", p.g)];
        for (name, x) in scalars.into_iter().chain(
            (0..MAX_BLOCKS)
                .flat_map(|j| [("alpha", p.alpha[j]), ("mus", p.mus[j]), ("muk", p.muk[j])]),
        ) {
            check_scalar(name, x).map_err(|e| format!("saved parameter {e}"))?;
        }
        return Ok(());
    };
    let fresh = v.build().map_err(|e| format!("saved parameter {e}"))?;
    let same_solver = match (sim, &fresh) {
        (Solver::Exact(a), Solver::Exact(b)) => a.settings() == b.settings(),
        (Solver::Regularized(a), Solver::Regularized(b)) => {
            a.eps().to_bits() == b.eps().to_bits() && a.step().to_bits() == b.step().to_bits()
        }
        _ => false,
    };
    if !same_solver {
        return Err("the saved simulator is not the one its saved parameters build".into());
    }
    if (d.start_time + sim.time() - d.time).abs() > tol {
        return Err(format!(
            "the saved simulator's time {} does not match the saved time {}",
            sim.time(),
            d.time - d.start_time
        ));
    }
    if let Some(message) = crate::limits::non_finite_message(&sim.outputs(), d.start_time) {
        return Err(format!("saved state: {message}"));
    }
    Ok(())
}
