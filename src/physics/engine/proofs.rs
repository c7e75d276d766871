//! The proofs that a substep of the exact map holds no switch and no
//! unseen peak, from its ends and the map's derivative bounds:
//!
//! - no guard changes sign: a guard `g` positive at both ends stays above
//!   their linear interpolation minus `h²/8 sup|g''|`, and `sup|g''|` is
//!   bounded from the substep's start state by the map's derivative bounds
//!   (`ExactMap::sup_v_abs`), so `min(g(0), g(h)) > h²/8 sup|g''|` excludes a
//!   crossing, a double one included; where that is too coarse, Taylor's
//!   bounds from both ends ([`stays_positive`]);
//! - no peak is missed: `|y|` is bounded by the cubic Hermite interpolant
//!   through the ends (exact values and derivatives) plus its remainder
//!   `h⁴/384 sup|y''''|`; a `y` proved monotone peaks at an end.
//!
//! The driver (`sweep.rs`) takes a substep only when these hold.

use super::exact_map::{ExactMap, MAP_H_OMEGA};
use super::Simulator;
use crate::physics::hermite;

/// Raises `peak` to the largest `|y|` over a substep of length `h` with end values `y0`, `y1` and
/// rates `d0`, `d1`, when that can be proved from the ends: `fourth` bounds `|y''''|` over the
/// substep and `third()` `|y'''|`. False when a new peak inside the substep cannot be excluded (the
/// caller then takes the substep on the general path).
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
    // Monotone: y' stays within h²/8 sup|y'''| of its linear interpolation, so it keeps its sign
    // when both ends exceed that (a peak rising with the motion, the usual case here).
    if d0 * d1 > 0.0 && d0.abs().min(d1.abs()) > 0.125 * h2 * third() {
        if ends > *peak {
            *peak = ends;
        }
        return true;
    }
    // The cubic's maximum is at least `ends`: above the peak, no bound can hold.
    ends + rest <= *peak && cubic_below(*peak, [y0, d0, y1, d1], h, rest)
}

/// Whether the cubic through the ends plus `rest` stays at or below `peak`.
#[inline(never)]
fn cubic_below(peak: f64, [y0, d0, y1, d1]: [f64; 4], h: f64, rest: f64) -> bool {
    hermite::max_abs(y0, d0, y1, d1, h) + rest <= peak
}

/// How long a guard linear in time, `g0 + rate t` (`t` in the rate's unit), stays positive from its
/// start: `INFINITY` where it never falls, `0` where it is not positive just after the start (at
/// zero it must grow). A guard between two clusters above the structure's is linear: their absolute
/// accelerations are constant in a mode.
#[inline(always)]
pub(super) fn linear_guard_lasts(g0: f64, rate: f64) -> f64 {
    if g0 >= 0.0 && rate >= 0.0 && g0 + rate > 0.0 {
        f64::INFINITY
    } else if g0 > 0.0 && rate < 0.0 {
        g0 / -rate
    } else {
        0.0
    }
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

/// The quick test of the slip guard between the structure's cluster and the one above over a
/// substep of length `h`: its ends `g0`, `g1` (the signed relative velocity) both above `h²/8` of
/// the coarse bound `|g''| <= sup|v0''| + |ag'| <= two_over_three s3 + |ag'|` (`s3` bounds
/// `|v0'''|`). Where it fails, [`slip_guard_proved`].
#[inline(always)]
pub(super) fn slip_guard_quick(map: &ExactMap, g: [f64; 2], h: f64, s3: f64, ag_rate: f64) -> bool {
    slip_guard_clear(g, h, map.two_over_three * s3 + ag_rate.abs())
}

/// Whether that slip guard stays positive where [`slip_guard_quick`] did not decide: its ends
/// `g0`, `g1`, `|g''| <= bound()`, `|g'''| <= s3`, and (only when those do not decide)
/// `rates()`: `g'` at the ends, `g''(0)`.
#[inline(always)]
pub(super) fn slip_guard_proved(
    [g0, g1]: [f64; 2],
    rates: impl FnOnce() -> [f64; 3],
    h: f64,
    s3: f64,
    bound: impl FnOnce() -> f64,
) -> bool {
    let bound = bound();
    slip_guard_clear([g0, g1], h, bound) || {
        let [d0, d1, c0] = rates();
        // A slip just begun (g0 near 0, g1 > 0): g >= g0 + τ (d0 + min(0, c0 h/2) - s3 h²/6).
        (g0 >= 0.0 && g1 > 0.0 && d0 + (0.5 * c0 * h).min(0.0) > s3 * h * h / 6.0)
            || stays_positive([g0, d0, g1, d1], h, bound)
    }
}

/// Both ends of a guard above the sag `h²/8 bound` (`|g''| <= bound`).
#[inline(always)]
fn slip_guard_clear([g0, g1]: [f64; 2], h: f64, bound: f64) -> bool {
    let sag = 0.125 * h * h * bound;
    g0 > sag && g1 > sag
}

/// Raises the structure's peaks of |u0| and |A0| over the substep from `z` (with `|z|`; end values
/// `u1`, `v1`; the absolute acceleration `a0` and `a1` at the ends, its rates `jerks()`) where that
/// is proved; returns which were: the quick tests' verdicts `quick` ([`peaks_quick`], taken by
/// the caller), else the cubic bounds.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn structure_peaks_proved(
    map: &ExactMap,
    [z, z_abs]: [&[f64; 4]; 2],
    [u1, v1]: [f64; 2],
    [a0, a1]: [f64; 2],
    jerks: impl FnOnce() -> [f64; 2],
    [h, s3]: [f64; 2],
    quick: [bool; 2],
    [peak_u0, peak_a0]: [&mut f64; 2],
) -> [bool; 2] {
    // Both at once (one branch on the usual path).
    if quick[0] & quick[1] {
        return quick;
    }
    let u_proved = quick[0]
        || raise_peak_proved(peak_u0, [z[0], z[1], u1, v1], h, s3, || {
            map.sup_v_abs(2, z_abs)
        });
    let a_proved = quick[1] || {
        let [j0, j1] = jerks();
        let fifth = map.five_over_three * s3;
        raise_peak_proved(peak_a0, [a0, j0, a1, j1], h, fifth, || {
            map.sup_v_abs(4, z_abs)
        })
    };
    [u_proved, a_proved]
}

/// The quick tests (`quick` of [`structure_peaks_proved`]) over a substep of `h` from `ends = [u0,
/// u1, A0, A1]`: the larger `|end|` plus `h²/8 sup|y''|` (`sup|u''| <= one_over_three s3`,
/// `sup|A''| = sup|v'''| <= s3`).
#[inline(always)]
pub(super) fn peaks_quick(
    map: &ExactMap,
    ends: [f64; 4],
    [h, s3]: [f64; 2],
    peaks: [f64; 2],
) -> [bool; 2] {
    let sag = 0.125 * h * h * s3;
    let larger = |a: f64, b: f64| if a.abs() > b.abs() { a.abs() } else { b.abs() };
    let u = larger(ends[0], ends[1]) + sag * map.one_over_three;
    [u <= peaks[0], larger(ends[2], ends[3]) + sag <= peaks[1]]
}

/// Whether a substep of the structure's cluster alone (its forcing `p = cf - ag` per unit mass,
/// `cf` constant) from `[u, v]` is proved free of new peaks and in the stick band by its energy,
/// `cost` bounding `∫|p|` (`h (|p(0)| + |p(h)|)/2`: `|p|` is convex on a substep). With `r =
/// sqrt(v² + w2 u²)`, `(r²/2)' = p v - cm v² <= |p| r`: `r` grows by `∫|p|` at most, and `|u| <=
/// r/ω`, `|A - cf| <= r sqrt(w2 + cm²)` must stay under the peaks and inside the band `[lo, hi]`
/// (±f64::MAX without one). Margins (1e-9) cover the rounding. `[w2, ω, 1/sqrt(w2 + cm²)]`: the
/// structure's.
#[inline(always)]
pub(super) fn energy_run(
    [w2, omega, inv_gain]: [f64; 3],
    [u, v]: [f64; 2],
    [cf, cost]: [f64; 2],
    [peak_u, peak_a, lo, hi]: [f64; 4],
) -> bool {
    let min = |a: f64, b: f64| if a < b { a } else { b }; // (f64::min's NaN rule: not needed)
    let a_room = min(min(peak_a - cf.abs(), cf - lo), hi - cf);
    let lim = min(omega * peak_u, a_room * inv_gain) * (1.0 - 1e-9);
    cost <= lim - (v * v + w2 * (u * u)).sqrt() * (1.0 + 1e-9)
}

/// Whether `g > 0` over `(0, h]` is proved from its ends (values `g0`, `g1`, rates `d0`, `d1`) and
/// `|g''| <= m2`: Taylor's bound from the start, `g(τ) >= g0 + d0 τ - m2 τ²/2`, is positive up to
/// its root `r0`, and the one from the end up to `h - r1`; together they cover the substep when
/// `r0 + r1 > h`. This admits a guard that starts at zero and grows (a contact that has just
/// switched), which the interpolation bound cannot.
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

/// The longest substep of the exact default on a prescribed support (s): a record's sample (5-20
/// ms) is then one substep, and the proofs' bounds (`h²/8 |ag'|` on a slip's rate) stay tight.
pub const PRESCRIBED_MAX_STEP: f64 = 0.02;

impl Simulator {
    /// The longest substep of the exact default: `ω h = MAP_H_OMEGA`, or `maxStep` where that is
    /// shorter (the default stays exact at any `maxStep`; a shorter one only costs more substeps).
    /// On a prescribed support (no spring, ω = 0) every motion in a piece is a polynomial of degree
    /// 3 at most and the proofs hold at any length: the substep is [`PRESCRIBED_MAX_STEP`], or
    /// `maxStep` where shorter.
    pub(super) fn map_step(&self) -> f64 {
        let h = if self.sys.omega_p > 0.0 {
            MAP_H_OMEGA / self.sys.omega_p
        } else {
            PRESCRIBED_MAX_STEP
        };
        if self.settings.max_step > 0.0 {
            h.min(self.settings.max_step)
        } else {
            h
        }
    }
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
        // Expected: y = sin(τ) over [0, 2] peaks at 1 (τ = π/2), inside: from a running peak of
        // 0.95 the substep is handed back (false); from 1 plus the remainder bound it is proved
        // (true). |y'''| and |y''''| are at most 1.
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
