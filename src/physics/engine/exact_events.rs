//! The default method's event path: a substep the fast path hands back (one that holds a switch or
//! a new interior peak) taken exactly, switches located on the exact motion.
//!
//! In one mode and one linear piece of excitation the structure's cluster is `z' = A z` over
//! `z = [u, v, p, p']` (`exact_map`), so over the rest of a substep its state is the Taylor series
//! of `exp(A τ) z`, summed to round-off (the substep keeps `ω h <= 0.5`): `u` and `v` are
//! polynomials in `s = τ / H`. The clusters above it move as exact polynomials of degree three at
//! most. Every guard is then a polynomial in `s`: a stick guard of the structure's cluster is a
//! band of its absolute acceleration, a slip guard a relative velocity.
//!
//! [`first_zero`] finds the first zero of a guard in `(0, 1]` with a proof that none comes before
//! it: a stretch is passed when Taylor's bounds from both of its ends (with a bound on `|g''|` from
//! the coefficients) keep the guard positive over it, and a sign change is refined by Newton's
//! method only on a stretch where `g' < 0` is proved (a single crossing); anything else is halved.
//! The motion is then taken to that instant with exact energies (the input work from `∫u`, the
//! viscous work from `∫v²`, both integrals of the polynomials) and exact running peaks (at the sign
//! changes of the derivative, found the same way); the guard fires, the mode is resolved, and the
//! rest of the substep continues in the new mode. Against chatter, a guard violated from the start
//! fires at once (a zero-length event), and every guard is muted after `MAX_EVENTS_PER_STEP`
//! events; an interface that fires at once twice in the substep, or a search that cannot decide
//! within its budget, hands the rest of the substep to fine stretches of the same exact motion
//! (`ω h <= 0.01`), where the contact is muted for one stretch only and an undecided search halves
//! the stretch.

use super::poly::*;
use super::*;
use crate::physics::mode::{Guard, Moving};

/// `u` and `v` of the structure's cluster over a stretch of length `h` from
/// `z = [u, v, p, p']` as polynomials of degree `deg` in `s = τ / h`: the
/// Taylor terms `(A h)^k z / k!`, whose u and v parts are the coefficients.
/// Returns their spreads (`Poly::spread(1)`, summed as they come) and
/// that of `v`'s terms past the second (inlined: dropped where unused).
#[inline(always)]
fn taylor_uv(z: [f64; 4], h: f64, [w2, cm]: [f64; 2], deg: usize, uv: [&mut Poly; 2]) -> [f64; 3] {
    let [u, v] = uv;
    // The forcing's part `[p, p']` is linear in time: after two terms its entries are
    // `f · 0.0 = +0.0` (`f > 0`), left out of the rest (`0.0 - w2 u`: the same values).
    let [mut y0, mut y1, p, p_rate] = z;
    (u.c[0], v.c[0]) = (y0, y1);
    let f = h * INV[0];
    let p1 = f * p_rate;
    [y0, y1] = [f * y1, f * (p - w2 * y0 - cm * y1)];
    (u.c[1], v.c[1]) = (y0, y1);
    let heads = [y0.abs(), y1.abs()];
    let f = h * INV[1];
    [y0, y1] = [f * y1, f * (p1 - w2 * y0 - cm * y1)];
    (u.c[2], v.c[2]) = (y0, y1);
    let heads = [heads[0] + y0.abs(), heads[1] + y1.abs()];
    let mut tails = [0.0, 0.0];
    // `u` and `v` carried as a pair (or their tails summed as one) would have the compiler pack
    // them, its shuffles lengthening the recurrence's chain by a third.
    let deg = deg.min(N_COEF - 1);
    for k in 3..deg + 1 {
        let f = h * INV[k - 1];
        (u.c[k], y1) = (f * y1, f * (0.0 - w2 * u.c[k - 1] - cm * y1));
        v.c[k] = y1;
        tails[1] += y1.abs();
    }
    tails[0] = u.c[3..=deg].iter().fold(0.0, |t, c| t + c.abs());
    (u.deg, v.deg) = (deg, deg);
    [heads[0] + tails[0], heads[1] + tails[1], tails[1]]
}

/// For the driver (`sweep.rs`), over one whole substep from `z` where its bounds could not
/// exclude a new interior peak: raises `peak_u` (when given) to the largest `|u|` and `peak_a` to
/// the largest absolute acceleration `cf + cf' τ - w2 u - cm v`, exactly, on the Taylor
/// polynomials; `ends`: u, v and A at the end; `fourth`: `sup|u''''|, sup|A''''|`.
#[inline(never)]
pub(super) fn raise_substep_peaks(
    [peak_u, peak_a]: [Option<&mut f64>; 2],
    z: [f64; 4],
    h: f64,
    [w2, cm, cf, cf_rate]: [f64; 4],
    deg: usize,
    [u_end, v_end, a_end]: [f64; 3],
    fourth: [f64; 2],
) -> Result<(), Undecided> {
    let (mut u, mut v) = (Poly::default(), Poly::default());
    taylor_uv(z, h, [w2, cm], deg, [&mut u, &mut v]);
    let tol = PEAK_TOL.max(EVENT_TIME_TOL / h);
    // y = ku u + kv v + c0 + c1 τ (u, or A), y', y'' and y''' at τ from the state.
    let y_at = |[ku, kv, c0, c1]: [f64; 4], t: f64, [u, v]: [f64; 2]| {
        let a = z[2] + z[3] * t - w2 * u - cm * v;
        let (j, y) = (z[3] - w2 * v - cm * a, ku * u + kv * v + c0 + c1 * t);
        let (d, e) = (c1 + ku * v + kv * a, ku * a + kv * j);
        [y, d, e, ku * j - kv * (w2 * a + cm * j)]
    };
    // The usual case first (else None): y' changes sign and |y''| >= m > 0 (its ends less
    // h²/8 sup|y''''|), one zero t*; Halley's steps from the inverse quintic through the ends
    // of y', y'', y''' until at t, |t* - t| <= q = |y'|/m and y(t*) = y - y'²/(2y'') within
    // b q³/2 <= 1e-17 |y| (b = |y'''| + h sup|y''''| bounds |y'''|; b q <= m).
    let start = |asked: bool, k: [f64; 4], fourth: f64, y_end: f64| {
        asked.then_some(())?;
        let ([y0, d0, e0, f0], [_, d1, e1, f1]) =
            (y_at(k, 0.0, [z[0], z[1]]), y_at(k, h, [u_end, v_end]));
        let m = e0.abs().min(e1.abs()) - 0.125 * h * h * fourth;
        let ends = y0.abs().max(y_end.abs());
        (e0 * e1 > 0.0 && m > 0.0 && !(d0 * d1).is_nan()).then_some(())?;
        if d0 * d1 >= 0.0 {
            return Some(Err(ends)); // y' monotone from ends of one sign: the peak is at an end
        }
        let (x, dd, g0, g1) = (d0 / (d0 - d1), d1 - d0, 1.0 / e0, 1.0 / e1);
        let (x1, x2) = (1.0 - x, x * x);
        let t = h * x2 * x * (10.0 - 15.0 * x + 6.0 * x2)
            + dd * x * x1 * (x1 * x1 * (1.0 + 3.0 * x) * g0 - x2 * (4.0 - 3.0 * x) * g1)
            - 0.5 * dd * dd * x2 * x1 * x1 * (x1 * f0 * g0 * g0 * g0 + x * f1 * g1 * g1 * g1);
        Some(Ok((k, fourth, m, t, ends)))
    };
    // u's and A's searches in step (their evaluations overlap); found peaks raised after the rest.
    let ks = [[1.0, 0.0, 0.0, 0.0], [-w2, -cm, cf, cf_rate]];
    let asked = [(peak_u.is_some(), u_end), (peak_a.is_some(), a_end)];
    let first: [_; 2] = std::array::from_fn(|j| start(asked[j].0, ks[j], fourth[j], asked[j].1));
    let (mut search, inv_h) = (first.map(|s| s.and_then(Result::ok)), 1.0 / h);
    let mut found = first.map(|s| s.and_then(Result::err));
    for _ in 0..4 {
        for (state, found) in search.iter_mut().zip(&mut found) {
            if let &mut Some((k, fourth, m, ref mut t, y_ends)) = state {
                // Horner's rule in s² on the even and odd terms (shorter chains; whole pairs,
                // the coefficient past an even degree being zero).
                let (s, s2) = (*t * inv_h, (*t * inv_h) * (*t * inv_h));
                let at = |p: &Poly| {
                    let pairs = p.c[..(deg + 2) & !1].chunks_exact(2).rev();
                    let [e, o] = pairs.fold([0.0, 0.0], |[e, o], c| [e * s2 + c[0], o * s2 + c[1]]);
                    e + s * o
                };
                let [y, d, e, f] = y_at(k, *t, [at(&u), at(&v)]);
                let bq = (f.abs() + h * fourth) * (d / m).abs(); // (one division: d / m)
                if bq <= m && bq * (d / m) * (d / m) <= 2e-17 * y.abs() && (0.0..=h).contains(t) {
                    *found = Some(y_ends.max((y - 0.5 * d * d / e).abs()));
                    *state = None;
                } else {
                    *t -= d / (e - 0.5 * d * f / e);
                }
            }
        }
    }
    if let Some(peak) = peak_u {
        match found[0] {
            Some(top) => *peak = peak.max(top),
            None => raise_peak_inside(peak, &u, Some(&v), u_end, 1.0, tol)?,
        }
    }
    if let Some(peak) = peak_a {
        match found[1] {
            Some(top) => *peak = peak.max(top),
            None => {
                accel_in_place(&mut u, &v, [w2, cm], [cf, cf_rate * h]); // u done with
                raise_peak_inside(peak, &u, None, a_end, 1.0, tol)?;
            }
        }
    }
    Ok(())
}

/// The absolute acceleration `c0 + c1 s - w2 u - cm v` in place of `u` (the
/// equation of motion on the Taylor polynomials, `c1` per stretch).
fn accel_in_place(u: &mut Poly, v: &Poly, [w2, cm]: [f64; 2], [c0, c1]: [f64; 2]) {
    for (ak, vk) in u.c[..=u.deg].iter_mut().zip(&v.c) {
        *ak = -w2 * *ak - cm * vk;
    }
    (u.c[0], u.c[1]) = (u.c[0] + c0, u.c[1] + c1);
}

/// The structure's cluster over the rest of a substep, of length `h`, from the current state in
/// the current mode: `u`, `v` and the absolute acceleration as polynomials in `s = τ / h`.
#[derive(Clone, Debug, Default)]
struct Flow {
    h: f64,
    u: Poly,
    v: Poly,
    /// `spread(1)` of `u` and `v`: how far each can move from its start over the stretch.
    u_spread: f64,
    v_spread: f64,
    /// That of `v`'s terms past the second.
    v_tail: f64,
    /// The absolute acceleration as `a0 + a1 τ - w2 u - cm v`, its start
    /// and a bound of how far it can move from it (from the spreads).
    accel_linear: [f64; 2],
    accel_start: f64,
    accel_spread_bound: f64,
    /// Its polynomial and exact spread, built in place only where that
    /// bound does not decide (most stretches need neither): `accel_built`.
    accel_poly: Poly,
    accel_spread: f64,
    accel_built: bool,
    w2: f64,
    cm: f64,
    ag0: f64,
    ag_rate: f64,
    /// The forcing per unit mass that does input work (`Fext / m - ag`)
    /// at the start, and its rate.
    q0: f64,
    p1: f64,
}

impl Flow {
    /// Starts the stretch of length `h` from the simulator's state, with
    /// Taylor polynomials of degree `deg` (filled in place: a flow is three
    /// arrays of coefficients; in line: each `crate::isa` copy has its own).
    #[inline(always)]
    fn start(&mut self, sim: &Simulator, exc: &Excitation, t_ref: f64, h: f64, deg: usize) {
        let (sys, d) = (&sim.sys, &sim.dynamics);
        let inv_mass = d.inv_mass0;
        let (w2, cm) = (sys.k * inv_mass, sys.c * inv_mass);
        let (ag0, fext0) = exc.at(sim.t - t_ref);
        let q0 = d.input_accel(ag0, fext0) - ag0;
        let p0 = d.load_accel0 + q0;
        let p1 = d.input_accel(exc.ag_rate, exc.fext_rate) - exc.ag_rate;
        let (z, uv) = ([sim.u[0], sim.v[0], p0, p1], [&mut self.u, &mut self.v]);
        [self.u_spread, self.v_spread, self.v_tail] = taylor_uv(z, h, [w2, cm], deg, uv);
        self.accel_linear = [p0 + ag0, p1 + exc.ag_rate];
        self.accel_start = p0 + ag0 - w2 * sim.u[0] - cm * sim.v[0];
        self.accel_spread_bound =
            (self.accel_linear[1] * h).abs() + w2 * self.u_spread + cm * self.v_spread;
        self.accel_built = false;
        (self.h, self.w2, self.cm, self.ag0, self.ag_rate) = (h, w2, cm, ag0, exc.ag_rate);
        (self.q0, self.p1) = (q0, p1);
    }

    /// The absolute acceleration `p - w2 u - cm v + ag` as a polynomial, and
    /// its spread.
    fn accel(&mut self) -> (&Poly, f64) {
        if !self.accel_built {
            let ([a0, a1], h, w2, cm) = (self.accel_linear, self.h, self.w2, self.cm);
            self.accel_poly = self.u;
            accel_in_place(&mut self.accel_poly, &self.v, [w2, cm], [a0, a1 * h]);
            self.accel_spread = self.accel_poly.spread(1.0);
            self.accel_built = true;
        }
        (&self.accel_poly, self.accel_spread)
    }

    /// Whether the guard `g` is proved positive over the whole stretch
    /// from its coefficients alone (most are: no polynomial is built).
    #[inline(always)]
    fn holds(&self, sim: &Simulator, g: &Guard) -> bool {
        match *g {
            Guard::Slip { hi, lo, sign } => {
                // Clusters above the structure's: quadratic velocities
                // (linear relative ones, the ground's terms cancel).
                let d = &sim.dynamics;
                let upper_rate = |c: usize| (d.accel_const[c] - self.ag0) * self.h;
                let upper_spread =
                    |c: usize| upper_rate(c).abs() + 0.5 * (self.ag_rate * self.h * self.h).abs();
                if lo == 0 {
                    let g0 = sign * (sim.v[d.bottom[hi]] - self.v.c[0]);
                    return g0 > upper_spread(hi) + self.v_spread;
                }
                // Linear over the stretch (its rate per stretch).
                let g0 = sign * (sim.v[d.bottom[hi]] - sim.v[d.bottom[lo]]);
                let rate = sign * (upper_rate(hi) - upper_rate(lo));
                super::proofs::linear_guard_lasts(g0, rate) > 1.0
            }
            Guard::Stuck {
                mass_above,
                f_top,
                cap,
            } => {
                // cap - |mass_above A0 + f_top| >= 0: A0 within [lo, hi].
                let (lo, hi) = Flow::stick_band(mass_above, f_top, cap);
                let (a0, bound) = (self.accel_start, self.accel_spread_bound);
                a0 - bound > lo && a0 + bound < hi
            }
        }
    }

    /// The band of the absolute acceleration inside which a stick holds.
    #[inline(always)]
    fn stick_band(mass_above: f64, f_top: f64, cap: f64) -> (f64, f64) {
        ((-cap - f_top) / mass_above, (cap - f_top) / mass_above)
    }

    /// The guard `g`, not proved by [`Flow::holds`], as polynomials (a
    /// stick band has two sides) written to `out`, without a side proved
    /// positive over the stretch by its exact spread; returns how many
    /// (written in place: no array of options moved per guard). With each,
    /// the scale of its start's rounding: its spread, or the size of the
    /// values it compares where smaller (a guard far from zero against
    /// those must not pass for zero because a strong load moves it far over
    /// the stretch).
    fn guard_polys(&mut self, sim: &Simulator, g: &Guard, out: &mut [(Poly, f64); 2]) -> usize {
        match *g {
            Guard::Slip { hi, lo, sign } => {
                // `sign (velocity(hi) - velocity(lo))`: the clusters above
                // the structure's have quadratic velocities (`hi > lo`: only
                // `lo` can be the structure's cluster).
                let d = &sim.dynamics;
                let upper = |c: usize| {
                    [
                        sim.v[d.bottom[c]],
                        (d.accel_const[c] - self.ag0) * self.h,
                        -0.5 * self.ag_rate * self.h * self.h,
                    ]
                };
                let vh = upper(hi);
                let (p, scale) = &mut out[0];
                if lo == 0 {
                    for (ck, vk) in p.c.iter_mut().zip(self.v.coefs()) {
                        *ck = sign * (0.0 - vk);
                    }
                    for (k, vhk) in vh.iter().enumerate() {
                        p.c[k] = sign * (vhk - self.v.c[k]);
                    }
                    p.deg = self.v.deg.max(2);
                } else {
                    let vl = upper(lo);
                    for k in 0..3 {
                        p.c[k] = sign * (vh[k] - vl[k]);
                    }
                    p.deg = 2;
                }
                // Its terms past the second are `v`'s, or none.
                let (tail, v_lo) = if lo == 0 {
                    (self.v_tail, self.v.c[0])
                } else {
                    (0.0, sim.v[d.bottom[lo]])
                };
                let spread = p.c[1].abs() + p.c[2].abs() + tail;
                *scale = spread.min(vh[0].abs() + v_lo.abs());
                usize::from(p.c[0] <= spread)
            }
            Guard::Stuck {
                mass_above,
                f_top,
                cap,
            } => {
                let (lo, hi) = Flow::stick_band(mass_above, f_top, cap);
                let a0 = self.accel_start;
                let (accel, spread) = self.accel();
                let mut n = 0;
                // A side's spread is the acceleration's (`±1` times its
                // coefficients past the first).
                if a0 - spread <= lo {
                    out[n].0.set_affine(accel, 1.0, -lo);
                    out[n].1 = spread.min(a0.abs() + lo.abs());
                    n += 1;
                }
                if a0 + spread >= hi {
                    out[n].0.set_affine(accel, -1.0, hi);
                    out[n].1 = spread.min(a0.abs() + hi.abs());
                    n += 1;
                }
                n
            }
        }
    }
}

/// Halvings of a fine stretch that cannot be decided before its guards are
/// muted and its peaks taken at its ends (a stretch of `h_fine / 4096`).
const MAX_SPLIT_DEPTH: u32 = 12;

/// [`raise_peak_exact`] up to `s` within `tol`, or the ends only (`ends_only`: a stretch at the
/// deepest split).
fn raise_peak_over(
    peak: &mut f64,
    y: &Poly,
    rate: Option<&Poly>,
    ends: [f64; 2],
    (s, tol, ends_only): (f64, f64, bool),
) -> Result<(), Undecided> {
    if ends_only {
        *peak = peak.max(y.c[0].abs()).max(ends[0].abs());
        return Ok(());
    }
    raise_peak_exact(peak, y, rate, ends, s, tol)
}

/// The event path's polynomials, kept over its stretches (zeroed once; each value read is written).
#[derive(Clone, Debug, Default)]
pub(crate) struct Scratch {
    flow: Flow,
    polys: [(Poly, f64); 2],
}

/// What the search of a stretch found.
enum Next {
    /// Guards violated from the start with no positive stretch after it.
    AtOnce(u32),
    /// The first zero (fraction of the stretch) and its interface; `None`:
    /// no guard reaches zero before the substep's end. With the guards
    /// searched (the others are proved positive over the whole stretch).
    Event(Option<(f64, usize)>, u32),
}

impl Simulator {
    /// The motion to `t1` within `piece`, switches located on it (see the module's text): the
    /// rest of a substep (`depth` 0) or a shorter stretch of it (`depth` >= 1). A substep that
    /// cannot be decided (a search over its budget, a contact that chatters) goes on in fine
    /// stretches of at most `h_fine`; in those a chattering contact is muted for the rest of the
    /// stretch (switched at its end), and a search that cannot decide halves the stretch, down
    /// to `MAX_SPLIT_DEPTH` halvings, where the guards are muted and the peaks taken at its ends.
    /// (Run as `exact_stretch`: `crate::isa`.)
    #[inline(always)]
    pub(crate) fn stretch_run(&mut self, t1: f64, piece: &Piece, depth: u32, work: &mut Scratch) {
        let (exc, t_ref) = (&piece.exc, piece.t_ref);
        let ends_only = depth >= MAX_SPLIT_DEPTH;
        let mut muted: u32 = 0;
        let mut fired_at_once: u32 = 0;
        let mut events = 0;
        // One degree for every stretch: that of the longest.
        let deg = self.maps.stretch_degree(&self.sys, t1 - self.t);
        let Scratch { flow, polys } = work;
        while self.t < t1 {
            let h = t1 - self.t;
            flow.start(self, exc, t_ref, h, deg);
            let tol = EVENT_TIME_TOL / h;
            let next = match self.next_event(flow, polys, muted, tol) {
                Ok(next) => next,
                Err(Undecided) if depth == 0 => return self.fine_stretches(t1, piece, work),
                Err(Undecided) if !ends_only => return self.split_stretch(t1, piece, depth, work),
                Err(Undecided) => {
                    muted |= self.dynamics.changing_guards;
                    continue;
                }
            };
            match next {
                Next::AtOnce(at_once) => {
                    // Fired once already: a contact that chatters (a degenerate stack, such as
                    // equal friction above and below a block), muted for a fine stretch only.
                    let again = at_once & fired_at_once;
                    if again != 0 && depth == 0 {
                        return self.fine_stretches(t1, piece, work);
                    }
                    muted |= again;
                    let fire = at_once & !fired_at_once;
                    fired_at_once |= fire;
                    if fire != 0 {
                        self.fire_violated(exc, t_ref, 0, fire);
                    }
                }
                Next::Event(event, searched) => {
                    let s = event.map_or(1.0, |(s, _)| s);
                    if self.take_exact(flow, s, tol, muted, ends_only).is_err() {
                        if depth == 0 {
                            return self.fine_stretches(t1, piece, work);
                        }
                        return self.split_stretch(t1, piece, depth, work);
                    }
                    if s >= 1.0 {
                        self.t = t1;
                    }
                    if let Some((_, j)) = event {
                        let located = [j as u32, searched];
                        self.fire_located(exc, t_ref, located, &mut muted, &mut events);
                    }
                }
            }
        }
        self.fire_muted(exc, t_ref, muted);
    }

    /// The rest of a substep to `t1` in equal stretches of at most `h_fine`.
    #[cold]
    #[inline(never)]
    fn fine_stretches(&mut self, t1: f64, piece: &Piece, work: &mut Scratch) {
        let t0 = self.t;
        let n = substeps(t1 - t0, self.h_fine) as usize;
        for i in 1..=n {
            let end = if i == n {
                t1
            } else {
                t0 + (t1 - t0) * i as f64 / n as f64
            };
            self.exact_stretch(end, piece, 1, work);
        }
    }

    /// The stretch to `t1` in two halves, one level deeper.
    #[cold]
    #[inline(never)]
    fn split_stretch(&mut self, t1: f64, piece: &Piece, depth: u32, work: &mut Scratch) {
        let mid = self.t + 0.5 * (t1 - self.t);
        self.exact_stretch(mid, piece, depth + 1, work);
        self.exact_stretch(t1, piece, depth + 1, work);
    }

    /// The first zero over the stretch of `flow` among the guards of the
    /// mode that are not `muted`, or the guards to fire at once.
    #[inline(always)]
    fn next_event(
        &self,
        flow: &mut Flow,
        polys: &mut [(Poly, f64); 2],
        muted: u32,
        tol: f64,
    ) -> Result<Next, Undecided> {
        let d = &self.dynamics;
        let mut ifaces = d.changing_guards;
        let mut earliest: Option<(f64, usize)> = None;
        let (mut at_once, mut searched) = (0u32, 0u32);
        // Every stick of the structure's cluster at once: the acceleration
        // kept inside the band inside all of them (then each guard's own
        // test, on a wider band, returns no polynomial either).
        let sticks_hold = d.stick_band.is_some_and(|(lo, hi)| {
            let (a0, bound) = (flow.accel_start, flow.accel_spread_bound);
            a0 - bound > lo && a0 + bound < hi
        });
        let skipped = if sticks_hold {
            muted | d.stuck_guards
        } else {
            muted
        };
        for g in &d.guards[..d.n_guards] {
            let j = ifaces.trailing_zeros() as usize;
            ifaces &= ifaces - 1;
            if skipped & (1 << j) != 0 {
                continue;
            }
            if flow.holds(self, g) {
                continue;
            }
            searched |= 1 << j;
            let n_polys = flow.guard_polys(self, g, polys);
            for (poly, scale) in &mut polys[..n_polys] {
                // A guard at zero (a contact that has just switched: up to
                // the rounding of its start) must grow from it, or it fires
                // at once.
                if !(poly.c[0] > 1e-12 * *scale || poly.divide_zero_start()) {
                    at_once |= 1 << j;
                    continue;
                }
                let poly = &*poly;
                // Value and derivative at 0: its first two coefficients.
                let (g0, d0) = (poly.c[0], if poly.deg >= 1 { poly.c[1] } else { 0.0 });
                // Only zeros before the earliest one found so far matter.
                let end = earliest.map_or(1.0, |(s, _)| s);
                let start = [0.0, g0.max(0.0), d0];
                if let Some(s) = first_zero(poly, start, end, tol)? {
                    if earliest.is_none_or(|(e, _)| s < e) {
                        earliest = Some((s, j));
                    }
                }
            }
        }
        Ok(if at_once != 0 {
            Next::AtOnce(at_once)
        } else {
            Next::Event(earliest, searched)
        })
    }

    /// Takes the stretch of `flow` up to `s` (a fraction of it), where no
    /// guard but the `muted` ones reaches zero: every body moves with its
    /// cluster, the work terms are added in closed form, and the peaks are
    /// raised to their largest values over it. Fails, changing nothing, when
    /// a peak cannot be decided.
    #[inline(always)]
    fn take_exact(
        &mut self,
        flow: &mut Flow,
        s: f64,
        tol: f64,
        muted: u32,
        ends_only: bool,
    ) -> Result<(), Undecided> {
        let n = self.sys.n;
        let d = &self.dynamics;
        let tau = if s >= 1.0 { flow.h } else { s * flow.h };
        let u0_start = self.u[0];
        let values = |s| values_and_integral(&flow.u, &flow.v, s);
        let [u0, v0, int_u] = if s < 1.0 { values(s) } else { values(1.0) };
        let [a0, a1] = flow.accel_linear;
        let accel_end = a0 + a1 * tau - flow.w2 * u0 - flow.cm * v0;

        // Peaks first (they can fail): |u0|, the absolute acceleration, and the slip of the
        // interface on top of the structure's cluster; between two upper clusters a slip is
        // quadratic in time and the cubic through the ends is exact.
        let (mut peak_u0, mut peak_a0) = (self.peak_u0, self.peak_a0);
        let how = (s, tol.max(PEAK_TOL), ends_only);
        let u_ends = [u0, flow.u_spread];
        raise_peak_over(&mut peak_u0, &flow.u, Some(&flow.v), u_ends, how)?;
        let a_start = flow.accel_start;
        peak_a0 = peak_a0.max(a_start.abs()).max(accel_end.abs());
        if a_start.abs() + flow.accel_spread_bound > peak_a0 {
            let (accel, spread) = flow.accel();
            raise_peak_over(&mut peak_a0, accel, None, [accel_end, spread], how)?;
        }
        let (mut du, mut v_end) = ([0.0; MAX_BODIES], [0.0; MAX_BODIES]);
        let mut upper_work = 0.0;
        for c in 1..d.n_clusters {
            let v = self.v[d.bottom[c]];
            let [dc, vc, work] =
                upper_cluster_step(v, d.accel_const[c], d.mass[c], flow.ag0, flow.ag_rate, tau);
            (du[c], v_end[c]) = (dc, vc);
            upper_work += work;
        }
        (du[0], v_end[0]) = (u0 - u0_start, v0);
        // A slip whose guard (its rate, signed) is watched (not muted: never a free interface)
        // keeps its direction over the stretch: it peaks at an end. The others' peaks can fail:
        // taken first, in copies (no copy of every slip's peak and work per stretch).
        let (watched, mut raised) = (d.changing_guards & !muted, [0.0; MAX_BODIES]);
        for m in d.moving[..d.n_moving]
            .iter()
            .filter(|m| watched & (1 << m.j) == 0)
        {
            let (j, hi, lo) = (m.j, m.hi, m.lo);
            let slip0 = self.u[j] - self.u[j - 1];
            let vrel = [self.v[j] - self.v[j - 1], v_end[hi] - v_end[lo]];
            let ends = [[slip0, slip0 + du[hi] - du[lo]], vrel];
            raised[j] = self.peak_slip[j];
            self.raise_unwatched_slip(&mut raised[j], flow, *m, ends, how)?;
        }
        // Friction's work: the constant force times the slip.
        for m in &d.moving[..d.n_moving] {
            let (j, hi, lo) = (m.j, m.hi, m.lo);
            let slip0 = self.u[j] - self.u[j - 1];
            let slip1 = slip0 + du[hi] - du[lo];
            self.e_friction[j] += friction_work(d.slip_force[j], du[hi] - du[lo]);
            let peak = self.peak_slip[j].max(slip0.abs()).max(slip1.abs());
            let watch = watched & (1 << j) != 0;
            self.peak_slip[j] = if watch { peak } else { raised[j] };
        }

        // Work: input `∫ (Fext - m ag) v = m (q0 Δu + p' (τ u(τ) - ∫u))`, viscous `c ∫ v²`.
        let mass = d.mass[0];
        let int_u = flow.h * int_u;
        let input = mass * (flow.q0 * (u0 - u0_start) + flow.p1 * (tau * u0 - int_u));
        let viscous = self.sys.c * flow.h * integral_of_square(&flow.v, s);
        move_bodies(&mut self.u, &mut self.v, d, n, u0, &du, &v_end);
        self.e_input += input + upper_work;
        // A prescribed support's drift from the input frame: its work on
        // the stack beyond the input (Dynamics::support_force).
        let support_work = d.support_force * (u0 - u0_start);
        if support_work != 0.0 {
            self.e_input += support_work;
        }
        self.e_viscous += viscous;
        self.peak_u0 = peak_u0;
        self.peak_a0 = peak_a0;
        self.t += tau;
        self.stats.steps += 1;
        Ok(())
    }
    /// The peak of a slip whose guard was not searched over the stretch
    /// (muted, or a free interface), up to `s`: `ends` are its slip and
    /// relative velocity at both ends. Out of line: most stretches watch
    /// every slip (its peak is then at an end), and the event path's code
    /// stays small.
    #[cold]
    #[inline(never)]
    fn raise_unwatched_slip(
        &self,
        peak: &mut f64,
        flow: &Flow,
        m: Moving,
        [[slip0, slip1], [vrel0, vrel1]]: [[f64; 2]; 2],
        how: (f64, f64, bool),
    ) -> Result<(), Undecided> {
        let (d, hi) = (&self.dynamics, m.hi);
        if m.lo == 0 {
            // slip(s) = slip0 + (cluster hi's displacement) - (u0(s) - u0(0)).
            let (h, rel) = (flow.h, d.accel_const[hi] - flow.ag0);
            let upper = [
                self.v[d.bottom[hi]] * h,
                0.5 * rel * h * h,
                -flow.ag_rate * h * h * h / 6.0,
            ];
            let spread = flow.u_spread + upper.iter().map(|x| x.abs()).sum::<f64>();
            if slip0.abs().max(slip1.abs()) > *peak || slip0.abs() + spread > *peak {
                let mut c = flow.u.c.map(|x| -x);
                c[0] = slip0;
                for k in 0..3 {
                    c[k + 1] += upper[k];
                }
                let slip = Poly {
                    c,
                    deg: flow.u.deg.max(3),
                };
                raise_peak_over(peak, &slip, None, [slip1, spread], how)?;
            }
        } else {
            let tau = if how.0 >= 1.0 { flow.h } else { how.0 * flow.h };
            hermite::raise_peak(peak, slip0, vrel0, slip1, vrel1, tau);
        }
        Ok(())
    }
}
