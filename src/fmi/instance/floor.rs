//! StackOnFloor over the engine: the scene of a stack on a prescribed
//! support (the engine's [`Support::Prescribed`]: block j's mass is
//! `alpha[j-1] * mp`, so the FMU sets `mp = 1 kg` and `alpha[j-1] = m[j]`),
//! and the derivatives of its outputs with respect to its inputs
//! (fmi2GetDirectionalDerivative).
//!
//! The rest is the storey's rules, which the engine's make hold for a
//! support too ([`crate::fmi::ports`]): the inputs taken and the outputs as
//! the next step starts ([`crate::fmi::ports::take_inputs`],
//! [`crate::fmi::ports::at_step_start`]), and their time derivatives
//! ([`crate::fmi::ports::derivatives`]).

use crate::fmi::variables::Id;
use crate::physics::engine::Outputs;
use crate::physics::params::{ParamError, Params, Support, MAX_BLOCKS};

/// The default scene: 2 blocks of [`crate::fmi::variables::FLOOR_DEFAULT_MASS`],
/// the storey's default friction.
pub fn default_params() -> Params {
    Params {
        mp: 1.0,
        alpha: [crate::fmi::variables::FLOOR_DEFAULT_MASS; MAX_BLOCKS],
        support: Support::Prescribed,
        ..Params::default()
    }
}

/// Whether a scene is a stack on a prescribed support.
pub fn is_prescribed(p: &Params) -> bool {
    p.support == Support::Prescribed
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
    for (mj, alpha) in m.iter_mut().zip(&p.alpha).take(p.n_blocks) {
        *mj = alpha * p.mp;
    }
    m
}

/// The number of blocks stuck to the support: interfaces 1..=top stuck.
pub fn attached_top(o: &Outputs, n: usize) -> usize {
    o.stuck[..n].iter().take_while(|&&s| s).count()
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
        Id::FloorForce => -o.attached_mass,
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
