//! The event-free fast path of the event-located method.
//!
//! Most internal steps switch nothing. For them the general step (a
//! `Segment`, guard bracketing, a per-body update) is mostly bookkeeping, so
//! a run of such steps is taken here with the mode's constants hoisted out of
//! the loop and the state in local variables: per cluster one displacement
//! increment and one velocity, per slipping interface its slip and peak. The
//! RK4 step of the structure's cluster is written as the affine map it is
//! for this linear system ([`Rk4Map`]); the upper clusters' motion, the
//! guards and the Hermite peaks are those of the general path, while the
//! upper clusters' input work and the friction work, exact closed forms, are
//! taken once per run of steps under one piece. The loop stops before
//! the first step at whose end a guard of the mode is negative, and the
//! caller takes that step with event location. The loop goes on from one
//! piece of excitation to the next (a record's samples), so that a whole
//! record costs one entry when nothing switches.
//!
//! A mode with every body in the structure's cluster (all interfaces stuck,
//! and always for a bare structure) has a loop of its own: one degree of
//! freedom, and its guards reduce to a band of the structure's acceleration.

use super::rk4_map::{Forced, Inputs, Rk4Map, StepEnd};
use super::{upper_cluster_step, Excitation, Piece, Simulator};
use crate::physics::hermite;
use crate::physics::mode::{Dynamics, Guard};
use crate::physics::params::MAX_BODIES;
use crate::physics::system::System;

/// A relative difference of step lengths above which the affine map is
/// built again; below it the difference is rounding of the piece's end
/// times, and [`Rk4Map::step`] corrects for it to first order.
pub(super) const SAME_STEP: f64 = 1e-9;

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
        // One loop per cluster count, so that the per-cluster arrays are
        // short, fixed and kept in registers.
        match self.dynamics.n_clusters {
            1 => self.lean_steps_one_cluster(piece, pieces),
            2 => self.lean_steps_clusters::<2>(piece, pieces),
            3 => self.lean_steps_clusters::<3>(piece, pieces),
            4 => self.lean_steps_clusters::<4>(piece, pieces),
            5 => self.lean_steps_clusters::<5>(piece, pieces),
            6 => self.lean_steps_clusters::<6>(piece, pieces),
            7 => self.lean_steps_clusters::<7>(piece, pieces),
            8 => self.lean_steps_clusters::<8>(piece, pieces),
            _ => self.lean_steps_clusters::<MAX_BODIES>(piece, pieces),
        }
    }

    /// The fast path for a mode with a single cluster: the structure with
    /// every block stuck on it.
    fn lean_steps_one_cluster(
        &mut self,
        piece: &mut Piece,
        pieces: &mut impl Iterator<Item = (f64, Excitation)>,
    ) -> Option<(f64, Excitation)> {
        let d = &self.dynamics;
        let mut st = Stepping::new(&self.sys, d, piece, self.h_max);
        let guards = &d.guards[..d.n_guards];
        let (band_lo, band_hi) = safe_accel_band(guards);

        let (mut u0, mut v0, mut t0) = (self.u[0], self.v[0], self.t);
        let (mut e_input, mut e_viscous) = (0.0, 0.0);
        let (mut peak_u0, mut peak_a0) = (self.peak_u0, self.peak_a0);
        let (mut inputs, mut a0, mut jerk0) = st.start(piece, t0, u0, v0);
        let mut taken = 0u64;
        let mut pending = None;
        loop {
            if piece.i > piece.n {
                if !st.next_piece(piece, pieces, t0, &mut pending) {
                    break;
                }
                (inputs, a0, jerk0) = st.start(piece, t0, u0, v0);
                continue;
            }
            let (t1, hs) = st.substep(piece, t0);
            let x = st.step(inputs, a0, hs, u0, v0);
            // Inside the band no stick can break; near or outside it the
            // guards decide exactly as on the general path.
            if !(x.accel >= band_lo && x.accel <= band_hi) && any_stuck_guard_fires(guards, x.accel)
            {
                break;
            }
            hermite::raise_peak(&mut peak_u0, u0, v0, x.u, x.v, hs);
            hermite::raise_peak(&mut peak_a0, a0, jerk0, x.accel, x.jerk, hs);
            (u0, v0, a0, jerk0, inputs) = (x.u, x.v, x.accel, x.jerk, x.inputs);
            e_input += x.input;
            e_viscous += x.viscous;
            t0 = t1;
            piece.i += 1;
            taken += 1;
        }

        if taken > 0 {
            let vel = [v0; MAX_BODIES];
            let shift = [0.0; MAX_BODIES]; // used by other clusters only
            super::move_bodies(&mut self.u, &mut self.v, d, self.sys.n, u0, &shift, &vel);
            self.end_run(t0, taken, [e_input, e_viscous], [peak_u0, peak_a0]);
        }
        pending
    }

    /// The fast path for a mode with `NC` >= 2 clusters. Cluster 0 is the
    /// structure's; moving interface m lies between clusters m and m + 1.
    fn lean_steps_clusters<const NC: usize>(
        &mut self,
        piece: &mut Piece,
        pieces: &mut impl Iterator<Item = (f64, Excitation)>,
    ) -> Option<(f64, Excitation)> {
        let d = &self.dynamics;
        debug_assert_eq!(d.n_clusters, NC);
        let mut st = Stepping::new(&self.sys, d, piece, self.h_max);
        let guards = &d.guards[..d.n_guards];
        let (band_lo, band_hi) = safe_accel_band(guards);
        // Per moving interface: its index j, and the sign of its slip (0 for
        // a free interface, which has no guard).
        let iface: [usize; NC] = std::array::from_fn(|m| d.moving[m.min(NC - 2)].j);
        let mut slip_sign = [0.0; NC];
        for g in guards {
            if let Guard::Slip { lo, sign, .. } = *g {
                slip_sign[lo] = sign;
            }
        }

        // Local state: per cluster the displacement since entry and the
        // velocity; per moving interface its slip and peak.
        let mut shift = [0.0; NC];
        let mut vel: [f64; NC] = std::array::from_fn(|c| self.v[d.bottom[c]]);
        let mut slip: [f64; NC] = std::array::from_fn(|m| {
            let j = iface[m];
            self.u[j] - self.u[j - 1]
        });
        let slip_at_entry = slip;
        let mut peak_slip: [f64; NC] = std::array::from_fn(|m| self.peak_slip[iface[m]]);
        let (mut u0, mut t0) = (self.u[0], self.t);
        let (mut e_input, mut e_viscous) = (0.0, 0.0);
        let (mut peak_u0, mut peak_a0) = (self.peak_u0, self.peak_a0);
        let (mut inputs, mut a0, mut jerk0) = st.start(piece, t0, u0, vel[0]);
        let mut upper = UpperClusters::<NC>::new(d, st.map.h, piece.exc.ag_rate);
        // The upper clusters' input work is taken over whole runs of steps
        // under one piece (exact there, as over a step): from this start.
        let mut run_start = (t0, inputs.ag, vel);
        let mut taken = 0u64;
        let mut pending = None;
        'steps: loop {
            if piece.i > piece.n {
                e_input += upper.work(run_start, t0);
                if !st.next_piece(piece, pieces, t0, &mut pending) {
                    run_start.0 = t0;
                    break;
                }
                (inputs, a0, jerk0) = st.start(piece, t0, u0, vel[0]);
                upper = UpperClusters::new(d, st.map.h, piece.exc.ag_rate);
                run_start = (t0, inputs.ag, vel);
                continue;
            }
            let (t1, hs) = st.substep(piece, t0);
            let x = st.step(inputs, a0, hs, u0, vel[0]);
            let ag0 = inputs.ag;
            // Per cluster over the step: displacement increment, end velocity.
            let (mut du, mut v_end) = ([0.0; NC], [0.0; NC]);
            (du[0], v_end[0]) = (x.u - u0, x.v);
            upper.step(&vel, ag0, hs, &mut du, &mut v_end);
            if !(x.accel >= band_lo && x.accel <= band_hi) && any_stuck_guard_fires(guards, x.accel)
            {
                break;
            }
            for m in 0..NC - 1 {
                if slip_sign[m] * (v_end[m + 1] - v_end[m]) < 0.0 {
                    break 'steps;
                }
            }
            // No switch in this step: take it.
            for m in 0..NC - 1 {
                let increment = du[m + 1] - du[m];
                let (vrel0, vrel1) = (vel[m + 1] - vel[m], v_end[m + 1] - v_end[m]);
                let s0 = slip[m];
                let peak = &mut peak_slip[m];
                hermite::raise_peak(peak, s0, vrel0, s0 + increment, vrel1, hs);
                slip[m] = s0 + increment;
            }
            for c in 1..NC {
                shift[c] += du[c];
            }
            hermite::raise_peak(&mut peak_u0, u0, vel[0], x.u, x.v, hs);
            hermite::raise_peak(&mut peak_a0, a0, jerk0, x.accel, x.jerk, hs);
            (u0, vel, a0, jerk0, inputs) = (x.u, v_end, x.accel, x.jerk, x.inputs);
            e_input += x.input;
            e_viscous += x.viscous;
            t0 = t1;
            piece.i += 1;
            taken += 1;
        }

        e_input += upper.work(run_start, t0);
        if taken > 0 {
            let (mut shift_all, mut vel_all) = ([0.0; MAX_BODIES], [0.0; MAX_BODIES]);
            shift_all[..NC].copy_from_slice(&shift);
            vel_all[..NC].copy_from_slice(&vel);
            let n = self.sys.n;
            super::move_bodies(&mut self.u, &mut self.v, d, n, u0, &shift_all, &vel_all);
            for m in 0..NC - 1 {
                // The friction force is constant in the mode: its work is
                // that force times the slip.
                let j = iface[m];
                self.e_friction[j] -= d.slip_force[j] * (slip[m] - slip_at_entry[m]);
                self.peak_slip[j] = peak_slip[m];
            }
            self.end_run(t0, taken, [e_input, e_viscous], [peak_u0, peak_a0]);
        }
        pending
    }

    /// Ends a run of `taken` steps at `t`: adds its input and viscous work,
    /// sets the structure's peaks (|u0|, |A0|).
    pub(super) fn end_run(
        &mut self,
        t: f64,
        taken: u64,
        [input, viscous]: [f64; 2],
        [u0, a0]: [f64; 2],
    ) {
        self.e_input += input;
        self.e_viscous += viscous;
        self.peak_u0 = u0;
        self.peak_a0 = a0;
        self.t = t;
        self.stats.steps += taken;
    }
}

/// The clusters above the structure's over the substeps of one piece: the
/// exact polynomials in time that RK4 gives them ([`upper_cluster_step`]),
/// with the terms that are constant over the piece collected once.
pub(super) struct UpperClusters<const NC: usize> {
    h: f64,
    half_h: f64,
    ag_rate: f64,
    /// Per cluster: absolute acceleration and mass (for steps of other
    /// lengths and the work), and the parts of the velocity change and of
    /// the displacement over a step that are constant over the piece.
    accel: [f64; NC],
    mass: [f64; NC],
    dv: [f64; NC],
    du: [f64; NC],
}

impl<const NC: usize> UpperClusters<NC> {
    pub(super) fn new(d: &Dynamics, h: f64, ag_rate: f64) -> Self {
        let accel: [f64; NC] = std::array::from_fn(|c| d.accel_const[c]);
        let (h2, h3) = (h * h, h * h * h);
        UpperClusters {
            h,
            half_h: 0.5 * h,
            ag_rate,
            accel,
            mass: std::array::from_fn(|c| d.mass[c]),
            dv: accel.map(|a| h * a - 0.5 * h2 * ag_rate),
            du: accel.map(|a| 0.5 * h2 * a - h3 * ag_rate / 6.0),
        }
    }

    /// Clusters 1.. over a substep of length `hs` from velocities `vel`,
    /// where the ground acceleration starts at `ag0`: their displacement
    /// increments and end velocities into `du` and `v_end`.
    #[inline(always)]
    pub(super) fn step(
        &self,
        vel: &[f64; NC],
        ag0: f64,
        hs: f64,
        du: &mut [f64; NC],
        v_end: &mut [f64; NC],
    ) {
        if hs != self.h {
            // A piece's last substep, longer or shorter by rounding.
            for c in 1..NC {
                let [dc, vc, _] =
                    upper_cluster_step(vel[c], self.accel[c], self.mass[c], ag0, self.ag_rate, hs);
                (du[c], v_end[c]) = (dc, vc);
            }
            return;
        }
        let h_ag = self.h * ag0;
        let half_h2_ag = self.half_h * h_ag;
        for c in 1..NC {
            let v = vel[c];
            du[c] = self.h * v - half_h2_ag + self.du[c];
            v_end[c] = v - h_ag + self.dv[c];
        }
    }

    /// Absolute acceleration of cluster `c` (constant in the mode).
    #[inline(always)]
    pub(super) fn accel(&self, c: usize) -> f64 {
        self.accel[c]
    }

    /// Input work on clusters 1.. from `(t, ag, vel)` (a time, the ground
    /// acceleration and the cluster velocities then) to `t_end`, under one
    /// piece: the closed form of `upper_cluster_step`, exact over any
    /// length.
    pub(super) fn work(&self, (t, ag, vel): (f64, f64, [f64; NC]), t_end: f64) -> f64 {
        let length = t_end - t;
        if length <= 0.0 {
            return 0.0;
        }
        (1..NC)
            .map(|c| {
                upper_cluster_step(
                    vel[c],
                    self.accel[c],
                    self.mass[c],
                    ag,
                    self.ag_rate,
                    length,
                )[2]
            })
            .sum()
    }
}

/// Whether a stuck guard among `guards` is negative at a step end where the
/// structure's absolute acceleration is `a1`: `|mass_above a1 + f_top| >
/// cap`, as the general path evaluates it.
fn any_stuck_guard_fires(guards: &[Guard], a1: f64) -> bool {
    guards.iter().any(|g| match *g {
        Guard::Stuck {
            mass_above,
            f_top,
            cap,
        } => cap - (mass_above * a1 + f_top).abs() < 0.0,
        Guard::Slip { .. } => false,
    })
}

/// A band of the structure's absolute acceleration inside which every
/// stuck guard of `guards` is positive by a margin far above rounding: the
/// stick `|mass_above A + f_top| <= cap` solved for A and shrunk by 1e-12
/// of its scale.
pub(super) fn safe_accel_band(guards: &[Guard]) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for g in guards {
        if let Guard::Stuck {
            mass_above,
            f_top,
            cap,
        } = *g
        {
            let margin = 1e-12 * (cap + f_top.abs()) / mass_above;
            lo = lo.max((-cap - f_top) / mass_above + margin);
            hi = hi.min((cap - f_top) / mass_above - margin);
        }
    }
    (lo, hi)
}

/// What the fast path steps with over the current piece: the structure's
/// RK4 step as an affine map, and the piece's constant terms.
struct Stepping<'a> {
    sys: &'a System,
    d: &'a Dynamics,
    h_max: f64,
    map: Rk4Map,
    forced: Forced,
}

impl<'a> Stepping<'a> {
    fn new(sys: &'a System, d: &'a Dynamics, piece: &Piece, h_max: f64) -> Stepping<'a> {
        let map = Rk4Map::new(sys, d, piece.h);
        Stepping {
            sys,
            d,
            h_max,
            forced: map.forced(&piece.exc),
            map,
        }
    }

    /// Moves on from the finished `piece`, at `t0`, to the next of `pieces`.
    /// False when the fast path must stop: no piece left, or one that the
    /// general path must begin (a jump of the external force, which can
    /// break a stick, or a bad value), which is put in `pending`.
    fn next_piece(
        &mut self,
        piece: &mut Piece,
        pieces: &mut impl Iterator<Item = (f64, Excitation)>,
        t0: f64,
        pending: &mut Option<(f64, Excitation)>,
    ) -> bool {
        let Some((t_end, exc)) = pieces.next() else {
            return false;
        };
        let p = &piece.exc;
        let fext_end = p.fext + p.fext_rate * (piece.t_end - piece.t_ref);
        if exc.fext != fext_end || exc.check(t0, t_end).is_err() {
            *pending = Some((t_end, exc));
            return false;
        }
        *piece = Piece::new(t0, t_end, &exc, self.h_max);
        if (piece.h - self.map.h).abs() > SAME_STEP * self.map.h {
            self.map = Rk4Map::new(self.sys, self.d, piece.h);
        }
        self.forced = self.map.forced(&piece.exc);
        true
    }

    /// End time and length of the substep `piece.i` from `t0`: the map's step,
    /// except that the piece's last substep ends exactly at its end.
    #[inline]
    fn substep(&self, piece: &Piece, t0: f64) -> (f64, f64) {
        if piece.i == piece.n {
            (piece.t_end, piece.t_end - t0)
        } else {
            (t0 + self.map.h, self.map.h)
        }
    }

    /// The structure's cluster after a substep of length `hs` from (u, v),
    /// where the inputs are `start` and the absolute acceleration `accel`.
    #[inline(always)]
    fn step(&self, start: Inputs, accel: f64, hs: f64, u: f64, v: f64) -> StepEnd {
        self.map.step(&self.forced, start, accel, hs, u, v)
    }

    /// The inputs at `t0`, and the structure's absolute acceleration and its
    /// rate there.
    fn start(&self, piece: &Piece, t0: f64, u: f64, v: f64) -> (Inputs, f64, f64) {
        let inputs = self.map.inputs(&self.forced, t0 - piece.t_ref);
        let (a, jerk) = self
            .map
            .accel_and_jerk_at(&self.forced, inputs.force, inputs.ag, u, v);
        (inputs, a, jerk)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::mode::{Contact, Mode};
    use crate::physics::params::Params;

    /// A 2-block scene with block 1 sliding forward on the structure, so
    /// that the structure's cluster carries a constant friction load.
    fn sliding_scene() -> (System, Dynamics) {
        let sys = System::new(&Params::default()).unwrap();
        let mut mode = Mode::all_stuck(&sys);
        mode.contact[1] = Contact::SlipForward;
        let d = Dynamics::new(&sys, &mode);
        assert!(d.slip_load[0] != 0.0 && d.n_clusters == 2);
        (sys, d)
    }

    fn close(a: f64, b: f64, scale: f64) -> bool {
        (a - b).abs() <= 1e-13 * scale
    }

    #[test]
    fn upper_clusters_move_as_their_exact_polynomials() {
        // Expected values: `upper_cluster_step`, the closed form the general
        // path uses.
        let (_, d) = sliding_scene();
        let (h, ag_rate, ag0) = (1.25e-3, 75.0, -1.2);
        let upper = UpperClusters::<2>::new(&d, h, ag_rate);
        let mut vel = [0.1, -0.25];
        for hs in [h, h * (1.0 + 1e-12)] {
            let (mut du, mut v_end) = ([0.0; 2], [0.0; 2]);
            upper.step(&vel, ag0, hs, &mut du, &mut v_end);
            let [du1, v1, _] =
                upper_cluster_step(vel[1], d.accel_const[1], d.mass[1], ag0, ag_rate, hs);
            assert!(close(du[1], du1, 1e-3) && close(v_end[1], v1, 1.0));
        }
        // The work over a run of steps equals the sum of the steps' works.
        let start = (0.0, ag0, vel);
        let mut sum = 0.0;
        for k in 0..4 {
            let ag = ag0 + ag_rate * k as f64 * h;
            let [_, v1, w] =
                upper_cluster_step(vel[1], d.accel_const[1], d.mass[1], ag, ag_rate, h);
            sum += w;
            vel[1] = v1;
        }
        let work = upper.work(start, 4.0 * h);
        assert!(close(work, sum, 10.0), "{work} {sum}");
    }

    #[test]
    fn the_stick_band_is_inside_every_stick() {
        // Expected: at the band's edges every stuck guard is still positive,
        // and just beyond them (1e-9 relative) one is negative.
        let sys = System::new(&Params::default()).unwrap();
        let d = Dynamics::new(&sys, &Mode::all_stuck(&sys));
        let guards = &d.guards[..d.n_guards];
        assert_eq!(guards.len(), 2);
        let (lo, hi) = safe_accel_band(guards);
        assert!(lo < 0.0 && hi > 0.0);
        assert!(!any_stuck_guard_fires(guards, lo) && !any_stuck_guard_fires(guards, hi));
        assert!(any_stuck_guard_fires(guards, hi * (1.0 + 1e-9)));
        assert!(any_stuck_guard_fires(guards, lo * (1.0 + 1e-9)));
    }
}
