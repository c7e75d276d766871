//! StackOnFloor over the engine: the scene of a stack on a prescribed
//! support (the engine's [`Support::Prescribed`]: block j's mass is
//! `alpha[j-1] * mp`, so the FMU sets `mp = 1 kg` and `alpha[j-1] = m[j]`),
//! and the public names of its parameters.
//!
//! The rest is the storey's rules, which the engine's make hold for a
//! support too ([`crate::fmi::ports`]): the inputs taken and the outputs as
//! the next step starts ([`crate::fmi::ports::take_inputs`],
//! [`crate::fmi::ports::at_step_start`]), and their time derivatives
//! ([`crate::fmi::ports::derivatives`]), and their derivatives with respect
//! to the inputs ([`crate::fmi::ports::directional`]).

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
