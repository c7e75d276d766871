//! StackOnFloor over the engine: the scene of a stack on a prescribed
//! support (the engine's [`Support::Prescribed`]: block j's mass is
//! `alpha[j-1] * mp`, so the FMU sets `mp = 1 kg` and `alpha[j-1] = m[j]`),
//! the support's mobility, the outputs only this model has, and their
//! derivatives: with respect to time (fmi2GetRealOutputDerivatives) and to
//! the inputs (fmi2GetDirectionalDerivative).
//!
//! In a mode, the cluster stuck to the support (blocks 1..=top, interfaces
//! 1..=top stuck) moves with it: its absolute acceleration is `ag`; every
//! other cluster has a constant absolute acceleration. So, with `ag` linear
//! over a step, every output's derivative follows from the outputs, the
//! masses and `ag`, `der(ag)` (docs/coupling-ports.md).

use crate::fmi::ports::SWITCH_LOOKAHEAD;
use crate::fmi::variables::Id;
use crate::physics::engine::{Excitation, Outputs, SimError, Simulator};
use crate::physics::params::{ParamError, Params, MAX_BLOCKS};
use crate::physics::solver::{Solver, Stepper};

/// The default scene: 2 blocks of [`crate::fmi::variables::FLOOR_DEFAULT_MASS`],
/// the storey's default friction.
pub fn default_params() -> Params {
    let mut p = Params {
        mp: 1.0,
        alpha: [crate::fmi::variables::FLOOR_DEFAULT_MASS; MAX_BLOCKS],
        ..Params::default()
    };
    make_prescribed(&mut p);
    p
}

/// Marks a scene as a stack on a prescribed support.
fn make_prescribed(p: &mut Params) {
    // PRE-MERGE: p.support = Support::Prescribed once the engine has it.
    let _ = p;
}

/// Whether a scene is a stack on a prescribed support.
pub fn is_prescribed(p: &Params) -> bool {
    // PRE-MERGE: p.support == Support::Prescribed.
    p.mp == 1.0
}

/// An error of the engine's checks as the FMU names it: StackOnFloor's
/// `alpha[j]` is its `m[j]` (kg).
pub fn public_error(p: &Params, e: ParamError) -> ParamError {
    match e.field.strip_prefix("alpha[") {
        Some(rest) if is_prescribed(p) => ParamError {
            field: format!("m[{rest}"),
            allowed: format!("{} (kg)", e.allowed),
            ..e
        },
        _ => e,
    }
}

/// The block masses of a StackOnFloor scene (kg), index j - 1.
pub fn masses(p: &Params) -> [f64; MAX_BLOCKS] {
    let mut m = [0.0; MAX_BLOCKS];
    for j in 0..p.n_blocks {
        m[j] = p.alpha[j] * p.mp;
    }
    m
}

/// The number of blocks stuck to the support: interfaces 1..=top stuck.
pub fn attached_top(o: &Outputs, n: usize) -> usize {
    o.stuck[..n].iter().take_while(|&&s| s).count()
}

/// `floorForce`, `attachedMass` and `slidingForce` of the outputs `o` of a
/// StackOnFloor scene `p` under support acceleration `ag`.
pub fn port_outputs(o: &Outputs, p: &Params, ag: f64) -> [f64; 3] {
    // PRE-MERGE: o.floor_force, o.attached_mass, o.sliding_force.
    let m = masses(p);
    let top = attached_top(o, p.n_blocks);
    let attached: f64 = m[..top].iter().sum();
    let floor_force = if p.n_blocks == 0 { 0.0 } else { -o.force[0] };
    [floor_force, attached, floor_force + attached * ag]
}

/// Derivative of output `unknown` with respect to input `known` in the
/// current mode (the mode the next step starts in): `Ok(None)` if `unknown`
/// is not a Real output or `known` not an input of the model.
///
/// - d floorForce / d ag = -attachedMass (the attached cluster moves with
///   the support: `floorForce = slidingForce - attachedMass ag`);
/// - d abAbs[j] / d ag = 1 for a block of the attached cluster, else 0;
/// - d F[j] / d ag = mass of blocks j..=top for an interface j of the
///   attached cluster (`F_j = M_{j..top} ag + F_{top+1}`), else 0;
/// - slidingForce, attachedMass and every state output: 0;
/// - any output with respect to `supportMobility`: 0 (it only enters the
///   choice of the mode at a switch).
pub fn directional(o: &Outputs, p: &Params, unknown: Id, known: Id) -> Option<f64> {
    let top = attached_top(o, p.n_blocks);
    let m = masses(p);
    let block_of_attached = |j: usize| j <= top && j <= p.n_blocks;
    match known {
        Id::SupportMobility => return Some(0.0),
        Id::Ag => {}
        _ => return None,
    }
    Some(match unknown {
        Id::FloorForce => -port_outputs(o, p, 0.0)[1],
        Id::AbAbs(j) => {
            if block_of_attached(j) {
                1.0
            } else {
                0.0
            }
        }
        Id::F(j) => {
            if block_of_attached(j) {
                // Summed downwards from the top, as the engine adds the
                // mass above a stuck interface.
                m[j - 1..top].iter().rev().sum()
            } else {
                0.0
            }
        }
        Id::AttachedMass
        | Id::SlidingForce
        | Id::Ub(_)
        | Id::Vb(_)
        | Id::Slip(_)
        | Id::PeakSlip(_)
        | Id::Einput
        | Id::Ekinetic
        | Id::Efriction
        | Id::TSwitch => 0.0,
        _ => return None,
    })
}

/// Gives the simulator the support's mobility (1/kg) it resolves modes with.
pub fn set_mobility(sim: &mut Solver, mobility: f64) -> Result<(), ParamError> {
    match sim {
        Solver::Exact(s) => set_exact_mobility(s, mobility),
        // StackOnFloor builds the exact engine only.
        Solver::Regularized(_) => Ok(()),
    }
}

fn set_exact_mobility(sim: &mut Simulator, mobility: f64) -> Result<(), ParamError> {
    // PRE-MERGE: sim.set_support_mobility(mobility)
    let _ = (sim, mobility);
    Ok(())
}

/// Applies the inputs set for the next step at the current instant: the
/// support's mobility, and `ag` (a jump of it can break a stick of the
/// cluster attached to the support). The engine acts on a jump only: with
/// `ag` unchanged this changes nothing.
pub fn take_inputs(sim: &mut Solver, exc: &Excitation, mobility: f64) -> Result<(), SimError> {
    set_mobility(sim, mobility).map_err(|e| SimError::BadInput {
        name: "supportMobility",
        value: e.value,
    })?;
    let now = sim.time();
    sim.advance(now, exc)
}

/// The solver as the next step starts (as [`crate::fmi::ports::at_step_start`]
/// for the storey): the inputs set for it taken at the current instant, and a
/// switch that the next step takes at its very start taken (looked for
/// [`SWITCH_LOOKAHEAD`] ahead).
pub fn at_step_start(sim: &Solver, exc: &Excitation, mobility: f64) -> Result<Solver, SimError> {
    let mut next = sim.clone();
    take_inputs(&mut next, exc, mobility)?;
    let mut ahead = next.clone();
    ahead.watch_switches();
    ahead.advance(next.time() + SWITCH_LOOKAHEAD, exc)?;
    Ok(if ahead.first_switch().is_nan() {
        next
    } else {
        ahead
    })
}
