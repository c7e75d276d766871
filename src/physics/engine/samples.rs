//! The default method over a record's samples, read from its arrays.
//!
//! The general path takes a record as a stream of linear pieces
//! (`advance_pieces`) and pays, per sample, for building the piece, for
//! a substep length that differs from its map's by rounding, and for the
//! exact energy forms. Here whole sample intervals of a uniform record
//! (`dt` the record's spacing, `n` equal substeps per sample so that
//! `ω dt / n <= 0.5`) go through a loop that reads the samples directly
//! and does the quick tests of `folded.rs`: a substep is taken when its
//! guards are proved from its ends and `h²/8 sup|g''|` (or Taylor's bounds
//! from both ends), and its peaks likewise or, where that fails, found
//! exactly on its Taylor polynomials (`exact_events::raise_substep_peaks`).
//! What the tests cannot decide (every switch) goes to the event path
//! (`exact_events.rs`) for the rest of that sample interval. What is exact
//! there is exact here: the same map, the structure's input and viscous
//! work from the same forms (summed per run), and the upper clusters'
//! input work in closed form per run.

use super::exact_events::raise_substep_peaks;
use super::exact_map::{dot, ExactMap};
use super::folded::{in_band_proved, raise_peak_proved, slip_guard_proved, structure_peaks_proved};
use super::lean::safe_accel_band;
use super::{move_bodies, Excitation, SimError, Simulator};
use crate::physics::hermite;
use crate::physics::mode::Guard;
use crate::physics::params::MAX_BODIES;

/// Whole samples of a record, from the simulator's current time
/// (`time[0]`) to `time[last]`: the ground acceleration is `scale *
/// accel[k] + ag_offset` at `time[k]`, linear in between; `fext` is
/// constant.
#[derive(Clone, Copy, Debug)]
pub struct Samples<'a> {
    /// Sample times (s), `time[0]` the simulator's current time.
    pub time: &'a [f64],
    /// The record's accelerations at those times (m/s²).
    pub accel: &'a [f64],
    /// Factor on the record.
    pub scale: f64,
    /// Held ground acceleration added to the record (m/s²).
    pub ag_offset: f64,
    /// Held external force on the structure (N).
    pub fext: f64,
    /// The record's spacing (its first interval).
    pub dt: f64,
}

impl Samples<'_> {
    #[inline(always)]
    fn ag(&self, k: usize) -> f64 {
        self.scale * self.accel[k] + self.ag_offset
    }

    /// The piece of sample interval `k` from `t` on, for the general path.
    pub fn piece(&self, k: usize, t: f64) -> (f64, Excitation) {
        let (t0, t1) = (self.time[k], self.time[k + 1]);
        let slope = self.scale * (self.accel[k + 1] - self.accel[k]) / (t1 - t0);
        let exc = Excitation {
            ag: self.ag(k) + slope * (t - t0),
            ag_rate: slope,
            fext: self.fext,
            fext_rate: 0.0,
        };
        (t1, exc)
    }

    /// Whether interval `k` is `dt` long up to the rounding of its times.
    #[inline(always)]
    fn is_uniform(&self, k: usize) -> bool {
        let (t0, t1) = (self.time[k], self.time[k + 1]);
        ((t1 - t0) - self.dt).abs() <= 1e-15 * (t1.abs() + self.dt)
    }

    /// The first interval from `k` on (before `last`) that is not `dt`
    /// long, or `last`: checked 32 at a time without stopping inside a
    /// block, which the compiler can vectorize.
    fn first_irregular(&self, mut k: usize, last: usize) -> usize {
        const BLOCK: usize = 32;
        while k + BLOCK <= last {
            if !(k..k + BLOCK).fold(true, |all, i| all & self.is_uniform(i)) {
                break;
            }
            k += BLOCK;
        }
        (k..last).find(|&i| !self.is_uniform(i)).unwrap_or(last)
    }
}

/// Where a run of the loop stopped: sample `k`, after `sub` of its substeps.
struct Stop {
    k: usize,
    sub: usize,
}

/// Sums over a run of the products `z_i z_j` and of `z_i`, for the
/// substeps' start vectors `z = [u, v, p, p']` (one map, one mode): the
/// structure cluster's viscous and input work are quadratic in `z`, so
/// their sums over the run follow from these at its end, instead of two
/// quadratic forms per substep.
#[derive(Default)]
struct WorkSums {
    /// Packed as `ExactMap::quad`: 00, 11, 22, 33, 01, 02, 03, 12, 13, 23.
    products: [f64; 10],
    linear: [f64; 4],
}

impl WorkSums {
    #[inline(always)]
    fn add(&mut self, z: &[f64; 4]) {
        let (s, [z0, z1, z2, z3]) = (&mut self.products, *z);
        s[0] += z0 * z0;
        s[1] += z1 * z1;
        s[2] += z2 * z2;
        s[3] += z3 * z3;
        s[4] += z0 * z1;
        s[5] += z0 * z2;
        s[6] += z0 * z3;
        s[7] += z1 * z2;
        s[8] += z1 * z3;
        s[9] += z2 * z3;
        for (l, x) in self.linear.iter_mut().zip(z) {
            *l += x;
        }
    }

    /// `Σ ∫ v² dτ`: the sum of `ExactMap::int_v2` over the substeps.
    fn int_v2(&self, map: &ExactMap) -> f64 {
        map.quad
            .iter()
            .zip(&self.products)
            .map(|(q, s)| q * s)
            .sum()
    }

    /// The input work per unit mass, summed: per substep
    /// `(p - L) (u1 - u) + p' (h u1 - ∫u)` with `u1 = U z` (as `folded`),
    /// `L` the mode's load per unit mass.
    fn input(&self, map: &ExactMap, load_accel: f64) -> f64 {
        let (s, l, u) = (&self.products, &self.linear, &map.u);
        let h = map.h;
        // Σ (p - L) (U z - u): the rows times the sums of p z_j and of z_j,
        // with U's first entry less one (the `- u`).
        let u0m1 = u[0] - 1.0;
        let with_p = u0m1 * s[5] + u[1] * s[7] + u[2] * s[2] + u[3] * s[9];
        let with_1 = u0m1 * l[0] + u[1] * l[1] + u[2] * l[2] + u[3] * l[3];
        // Σ p' (h U - I) z.
        let w: [f64; 4] = std::array::from_fn(|j| h * u[j] - map.int_u[j]);
        let with_rate = w[0] * s[6] + w[1] * s[8] + w[2] * s[9] + w[3] * s[3];
        with_p - load_accel * with_1 + with_rate
    }
}

impl Simulator {
    /// Whether [`Simulator::advance_samples`] applies: the default method,
    /// inputs held constant (no slopes).
    pub fn takes_samples(&self, extra: &Excitation) -> bool {
        self.exact && extra.ag_rate == 0.0 && extra.fext_rate == 0.0
    }

    /// Advances over the samples of `s` (the simulator is at `s.time[0]`),
    /// as `advance_pieces` would over their pieces, up to rounding.
    pub fn advance_samples(&mut self, s: &Samples<'_>) -> Result<(), SimError> {
        let last = s.time.len() - 1;
        if last == 0 {
            return Ok(());
        }
        // A jump of Fext at the start, and the checks, as a piece's start.
        let (t1, exc) = s.piece(0, self.t);
        self.begin_piece(t1, &exc)?;
        let n_sub = super::substeps(s.dt, self.map_step()) as usize;
        let mut k = 0;
        // Runs go up to the next interval that is not `dt` long.
        let mut uniform_to = k;
        while k < last {
            if uniform_to <= k {
                uniform_to = s.first_irregular(k, last);
            }
            let stop = if k < uniform_to {
                self.sample_run(s, k, uniform_to, n_sub)
            } else {
                Stop { k, sub: 0 }
            };
            if stop.k >= last {
                break;
            }
            // The event path takes the rest of that sample interval.
            let (t1, exc) = s.piece(stop.k, self.t);
            self.exact_interval(t1, &exc)?;
            self.check_work()?;
            k = stop.k + 1;
        }
        self.t = s.time[last];
        self.ag_now = s.ag(last);
        self.fext_now = s.fext;
        self.check_finite()
    }

    /// From now to `t1` (the rest of a sample interval the loop could not
    /// take) on the event path directly: the fast path's proofs are the
    /// loop's, and would fail there too.
    fn exact_interval(&mut self, t1: f64, exc: &Excitation) -> Result<(), SimError> {
        let mut piece = self.begin_piece(t1, exc)?;
        while piece.i <= piece.n {
            self.exact_substep(piece.end_of(piece.i), &piece);
            piece.i += 1;
        }
        self.end_piece(&piece);
        Ok(())
    }

    fn sample_run(&mut self, s: &Samples<'_>, k: usize, last: usize, n_sub: usize) -> Stop {
        if n_sub == 1 {
            self.sample_run_nc::<true>(s, k, last, n_sub)
        } else {
            self.sample_run_nc::<false>(s, k, last, n_sub)
        }
    }

    fn sample_run_nc<const ONE: bool>(
        &mut self,
        s: &Samples<'_>,
        k: usize,
        last: usize,
        n_sub: usize,
    ) -> Stop {
        match self.dynamics.n_clusters {
            1 => self.sample_run_clusters::<1, ONE>(s, k, last, n_sub),
            2 => self.sample_run_clusters::<2, ONE>(s, k, last, n_sub),
            3 => self.sample_run_clusters::<3, ONE>(s, k, last, n_sub),
            4 => self.sample_run_clusters::<4, ONE>(s, k, last, n_sub),
            5 => self.sample_run_clusters::<5, ONE>(s, k, last, n_sub),
            6 => self.sample_run_clusters::<6, ONE>(s, k, last, n_sub),
            7 => self.sample_run_clusters::<7, ONE>(s, k, last, n_sub),
            8 => self.sample_run_clusters::<8, ONE>(s, k, last, n_sub),
            _ => self.sample_run_clusters::<MAX_BODIES, ONE>(s, k, last, n_sub),
        }
    }

    /// Takes the substeps of samples `k..last` on the exact map, in the
    /// current mode with `NC` clusters (cluster 0 the structure's), until a
    /// quick test fails; commits what it took and returns where it stopped.
    /// `ONE`: one substep per sample interval (`n_sub == 1`).
    fn sample_run_clusters<const NC: usize, const ONE: bool>(
        &mut self,
        s: &Samples<'_>,
        k_start: usize,
        last: usize,
        n_sub: usize,
    ) -> Stop {
        let h = s.dt / n_sub as f64;
        let (sys, d) = (&self.sys, &self.dynamics);
        let map_index = self.maps.index(sys, d.mass[0], h);
        let map: &ExactMap = self.maps.get(map_index);
        let guards = &d.guards[..d.n_guards];
        let (band_lo, band_hi) = safe_accel_band(guards);
        let has_band = guards.iter().any(|g| matches!(g, Guard::Stuck { .. }));
        let mut slip_sign = [0.0; NC];
        for g in guards {
            if let Guard::Slip { lo, sign, .. } = *g {
                slip_sign[lo] = sign;
            }
        }
        let iface: [usize; NC] = std::array::from_fn(|m| {
            if NC > 1 {
                d.moving[m.min(NC.saturating_sub(2))].j
            } else {
                0
            }
        });
        // Constants of the run: the structure cluster's forcing per unit
        // mass is `cf - ag`, its absolute acceleration `cf - w2 u - cm v`.
        let fm = s.fext * d.inv_mass0;
        let cf = d.slip_load[0] * d.inv_mass0 + fm;
        let (w2, cm, inv_h) = (map.w2, map.cm, 1.0 / h);
        let inv_n = 1.0 / n_sub as f64;
        // Degree of the Taylor polynomials of a substep (exact peaks).
        let degree = map.degree;
        let accel_c: [f64; NC] = std::array::from_fn(|c| d.accel_const[c]);
        let dv_c = accel_c.map(|a| h * a);
        let du_c = accel_c.map(|a| 0.5 * h * h * a);

        let mut u0 = self.u[0];
        let mut vel: [f64; NC] = std::array::from_fn(|c| self.v[d.bottom[c]]);
        let vel_start = vel;
        let mut slip: [f64; NC] = std::array::from_fn(|m| {
            let j = iface[m];
            if NC > 1 {
                self.u[j] - self.u[j - 1]
            } else {
                0.0
            }
        });
        let slip_start = slip;
        let mut shift = [0.0; NC];
        let mut peak_slip: [f64; NC] = std::array::from_fn(|m| self.peak_slip[iface[m]]);
        let (mut peak_u0, mut peak_a0) = (self.peak_u0, self.peak_a0);
        let mut work = WorkSums::default();
        let mut a_abs = cf - w2 * u0 - cm * vel[0];
        let mut taken = 0u64;
        let mut stop = Stop { k: last, sub: 0 };

        let mut k = k_start;
        let mut a_s = s.ag(k);
        'samples: while k < last {
            let ag_next = s.ag(k + 1);
            let dag = if ONE { 0.0 } else { (ag_next - a_s) * inv_n };
            for sub in 0..(if ONE { 1 } else { n_sub }) {
                let a_e = if ONE || sub + 1 == n_sub {
                    ag_next
                } else {
                    a_s + dag
                };
                let dp = (a_s - a_e) * inv_h;
                let z = [u0, vel[0], cf - a_s, dp];
                let (u1, v1) = (dot(&map.u, &z), dot(&map.v, &z));
                let a1 = cf - w2 * u1 - cm * v1;
                let s3 = map.sup_v(3, &z);
                // Stuck interfaces: the absolute acceleration stays in the
                // band. Rates: A' = -w2 v - cm (A - ag) (no slope of Fext here).
                let ends = [a_abs, a1];
                let jerks = || {
                    let j0 = -w2 * vel[0] - cm * (a_abs - a_s);
                    [j0, -w2 * v1 - cm * (a1 - a_e)]
                };
                if has_band && !in_band_proved(ends, jerks, h, s3, [band_lo, band_hi]) {
                    stop = Stop { k, sub };
                    break 'samples;
                }
                // Upper clusters: exact polynomials; the ground's terms are
                // common to all.
                let g1 = 0.5 * h * (a_s + a_e);
                let g2 = h * h * (a_s / 3.0 + a_e / 6.0);
                let (mut du, mut v_end) = ([0.0; NC], [0.0; NC]);
                (du[0], v_end[0]) = (u1 - u0, v1);
                for c in 1..NC {
                    du[c] = h * vel[c] + du_c[c] - g2;
                    v_end[c] = vel[c] + dv_c[c] - g1;
                }
                let ag_rate = -dp;
                let s2 = if NC > 1 { map.sup_v(2, &z) } else { 0.0 };
                for m in 0..NC - 1 {
                    let sign = slip_sign[m];
                    if sign == 0.0 {
                        continue;
                    }
                    let (g0, g1) = (
                        sign * (vel[m + 1] - vel[m]),
                        sign * (v_end[m + 1] - v_end[m]),
                    );
                    let holds = if m == 0 {
                        let rates = || [sign * (accel_c[1] - a_abs), sign * (accel_c[1] - a1)];
                        slip_guard_proved([g0, g1], rates, h, s2 + ag_rate.abs())
                    } else {
                        // Linear in time between two upper clusters.
                        g0 >= 0.0 && g1 > 0.0
                    };
                    if !holds {
                        stop = Stop { k, sub };
                        break 'samples;
                    }
                }
                // Peaks of |u0| and |A0|; where the bounds cannot exclude a
                // new one inside, on the polynomials.
                let peaks = [&mut peak_u0, &mut peak_a0];
                let [u_proved, a_proved] =
                    structure_peaks_proved(map, &z, [u1, v1], ends, jerks, h, s3, peaks);
                if !(u_proved && a_proved) {
                    let peaks = [
                        (!u_proved).then_some(&mut peak_u0),
                        (!a_proved).then_some(&mut peak_a0),
                    ];
                    let rates = [w2, cm, cf];
                    if raise_substep_peaks(peaks, z, h, rates, degree, [u1, a1]).is_err() {
                        stop = Stop { k, sub };
                        break 'samples;
                    }
                }
                // Slips. One whose guard was proved above keeps its
                // direction: it peaks at an end. Otherwise (a free
                // interface) slip''' = -(ag' + v0''), slip'''' = -v0''' at the
                // structure; a quadratic in time between upper clusters.
                let mut new_slip = slip;
                for m in 0..NC - 1 {
                    let increment = du[m + 1] - du[m];
                    let (vr0, vr1) = (vel[m + 1] - vel[m], v_end[m + 1] - v_end[m]);
                    new_slip[m] = slip[m] + increment;
                    let ends = [slip[m], vr0, new_slip[m], vr1];
                    if slip_sign[m] != 0.0 {
                        let (e0, e1) = (slip[m].abs(), new_slip[m].abs());
                        let end = if e0 > e1 { e0 } else { e1 };
                        if end > peak_slip[m] {
                            peak_slip[m] = end;
                        }
                    } else if m == 0 {
                        let third = s2 + ag_rate.abs();
                        if !raise_peak_proved(&mut peak_slip[m], ends, h, s3, || third) {
                            stop = Stop { k, sub };
                            break 'samples;
                        }
                    } else {
                        let (y0, y1) = (ends[0], ends[2]);
                        hermite::raise_peak(&mut peak_slip[m], y0, vr0, y1, vr1, h);
                    }
                }
                // Taken.
                work.add(&z);
                slip = new_slip;
                for c in 1..NC {
                    shift[c] += du[c];
                }
                (u0, vel, a_abs, a_s) = (u1, v_end, a1, a_e);
                taken += 1;
            }
            k += 1;
        }

        if taken > 0 {
            let d = &self.dynamics;
            // Input work on the upper clusters over the run, exact: with
            // v_c' = A_c - ag, -m ag v_c = d(m v_c²/2)/dt - m A_c v_c.
            let mut upper = 0.0;
            for c in 1..NC {
                let m = d.mass[c];
                upper += 0.5 * m * (vel[c] * vel[c] - vel_start[c] * vel_start[c])
                    - m * accel_c[c] * shift[c];
            }
            let map = self.maps.get(map_index);
            let load_accel = d.slip_load[0] * d.inv_mass0;
            self.e_input += d.mass[0] * work.input(map, load_accel) + upper;
            self.e_viscous += self.sys.c * work.int_v2(map);
            let (mut shift_all, mut vel_all) = ([0.0; MAX_BODIES], [0.0; MAX_BODIES]);
            shift_all[..NC].copy_from_slice(&shift);
            vel_all[..NC].copy_from_slice(&vel);
            move_bodies(
                &mut self.u,
                &mut self.v,
                d,
                self.sys.n,
                u0,
                &shift_all,
                &vel_all,
            );
            for m in 0..NC - 1 {
                let j = iface[m];
                self.e_friction[j] -= d.slip_force[j] * (slip[m] - slip_start[m]);
                self.peak_slip[j] = peak_slip[m];
            }
            self.peak_u0 = peak_u0;
            self.peak_a0 = peak_a0;
            self.stats.steps += taken;
            self.t = s.time[stop.k] + stop.sub as f64 * h;
        }
        stop
    }
}
