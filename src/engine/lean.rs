//! The event-free fast path of the event-located method.
//!
//! Most internal steps switch nothing. For them the general step (a
//! `Segment`, guard bracketing, a per-body update) is mostly bookkeeping, so
//! a run of such steps is taken here with the mode's constants hoisted out of
//! the loop and the state in local variables: per cluster one displacement
//! increment and one velocity, per slipping interface its slip, friction work
//! and peak. The same RK4 step, closed-form upper clusters, guards and
//! Hermite peaks as the general path are used; the loop stops before the
//! first step at whose end a guard of the mode is negative, and the caller
//! takes that step with event location. The loop goes on from one piece of
//! excitation to the next (a record's samples), so that a whole record costs
//! one entry when nothing switches.

use super::{upper_cluster_step, Excitation, Piece, Simulator, StructureRk4};
use crate::hermite;
use crate::mode::Guard;
use crate::params::MAX_BODIES;

impl Simulator {
    /// Takes the substeps of `piece` from `piece.i` on, then those of the
    /// following `pieces`, until a substep would end with a guard below
    /// zero: `piece` is then the piece it belongs to, `piece.i` its index.
    /// Otherwise `piece` is the last piece taken, finished; a next piece
    /// that the general path must begin (a jump of the external force, or a
    /// bad value) is returned untouched.
    pub(super) fn lean_steps(
        &mut self,
        piece: &mut Piece,
        pieces: &mut impl Iterator<Item = (f64, Excitation)>,
    ) -> Option<(f64, Excitation)> {
        let (sys, d, h_max) = (&self.sys, &self.dynamics, self.h_max);
        let mut rk = StructureRk4::new(sys, d, &piece.exc, piece.t_ref);
        let nc = d.n_clusters;

        let guards = &d.guards[..d.n_guards];
        let moving = &d.moving[..d.n_moving];

        // Local state: per cluster the displacement since entry and the
        // velocity; the structure's own displacement; work and peaks.
        let mut shift = [0.0; MAX_BODIES];
        let mut vel = [0.0; MAX_BODIES];
        for c in 0..nc {
            vel[c] = self.v[d.bottom[c]];
        }
        let mut slip = [0.0; MAX_BODIES];
        for mv in moving {
            slip[mv.j] = self.u[mv.j] - self.u[mv.j - 1];
        }
        let (mut u0, mut t0) = (self.u[0], self.t);
        let (mut e_input, mut e_viscous) = (0.0, 0.0);
        let mut e_friction = [0.0; MAX_BODIES];
        let (mut peak_u0, mut peak_a0) = (self.peak_u0, self.peak_a0);
        let mut peak_slip = self.peak_slip;
        let (mut a0, mut jerk0) = rk.accel_and_jerk(t0, u0, vel[0]);

        // Per cluster over the current step: displacement increment, end
        // velocity, input work (reused from step to step).
        let mut step = [[0.0; 3]; MAX_BODIES];
        let mut taken = 0u64;
        let mut pending = None;
        'steps: loop {
            if piece.i > piece.n {
                let Some((t_end, exc)) = pieces.next() else {
                    break;
                };
                let p = &piece.exc;
                let fext_end = p.fext + p.fext_rate * (piece.t_end - piece.t_ref);
                if exc.fext != fext_end || exc.check(t0, t_end).is_err() {
                    pending = Some((t_end, exc));
                    break;
                }
                *piece = Piece::new(t0, t_end, &exc, h_max);
                rk = StructureRk4::new(sys, d, &piece.exc, piece.t_ref);
                // The acceleration's slope jumps with the excitation's.
                (a0, jerk0) = rk.accel_and_jerk(t0, u0, vel[0]);
                continue;
            }
            let exc = &piece.exc;
            let t1 = piece.end_of(piece.i);
            let hs = t1 - t0;
            let x1 = rk.step(t0, u0, vel[0], hs);
            let (a1, jerk1) = rk.accel_and_jerk(t1, x1[0], x1[1]);
            let ag0 = exc.ag + exc.ag_rate * (t0 - piece.t_ref);
            step[0] = [x1[0] - u0, x1[1], x1[2]];
            for c in 1..nc {
                step[c] =
                    upper_cluster_step(vel[c], d.accel_const[c], d.mass[c], ag0, exc.ag_rate, hs);
            }
            for g in guards {
                let value = match *g {
                    Guard::Stuck {
                        mass_above,
                        f_top,
                        cap,
                    } => cap - (mass_above * a1 + f_top).abs(),
                    Guard::Slip { hi, lo, sign } => sign * (step[hi][1] - step[lo][1]),
                };
                if value < 0.0 {
                    break 'steps;
                }
            }
            // No switch in this step: take it.
            for mv in moving {
                let increment = step[mv.hi][0] - step[mv.lo][0];
                let (vrel0, vrel1) = (vel[mv.hi] - vel[mv.lo], step[mv.hi][1] - step[mv.lo][1]);
                let s0 = slip[mv.j];
                e_friction[mv.j] -= d.slip_force[mv.j] * increment;
                let peak = &mut peak_slip[mv.j];
                *peak = peak.max(hermite::max_abs_above(
                    s0,
                    vrel0,
                    s0 + increment,
                    vrel1,
                    hs,
                    *peak,
                ));
                slip[mv.j] = s0 + increment;
            }
            for c in 1..nc {
                shift[c] += step[c][0];
                vel[c] = step[c][1];
                e_input += step[c][2];
            }
            peak_u0 = peak_u0.max(hermite::max_abs_above(
                u0, vel[0], x1[0], x1[1], hs, peak_u0,
            ));
            peak_a0 = peak_a0.max(hermite::max_abs_above(a0, jerk0, a1, jerk1, hs, peak_a0));
            shift[0] += x1[0] - u0;
            (u0, vel[0], a0, jerk0) = (x1[0], x1[1], a1, jerk1);
            e_input += x1[2];
            e_viscous += x1[3];
            t0 = t1;
            piece.i += 1;
            taken += 1;
        }

        if taken > 0 {
            super::move_bodies(&mut self.u, &mut self.v, d, sys.n, u0, &shift, &vel);
            for mv in moving {
                self.e_friction[mv.j] += e_friction[mv.j];
            }
            self.e_input += e_input;
            self.e_viscous += e_viscous;
            self.peak_u0 = peak_u0;
            self.peak_a0 = peak_a0;
            self.peak_slip = peak_slip;
            self.t = t0;
            self.stats.steps += taken;
        }
        pending
    }
}
