//! The exact default's one driver: every input source (a record's samples,
//! the FMU's inputs with their slopes and jumps, both together) comes as
//! consecutive pieces on which `ag` and `Fext` are linear, and one loop
//! takes their substeps on the exact map of the current mode.
//!
//! A substep (`ω h <= 0.5`, or `maxStep`) is taken here only when the
//! proofs of `proofs.rs` show that no guard changes sign inside it; a new
//! interior peak of `|u0|` or `|A0|` that the bounds cannot exclude is found
//! in place on the substep's Taylor polynomials. Anything else (every
//! switch) goes back to `Simulator::advance_pieces`, which hands that
//! substep to the event path (`exact_events.rs`) and then returns here.
//!
//! The energy terms are exact and summed per run: the structure cluster's
//! input and viscous work are quadratic in the substeps' start vectors
//! `z = [u, v, p, p']`, so a run keeps the sums of `z_i z_j` and `z_i`
//! ([`WorkSums`]) instead of two quadratic forms per substep; the upper
//! clusters' input work is `Δ(m v²/2) - m A Δu` over the run (their
//! absolute acceleration `A` is constant in a mode, whatever `ag` does).
//!
//! The maps are cached by substep length up to rounding
//! (`exact_map::canonical_length`); a substep whose length differs from
//! its map's by that rounding (at most 1e-9 relative) is completed to first
//! order in the difference, which leaves an error of its square.

use super::bodies::upper_cluster_motion;
use super::exact_events::raise_substep_peaks;
use super::exact_map::{canonical_length, dot, ExactMap};
use super::pieces::is_jump;
use super::proofs::{
    energy_run, in_band_proved, linear_guard_lasts, peaks_quick, raise_peak_proved,
    slip_guard_proved, slip_guard_quick, structure_peaks_proved,
};
use super::{friction_work, move_bodies, Excitation, Piece, PieceSource, Simulator};
use crate::physics::hermite;
use crate::physics::params::MAX_BODIES;

/// Sums over a run of the products `z_i z_j` and of `z_i`, for the
/// substeps' start vectors `z = [u, v, p, p']` on one map: the structure
/// cluster's viscous and input work are quadratic in `z`, so their sums over
/// the run follow from these at its end.
#[derive(Clone, Copy, Default)]
struct WorkSums {
    /// In pairs of two lanes: 00 11, 22 33, 02 13, 03 12, 01 23
    /// ([`QUAD_ORDER`] maps `ExactMap::quad`'s packing to them).
    products: [f64; 10],
    linear: [f64; 4],
}

/// Where each product of `ExactMap::quad`'s packing (00, 11, 22, 33, 01,
/// 02, 03, 12, 13, 23) is in [`WorkSums::products`].
const QUAD_ORDER: [usize; 10] = [0, 1, 2, 3, 8, 4, 6, 7, 5, 9];

impl WorkSums {
    #[inline(always)]
    fn add(&mut self, z: &[f64; 4]) {
        let [z0, z1, z2, z3] = *z;
        // Two lanes at a time: [z0, z1] and [z2, z3] times themselves, each
        // other, each other swapped; then [z0, z2] times [z1, z3].
        let left = [z0, z1, z2, z3, z0, z1, z0, z1, z0, z2];
        let right = [z0, z1, z2, z3, z2, z3, z3, z2, z1, z3];
        for ((s, l), r) in self.products.iter_mut().zip(left).zip(right) {
            *s += l * r;
        }
        for (l, x) in self.linear.iter_mut().zip(z) {
            *l += x;
        }
    }

    /// Adds the sums' work to `[input, viscous]` and starts anew, with the
    /// coefficients of `rows` (the map's exact work forms and the first
    /// order in the rest of its length, [`Rows::new`]): per unit mass the
    /// input work is `P·S - L (W·Σz)`, the viscous `c (V·S)`.
    #[inline(never)]
    fn flush(&mut self, rows: &Rows, mass: f64, load_accel: f64, work: &mut [f64; 2]) {
        self.add_work(rows, mass, load_accel, work);
        *self = WorkSums::default();
    }

    /// The sums' work added to `[input, viscous]` (as [`WorkSums::flush`],
    /// the sums left as they are: a run's last use).
    #[inline(always)]
    fn add_work(&self, rows: &Rows, mass: f64, load_accel: f64, work: &mut [f64; 2]) {
        let (s, l) = (&self.products, &self.linear);
        // Both forms at once, in two lanes (each summed in its own order).
        let mut pv = [0.0; 2];
        for k in 0..10 {
            let x = s[QUAD_ORDER[k]];
            pv[0] += rows.work_pv[k][0] * x;
            pv[1] += rows.work_pv[k][1] * x;
        }
        let with_load = dot(&rows.work_l, l);
        work[0] += mass * (pv[0] - load_accel * with_load);
        work[1] += rows.c * pv[1];
    }
}

impl Simulator {
    /// Takes the substeps of `piece` from `piece.i` on, then those of the
    /// following `pieces`, until one cannot be proved free of switches:
    /// `piece` is then the piece it belongs to, `piece.i` its index.
    /// Otherwise `piece` is the last piece taken, finished; a next piece
    /// that must be begun anew (a jump of `Fext`, or a bad value) is
    /// returned untouched.
    pub(super) fn sweep(
        &mut self,
        piece: &mut Piece,
        pieces: &mut impl PieceSource,
    ) -> Option<(f64, Excitation)> {
        // One instance per cluster count, and per input rule: a structure's
        // substeps do not pay for a prescribed support's `ag` term.
        if self.sys.prescribed() {
            self.sweep_rule::<true, 0>(piece, pieces)
        } else {
            self.sweep_rule::<false, 2>(piece, pieces)
        }
    }

    #[inline(always)]
    fn sweep_rule<const AG: bool, const RUNS: u8>(
        &mut self,
        piece: &mut Piece,
        pieces: &mut impl PieceSource,
    ) -> Option<(f64, Excitation)> {
        match self.dynamics.n_clusters {
            // The structure's cluster alone (no block, or all stuck): its energy runs.
            1 if !AG && self.dynamics.stick_band.is_none() => {
                self.sweep_clusters::<1, AG, 1>(piece, pieces)
            }
            1 if !AG => self.sweep_clusters::<1, AG, 2>(piece, pieces),
            1 => self.sweep_clusters::<1, AG, 0>(piece, pieces),
            // Upper clusters on a structure: energy runs (in the stick band of its cluster, if any).
            2 => self.sweep_clusters::<2, AG, RUNS>(piece, pieces),
            3 => self.sweep_clusters::<3, AG, RUNS>(piece, pieces),
            4 => self.sweep_clusters::<4, AG, RUNS>(piece, pieces),
            5 => self.sweep_clusters::<5, AG, RUNS>(piece, pieces),
            6 => self.sweep_clusters::<6, AG, RUNS>(piece, pieces),
            7 => self.sweep_clusters::<7, AG, RUNS>(piece, pieces),
            8 => self.sweep_clusters::<8, AG, RUNS>(piece, pieces),
            _ => self.sweep_clusters::<MAX_BODIES, AG, RUNS>(piece, pieces),
        }
    }

    /// [`Simulator::sweep`] in a mode with `NC` clusters (cluster 0 the structure's; moving
    /// interface m between clusters m and m + 1), with the input rule `Dynamics::input_rule::<AG>`
    /// (`AG`: a prescribed support); `RUNS` 1 or 2: energy runs on a structure (2: its cluster may
    /// have a stick band; 1: the structure's cluster alone without one).
    ///
    /// The clusters above the structure's have constant absolute
    /// accelerations `A_c` in the mode: a guard between two of them is
    /// linear in time over the run (the ground's terms cancel), so it holds
    /// up to its zero, found once per run. A slip whose guard holds keeps
    /// its direction: its peak is at an end of the run. Relative to cluster 1
    /// their motion is quadratic: only cluster 1 is carried substep by substep. (Run as `sweep_clusters`, `crate::isa`.)
    #[inline(always)]
    pub(crate) fn sweep_run<const NC: usize, const AG: bool, const RUNS: u8>(
        &mut self,
        piece: &mut Piece,
        pieces: &mut impl PieceSource,
    ) -> Option<(f64, Excitation)> {
        let h_max = self.h_max;
        let (sys, d, maps) = (&self.sys, &self.dynamics, &mut self.maps);
        debug_assert!(d.n_clusters == NC && (RUNS == 0 || !AG));
        // Constants of the mode.
        let has_band = RUNS != 1 && d.stick_band.is_some();
        let band: [f64; 2] = d.stick_band.unwrap_or((-f64::MAX, f64::MAX)).into();
        // Moving interface m (between clusters m and m + 1), and its slip in `u`.
        let iface = |m: usize| {
            if NC > 1 {
                d.moving[m.min(NC.saturating_sub(2))].j
            } else {
                0
            }
        };
        let slip_in = |u: &[f64; MAX_BODIES], m: usize| {
            let j = iface(m);
            if NC > 1 {
                u[j] - u[j - 1]
            } else {
                0.0
            }
        };
        let (mass, inv_mass) = (d.mass[0], d.inv_mass0);
        let load_accel = d.load_accel0;
        debug_assert!(
            d.prescribed || load_accel.to_bits() == (d.slip_load[0] * inv_mass).to_bits()
        );
        debug_assert_eq!(AG, sys.prescribed());
        let rule = d.input_rule::<AG>();
        let accel_c: [f64; NC] = std::array::from_fn(|c| d.accel_const[c]);
        // The piece in locals (written back at the end): the loop reads them every substep.
        let mut cur = piece.read_by_field();
        // Kept rows (a master's calls: a few lengths); a piece of another
        // length met on the way has its own.
        let (mut map, mut rows) = maps.rows(sys, mass, cur.h);
        let mut own_rows: Rows;
        let (mut row_u, mut row_v) = (rows.u, rows.v);
        let accel1 = if NC > 1 { accel_c[1] } else { 0.0 };
        let (mut w2, mut cm) = (map.w2, map.cm);
        // For the energy runs (w2 and cm are the mode's, whatever the map).
        let rates = [w2, w2.sqrt(), 1.0 / (w2 + cm * cm).sqrt()];

        // The run's state (the bodies keep the start's until they move at its end).
        let mut u0 = self.u[0];
        let u0_start = u0;
        let vel_start = |c: usize| self.v[d.bottom[c]];
        // Substep by substep: the structure's cluster and cluster 1 (the clusters above follow at
        // the run's end: relative to cluster 1 their motion is quadratic in time).
        let mut v0 = vel_start(0);
        let mut one = Cluster1::default();
        if NC > 1 {
            (one.vel, one.slip) = (vel_start(1), slip_in(&self.u, 0));
        }
        // The run's length, and the guards between upper clusters, `g(0) >=
        // 0` and `g > 0` after: the run stops before the first zero (less
        // four roundings of it).
        let mut tau = 0.0;
        let mut tau_lim = f64::INFINITY;
        for m in (1..NC.saturating_sub(1)).filter(|&m| d.slip_sign[m] != 0.0) {
            let sign = d.slip_sign[m];
            let g0 = sign * (vel_start(m + 1) - vel_start(m));
            let rate = sign * (accel_c[m + 1] - accel_c[m]);
            tau_lim = tau_lim.min(linear_guard_lasts(g0, rate) * (1.0 - 4.0 * f64::EPSILON));
        }
        // The structure's slip's peak where its interface is free (no guard:
        // raised substep by substep).
        let sign0 = d.slip_sign[0];
        let mut peak_slip0 = self.peak_slip[iface(0)];
        let (mut peak_u0, mut peak_a0) = (self.peak_u0, self.peak_a0);
        let mut sums = WorkSums::default();
        // Work of the substeps already summed and flushed.
        let mut work = [0.0; 2];
        let mut t0 = self.t;
        // The inputs (values at the substep's start, slopes over the piece).
        let mut inp = cur.exc;
        (inp.ag, inp.fext) = cur.exc.at(t0 - cur.t_ref);
        let mut a_abs = load_accel + rule.accel(inp.ag, inp.fext) - w2 * u0 - cm * v0;
        // After an energy run's unproved substep: the general loop's, until the quick tests clear
        // one.
        let mut wait = false;
        let mut taken = 0u64;
        let mut pending = None;
        // The pieces the source promised to continue the last: `lean[0]`
        // of `lean[1]` taken (the source is told at the end).
        let mut lean = [0, pieces.promised()];

        loop {
            if cur.i > cur.n {
                if continue_piece(pieces, &mut cur, &mut inp, &mut lean, t0) {
                    // Its first substep follows at once.
                } else {
                    pieces.skip(lean[0]);
                    lean = [0, 0];
                    let Some((t_end, exc)) = pieces.next_piece() else {
                        break;
                    };
                    // A jump of Fext, or a bad value: the piece is begun anew;
                    // on a prescribed support a jump of ag too, or any Fext.
                    let on_support = AG && (is_jump(exc.ag, inp.ag) || exc.fext_rate != 0.0);
                    if is_jump(exc.fext, inp.fext) || exc.check(t0, t_end).is_err() || on_support {
                        pending = Some((t_end, exc));
                        break;
                    }
                    if cur.same_length(t0, t_end) {
                        // A record's next sample: the same substeps, map and rows.
                        (cur.t_ref, cur.t_end, cur.exc, cur.i) = (t0, t_end, exc, 1);
                    } else {
                        sums.flush(rows, mass, load_accel, &mut work);
                        cur = Piece::new(t0, t_end, &exc, h_max);
                        let hc = canonical_length(cur.h);
                        if hc != map.h {
                            let i = maps.index(sys, mass, hc);
                            map = maps.get(i);
                            (w2, cm) = (map.w2, map.cm);
                        }
                        own_rows = Rows::new(map, cur.h);
                        rows = &own_rows;
                        (row_u, row_v) = (rows.u, rows.v);
                    }
                    lean[1] = pieces.promised();
                    // A0 carries over: it is continuous (a jump of Fext ends the run).
                    inp = exc;
                    continue;
                }
            }
            // Energy runs: through the pieces the source promised (Fext constant), the substeps
            // whose structure's cluster its energy proves at once (`energy_run`), else the quick
            // tests (peaks, band), and whose cluster 1 above it the quick test of its slip guard
            // (a free interface there: the general loop, which raises its peak).
            if RUNS > 0
                && !wait
                && lean[0] < lean[1]
                && inp.fext_rate == 0.0
                && (NC == 1 || sign0 != 0.0)
            {
                let cf = load_accel + rule.accel(inp.ag, inp.fext);
                let rate_m = rule.accel(inp.ag_rate, inp.fext_rate);
                let peaks = [peak_u0, peak_a0];
                let limits = [peak_u0, peak_a0, band[0], band[1]];
                // In copies the loop keeps in registers.
                let (mut c, mut i, mut l, mut s) = (cur, inp, lean, sums);
                let (mut t, mut u, mut v, mut n) = (t0, u0, v0, taken);
                let (mut o, mut tq) = (one, tau);
                let unproved = loop {
                    if c.i > c.n && !continue_piece(pieces, &mut c, &mut i, &mut l, t) {
                        break false;
                    }
                    let hs = c.h;
                    if NC > 2 && tq + hs >= tau_lim {
                        break true;
                    }
                    let z = [u, v, cf - i.ag, rate_m - i.ag_rate];
                    let cost = (0.5 + 1e-9) * hs * (z[2].abs() + (z[2] + hs * z[3]).abs());
                    let (u1, v1) = (dot(&row_u, &z), dot(&row_v, &z));
                    if !energy_run(rates, [u, v], [cf, cost], limits) {
                        let ends = [u, u1, cf - w2 * u - cm * v, cf - w2 * u1 - cm * v1];
                        let s3 = map.sup_v_abs(3, &z.map(f64::abs));
                        let [u_ok, a_ok] = peaks_quick(map, ends, [hs, s3], peaks);
                        // The band's quick test (NaN rates): the general loop decides the rest.
                        let out = |a| !in_band_proved(a, || [f64::NAN; 2], hs, s3, band);
                        if !(u_ok && a_ok) || has_band && out([ends[2], ends[3]]) {
                            break true;
                        }
                    }
                    if NC > 1 {
                        let next = o.step(hs, accel1, [i.ag, i.ag_rate], u1 - u);
                        let s3 = map.sup_v_abs(3, &z.map(f64::abs));
                        let g = [sign0 * (o.vel - v), sign0 * (next.vel - v1)];
                        if !slip_guard_quick(map, g, hs, s3, i.ag_rate) {
                            break true;
                        }
                        (o, tq) = (next, tq + hs);
                    }
                    t = if c.i == c.n { c.t_end } else { t + hs };
                    (u, v) = (u1, v1);
                    s.add(&z);
                    i.ag += i.ag_rate * hs;
                    (c.i, n) = (c.i + 1, n + 1);
                };
                let before = taken;
                (cur, inp, lean, sums, t0, u0, v0, taken) = (c, i, l, s, t, u, v, n);
                (one, tau) = (o, tq);
                if taken > before {
                    a_abs = cf - w2 * u0 - cm * v0;
                }
                // A substep the run could not prove: the general loop takes it.
                if taken > before && !unproved {
                    continue;
                }
                wait = true;
            }
            // Every substep of a piece is `cur.h` long; the last ends at the
            // piece's end, which differs from `t0 + h` only by the rounding
            // of the times.
            let hs = cur.h;
            let t1 = if cur.i == cur.n { cur.t_end } else { t0 + hs };
            let tau1 = tau + hs;
            if NC > 2 && tau1 >= tau_lim {
                break;
            }
            let fext_rate_m = rule.accel(inp.ag_rate, inp.fext_rate);
            let z = [
                u0,
                v0,
                load_accel + rule.accel(inp.ag, inp.fext) - inp.ag,
                fext_rate_m - inp.ag_rate,
            ];
            let (u1, v1) = (dot(&row_u, &z), dot(&row_v, &z));
            let (ag1, fext1) = (inp.ag + inp.ag_rate * hs, inp.fext + inp.fext_rate * hs);
            let a1 = load_accel + rule.accel(ag1, fext1) - w2 * u1 - cm * v1;
            let z_abs = z.map(f64::abs);
            let s3 = map.sup_v_abs(3, &z_abs);
            // Stuck interfaces: the absolute acceleration stays in the band.
            // Its rate: A' = Fext'/m - w2 v - cm (A - ag).
            let ends = [a_abs, a1];
            let jerks = || {
                [
                    fext_rate_m - w2 * v0 - cm * (a_abs - inp.ag),
                    fext_rate_m - w2 * v1 - cm * (a1 - ag1),
                ]
            };
            if has_band && !in_band_proved(ends, jerks, hs, s3, band) {
                break;
            }
            let next1 = one.step(hs, accel1, [inp.ag, inp.ag_rate], u1 - u0);
            // Whether the quick tests clear this substep (then energy runs again).
            let mut guard_quick = true;
            if NC > 1 && sign0 != 0.0 {
                // The structure's slip guard; |g''| <= sup|v0''| + |ag'|.
                let g = [sign0 * (one.vel - v0), sign0 * (next1.vel - v1)];
                let d = |a: f64| sign0 * (accel_c[1] - a);
                let rates = || [d(a_abs), d(a1), -sign0 * jerks()[0]];
                let bound = || map.sup_v_abs(2, &z_abs) + inp.ag_rate.abs();
                guard_quick = slip_guard_quick(map, g, hs, s3, inp.ag_rate);
                if !guard_quick && !slip_guard_proved(g, rates, hs, s3, bound) {
                    break;
                }
            }
            // Peaks of |u0| and |A0|; where the bounds cannot exclude a new one inside, on the
            // polynomials.
            let quick = peaks_quick(map, [u0, u1, a_abs, a1], [hs, s3], [peak_u0, peak_a0]);
            if RUNS > 0 && quick == [true; 2] && guard_quick {
                wait = false;
            }
            let peaks = [&mut peak_u0, &mut peak_a0];
            let (hs3, zs) = ([hs, s3], [&z, &z_abs]);
            let [u_proved, a_proved] =
                structure_peaks_proved(map, zs, [u1, v1], ends, jerks, hs3, quick, peaks);
            if !(u_proved && a_proved) {
                let peaks = [
                    (!u_proved).then_some(&mut peak_u0),
                    (!a_proved).then_some(&mut peak_a0),
                ];
                let cf = load_accel + rule.accel(inp.ag, inp.fext);
                let rates = [w2, cm, cf, fext_rate_m];
                let (ends, fourth) = ([u1, v1, a1], [s3, map.five_over_three * s3]);
                if raise_substep_peaks(peaks, z, hs, rates, map.degree, ends, fourth).is_err() {
                    break;
                }
            }
            // A free interface on the structure: slip''' = -(ag' + v0''),
            // slip'''' = -v0'''.
            if NC > 1 && sign0 == 0.0 {
                let third = map.sup_v_abs(2, &z_abs) + inp.ag_rate.abs();
                let ends = [one.slip, one.vel - v0, next1.slip, next1.vel - v1];
                if !raise_peak_proved(&mut peak_slip0, ends, hs, s3, || third) {
                    break;
                }
            }
            // Taken.
            sums.add(&z);
            (u0, v0, a_abs, tau, one) = (u1, v1, a1, tau1, next1);
            (inp.ag, inp.fext) = (ag1, fext1);
            t0 = t1;
            cur.i += 1;
            taken += 1;
        }

        pieces.skip(lean[0]);
        *piece = cur;
        if taken > 0 {
            sums.add_work(rows, mass, load_accel, &mut work);
            // The clusters above cluster 1 from it: between two upper clusters the relative
            // acceleration is `A_{m+1} - A_m` (the ground's terms cancel).
            let vel_start: [f64; NC] = std::array::from_fn(vel_start);
            let slip_start: [f64; NC] = std::array::from_fn(|m| slip_in(&self.u, m));
            let (mut vel, mut shift, mut slip) = (vel_start, [0.0; NC], slip_start);
            vel[0] = v0;
            if NC > 1 {
                (vel[1], shift[1], slip[0]) = (one.vel, one.shift, one.slip);
            }
            for m in 1..NC.saturating_sub(1) {
                let rel_v0 = vel_start[m + 1] - vel_start[m];
                let rel_a = accel_c[m + 1] - accel_c[m];
                let moved = tau * (rel_v0 + 0.5 * rel_a * tau);
                slip[m] = slip_start[m] + moved;
                shift[m + 1] = shift[m] + moved;
                vel[m + 1] = vel[m] + (rel_v0 + rel_a * tau);
            }
            // Input work on the upper clusters over the run, exact: with
            // v_c' = A_c - ag, -m ag v_c = d(m v_c²/2)/dt - m A_c v_c.
            let mut upper = 0.0;
            for c in 1..NC {
                let m = d.mass[c];
                upper += 0.5 * m * (vel[c] * vel[c] - vel_start[c] * vel_start[c])
                    - m * accel_c[c] * shift[c];
            }
            self.e_input += work[0] + upper;
            // A prescribed support's drift from the input frame: its work
            // on the stack beyond the input (Dynamics::support_force).
            // (0 on a structure: its run does not compute it.)
            if AG {
                let support_work = d.support_force * (u0 - u0_start);
                if support_work != 0.0 {
                    self.e_input += support_work;
                }
            }
            self.e_viscous += work[1];
            let (mut shift_all, mut vel_all) = ([0.0; MAX_BODIES], [0.0; MAX_BODIES]);
            shift_all[..NC].copy_from_slice(&shift);
            vel_all[..NC].copy_from_slice(&vel);
            let n = self.sys.n;
            move_bodies(&mut self.u, &mut self.v, d, n, u0, &shift_all, &vel_all);
            for m in 0..NC - 1 {
                let j = iface(m);
                let (start, end) = (slip_start[m], slip[m]);
                self.e_friction[j] += friction_work(d.slip_force[j], end - start);
                let peak = &mut self.peak_slip[j];
                if d.slip_sign[m] != 0.0 {
                    // Its guard held: it kept its direction. (Not `f64::max`: no NaN's case.)
                    let hi = if end.abs() > start.abs() { end } else { start }.abs();
                    if hi > *peak {
                        *peak = hi;
                    }
                } else if m == 0 {
                    *peak = peak_slip0;
                } else {
                    // Free between upper clusters: a quadratic in τ over the
                    // run, which the cubic gives exactly.
                    let (vr0, vr1) = (vel_start[m + 1] - vel_start[m], vel[m + 1] - vel[m]);
                    hermite::raise_peak(peak, start, vr0, end, vr1, tau);
                }
            }
            self.peak_u0 = peak_u0;
            self.peak_a0 = peak_a0;
            self.stats.steps += taken;
            self.t = t0;
        }
        pending
    }
}

/// Cluster 1, on the structure's moving interface: its velocity, its displacement over the run,
/// and the slip of that interface.
#[derive(Clone, Copy, Default)]
struct Cluster1 {
    vel: f64,
    shift: f64,
    slip: f64,
}

impl Cluster1 {
    /// After a substep of `h` with its absolute acceleration `accel`, `ag` linear from `ag0` at
    /// `ag_rate`, the structure moving by `du0` ([`upper_cluster_motion`]).
    #[inline(always)]
    fn step(self, h: f64, accel: f64, [ag0, ag_rate]: [f64; 2], du0: f64) -> Cluster1 {
        let [du, vel] = upper_cluster_motion(self.vel, accel, ag0, ag_rate, h);
        let (shift, slip) = (self.shift + du, self.slip + (du - du0));
        Cluster1 { vel, shift, slip }
    }
}

/// Moves `cur` from `t0` on to the next piece the source promised to
/// continue it (a record's next sample, as long as the last, Fext constant
/// as it is, every value finite): false where there is none.
#[inline(always)]
fn continue_piece(
    pieces: &mut impl PieceSource,
    cur: &mut Piece,
    inp: &mut Excitation,
    lean: &mut [usize; 2],
    t0: f64,
) -> bool {
    if lean[0] >= lean[1] {
        return false;
    }
    let Some((t_end, ag, ag_rate)) = pieces.continuing(lean[0]) else {
        return false;
    };
    lean[0] += 1;
    debug_assert!(cur.n >= 1);
    (cur.t_ref, cur.t_end, cur.i) = (t0, t_end, 1);
    (cur.exc.ag, cur.exc.ag_rate) = (ag, ag_rate);
    (inp.ag, inp.ag_rate) = (ag, ag_rate);
    true
}

/// The rows of a substep of length `h` on `z = [u, v, p, p']`: the map's
/// (built for `h` up to rounding), completed to first order in their
/// difference `delta` (u' = v, v' the acceleration); and the coefficients
/// of the run's work on the [`WorkSums`] (products packed as
/// `ExactMap::quad`).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Rows {
    u: [f64; 4],
    v: [f64; 4],
    /// Pairs `[input, viscous]` per product: input work per unit mass over
    /// a substep without the mode's load, `(p - L)(u1 - u) + p' (h u1 - ∫u)`
    /// on the map plus `delta` times `(p - L) v` at its end (`v = V z`, `p =
    /// z_2 + h z_3`), its terms in `p` (`work_l`: the row of `-L`, on the
    /// sums of `z`); `∫ v²` on the map plus `delta v²` at its end.
    work_pv: [[f64; 2]; 10],
    work_l: [f64; 4],
    c: f64,
}

impl Rows {
    /// The rows of a substep of length `h` on `map`: `map.rows` plus `h -
    /// map.h` times `map.rows_rate`.
    #[inline]
    pub(super) fn new(map: &ExactMap, h: f64) -> Rows {
        let delta = h - map.h;
        let (r, d) = (&map.rows, &map.rows_rate);
        Rows {
            u: std::array::from_fn(|k| r.u[k] + delta * d.u[k]),
            v: std::array::from_fn(|k| r.v[k] + delta * d.v[k]),
            work_pv: std::array::from_fn(|k| {
                let (r, d) = (r.work_pv[k], d.work_pv[k]);
                [r[0] + delta * d[0], r[1] + delta * d[1]]
            }),
            work_l: std::array::from_fn(|k| r.work_l[k] + delta * d.work_l[k]),
            c: r.c,
        }
    }

    /// The map's own rows (`delta = 0`) and their rates in `delta`, from
    /// its Taylor sums: `[rows, rate]`.
    pub(super) fn of_map(map: &ExactMap) -> [Rows; 2] {
        let (u, v, hm) = (&map.u, &map.v, map.h);
        // The acceleration relative to the support at the end as a row.
        let p = [0.0, 0.0, 1.0, hm];
        let accel = std::array::from_fn(|k| p[k] - map.w2 * u[k] - map.cm * v[k]);
        // Σ (p - L)(U z - u) over products with p = z_2 (U's first entry
        // less one for the `- u`), Σ p' (h U - I) z with p' = z_3.
        let u0m1 = u[0] - 1.0;
        let w: [f64; 4] = std::array::from_fn(|j| hm * u[j] - map.int_u[j]);
        // Packed: 00, 11, 22, 33, 01, 02, 03, 12, 13, 23.
        let pair = |p: [f64; 10], v: [f64; 10]| std::array::from_fn(|k| [p[k], v[k]]);
        let rows = Rows {
            u: *u,
            v: *v,
            work_pv: pair(
                [
                    0.0,
                    0.0,
                    u[2],
                    w[3],
                    0.0,
                    u0m1,
                    w[0],
                    u[1],
                    w[1],
                    u[3] + w[2],
                ],
                map.quad,
            ),
            work_l: [u0m1, u[1], u[2], u[3]],
            c: map.c,
        };
        // The rest `delta`, to first order: u' = v, v' the acceleration;
        // the input work's integrand at the end `(z_2 + h z_3 - L) (V z)`,
        // the viscous one `(V z)²`.
        let hv: [f64; 4] = std::array::from_fn(|j| hm * v[j]);
        let rate = Rows {
            u: *v,
            v: accel,
            work_pv: pair(
                [
                    0.0,
                    0.0,
                    v[2],
                    hv[3],
                    0.0,
                    v[0],
                    hv[0],
                    v[1],
                    hv[1],
                    v[3] + hv[2],
                ],
                [
                    v[0] * v[0],
                    v[1] * v[1],
                    v[2] * v[2],
                    v[3] * v[3],
                    2.0 * v[0] * v[1],
                    2.0 * v[0] * v[2],
                    2.0 * v[0] * v[3],
                    2.0 * v[1] * v[2],
                    2.0 * v[1] * v[3],
                    2.0 * v[2] * v[3],
                ],
            ),
            work_l: *v,
            c: 0.0,
        };
        [rows, rate]
    }
}
