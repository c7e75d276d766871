//! Peaks between steps: the largest |p| of the cubic Hermite interpolant
//! through two step ends. Sampling only at step ends is O(h^2) accurate for a
//! peak; the cubic keeps it at the method's order.

/// Raises `peak` to the largest |p| of the cubic (as [`max_abs`]) when that
/// is larger. Returns at once, without solving for the cubic's extrema,
/// when it cannot exceed `peak`: the Hermite basis bounds |p| by
/// max(|y0|, |y1|) + 4/27 h (|d0| + |d1|). This test is all that most steps
/// cost, so it is kept to plain comparisons.
#[inline(always)]
pub fn raise_peak(peak: &mut f64, y0: f64, d0: f64, y1: f64, d1: f64, h: f64) {
    let (a0, a1) = (y0.abs(), y1.abs());
    let ends = if a0 > a1 { a0 } else { a1 };
    if ends + 4.0 / 27.0 * h * (d0.abs() + d1.abs()) <= *peak {
        return;
    }
    let largest = max_abs(y0, d0, y1, d1, h);
    if largest > *peak {
        *peak = largest;
    }
}

/// Largest |p(θ)| over θ in [0, 1] for the cubic with values `y0`, `y1` and
/// time derivatives `d0`, `d1` at the ends of a step of length `h`. Out of
/// line: [`raise_peak`] calls it on a few steps only.
#[inline(never)]
pub fn max_abs(y0: f64, d0: f64, y1: f64, d1: f64, h: f64) -> f64 {
    let b = h * d0;
    let c = 3.0 * (y1 - y0) - h * (2.0 * d0 + d1);
    let d = 2.0 * (y0 - y1) + h * (d0 + d1);
    let p = |t: f64| y0 + t * (b + t * (c + t * d));
    let mut best = y0.abs().max(y1.abs());
    // p'(θ) = b + 2cθ + 3dθ² = 0
    let (qa, qb, qc) = (3.0 * d, 2.0 * c, b);
    let mut consider = |t: f64| {
        if t > 0.0 && t < 1.0 {
            best = best.max(p(t).abs());
        }
    };
    if qa.abs() <= 1e-14 * (qb.abs() + qc.abs()) {
        if qb != 0.0 {
            consider(-qc / qb);
        }
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            // Stable quadratic roots.
            let q = -0.5 * (qb + qb.signum() * disc.sqrt());
            if q != 0.0 {
                consider(q / qa);
                consider(qc / q);
            } else {
                consider(0.0);
            }
        }
    }
    best
}
