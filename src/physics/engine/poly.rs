//! Polynomials of the exact motion over a stretch, `Σ c[k] s^k` on
//! `s ∈ [0, 1]`: evaluation, bounds of their derivatives, the first zero of
//! a guard with a proof that none comes before it ([`first_zero`]), the
//! largest `|y|` over a stretch ([`raise_peak_exact`]), and the integrals
//! the work terms need. Used by the event path (`exact_events.rs`) and, for
//! peaks, by the one driver (`sweep.rs`).

use super::proofs::stays_positive;

/// Coefficients of a polynomial (degree at most `exact_map`'s largest, plus
/// the integral's one).
pub(super) const N_COEF: usize = 24;

/// Evaluations [`first_zero`] may spend on one guard before it gives up
/// (a guard hovering at rounding level over the substep); the substep is
/// then taken in fine stretches of the exact motion (`exact_events`).
const EVALUATION_BUDGET: u32 = 400;

/// Width (fraction of a stretch) to which a peak's critical point is
/// located: the peak is then within `sup|y''| δ² / 2`, below 1e-15 of it
/// (`|y''| <= (ω H)² |y|`-sized over a stretch with `ω H <= 0.5`).
pub(super) const PEAK_TOL: f64 = 1e-7;

/// Critical points of a peak's polynomial looked at in one stretch (its
/// derivative changes sign at most a few times over `ω H <= 0.5`).
const MAX_CRITICAL_POINTS: usize = 8;

/// `[k (k - 1), k - 2]` for k = 2.. ([`Poly::bound`]'s factors, exact).
const FALLING_2: [[f64; 2]; N_COEF] = {
    let (mut f, mut k) = ([[0.0; 2]; N_COEF], 2);
    while k < N_COEF {
        (f[k], k) = ([(k * (k - 1)) as f64, k as f64 - 2.0], k + 1);
    }
    f
};

/// A polynomial `Σ c[k] s^k` on `s ∈ [0, 1]`.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Poly {
    pub(super) c: [f64; N_COEF],
    pub(super) deg: usize,
}

impl Poly {
    /// A bound of `|p''|` (`n` = 2) or `|p'''|` (3) over [0, 1] (triangle
    /// inequality; the factor covers the rounding of the coefficients and
    /// of the sums).
    pub(super) fn bound(&self, n: usize) -> f64 {
        let (mut m, top) = (0.0, self.deg + 1);
        for (c, [k2, k]) in self.c[top.min(2)..top].iter().zip(&FALLING_2[2..]) {
            let term = k2 * c.abs();
            m += if n == 2 { term } else { term * k };
        }
        m * (1.0 + 1e-12)
    }

    /// `Σ_(k >= 1) |c_k| s^k`: a bound of `|p(σ) - p(0)|` over `[0, s]`.
    pub(super) fn spread(&self, s: f64) -> f64 {
        let rest = &self.c[1..=self.deg];
        rest.iter().rev().fold(0.0, |y, c| (y + c.abs()) * s)
    }

    /// `Σ_(k > n) k!/(k-n)! |c_k| s^(k-n)`, n = 1 or 2: the [`Poly::spread`]
    /// of the n-th derivative, a bound of `|p^(n) - p^(n)(0)|` over `[0, s]`.
    pub(super) fn rate_spread(&self, n: usize, s: f64) -> f64 {
        let (mut y, mut k) = (0.0, self.deg as f64);
        for c in self.c[n + 1..self.deg + 1].iter().rev() {
            let f = if n == 1 { k } else { k * (k - 1.0) };
            y = (y + (f * c).abs()) * s;
            k -= 1.0;
        }
        y
    }

    pub(super) fn negate(&mut self) {
        for c in &mut self.c[..=self.deg] {
            *c = -*c;
        }
    }

    /// Sets `self` to `sign p + offset` (its coefficients past the degree
    /// are never read: left as they are).
    #[inline]
    pub(super) fn set_affine(&mut self, p: &Poly, sign: f64, offset: f64) {
        for (c, pk) in self.c[..=p.deg].iter_mut().zip(&p.c) {
            *c = sign * pk;
        }
        self.c[0] += offset;
        self.deg = p.deg;
    }

    /// For a guard that is zero at `s = 0` up to rounding: `p / s^m` in
    /// place, `m` its leading coefficients at rounding level (at most
    /// three), which has the zeros of `p` in (0, 1]. False (`self`
    /// unchanged) when the first coefficient left is negative: the guard
    /// does not grow from its zero.
    pub(super) fn divide_zero_start(&mut self) -> bool {
        let scale: f64 = self.c[1..self.deg + 1].iter().map(|c| c.abs()).sum();
        let m = (0..self.deg.min(3) + 1).find(|&k| self.c[k].abs() > 1e-12 * scale);
        let Some(m) = m.filter(|&m| self.c[m] >= 0.0) else {
            return false;
        };
        self.c.copy_within(m..=self.deg, 0);
        self.deg -= m;
        true
    }

    pub(super) fn coefs(&self) -> &[f64] {
        &self.c[..=self.deg]
    }

    #[inline]
    pub(super) fn eval(&self, s: f64) -> f64 {
        let (top, rest) = self.c[..=self.deg].split_last().unwrap();
        rest.iter().rev().fold(*top, |y, c| y * s + c)
    }

    /// Value and derivative at `s` (inlined: at `s = 1` the products by 1 fold away).
    #[inline]
    pub(super) fn eval_d(&self, s: f64) -> (f64, f64) {
        let (top, rest) = self.c[..=self.deg].split_last().unwrap();
        let (mut y, mut d) = (*top, 0.0);
        for c in rest.iter().rev() {
            d = d * s + y;
            y = y * s + c;
        }
        (y, d)
    }

    pub(super) fn derivative(&self) -> Poly {
        let mut c = [0.0; N_COEF];
        for k in 1..self.deg + 1 {
            c[k - 1] = k as f64 * self.c[k];
        }
        Poly {
            c,
            deg: self.deg.max(1) - 1,
        }
    }
}

/// Why a guard or a peak could not be decided within the budget.
#[derive(Debug, PartialEq)]
pub(super) struct Undecided;

/// The first zero of `g` in `(a, e]`, where `g(a) = ga >= 0` with rate `da`
/// (`ga = 0` only for a guard that grows from a zero): `None` when `g > 0`
/// over `(a, e]` is proved (with [`Poly::bound`]s, each computed where it
/// is first needed: most searches need one). `tol` is the width below which a stretch is
/// not split further: a sign change there is the zero, and a dip below zero
/// and back inside it is not seen (a graze).
#[inline(always)]
pub(super) fn first_zero(
    g: &Poly,
    [mut a, mut ga, mut da]: [f64; 3],
    e: f64,
    tol: f64,
) -> Result<Option<f64>, Undecided> {
    let mut width = e - a;
    let (mut evaluations, mut m2, mut m3) = (0, None, None);
    while a < e {
        evaluations += 1;
        if evaluations > EVALUATION_BUDGET {
            return Err(Undecided);
        }
        let b = if a + width >= e { e } else { a + width };
        let l = b - a;
        let (gb, db) = if b < 1.0 { g.eval_d(b) } else { g.eval_d(1.0) };
        if gb > 0.0 {
            let m2 = *m2.get_or_insert_with(|| g.bound(2));
            if l <= tol || stays_positive([ga, da, gb, db], l, m2) {
                (a, ga, da) = (b, gb, db);
                width = 2.0 * l;
                continue;
            }
        } else {
            // g' < 0 over the stretch (it stays within l²/8 sup|g'''| of its
            // linear interpolation): a single crossing.
            let m3 = *m3.get_or_insert_with(|| g.bound(3));
            let falling = -da.max(db) > 0.125 * l * l * m3;
            if l <= tol || falling {
                return Ok(Some(refine(g, [a, ga], [b, gb], [tol, 0.0])));
            }
        }
        width = 0.5 * l;
    }
    Ok(None)
}

/// The zero of `g` between `a` (g > 0) and `b` (g <= 0), where it is the
/// only one: Newton's method kept inside the bracket (bisection when it
/// leaves it), to well below `tol`; the instant returned is past the zero
/// by at most `tol`, where `g <= 0`. For a peak, `|g(x)| < near = m1 tol`
/// with `|g'| >= m1` ends it at `x`, within `tol` of the zero.
#[inline(always)]
fn refine(g: &Poly, [mut a, ga]: [f64; 2], [mut b, gb]: [f64; 2], [tol, near]: [f64; 2]) -> f64 {
    // Newton's last step, and how far past its zero a switch is placed.
    let past = 1e-3 * tol;
    // The secant, or the middle from a start clamped at zero.
    let mut x = if ga > 0.0 {
        a + ga / (ga - gb) * (b - a)
    } else {
        0.5 * (a + b)
    };
    for _ in 0..100 {
        if b - a <= tol {
            return b;
        }
        let (gx, dx) = g.eval_d(x);
        if gx.abs() < near {
            return x;
        } else if gx > 0.0 {
            a = x;
        } else if gx < 0.0 {
            b = x;
        } else {
            return (x + past).min(b);
        }
        let mut next = x - gx / dx;
        if !(next > a && next < b) {
            next = 0.5 * (a + b);
        }
        if (next - x).abs() <= past {
            // Just past the zero, where the guard has changed sign and one reaching zero at the
            // same instant up to rounding (equal frictions) fires with it; no further: the motion
            // up to there runs in the old mode (half `tol`, 5e-13 s, was the largest error left).
            return (next + past).min(b);
        }
        x = next;
    }
    b
}

/// Raises `peak` to the largest `|y|` over `[0, e]`: at the ends (`y_end`
/// the value at `e`), or where `y'` changes sign. `spread` bounds
/// `|y - y(0)|` over `[0, 1]` (`Poly::spread`): when it keeps `|y|` below
/// the peak, nothing else is computed. `rate`: a positive multiple of `y'`
/// when the caller has one (`v` for `u`), else `y'` is built.
#[inline]
pub(super) fn raise_peak_exact(
    peak: &mut f64,
    y: &Poly,
    rate: Option<&Poly>,
    [y_end, spread]: [f64; 2],
    e: f64,
    tol: f64,
) -> Result<(), Undecided> {
    let ends = y.c[0].abs().max(y_end.abs());
    let least = if ends > *peak { ends } else { *peak };
    if y.c[0].abs() + spread <= least || y.c[0].abs() + y.spread(e) <= least {
        *peak = least;
        return Ok(());
    }
    raise_peak_inside(peak, y, rate, y_end, e, tol)
}

/// [`raise_peak_exact`] where its bounds leave an interior peak possible,
/// or at once for a caller whose own bounds have: out of line, so that the
/// usual case (the bounds decide) is a few instructions at its callers.
#[inline(never)]
pub(super) fn raise_peak_inside(
    peak: &mut f64,
    y: &Poly,
    rate: Option<&Poly>,
    y_end: f64,
    e: f64,
    tol: f64,
) -> Result<(), Undecided> {
    *peak = peak.max(y.c[0].abs()).max(y_end.abs());
    let derivative;
    let dy = match rate {
        Some(rate) => rate,
        None => {
            derivative = y.derivative();
            &derivative
        }
    };
    // The common case first, one critical point: y' changes sign between
    // the ends, and over [0, e] |y''| >= m1 > 0 or y''' keeps its sign (y'
    // convex or concave: it crosses zero once).
    let (d0, d_end) = (dy.c[0], dy.eval(e));
    if d0 * d_end < 0.0 && dy.deg >= 2 {
        let m1 = dy.c[1].abs() - dy.rate_spread(1, e);
        if m1 > 0.0 || 2.0 * dy.c[2].abs() > dy.rate_spread(2, e) {
            let ends = [[0.0, d0.abs()], [e, -d_end.abs()]];
            let near = m1.max(0.0) * tol;
            let r = if d0 > 0.0 {
                refine(dy, ends[0], ends[1], [tol, near])
            } else {
                let mut g = *dy;
                g.negate(); // (its end values negated exactly too)
                refine(&g, ends[0], ends[1], [tol, near])
            };
            *peak = peak.max(y.eval(r).abs());
            return Ok(());
        }
    }
    // y' keeps its sign, or is monotone (|y''| > 0 over [0, e]) from ends of one sign: the
    // ends decide.
    let dy_spread = dy.spread(e);
    let one_sign = d0.min(d_end) >= 0.0 || d0.max(d_end) <= 0.0;
    if dy.c[0].abs() > dy_spread
        || (dy.deg >= 2 && one_sign && dy.c[1].abs() > dy.rate_spread(1, e))
    {
        return Ok(());
    }
    // The sign of y' just after 0 (y' may start at zero).
    let scale = dy.c[0].abs() + dy_spread;
    let Some(&lead) = dy.coefs().iter().find(|x| x.abs() > 1e-12 * scale) else {
        return Ok(()); // y is constant
    };
    // y' with the sign it has just after 0; searched past a zero start.
    let mut g = *dy;
    if lead < 0.0 {
        g.negate();
    }
    let mut past = g;
    let start = if g.c[0] <= 1e-12 * scale && past.divide_zero_start() {
        &past
    } else {
        &g
    };
    let (g0, d0) = start.eval_d(0.0);
    let mut zero = first_zero(start, [0.0, g0.max(0.0), d0], e, tol)?;
    for _ in 0..MAX_CRITICAL_POINTS {
        let Some(r) = zero else {
            return Ok(());
        };
        *peak = peak.max(y.eval(r).abs());
        // The next sign change of y', from the other side.
        g.negate();
        let (ga, da) = g.eval_d(r);
        zero = first_zero(&g, [r, ga.max(0.0), da], e, tol)?;
    }
    Err(Undecided)
}

/// `1 / (k + 1)` for k = 0.., to take the integrals' and the Taylor
/// terms' divisions as products.
pub(super) const INV: [f64; N_COEF + 1] = {
    let mut inv = [0.0; N_COEF + 1];
    let mut k = 0;
    while k <= N_COEF {
        inv[k] = 1.0 / (k + 1) as f64;
        k += 1;
    }
    inv
};

/// `[u(s), v(s), ∫_0^s u(σ) dσ]` of two polynomials of one degree, in one
/// pass (each Horner's sum as alone; inlined: at `s = 1` its products fold).
#[inline(always)]
pub(super) fn values_and_integral(u: &Poly, v: &Poly, s: f64) -> [f64; 3] {
    let (mut yu, mut yv, mut total) = (0.0, 0.0, 0.0);
    let terms = u.coefs().iter().zip(v.coefs()).zip(&INV).rev();
    for ((uk, vk), inv) in terms {
        (yu, yv, total) = (yu * s + uk, yv * s + vk, total * s + uk * inv);
    }
    [yu, yv, total * s]
}

/// Gauss–Legendre rules on [0, 1] as their first halves (nodes, weights: the doubles nearest
/// their 50-digit values; the rest mirrored: `1 - x`, within an ulp of the node): 6, 8 and 12
/// points, exact for polynomials of degree 11, 15 and 23.
#[rustfmt::skip]
const GAUSS_6: [[f64; 3]; 2] = [
    [0.03376524289842399, 0.16939530676686773, 0.38069040695840156],
    [0.08566224618958518, 0.1803807865240693, 0.23395696728634552],
];
#[rustfmt::skip]
const GAUSS_8: [[f64; 4]; 2] = [
    [0.019855071751231884, 0.10166676129318664, 0.2372337950418355, 0.4082826787521751],
    [0.05061426814518813, 0.11119051722668724, 0.15685332293894363, 0.181341891689181],
];
#[rustfmt::skip]
const GAUSS_12: [[f64; 6]; 2] = [
    [0.009219682876640375, 0.04794137181476257, 0.11504866290284765,
        0.2063410228566913, 0.3160842505009099, 0.43738329574426554],
    [0.023587668193255914, 0.05346966299765921, 0.08003916427167311,
        0.10158371336153296, 0.1167462682691774, 0.12457352290670139],
];

/// `∫_0^s v(σ)² dσ` for the structure's velocity `v` over a stretch, a Taylor polynomial of degree
/// `deg` ([`super::exact_map::degree`]), by a Gauss rule: 6 points for `deg <= 9` (`ρ = h (ω +
/// c/m) <= 0.0692`), 8 for `deg <= 14` (`ρ <= 0.551`), else 12. As `v'' + (c/m) v' + ω² v` is
/// constant (a load linear in time), `v` is set by `v(0)`, `v'(0)`, `v''(0)`: the largest ratio of
/// the rule's error to the integral over them (a generalized eigenvalue, 50 digits, ζ 0 to 0.999,
/// each rule's largest `ρ`) is 1.4e-19 (6 points), 1.9e-20 (8), 1.9e-25 (12); sums round at ulps.
#[inline]
pub(super) fn integral_of_square(p: &Poly, s: f64) -> f64 {
    if p.deg <= 9 {
        gauss_square(p, s, GAUSS_6)
    } else if p.deg <= 14 {
        gauss_square(p, s, GAUSS_8)
    } else {
        gauss_square(p, s, GAUSS_12)
    }
}

/// [`integral_of_square`] by the rule of `2 H` points given by its half.
#[inline(always)]
fn gauss_square<const H: usize>(p: &Poly, s: f64, [nodes, weights]: [[f64; H]; 2]) -> f64 {
    let (x, x_mirror) = (nodes.map(|x| x * s), nodes.map(|x| (1.0 - x) * s));
    let (mut y, mut y_mirror) = ([0.0; H], [0.0; H]);
    for &c in p.coefs().iter().rev() {
        for i in 0..H {
            y[i] = y[i] * x[i] + c;
            y_mirror[i] = y_mirror[i] * x_mirror[i] + c;
        }
    }
    let mut total = 0.0;
    for i in 0..H {
        total += weights[i] * (y[i] * y[i] + y_mirror[i] * y_mirror[i]);
    }
    total * s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn poly(c: &[f64]) -> Poly {
        let mut k = [0.0; N_COEF];
        k[..c.len()].copy_from_slice(c);
        Poly {
            c: k,
            deg: c.len() - 1,
        }
    }

    /// Coefficients of `lead · Π (s - r)`.
    fn from_roots(lead: f64, roots: &[f64]) -> Poly {
        let mut c = vec![lead];
        for r in roots {
            let mut next = vec![0.0; c.len() + 1];
            for (k, x) in c.iter().enumerate() {
                next[k + 1] += x;
                next[k] -= r * x;
            }
            c = next;
        }
        poly(&c)
    }

    fn first_zero_from_start(g: &Poly) -> Option<f64> {
        let (g0, d0) = g.eval_d(0.0);
        first_zero(g, [0.0, g0, d0], 1.0, 1e-13).unwrap()
    }

    #[test]
    fn a_located_zero_is_just_past_it() {
        // Expected: for falling polynomials with one zero r in (0, 1) (built
        // from their roots), the instant returned lies in [r, r + tol] and
        // the polynomial is <= 0 there, so that a second guard crossing at
        // the same instant up to rounding has crossed too.
        let tol = 1e-12;
        let mut seed = 7u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..2000 {
            let r = 0.05 + 0.9 * next();
            // (r - s) (1 + a s + b s^2) with the second factor positive on [0, 1].
            let (a, b) = (next() - 0.5, 0.5 * next());
            let g = poly(&[r, r * a - 1.0, r * b - a, -b]);
            let x = refine(&g, [0.0, g.eval(0.0)], [1.0, g.eval(1.0)], [tol, 0.0]);
            assert!(x >= r - 1e-15 && x <= r + tol, "r {r}: x - r = {:e}", x - r);
            assert!(g.eval(x) <= 0.0, "r {r}: g(x) = {:e}", g.eval(x));
        }
    }

    #[test]
    fn the_first_of_close_zeros_is_found() {
        // Expected: the smallest root of polynomials built from their roots
        // (positive at 0), to 1e-12; a dip below zero between two roots
        // 2e-3 apart is not passed over; a graze 1e-9 above zero has none.
        let cases: [(&[f64], f64); 4] = [
            (&[0.3, 0.35, 0.8], -1.0),
            (&[0.499, 0.501], 1.0),
            (&[0.9], -2.0),
            (&[0.05, 0.0501, 0.6, 0.61], 1.0),
        ];
        for (roots, lead) in cases {
            let g = from_roots(lead, roots);
            assert!(g.eval(0.0) > 0.0);
            let s = first_zero_from_start(&g).expect("a zero");
            assert!((s - roots[0]).abs() < 1e-12, "{roots:?}: {s}");
        }
        let mut graze = from_roots(1.0, &[0.5, 0.5]);
        graze.c[0] += 1e-9;
        assert_eq!(first_zero_from_start(&graze), None);
        // A guard at zero that grows as s²: searched past its zero start.
        let g = poly(&[0.0, 0.0, 1.0, -1.6]); // s²(1 - 1.6 s): zero at 0.625
        let mut past = g;
        assert!(past.divide_zero_start());
        assert!((first_zero_from_start(&past).unwrap() - 0.625).abs() < 1e-12);
        let mut falling = poly(&[0.0, -1.0, 3.0]);
        assert!(!falling.divide_zero_start() && falling.deg == 2);
        // A guard hovering 1e-18 above zero over a stretch of ~0.01
        // (1e-18 + 1e-3 (s - 0.5)^6): no proof reaches across it within
        // the budget, and the search says so instead of guessing.
        let mut hover = from_roots(1e-3, &[0.5; 6]);
        hover.c[0] += 1e-18;
        let (g0, d0) = hover.eval_d(0.0);
        assert_eq!(
            first_zero(&hover, [0.0, g0, d0], 1.0, 1e-13),
            Err(Undecided)
        );
    }
}
