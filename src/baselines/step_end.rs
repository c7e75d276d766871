//! The paper's method (`solver = 2`,
//! [`Method::StepEnd`](crate::physics::params::Method::StepEnd)): RK4 of the
//! structure's cluster, the clusters above it on their exact Taylor step,
//! and modes switched only at step ends. A baseline: the exact default
//! never enters it; the stepping loop calls [`Simulator::step_switch_at_end`]
//! for `Method::StepEnd` only.
//!
//! It reaches into the engine through what the engine exposes `pub(crate)`
//! for it: the fields `sys`, `t`, `u`, `v`, `dynamics`, `e_input`,
//! `e_viscous`, `e_friction`, `peak_u0`, `peak_slip`, `peak_a0`, `stats`;
//! the methods `Simulator::violated_now`, `join_velocities`,
//! `against_contact` and `resolve_mode`; and the default's `move_bodies`
//! and `upper_cluster_step`.

use crate::physics::engine::{move_bodies, upper_cluster_step, Excitation, Simulator};
use crate::physics::hermite;
use crate::physics::mode::{self, Dynamics};
use crate::physics::params::MAX_BODIES;
use crate::physics::system::System;

/// The structure's cluster during a step: displacement, velocity, and the
/// input and viscous work done on it since the step start.
type Structure = [f64; 4];

/// RK4 of the structure's cluster in one mode under one excitation piece:
/// (u0, v0) plus the input and viscous work, as one short vector.
#[derive(Clone, Copy, Debug)]
struct StructureRk4 {
    k: f64,
    c: f64,
    mass0: f64,
    inv_mass0: f64,
    ag_gain: f64,
    slip_load0: f64,
    /// A prescribed support's constant acceleration `c` and its flag
    /// ([`Dynamics::load_accel0`]).
    load_accel0: f64,
    prescribed: bool,
    exc: Excitation,
    t_ref: f64,
}

impl StructureRk4 {
    fn new(sys: &System, d: &Dynamics, exc: &Excitation, t_ref: f64) -> StructureRk4 {
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
    fn inputs(&self, t: f64) -> (f64, f64) {
        self.exc.at(t - self.t_ref)
    }

    /// Absolute acceleration of the structure's cluster at a state (the
    /// rule of [`Dynamics::input_accel`] and [`Dynamics::accel0`]: `g ag +
    /// c` on a prescribed support, where every other term is 0).
    #[inline]
    fn accel(&self, ag: f64, fext: f64, u0: f64, v0: f64) -> f64 {
        if self.prescribed {
            return mode::support_accel(self.ag_gain, self.load_accel0, ag);
        }
        (self.slip_load0 + fext - self.k * u0 - self.c * v0) * self.inv_mass0 + ag * self.ag_gain
    }

    /// Absolute acceleration of the structure and its time derivative at `t`
    /// (the rate by [`Dynamics::accel0_rate`]).
    #[inline]
    fn accel_and_jerk(&self, sim: &Simulator, t: f64) -> (f64, f64) {
        let (u0, v0) = (sim.u[0], sim.v[0]);
        let (ag, fext) = self.inputs(t);
        let a = self.accel(ag, fext, u0, v0);
        let rates = [self.exc.ag_rate, self.exc.fext_rate];
        (a, sim.dynamics.accel0_rate(&sim.sys, [v0, a, ag], rates))
    }

    /// Rates of (u0, v0, input work, viscous work).
    #[inline]
    fn rates(&self, t: f64, u0: f64, v0: f64) -> Structure {
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
    fn step(&self, t0: f64, u: f64, v: f64, tau: f64) -> Structure {
        let k1 = self.rates(t0, u, v);
        let k2 = self.rates(t0 + 0.5 * tau, u + 0.5 * tau * k1[0], v + 0.5 * tau * k1[1]);
        let k3 = self.rates(t0 + 0.5 * tau, u + 0.5 * tau * k2[0], v + 0.5 * tau * k2[1]);
        let k4 = self.rates(t0 + tau, u + tau * k3[0], v + tau * k3[1]);
        let w = tau / 6.0;
        let sum = |i: usize| w * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
        [u + sum(0), v + sum(1), sum(2), sum(3)]
    }
}

impl Simulator {
    /// One internal step to `t1` switching modes only at its end (baseline).
    pub(crate) fn step_switch_at_end(&mut self, t1: f64, exc: &Excitation, t_ref: f64) {
        let h = t1 - self.t;
        let rk = StructureRk4::new(&self.sys, &self.dynamics, exc, t_ref);
        let x1 = rk.step(self.t, self.u[0], self.v[0], h);
        self.accept(&x1, h, exc, t_ref);
        self.t = t1;
        self.switch_at_end(exc, t_ref);
    }

    /// Every violated guard switches at the step's end, as in the default
    /// (`Simulator::fire_violated`), but a join moves the bodies by the
    /// step's overshoot: a slip next to it that this turns against its
    /// direction is joined too.
    fn switch_at_end(&mut self, exc: &Excitation, t_ref: f64) {
        let all = self.sys.interfaces();
        let (mut slip_zeroed, must_break) = self.violated_now(exc, t_ref, all, 0);
        let mut joined = 0;
        while slip_zeroed != joined {
            self.join_velocities(slip_zeroed);
            joined = slip_zeroed;
            slip_zeroed |= self.against_contact();
        }
        if slip_zeroed | must_break != 0 {
            self.resolve_mode(must_break, slip_zeroed);
        }
    }

    /// Takes the step of length `h` that ends with the structure's cluster at
    /// `x1`: moves every body with its cluster, adds the work terms, and raises
    /// the peaks to the largest value of the cubic between the step ends.
    fn accept(&mut self, x1: &Structure, h: f64, exc: &Excitation, t_ref: f64) {
        let n = self.sys.n;
        let (mut du, mut v_end) = ([0.0; MAX_BODIES], [0.0; MAX_BODIES]);
        du[0] = x1[0] - self.u[0];
        v_end[0] = x1[1];
        // Clusters above the structure's: exact polynomials in time (what RK4
        // gives them), and Simpson's rule, exact, for their input work.
        let mut upper_work = 0.0;
        let d = &self.dynamics;
        let ag0 = exc.at(self.t - t_ref).0;
        for c in 1..d.n_clusters {
            let v = self.v[d.bottom[c]];
            let [dc, vc, work] =
                upper_cluster_step(v, d.accel_const[c], d.mass[c], ag0, exc.ag_rate, h);
            (du[c], v_end[c]) = (dc, vc);
            upper_work += work;
        }
        let rk = StructureRk4::new(&self.sys, d, exc, t_ref);
        let (a0_start, jerk_start) = rk.accel_and_jerk(self, self.t);
        let (u0_start, v0_start) = (self.u[0], self.v[0]);
        let d = &self.dynamics;
        for j in 1..=n {
            let (hi, lo) = (d.cluster_of[j], d.cluster_of[j - 1]);
            if hi != lo {
                let slip0 = self.u[j] - self.u[j - 1];
                let increment = du[hi] - du[lo];
                let (vrel0, vrel1) = (self.v[j] - self.v[j - 1], v_end[hi] - v_end[lo]);
                self.e_friction[j] -= d.slip_force[j] * increment;
                let peak = &mut self.peak_slip[j];
                hermite::raise_peak(peak, slip0, vrel0, slip0 + increment, vrel1, h);
            }
        }
        move_bodies(&mut self.u, &mut self.v, d, n, x1[0], &du, &v_end);
        self.e_input += x1[2] + upper_work;
        self.e_viscous += x1[3];
        self.t += h;
        self.stats.steps += 1;

        let (a0_end, jerk_end) = rk.accel_and_jerk(self, self.t);
        hermite::raise_peak(&mut self.peak_u0, u0_start, v0_start, x1[0], x1[1], h);
        hermite::raise_peak(&mut self.peak_a0, a0_start, jerk_start, a0_end, jerk_end, h);
    }
}
