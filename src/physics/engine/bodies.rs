//! The exact step of the clusters above the structure's, and moving every
//! body with its cluster: the default's (`exact_events`, `sweep`), also
//! used by the step-end baseline (`crate::baselines::step_end`).

use super::*;

const SIXTH: f64 = 1.0 / 6.0;

/// A cluster above the structure's over a step of length `h` from velocity `v`: its absolute
/// acceleration `accel` is constant in the mode, so with `ag` linear (`ag0`, `ag_rate`) its
/// velocity is a quadratic. Returns (displacement increment, end velocity).
#[inline(always)]
pub(crate) fn upper_cluster_motion(v: f64, accel: f64, ag0: f64, ag_rate: f64, h: f64) -> [f64; 2] {
    let rel = accel - ag0;
    let v_end = v + h * rel - 0.5 * h * h * ag_rate;
    let du = h * (v + h * (0.5 * rel - h * ag_rate * SIXTH));
    [du, v_end]
}

/// [`upper_cluster_motion`] and its input work, by Simpson's rule (exact for the work's cubic).
/// Returns (displacement increment, end velocity, input work).
#[inline]
pub(crate) fn upper_cluster_step(
    v: f64,
    accel: f64,
    mass: f64,
    ag0: f64,
    ag_rate: f64,
    h: f64,
) -> [f64; 3] {
    let [du, v_end] = upper_cluster_motion(v, accel, ag0, ag_rate, h);
    let vm = v + 0.5 * h * (accel - ag0) - 0.125 * h * h * ag_rate;
    let (agm, ag1) = (ag0 + 0.5 * h * ag_rate, ag0 + h * ag_rate);
    let work = -mass * h * SIXTH * (ag0 * v + 4.0 * agm * vm + ag1 * v_end);
    [du, v_end, work]
}

/// Friction's work (the default's) as `force` moves through `slip`: never negative (a slip
/// that stops where it ends can come out a few ulps back).
pub(crate) fn friction_work(force: f64, slip: f64) -> f64 {
    (-force * slip).max(0.0)
}

/// Moves every body with its cluster: the structure to `u0`, the other
/// bodies of its cluster by keeping their offset from it (so a body stuck
/// at zero slip stays at exactly zero slip), those of the other clusters by
/// their cluster's displacement increment `du[c]`; velocities to `v[c]`.
pub(crate) fn move_bodies(
    u: &mut [f64; MAX_BODIES],
    v: &mut [f64; MAX_BODIES],
    d: &Dynamics,
    n: usize,
    u0: f64,
    du: &[f64; MAX_BODIES],
    v_cluster: &[f64; MAX_BODIES],
) {
    let u0_before = u[0];
    u[0] = u0;
    v[0] = v_cluster[0];
    // (Zipped: no bounds check per body.)
    let bodies = u[1..=n].iter_mut().zip(&mut v[1..=n]);
    for ((ui, vi), &c) in bodies.zip(&d.cluster_of[1..=n]) {
        *ui = if c == 0 {
            u0 + (*ui - u0_before)
        } else {
            *ui + du[c]
        };
        *vi = v_cluster[c];
    }
}
