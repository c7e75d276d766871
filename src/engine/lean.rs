//! The event-free fast path of the event-located method.
//!
//! Most internal steps switch nothing. For them the general step (a
//! `Segment`, guard bracketing, a per-body update) is mostly bookkeeping, so
//! a run of such steps is taken here with the mode's constants hoisted out of
//! the loop and the state in local variables: per cluster one displacement
//! increment and one velocity, per slipping interface its slip, friction work
//! and peak. The RK4 step of the structure's cluster is written as the affine
//! map it is for this linear system ([`Rk4Map`]); the upper clusters, guards
//! and Hermite peaks are those of the general path. The loop stops before
//! the first step at whose end a guard of the mode is negative, and the
//! caller takes that step with event location. The loop goes on from one
//! piece of excitation to the next (a record's samples), so that a whole
//! record costs one entry when nothing switches.
//!
//! A mode with every body in the structure's cluster (all interfaces stuck,
//! and always for a bare structure) has a loop of its own: one degree of
//! freedom, and its guards reduce to a band of the structure's acceleration.

use super::{upper_cluster_step, Excitation, Piece, Simulator};
use crate::hermite;
use crate::mode::{Dynamics, Guard};
use crate::params::MAX_BODIES;
use crate::system::System;

/// A relative difference of step lengths above which the affine map is
/// built again; below it the difference is rounding of the piece's end
/// times, and [`Rk4Map::step`] corrects for it to first order.
const SAME_STEP: f64 = 1e-9;

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
            self.e_input += e_input;
            self.e_viscous += e_viscous;
            self.peak_u0 = peak_u0;
            self.peak_a0 = peak_a0;
            self.t = t0;
            self.stats.steps += taken;
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
        // velocity; per moving interface its slip, friction work and peak.
        let mut shift = [0.0; NC];
        let mut vel: [f64; NC] = std::array::from_fn(|c| self.v[d.bottom[c]]);
        let mut slip: [f64; NC] = std::array::from_fn(|m| {
            let j = iface[m];
            self.u[j] - self.u[j - 1]
        });
        let mut peak_slip: [f64; NC] = std::array::from_fn(|m| self.peak_slip[iface[m]]);
        let mut e_friction = [0.0; NC];
        let (mut u0, mut t0) = (self.u[0], self.t);
        let (mut e_input, mut e_viscous) = (0.0, 0.0);
        let (mut peak_u0, mut peak_a0) = (self.peak_u0, self.peak_a0);
        let (mut inputs, mut a0, mut jerk0) = st.start(piece, t0, u0, vel[0]);
        let mut upper = UpperClusters::<NC>::new(d, st.map.h, piece.exc.ag_rate);
        let mut taken = 0u64;
        let mut pending = None;
        'steps: loop {
            if piece.i > piece.n {
                if !st.next_piece(piece, pieces, t0, &mut pending) {
                    break;
                }
                (inputs, a0, jerk0) = st.start(piece, t0, u0, vel[0]);
                upper = UpperClusters::new(d, st.map.h, piece.exc.ag_rate);
                continue;
            }
            let (t1, hs) = st.substep(piece, t0);
            let x = st.step(inputs, a0, hs, u0, vel[0]);
            let ag0 = inputs.ag;
            // Per cluster over the step: displacement increment, end velocity.
            let (mut du, mut v_end) = ([0.0; NC], [0.0; NC]);
            (du[0], v_end[0]) = (x.u - u0, x.v);
            let upper_work = upper.step(&vel, ag0, hs, &mut du, &mut v_end);
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
                e_friction[m] -= d.slip_force[iface[m]] * increment;
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
            e_input += x.input + upper_work;
            e_viscous += x.viscous;
            t0 = t1;
            piece.i += 1;
            taken += 1;
        }

        if taken > 0 {
            let (mut shift_all, mut vel_all) = ([0.0; MAX_BODIES], [0.0; MAX_BODIES]);
            shift_all[..NC].copy_from_slice(&shift);
            vel_all[..NC].copy_from_slice(&vel);
            let n = self.sys.n;
            super::move_bodies(&mut self.u, &mut self.v, d, n, u0, &shift_all, &vel_all);
            for m in 0..NC - 1 {
                self.e_friction[iface[m]] += e_friction[m];
                self.peak_slip[iface[m]] = peak_slip[m];
            }
            self.e_input += e_input;
            self.e_viscous += e_viscous;
            self.peak_u0 = peak_u0;
            self.peak_a0 = peak_a0;
            self.t = t0;
            self.stats.steps += taken;
        }
        pending
    }
}

/// The clusters above the structure's over the substeps of one piece: the
/// exact polynomials in time that RK4 gives them ([`upper_cluster_step`]),
/// with the terms that are constant over the piece collected once.
struct UpperClusters<const NC: usize> {
    h: f64,
    half_h: f64,
    ag_rate: f64,
    /// Per cluster: absolute acceleration and mass (for a step of another
    /// length), `mass h / 6`, and the constant parts of the velocity
    /// change, the displacement and the mid-step velocity.
    accel: [f64; NC],
    mass: [f64; NC],
    mass_sixth_h: [f64; NC],
    dv: [f64; NC],
    du: [f64; NC],
    vm: [f64; NC],
}

impl<const NC: usize> UpperClusters<NC> {
    fn new(d: &Dynamics, h: f64, ag_rate: f64) -> Self {
        let accel: [f64; NC] = std::array::from_fn(|c| d.accel_const[c]);
        let (h2, h3) = (h * h, h * h * h);
        UpperClusters {
            h,
            half_h: 0.5 * h,
            ag_rate,
            accel,
            mass: std::array::from_fn(|c| d.mass[c]),
            mass_sixth_h: std::array::from_fn(|c| d.mass[c] * h / 6.0),
            dv: accel.map(|a| h * a - 0.5 * h2 * ag_rate),
            du: accel.map(|a| 0.5 * h2 * a - h3 * ag_rate / 6.0),
            vm: accel.map(|a| 0.5 * h * a - 0.125 * h2 * ag_rate),
        }
    }

    /// Clusters 1.. over a substep of length `hs` from velocities `vel`,
    /// where the ground acceleration starts at `ag0`: their displacement
    /// increments and end velocities into `du` and `v_end`; returns their
    /// input work.
    #[inline(always)]
    fn step(
        &self,
        vel: &[f64; NC],
        ag0: f64,
        hs: f64,
        du: &mut [f64; NC],
        v_end: &mut [f64; NC],
    ) -> f64 {
        let mut work = 0.0;
        if hs != self.h {
            // A piece's last substep, longer or shorter by rounding.
            for c in 1..NC {
                let [dc, vc, w] =
                    upper_cluster_step(vel[c], self.accel[c], self.mass[c], ag0, self.ag_rate, hs);
                (du[c], v_end[c]) = (dc, vc);
                work += w;
            }
            return work;
        }
        let h_ag = self.h * ag0;
        let half_h2_ag = self.half_h * h_ag;
        let ag_mid = ag0 + self.half_h * self.ag_rate;
        let ag_end = ag0 + self.h * self.ag_rate;
        for c in 1..NC {
            let v = vel[c];
            let ve = v - h_ag + self.dv[c];
            let vm = v - 0.5 * h_ag + self.vm[c];
            du[c] = self.h * v - half_h2_ag + self.du[c];
            v_end[c] = ve;
            work -= self.mass_sixth_h[c] * (ag0 * v + 4.0 * ag_mid * vm + ag_end * ve);
        }
        work
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
fn safe_accel_band(guards: &[Guard]) -> (f64, f64) {
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

/// The structure's cluster at the end of a fast-path step.
#[derive(Clone, Copy, Debug)]
struct StepEnd {
    u: f64,
    v: f64,
    /// Input and viscous work over the step.
    input: f64,
    viscous: f64,
    /// Absolute acceleration and its time derivative.
    accel: f64,
    jerk: f64,
    /// The inputs at the end (at the step's nominal length).
    inputs: Inputs,
}

/// The input force `fext - m ag` on the structure's cluster (N) and the
/// ground acceleration (m/s^2) at an instant: carried from step to step.
#[derive(Clone, Copy, Debug)]
struct Inputs {
    force: f64,
    ag: f64,
}

/// RK4's step for the structure's cluster as the affine map that it is for
/// this linear ODE under a force linear in time: the stages of
/// `StructureRk4::step` evaluated once per mode and step length on unit
/// inputs, so that a step is a few independent dot products instead of four
/// dependent stage evaluations (same method, same result up to rounding).
/// With `f(τ) = f0 + f1 τ` the cluster's forcing per unit mass (τ from the
/// step start), the end state (u1, v1) and the stage velocities V2, V3, V4
/// are linear in (u, v, f0, f1); the work integrals are RK4's quadrature over
/// the stage velocities.
#[derive(Clone, Copy, Debug)]
struct Rk4Map {
    /// Step length, half and a sixth of it (RK4's weights).
    h: f64,
    half_h: f64,
    sixth_h: f64,
    /// For u1 - u, v1, V2, V3, V4, the outputs of `rk4_stages` in order
    /// (`step` takes V2 from the acceleration at the start instead): the
    /// coefficients of u, v and the input force
    /// `fext - m ag` at the step start.
    rows: [[f64; 3]; 5],
    /// The same outputs' terms from the slipping interfaces' constant load.
    load_terms: [f64; 5],
    /// Their coefficients of `f1`.
    slope_rows: [f64; 5],
    mass: f64,
    inv_mass: f64,
    /// Acceleration of the constant load alone, `slip_load / mass`.
    load_accel: f64,
    /// k / mass and c / mass of the cluster, and c.
    w2: f64,
    cm: f64,
    c: f64,
}

/// The parts of a step that are constant over a piece.
#[derive(Clone, Copy, Debug)]
struct Forced {
    exc: Excitation,
    /// Input force `fext - m ag` at the piece start (N) and its slope (N/s).
    force: f64,
    force_rate: f64,
    /// Its increase over a step, and that of `ag`.
    step_force: f64,
    step_ag: f64,
    /// RK4's weight of the force's slope in the input work: `h^2 / 6` times it.
    input_slope: f64,
    /// Each output's terms from the constant load and the forcing's slope.
    constant_terms: [f64; 5],
    /// `fext_rate / mass`, the forcing's part of the jerk.
    jerk_forced: f64,
}

impl Rk4Map {
    fn new(sys: &System, d: &Dynamics, h: f64) -> Rk4Map {
        let (w2, cm) = (sys.k * d.inv_mass0, sys.c * d.inv_mass0);
        let unit = |i: usize| {
            let e = |j: usize| if i == j { 1.0 } else { 0.0 };
            rk4_stages(w2, cm, h, [e(0), e(1), e(2), e(3)])
        };
        let columns = [unit(0), unit(1), unit(2), unit(3)];
        let load_accel = d.slip_load[0] * d.inv_mass0;
        Rk4Map {
            h,
            half_h: 0.5 * h,
            sixth_h: h / 6.0,
            rows: std::array::from_fn(|r| {
                [columns[0][r], columns[1][r], columns[2][r] * d.inv_mass0]
            }),
            load_terms: columns[2].map(|f0_coefficient| f0_coefficient * load_accel),
            slope_rows: columns[3],
            mass: d.mass[0],
            inv_mass: d.inv_mass0,
            load_accel,
            w2,
            cm,
            c: sys.c,
        }
    }

    #[inline]
    fn forced(&self, exc: &Excitation) -> Forced {
        let force_rate = exc.fext_rate - self.mass * exc.ag_rate;
        let f1 = force_rate * self.inv_mass;
        Forced {
            exc: *exc,
            force: exc.fext - self.mass * exc.ag,
            force_rate,
            step_force: self.h * force_rate,
            step_ag: self.h * exc.ag_rate,
            input_slope: self.sixth_h * self.h * force_rate,
            constant_terms: std::array::from_fn(|r| self.load_terms[r] + self.slope_rows[r] * f1),
            jerk_forced: exc.fext_rate * self.inv_mass,
        }
    }

    /// The inputs at `tau` into the piece.
    fn inputs(&self, forced: &Forced, tau: f64) -> Inputs {
        Inputs {
            force: forced.force + forced.force_rate * tau,
            ag: forced.exc.ag + forced.exc.ag_rate * tau,
        }
    }

    /// The same where the input force is `force` and the ground acceleration `ag`.
    #[inline(always)]
    fn accel_and_jerk_at(
        &self,
        forced: &Forced,
        force: f64,
        ag: f64,
        u: f64,
        v: f64,
    ) -> (f64, f64) {
        let relative = force * self.inv_mass + self.load_accel - self.w2 * u - self.cm * v;
        let jerk = forced.jerk_forced - self.w2 * v - self.cm * relative;
        (relative + ag, jerk)
    }

    /// One step of length `hs` from (u, v) where the inputs are `start` and
    /// the absolute acceleration `accel`. `hs` is
    /// `self.h` except on a piece's last substep, where it differs by
    /// rounding of the piece's end times (at most [`SAME_STEP`] relative):
    /// that rest is carried to first order with the rates at the end.
    #[inline(always)]
    fn step(&self, forced: &Forced, start: Inputs, accel: f64, hs: f64, u: f64, v: f64) -> StepEnd {
        let force = start.force;
        let out = |r: usize| {
            let row = &self.rows[r];
            row[0] * u + row[1] * v + row[2] * force + forced.constant_terms[r]
        };
        // The first stage's rate is the acceleration at the start, known
        // from the step before: V2 = v + h/2 a.
        let v2 = v + self.half_h * (accel - start.ag);
        let (du, v1, v3, v4) = (out(0), out(1), out(3), out(4));
        let u1 = u + du;
        let inputs = Inputs {
            force: force + forced.step_force,
            ag: start.ag + forced.step_ag,
        };
        let (force_end, ag_end) = (inputs.force, inputs.ag);
        let (accel, jerk) = self.accel_and_jerk_at(forced, force_end, ag_end, u1, v1);
        let mut end = StepEnd {
            u: u1,
            v: v1,
            // RK4's quadrature of (force v): with the force linear over the
            // step, `force du` plus the slope's share over the stages.
            input: force * du + forced.input_slope * (v2 + v3 + v4),
            viscous: self.sixth_h * self.c * (v * v + 2.0 * (v2 * v2 + v3 * v3) + v4 * v4),
            accel,
            jerk,
            inputs,
        };
        if hs != self.h {
            let delta = hs - self.h;
            end.u += delta * v1;
            end.v += delta * (accel - ag_end);
            end.input += delta * force_end * v1;
            end.viscous += delta * self.c * v1 * v1;
            end.accel += delta * jerk;
            let relative_jerk = jerk - forced.exc.ag_rate;
            end.jerk -= delta * (self.w2 * (accel - ag_end) + self.cm * relative_jerk);
        }
        end
    }
}

/// RK4's stages for u' = v, v' = f0 + f1 τ - w2 u - cm v over one step `h`
/// from `[u, v, f0, f1]`: (u1 - u, v1, V2, V3, V4), linear in the four inputs.
fn rk4_stages(w2: f64, cm: f64, h: f64, [u, v, f0, f1]: [f64; 4]) -> [f64; 5] {
    let accel = |tau: f64, u: f64, v: f64| f0 + f1 * tau - w2 * u - cm * v;
    let a1 = accel(0.0, u, v);
    let (u2, v2) = (u + 0.5 * h * v, v + 0.5 * h * a1);
    let a2 = accel(0.5 * h, u2, v2);
    let (u3, v3) = (u + 0.5 * h * v2, v + 0.5 * h * a2);
    let a3 = accel(0.5 * h, u3, v3);
    let (u4, v4) = (u + h * v3, v + h * a3);
    let a4 = accel(h, u4, v4);
    let w = h / 6.0;
    [
        w * (v + 2.0 * (v2 + v3) + v4),
        v + w * (a1 + 2.0 * (a2 + a3) + a4),
        v2,
        v3,
        v4,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::StructureRk4;
    use crate::mode::{Contact, Mode};
    use crate::params::Params;

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
    fn the_affine_map_is_the_rk4_step() {
        // Expected values: the stage-by-stage RK4 of the general path.
        let (sys, d) = sliding_scene();
        let exc = Excitation {
            ag: 2.5,
            ag_rate: -40.0,
            fext: 300.0,
            fext_rate: 5e3,
        };
        let (t_ref, h) = (0.3, 1.25e-3);
        let rk = StructureRk4::new(&sys, &d, &exc, t_ref);
        let map = Rk4Map::new(&sys, &d, h);
        let forced = map.forced(&exc);
        for (k, (u, v)) in [(0.0, 0.0), (0.012, -0.3), (-0.04, 0.7)]
            .into_iter()
            .enumerate()
        {
            let t0 = t_ref + k as f64 * h;
            // Whole steps, and a last substep longer by rounding-sized rests.
            for hs in [h, h * (1.0 + 1e-12), h * (1.0 - 4e-10)] {
                let want = rk.step(t0, u, v, hs);
                let (a1, jerk1) = rk.accel_and_jerk(t0 + hs, want[0], want[1]);
                let start = map.inputs(&forced, t0 - t_ref);
                let (a0, _) = map.accel_and_jerk_at(&forced, start.force, start.ag, u, v);
                let got = map.step(&forced, start, a0, hs, u, v);
                assert!(close(got.u, want[0], 0.1), "u {} {}", got.u, want[0]);
                assert!(close(got.v, want[1], 1.0), "v {} {}", got.v, want[1]);
                assert!(
                    close(got.input, want[2], 10.0),
                    "input {} {}",
                    got.input,
                    want[2]
                );
                assert!(close(got.viscous, want[3], 10.0));
                assert!(close(got.accel, a1, 10.0), "accel {} {a1}", got.accel);
                assert!(close(got.jerk, jerk1, 1e3), "jerk {} {jerk1}", got.jerk);
            }
            let (a0, jerk0) = rk.accel_and_jerk(t0, u, v);
            let start = map.inputs(&forced, t0 - t_ref);
            let (a, jerk) = map.accel_and_jerk_at(&forced, start.force, start.ag, u, v);
            assert!(close(a, a0, 10.0) && close(jerk, jerk0, 1e3));
        }
    }

    #[test]
    fn upper_clusters_move_as_their_exact_polynomials() {
        // Expected values: `upper_cluster_step`, the closed form the general
        // path uses.
        let (_, d) = sliding_scene();
        let (h, ag_rate, ag0) = (1.25e-3, 75.0, -1.2);
        let upper = UpperClusters::<2>::new(&d, h, ag_rate);
        let vel = [0.1, -0.25];
        for hs in [h, h * (1.0 + 1e-12)] {
            let (mut du, mut v_end) = ([0.0; 2], [0.0; 2]);
            let work = upper.step(&vel, ag0, hs, &mut du, &mut v_end);
            let [du1, v1, w1] =
                upper_cluster_step(vel[1], d.accel_const[1], d.mass[1], ag0, ag_rate, hs);
            assert!(close(du[1], du1, 1e-3) && close(v_end[1], v1, 1.0));
            assert!(close(work, w1, 10.0), "{work} {w1}");
        }
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
