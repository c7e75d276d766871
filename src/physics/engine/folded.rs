//! The default method's fast path: whole substeps on the exact map.
//!
//! With the automatic step (`maxStep = 0`), a substep of a record's piece
//! (one substep per sample unless `ω dt > 0.5`) is taken in one product
//! with the structure cluster's exact map ([`ExactMap`]); the upper
//! clusters move as their exact polynomials, as on every path. A substep is
//! taken here only when it is *proved* that nothing happens inside it:
//!
//! - no guard changes sign: a guard `g` positive at both ends stays above
//!   their linear interpolation minus `h²/8 sup|g''|`, and `sup|g''|` is
//!   bounded from the substep's start state by the map's derivative bounds
//!   (`ExactMap::sup_v`), so `min(g(0), g(h)) > h²/8 sup|g''|` excludes a
//!   crossing, a double one included;
//! - no peak is missed: `|y|` is bounded by the cubic Hermite interpolant
//!   through the ends (exact values and derivatives) plus its remainder
//!   `h⁴/384 sup|y''''|`; a `y` proved monotone peaks at an end.
//!
//! A substep where either proof fails is handed back and taken by the
//! event path on the exact motion (`exact_events.rs`): every event, and
//! the few substeps holding a new interior peak. The energy terms are
//! exact: the viscous work a quadratic form, the input work bilinear in the
//! state, `∫ u` and the inputs.

use super::exact_map::{canonical_length, dot, ExactMap, MAP_H_OMEGA};
use super::upper::UpperClusters;
use super::{Excitation, Piece, Simulator};
use crate::physics::hermite;
use crate::physics::mode::safe_accel_band;
use crate::physics::mode::{Dynamics, Guard};
use crate::physics::params::MAX_BODIES;

/// The structure cluster at the end of a substep.
#[derive(Clone, Copy, Debug)]
struct End {
    u: f64,
    v: f64,
    /// Absolute acceleration.
    accel: f64,
    /// Forcing per unit mass and ground acceleration at the end.
    p: f64,
    ag: f64,
    input: f64,
    viscous: f64,
}

/// What the fast path steps with over the current piece.
struct Stepping {
    h_map_max: f64,
    /// The cluster's mass and the mode's constant load per unit mass.
    mass: f64,
    inv_mass: f64,
    load_accel: f64,
    /// Slopes over the piece: forcing per unit mass and ground acceleration.
    p1: f64,
    ag_rate: f64,
    fext_rate_m: f64,
}

impl Stepping {
    fn new(d: &Dynamics, h_map_max: f64) -> Stepping {
        Stepping {
            h_map_max,
            mass: d.mass[0],
            inv_mass: d.inv_mass0,
            load_accel: d.slip_load[0] * d.inv_mass0,
            p1: 0.0,
            ag_rate: 0.0,
            fext_rate_m: 0.0,
        }
    }

    /// Takes the piece's slopes; returns (p, ag) at `t0`.
    fn begin(&mut self, piece: &Piece, t0: f64) -> (f64, f64) {
        let e = &piece.exc;
        let dt = t0 - piece.t_ref;
        self.ag_rate = e.ag_rate;
        self.fext_rate_m = e.fext_rate * self.inv_mass;
        self.p1 = self.fext_rate_m - e.ag_rate;
        let ag = e.ag + e.ag_rate * dt;
        let fext = e.fext + e.fext_rate * dt;
        (self.load_accel + fext * self.inv_mass - ag, ag)
    }

    /// Absolute acceleration from (u, v, p, ag).
    #[inline(always)]
    fn accel(&self, map: &ExactMap, u: f64, v: f64, p: f64, ag: f64) -> f64 {
        p - map.w2 * u - map.cm * v + ag
    }

    /// Rate of the absolute acceleration where the velocity is `v`, the
    /// absolute acceleration `accel` and the ground's `ag` (taken only on
    /// the few substeps whose quick tests fail).
    #[inline(always)]
    fn jerk(&self, map: &ExactMap, v: f64, accel: f64, ag: f64) -> f64 {
        self.p1 - map.w2 * v - map.cm * (accel - ag) + self.ag_rate
    }

    /// One substep of length `hs` (the map's, up to rounding) from `z`.
    #[inline(always)]
    fn step(&self, map: &ExactMap, z: &[f64; 4], ag: f64, hs: f64) -> End {
        let (mut u, mut v, iu) = (dot(&map.u, z), dot(&map.v, z), dot(&map.int_u, z));
        let h = map.h;
        let q0 = z[2] - self.load_accel;
        let mut input = self.mass * (q0 * (u - z[0]) + z[3] * (h * u - iu));
        let mut viscous = map.c * map.int_v2(z);
        if hs != h {
            // The rest of the substep (rounding of the piece's times and of
            // the map's length, at most 1e-9 relative), to first order.
            let delta = hs - h;
            let p_nominal = z[2] + z[3] * h;
            let rel = p_nominal - map.w2 * u - map.cm * v;
            input += delta * self.mass * (p_nominal - self.load_accel) * v;
            viscous += delta * map.c * v * v;
            u += delta * v;
            v += delta * rel;
        }
        let (p, ag) = (z[2] + z[3] * hs, ag + self.ag_rate * hs);
        let accel = self.accel(map, u, v, p, ag);
        End {
            u,
            v,
            accel,
            p,
            ag,
            input,
            viscous,
        }
    }
}

/// Raises `peak` to the largest `|y|` over a substep of length `h` with end
/// values `y0`, `y1` and rates `d0`, `d1`, when that can be proved from the
/// ends: `fourth` bounds `|y''''|` over the substep and `third()` `|y'''|`.
/// False when a new peak inside the substep cannot be excluded (the caller
/// then takes the substep on the general path).
#[inline(always)]
pub(super) fn raise_peak_proved(
    peak: &mut f64,
    [y0, d0, y1, d1]: [f64; 4],
    h: f64,
    fourth: f64,
    third: impl FnOnce() -> f64,
) -> bool {
    let h2 = h * h;
    let rest = h2 * h2 / 384.0 * fourth;
    let (a0, a1) = (y0.abs(), y1.abs());
    let ends = if a0 > a1 { a0 } else { a1 };
    // The cubic's bound of `hermite::raise_peak`, plus its remainder.
    if ends + 4.0 / 27.0 * h * (d0.abs() + d1.abs()) + rest <= *peak {
        return true;
    }
    peak_near(peak, [y0, d0, y1, d1], h, rest, ends, third)
}

#[inline(never)]
fn peak_near(
    peak: &mut f64,
    [y0, d0, y1, d1]: [f64; 4],
    h: f64,
    rest: f64,
    ends: f64,
    third: impl FnOnce() -> f64,
) -> bool {
    // Monotone: y' stays within h²/8 sup|y'''| of its linear interpolation,
    // so it keeps its sign when both ends exceed that.
    if d0 * d1 > 0.0 && d0.abs().min(d1.abs()) > 0.125 * h * h * third() {
        if ends > *peak {
            *peak = ends;
        }
        return true;
    }
    hermite::max_abs(y0, d0, y1, d1, h) + rest <= *peak
}

/// Whether the absolute acceleration stays inside the stick band `[lo, hi]`
/// over a substep of length `h`: its ends `a0`, `a1`, `sup|A''| <= s3`, and
/// (only when that does not decide) its rates at the ends, `jerks()`.
#[inline(always)]
pub(super) fn in_band_proved(
    [a0, a1]: [f64; 2],
    jerks: impl FnOnce() -> [f64; 2],
    h: f64,
    s3: f64,
    [lo, hi]: [f64; 2],
) -> bool {
    let sag = 0.125 * h * h * s3;
    // Plain comparisons (f64::min and max carry NaN rules not needed here).
    let (low, high) = if a0 < a1 { (a0, a1) } else { (a1, a0) };
    (low - sag > lo && high + sag < hi) || {
        let [j0, j1] = jerks();
        stays_positive([a0 - lo, j0, a1 - lo, j1], h, s3)
            && stays_positive([hi - a0, -j0, hi - a1, -j1], h, s3)
    }
}

/// Whether the slip guard between the structure's cluster and the one above
/// stays positive over a substep of length `h`: its ends `g0`, `g1` (the
/// signed relative velocity), `|g''| <= bound`, and (only when that does not
/// decide) its rates at the ends, `rates()`.
#[inline(always)]
pub(super) fn slip_guard_proved(
    [g0, g1]: [f64; 2],
    rates: impl FnOnce() -> [f64; 2],
    h: f64,
    bound: f64,
) -> bool {
    let sag = 0.125 * h * h * bound;
    (g0 > sag && g1 > sag) || {
        let [d0, d1] = rates();
        stays_positive([g0, d0, g1, d1], h, bound)
    }
}

/// Raises the structure's peaks of |u0| and |A0| over the substep from `z`
/// (end values `u1`, `v1`; the absolute acceleration `a0` and `a1` at the
/// ends, its rates `jerks()`) where that is proved; returns which were.
/// Quick tests first: the larger end plus `h²/8 sup|y''|` (`sup|u''| =
/// sup|v'|`, `sup|A''| = sup|v'''| <= s3`); then the cubic bounds with the
/// rates.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn structure_peaks_proved(
    map: &ExactMap,
    z: &[f64; 4],
    [u1, v1]: [f64; 2],
    [a0, a1]: [f64; 2],
    jerks: impl FnOnce() -> [f64; 2],
    h: f64,
    s3: f64,
    [peak_u0, peak_a0]: [&mut f64; 2],
) -> [bool; 2] {
    let sag = 0.125 * h * h * s3;
    let (e0, e1) = (z[0].abs(), u1.abs());
    let ends = if e0 > e1 { e0 } else { e1 };
    let u_proved = ends + sag * map.one_over_three <= *peak_u0
        || raise_peak_proved(peak_u0, [z[0], z[1], u1, v1], h, s3, || map.sup_v(2, z));
    let (e0, e1) = (a0.abs(), a1.abs());
    let ends = if e0 > e1 { e0 } else { e1 };
    let a_proved = ends + sag <= *peak_a0 || {
        let [j0, j1] = jerks();
        let fifth = map.five_over_three * s3;
        raise_peak_proved(peak_a0, [a0, j0, a1, j1], h, fifth, || map.sup_v(4, z))
    };
    [u_proved, a_proved]
}

/// Whether `g > 0` over `(0, h]` is proved from its ends (values `g0`, `g1`,
/// rates `d0`, `d1`) and `|g''| <= m2`: Taylor's bound from the start,
/// `g(τ) >= g0 + d0 τ - m2 τ²/2`, is positive up to its root `r0`, and the
/// one from the end up to `h - r1`; together they cover the substep when
/// `r0 + r1 > h`. This admits a guard that starts at zero and grows (a
/// contact that has just switched), which the interpolation bound cannot.
#[inline(never)]
pub(super) fn stays_positive([g0, d0, g1, d1]: [f64; 4], h: f64, m2: f64) -> bool {
    // Length over which `g + d τ - m2 τ²/2` stays positive from τ = 0+.
    let reach = |g: f64, d: f64| -> f64 {
        if g < 0.0 || (g == 0.0 && d <= 0.0) {
            0.0
        } else if m2 > 0.0 {
            (d + (d * d + 2.0 * m2 * g).sqrt()) / m2
        } else if d >= 0.0 {
            f64::INFINITY
        } else {
            g / -d
        }
    };
    g1 > 0.0 && reach(g0, d0) + reach(g1, -d1) > h
}

impl Simulator {
    /// The default method's fast path: takes the substeps of `piece` from
    /// `piece.i` on, then those of the following `pieces`, until one cannot
    /// be proved free of events and unseen peaks; as [`Simulator::lean_steps`].
    pub(super) fn folded_steps(
        &mut self,
        piece: &mut Piece,
        pieces: &mut impl Iterator<Item = (f64, Excitation)>,
    ) -> Option<(f64, Excitation)> {
        match self.dynamics.n_clusters {
            1 => self.folded_one_cluster(piece, pieces),
            2 => self.folded_clusters::<2>(piece, pieces),
            3 => self.folded_clusters::<3>(piece, pieces),
            4 => self.folded_clusters::<4>(piece, pieces),
            5 => self.folded_clusters::<5>(piece, pieces),
            6 => self.folded_clusters::<6>(piece, pieces),
            7 => self.folded_clusters::<7>(piece, pieces),
            8 => self.folded_clusters::<8>(piece, pieces),
            _ => self.folded_clusters::<MAX_BODIES>(piece, pieces),
        }
    }

    /// Largest substep on the exact map.
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

    /// The longest substep of the exact default: `ω h = MAP_H_OMEGA`, or
    /// `maxStep` where that is shorter (the default stays exact at any
    /// `maxStep`; a shorter one only costs more substeps).
    pub(super) fn map_step(&self) -> f64 {
        let h = MAP_H_OMEGA / self.sys.omega_p;
        if self.settings.max_step > 0.0 {
            h.min(self.settings.max_step)
        } else {
            h
        }
    }

    fn folded_one_cluster(
        &mut self,
        piece: &mut Piece,
        pieces: &mut impl Iterator<Item = (f64, Excitation)>,
    ) -> Option<(f64, Excitation)> {
        let h_map_max = self.map_step();
        let (sys, d, maps) = (&self.sys, &self.dynamics, &mut self.maps);
        let guards = &d.guards[..d.n_guards];
        let (band_lo, band_hi) = safe_accel_band(guards);
        let has_band = d.n_guards > 0;
        let mut st = Stepping::new(d, h_map_max);
        let first = maps.index(sys, st.mass, canonical_length(piece.h));
        let mut map = maps.get(first);

        let (mut u0, mut v0, mut t0) = (self.u[0], self.v[0], self.t);
        let (mut e_input, mut e_viscous) = (0.0, 0.0);
        let (mut peak_u0, mut peak_a0) = (self.peak_u0, self.peak_a0);
        let (mut p, mut ag) = st.begin(piece, t0);
        let mut a0 = st.accel(map, u0, v0, p, ag);
        let mut taken = 0u64;
        let mut pending = None;
        loop {
            if piece.i > piece.n {
                if !next_piece(piece, pieces, t0, &mut pending, st.h_map_max) {
                    break;
                }
                let hc = canonical_length(piece.h);
                if hc != map.h {
                    let i = maps.index(sys, st.mass, hc);
                    map = maps.get(i);
                }
                // A0 carries over: it is continuous (a jump of Fext ends the run).
                (p, ag) = st.begin(piece, t0);
                continue;
            }
            let (t1, hs) = substep(piece, t0);
            let z = [u0, v0, p, st.p1];
            let x = st.step(map, &z, ag, hs);
            let s3 = map.sup_v(3, &z);
            let ends = [a0, x.accel];
            let jerks = || [st.jerk(map, z[1], a0, ag), st.jerk(map, x.v, x.accel, x.ag)];
            if has_band && !in_band_proved(ends, jerks, hs, s3, [band_lo, band_hi]) {
                break;
            }
            let peaks = [&mut peak_u0, &mut peak_a0];
            if structure_peaks_proved(map, &z, [x.u, x.v], ends, jerks, hs, s3, peaks) != [true; 2]
            {
                break;
            }
            (u0, v0, a0, p, ag) = (x.u, x.v, x.accel, x.p, x.ag);
            e_input += x.input;
            e_viscous += x.viscous;
            t0 = t1;
            piece.i += 1;
            taken += 1;
        }
        if taken > 0 {
            let vel = [v0; MAX_BODIES];
            let shift = [0.0; MAX_BODIES];
            super::move_bodies(&mut self.u, &mut self.v, d, self.sys.n, u0, &shift, &vel);
            self.end_run(t0, taken, [e_input, e_viscous], [peak_u0, peak_a0]);
        }
        pending
    }

    /// The fast path for a mode with `NC` >= 2 clusters (cluster 0 the
    /// structure's; moving interface m between clusters m and m + 1).
    fn folded_clusters<const NC: usize>(
        &mut self,
        piece: &mut Piece,
        pieces: &mut impl Iterator<Item = (f64, Excitation)>,
    ) -> Option<(f64, Excitation)> {
        let h_map_max = self.map_step();
        let (sys, d, maps) = (&self.sys, &self.dynamics, &mut self.maps);
        debug_assert_eq!(d.n_clusters, NC);
        let guards = &d.guards[..d.n_guards];
        let (band_lo, band_hi) = safe_accel_band(guards);
        let has_band = guards.iter().any(|g| matches!(g, Guard::Stuck { .. }));
        let iface: [usize; NC] = std::array::from_fn(|m| d.moving[m.min(NC - 2)].j);
        let mut slip_sign = [0.0; NC];
        for g in guards {
            if let Guard::Slip { lo, sign, .. } = *g {
                slip_sign[lo] = sign;
            }
        }
        let mut st = Stepping::new(d, h_map_max);
        let first = maps.index(sys, st.mass, canonical_length(piece.h));
        let mut map = maps.get(first);

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
        let (mut p, mut ag) = st.begin(piece, t0);
        let mut a0 = st.accel(map, u0, vel[0], p, ag);
        let mut upper = UpperClusters::<NC>::new(d, piece.h, piece.exc.ag_rate);
        let mut run_start = (t0, ag, vel);
        let mut taken = 0u64;
        let mut pending = None;
        'steps: loop {
            if piece.i > piece.n {
                e_input += upper.work(run_start, t0);
                if !next_piece(piece, pieces, t0, &mut pending, st.h_map_max) {
                    run_start.0 = t0;
                    break;
                }
                let hc = canonical_length(piece.h);
                if hc != map.h {
                    let i = maps.index(sys, st.mass, hc);
                    map = maps.get(i);
                }
                // A0 carries over: it is continuous (a jump of Fext ends the run).
                (p, ag) = st.begin(piece, t0);
                upper = UpperClusters::new(d, piece.h, piece.exc.ag_rate);
                run_start = (t0, ag, vel);
                continue;
            }
            let (t1, hs) = substep(piece, t0);
            let z = [u0, vel[0], p, st.p1];
            let x = st.step(map, &z, ag, hs);
            let (mut du, mut v_end) = ([0.0; NC], [0.0; NC]);
            (du[0], v_end[0]) = (x.u - u0, x.v);
            upper.step(&vel, ag, hs, &mut du, &mut v_end);
            let s3 = map.sup_v(3, &z);
            let ends = [a0, x.accel];
            let jerks = || [st.jerk(map, z[1], a0, ag), st.jerk(map, x.v, x.accel, x.ag)];
            if has_band && !in_band_proved(ends, jerks, hs, s3, [band_lo, band_hi]) {
                break;
            }
            // sup|v0''|, and with the ground's slope the bound on the second
            // derivative of a relative velocity to the structure's cluster.
            let s2 = map.sup_v(2, &z);
            for m in 0..NC - 1 {
                let s = slip_sign[m];
                let (g0, g1) = (s * (vel[m + 1] - vel[m]), s * (v_end[m + 1] - v_end[m]));
                // Between two upper clusters the relative velocity is linear
                // in time (the ground's terms cancel): the ends decide.
                let holds = if m == 0 {
                    // Rates: the upper cluster's constant acceleration minus
                    // the structure's.
                    let rates = || [s * (upper.accel(1) - a0), s * (upper.accel(1) - x.accel)];
                    slip_guard_proved([g0, g1], rates, hs, s2 + st.ag_rate.abs())
                } else {
                    g0 >= 0.0 && g1 > 0.0
                };
                if s != 0.0 && !holds {
                    break 'steps;
                }
            }
            let peaks = [&mut peak_u0, &mut peak_a0];
            let peaks_proved =
                structure_peaks_proved(map, &z, [x.u, x.v], ends, jerks, hs, s3, peaks);
            let mut proved = peaks_proved == [true; 2];
            let mut new_slip = slip;
            for m in 0..NC - 1 {
                let increment = du[m + 1] - du[m];
                let (vrel0, vrel1) = (vel[m + 1] - vel[m], v_end[m + 1] - v_end[m]);
                let ends = [slip[m], vrel0, slip[m] + increment, vrel1];
                new_slip[m] = slip[m] + increment;
                if m == 0 {
                    // slip''' = -(ag' + v0''), slip'''' = -v0'''.
                    let third = s2 + st.ag_rate.abs();
                    proved &= raise_peak_proved(&mut peak_slip[m], ends, hs, s3, || third);
                } else {
                    // A quadratic in time: the cubic through the ends is exact.
                    hermite::raise_peak(&mut peak_slip[m], ends[0], vrel0, ends[2], vrel1, hs);
                }
            }
            if !proved {
                break;
            }
            slip = new_slip;
            for c in 1..NC {
                shift[c] += du[c];
            }
            (u0, vel, a0, p, ag) = (x.u, v_end, x.accel, x.p, x.ag);
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
                let j = iface[m];
                self.e_friction[j] -= d.slip_force[j] * (slip[m] - slip_at_entry[m]);
                self.peak_slip[j] = peak_slip[m];
            }
            self.end_run(t0, taken, [e_input, e_viscous], [peak_u0, peak_a0]);
        }
        pending
    }
}

/// End time and length of substep `piece.i` from `t0` (the last one ends
/// exactly at the piece's end).
#[inline(always)]
fn substep(piece: &Piece, t0: f64) -> (f64, f64) {
    if piece.i == piece.n {
        (piece.t_end, piece.t_end - t0)
    } else {
        (t0 + piece.h, piece.h)
    }
}

/// Moves on from the finished `piece`, at `t0`, to the next of `pieces`
/// (as the RK4 fast path does): false when there is none, or when the
/// general path must begin it (a jump of `Fext`, or a bad value), which is
/// then put in `pending`.
#[inline(always)]
fn next_piece(
    piece: &mut Piece,
    pieces: &mut impl Iterator<Item = (f64, Excitation)>,
    t0: f64,
    pending: &mut Option<(f64, Excitation)>,
    h_max: f64,
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
    *piece = Piece::new(t0, t_end, &exc, h_max);
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positivity_is_proved_only_where_it_holds() {
        // Expected: for g(τ) = g0 + d0 τ - m2 τ²/2 (the extreme case of the
        // bound), a proof only when g stays positive on (0, h], found by a
        // dense scan; and the proof for a guard that starts at zero and grows.
        let h = 1.0;
        let mut proved = 0;
        for g0 in [0.0, 0.01, 0.1, 0.5] {
            for d0 in [-1.0, -0.3, 0.0, 0.3, 1.0] {
                for m2 in [0.0, 0.5, 2.0, 8.0] {
                    let g = |t: f64| g0 + d0 * t - 0.5 * m2 * t * t;
                    let dg = |t: f64| d0 - m2 * t;
                    let ok = stays_positive([g0, d0, g(h), dg(h)], h, m2);
                    let positive = (1..=10_000).all(|k| g(k as f64 / 10_000.0) > 0.0);
                    assert!(!ok || positive, "g0 {g0} d0 {d0} m2 {m2}");
                    proved += ok as u32;
                }
            }
        }
        assert!(proved > 10);
        assert!(stays_positive([0.0, 1.0, 0.9, 0.8], 1.0, 0.2));
    }

    #[test]
    fn a_peak_inside_the_substep_is_not_passed_over() {
        // Expected: y = sin(τ) over [0, 2] peaks at 1 (τ = π/2), inside:
        // from a running peak of 0.95 the substep is handed back (false);
        // from 1 plus the remainder bound it is proved (true). |y'''| and
        // |y''''| are at most 1.
        let ends = [0.0, 1.0, 2f64.sin(), 2f64.cos()];
        let mut peak = 0.95;
        assert!(!raise_peak_proved(&mut peak, ends, 2.0, 1.0, || 1.0));
        let mut peak = 1.0 + 2f64.powi(4) / 384.0;
        assert!(raise_peak_proved(&mut peak, ends, 2.0, 1.0, || 1.0));
        // Monotone: y = τ on [0, 1] from a peak of 0.5 goes to 1 exactly.
        let mut peak = 0.5;
        assert!(raise_peak_proved(
            &mut peak,
            [0.0, 1.0, 1.0, 1.0],
            1.0,
            0.0,
            || 0.0
        ));
        assert_eq!(peak, 1.0);
    }
}
