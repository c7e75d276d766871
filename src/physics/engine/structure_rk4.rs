//! RK4 of the structure's cluster, the exact Taylor step of the clusters
//! above it, and moving every body with its cluster.

use super::*;

/// The structure's cluster during a step: displacement, velocity, and the
/// input and viscous work done on it since the step start.
pub(super) type Structure = [f64; 4];

/// RK4 of the structure's cluster in one mode under one excitation piece:
/// (u0, v0) plus the input and viscous work, as one short vector.
#[derive(Clone, Copy, Debug)]
pub(super) struct StructureRk4 {
    pub(super) k: f64,
    pub(super) c: f64,
    pub(super) mass0: f64,
    pub(super) inv_mass0: f64,
    pub(super) ag_gain: f64,
    pub(super) slip_load0: f64,
    /// A prescribed support's constant acceleration `c` and its flag
    /// ([`Dynamics::load_accel0`]).
    pub(super) load_accel0: f64,
    pub(super) prescribed: bool,
    pub(super) exc: Excitation,
    pub(super) t_ref: f64,
}

impl StructureRk4 {
    pub(super) fn new(sys: &System, d: &Dynamics, exc: &Excitation, t_ref: f64) -> StructureRk4 {
        StructureRk4 {
            k: sys.k,
            c: sys.c,
            mass0: d.mass[0],
            inv_mass0: d.inv_mass0,
            ag_gain: d.ag_gain,
            slip_load0: d.slip_load[0],
            load_accel0: d.load_accel0,
            prescribed: d.prescribed,
            exc: *exc,
            t_ref,
        }
    }

    /// (ag, fext) at `t`.
    #[inline]
    pub(super) fn inputs(&self, t: f64) -> (f64, f64) {
        self.exc.at(t - self.t_ref)
    }

    /// Absolute acceleration of the structure's cluster at a state (the
    /// rule of [`Dynamics::input_accel`] and [`Dynamics::accel0`]: `g ag +
    /// c` on a prescribed support, where every other term is 0).
    #[inline]
    pub(super) fn accel(&self, ag: f64, fext: f64, u0: f64, v0: f64) -> f64 {
        if self.prescribed {
            return mode::support_accel(self.ag_gain, self.load_accel0, ag);
        }
        (self.slip_load0 + fext - self.k * u0 - self.c * v0) * self.inv_mass0 + ag * self.ag_gain
    }

    /// Absolute acceleration of the structure and its time derivative at `t`.
    #[inline]
    pub(super) fn accel_and_jerk(&self, t: f64, u0: f64, v0: f64) -> (f64, f64) {
        let (ag, fext) = self.inputs(t);
        let a = self.accel(ag, fext, u0, v0);
        let jerk = (self.exc.fext_rate - self.k * v0 - self.c * (a - ag)) * self.inv_mass0
            + self.exc.ag_rate * self.ag_gain;
        (a, jerk)
    }

    /// Rates of (u0, v0, input work, viscous work).
    #[inline]
    pub(super) fn rates(&self, t: f64, u0: f64, v0: f64) -> Structure {
        let (ag, fext) = self.inputs(t);
        let a = self.accel(ag, fext, u0, v0) - ag;
        // On a prescribed support the work on its cluster beyond friction:
        // the input and the support's drift, (M' (a0 - ag) - s') v0.
        let input = if self.prescribed {
            (self.mass0 * a - self.slip_load0) * v0
        } else {
            (fext - ag * self.mass0) * v0
        };
        [v0, a, input, self.c * v0 * v0]
    }

    /// One RK4 step of length `tau` from (u, v) at `t0`; the work terms are
    /// the increments over the step.
    #[inline]
    pub(super) fn step(&self, t0: f64, u: f64, v: f64, tau: f64) -> Structure {
        let k1 = self.rates(t0, u, v);
        let k2 = self.rates(t0 + 0.5 * tau, u + 0.5 * tau * k1[0], v + 0.5 * tau * k1[1]);
        let k3 = self.rates(t0 + 0.5 * tau, u + 0.5 * tau * k2[0], v + 0.5 * tau * k2[1]);
        let k4 = self.rates(t0 + tau, u + tau * k3[0], v + tau * k3[1]);
        let w = tau / 6.0;
        let sum = |i: usize| w * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
        [u + sum(0), v + sum(1), sum(2), sum(3)]
    }
}

/// A cluster above the structure's over a step of length `h`: its absolute
/// acceleration is constant in the mode, so RK4 gives it exactly its Taylor
/// polynomial, and Simpson's rule, exact for it, its input work. Returns
/// (displacement increment, end velocity, input work) from velocity `v`.
#[inline]
pub(super) fn upper_cluster_step(
    v: f64,
    accel: f64,
    mass: f64,
    ag0: f64,
    ag_rate: f64,
    h: f64,
) -> [f64; 3] {
    let rel = accel - ag0;
    let vm = v + 0.5 * h * rel - 0.125 * h * h * ag_rate;
    let v_end = v + h * rel - 0.5 * h * h * ag_rate;
    const SIXTH: f64 = 1.0 / 6.0;
    let du = h * (v + h * (0.5 * rel - h * ag_rate * SIXTH));
    let (agm, ag1) = (ag0 + 0.5 * h * ag_rate, ag0 + h * ag_rate);
    let work = -mass * h * SIXTH * (ag0 * v + 4.0 * agm * vm + ag1 * v_end);
    [du, v_end, work]
}

/// Moves every body with its cluster: the structure to `u0`, the other
/// bodies of its cluster by keeping their offset from it (so a body stuck
/// at zero slip stays at exactly zero slip), those of the other clusters by
/// their cluster's displacement increment `du[c]`; velocities to `v[c]`.
pub(super) fn move_bodies(
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
    for i in 1..=n {
        let c = d.cluster_of[i];
        u[i] = if c == 0 {
            u0 + (u[i] - u0_before)
        } else {
            u[i] + du[c]
        };
        v[i] = v_cluster[c];
    }
}
