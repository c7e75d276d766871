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
use crate::physics::engine::{Excitation, Outputs, SimError};
use crate::physics::params::{ParamError, Params, Support, MAX_BLOCKS};
use crate::physics::solver::{Solver, Stepper};

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

/// Applies the inputs set for the next step at the current instant: the
/// support's mobility, and `ag` (a jump of it can break a stick of the
/// cluster attached to the support). The engine acts on a jump only: with
/// `ag` unchanged this changes nothing.
pub fn take_inputs(sim: &mut Solver, exc: &Excitation, mobility: f64) -> Result<(), SimError> {
    sim.set_support_mobility(mobility)
        .map_err(|e| SimError::BadInput {
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

/// First and second time derivatives of every continuous output of a
/// StackOnFloor in the state `o` (from [`at_step_start`]: the mode the next
/// step starts in) under the excitation `exc` of that step (`ag` now and its
/// slope). The attached cluster moves with the support (absolute
/// acceleration `ag`, derivative `der(ag)`); every other cluster has a
/// constant absolute acceleration; `ag` is linear over a step. Entries that
/// are not derivatives of continuous outputs are left at 0.
pub fn derivatives(o: &Outputs, p: &Params, exc: &Excitation) -> [Outputs; 2] {
    let n = p.n_blocks;
    let m = masses(p);
    let top = attached_top(o, n);
    let (ag, ag1) = (exc.ag, exc.ag_rate);
    // Body i = 0 (the support) ..= n: velocity relative to the support,
    // absolute acceleration and its derivative.
    let velocity = |i: usize| if i == 0 { 0.0 } else { o.vb[i - 1] };
    let accel = |i: usize| match i {
        0 => [ag, ag1],
        i if i <= top => [o.ab_abs[i - 1], ag1],
        i => [o.ab_abs[i - 1], 0.0],
    };
    let (mut d1, mut d2) = (Outputs::default(), Outputs::default());
    // A running peak is taken in continuous time between steps, to the
    // engine's accuracy (as ports::derivatives).
    const ROUNDING: f64 = 1e-9;
    let (mut p0, mut p1, mut ek1, mut ek2) = (0.0, 0.0, 0.0, 0.0);
    for j in 1..=n {
        let b = j - 1;
        let (a, below) = (accel(j), accel(j - 1));
        let (v, rel, rel1) = (velocity(j), a[0] - ag, a[1] - ag1);
        let (v_rel, a_rel) = (v - velocity(j - 1), a[0] - below[0]);
        [d1.ub[b], d2.ub[b]] = [v, rel];
        [d1.vb[b], d2.vb[b]] = [rel, rel1];
        [d1.slip[b], d2.slip[b]] = [v_rel, a_rel];
        [d1.ab_abs[b], d2.ab_abs[b]] = [a[1], 0.0];
        // A stuck interface of the attached cluster carries M_{j..top} ag
        // plus a constant; any other a constant.
        let mass_above: f64 = if j <= top {
            m[b..top].iter().rev().sum()
        } else {
            0.0
        };
        d1.force[b] = mass_above * ag1;
        let f = o.force[b];
        d1.e_friction_of[b] = -f * v_rel;
        d2.e_friction_of[b] = -(d1.force[b] * v_rel + f * a_rel);
        let body = |i: usize| if i == 0 { 0.0 } else { o.ub[i - 1] };
        let slack = ROUNDING * (o.peak_slip[b] + body(j).abs() + body(j - 1).abs());
        [d1.peak_slip[b], d2.peak_slip[b]] =
            crate::fmi::ports::running_peak(o.peak_slip[b], o.slip[b], v_rel, a_rel, slack);
        p0 += m[b] * v;
        p1 += m[b] * rel;
        ek1 += m[b] * v * rel;
        ek2 += m[b] * (rel * rel + v * rel1);
    }
    [d1.e_kinetic, d2.e_kinetic] = [ek1, ek2];
    // Input energy in relative coordinates: -integral(sum m_j ag v_j dt).
    d1.e_input = -ag * p0;
    d2.e_input = -ag1 * p0 - ag * p1;
    d1.e_friction = d1.e_friction_of.iter().sum();
    d2.e_friction = d2.e_friction_of.iter().sum();
    // floorForce = slidingForce - attachedMass ag.
    d1.floor_force = -o.attached_mass * ag1;
    [d1, d2]
}
