//! The default method's event path: a substep the fast path hands back (one
//! that holds a switch or a new interior peak) taken exactly, switches
//! located on the exact motion instead of on RK4 re-steps.
//!
//! In one mode and one linear piece of excitation the structure's cluster is
//! `z' = A z` over `z = [u, v, p, p']` (`exact_map`), so over the rest of a
//! substep its state is the Taylor series of `exp(A τ) z`, summed to
//! round-off (the substep keeps `ω h <= 0.25`): `u` and `v` are polynomials
//! in `s = τ / H`. The clusters above it move as exact polynomials of degree
//! three at most. Every guard is then a polynomial in `s`: a stick guard of
//! the structure's cluster is a band of its absolute acceleration, a slip
//! guard a relative velocity.
//!
//! [`first_zero`] finds the first zero of a guard in `(0, 1]` with a proof
//! that none comes before it: a stretch is passed when Taylor's bounds from
//! both of its ends (with a bound on `|g''|` from the coefficients) keep the
//! guard positive over it, and a sign change is refined by Newton's method
//! only on a stretch where `g' < 0` is proved (a single crossing); anything
//! else is halved. The motion is then taken to that instant with exact
//! energies (the input work from `∫u`, the viscous work from `∫v²`, both
//! integrals of the polynomials) and exact running peaks (at the sign changes
//! of the derivative, found the same way); the guard fires, the mode is
//! resolved, and the rest of the substep continues in the new mode. The
//! chatter guards of `Simulator::step_located` are kept: a guard violated
//! from the start fires at once (a zero-length event), an interface that
//! does so twice in the substep is muted until its end, and so is every
//! guard after `MAX_EVENTS_PER_STEP` events.

use super::exact_map::degree;
use super::*;
use crate::physics::mode::Guard;

/// Coefficients of a polynomial (degree at most `exact_map`'s largest, plus
/// the integral's one).
const N_COEF: usize = 24;

/// Evaluations [`first_zero`] may spend on one guard before it gives up
/// (a guard hovering at rounding level over the substep); the substep is
/// then taken by fine RK4 steps (`Simulator::fine_steps`).
const EVALUATION_BUDGET: u32 = 400;

/// Critical points of a peak's polynomial looked at in one stretch (its
/// derivative changes sign at most a few times over `ω H <= 0.25`).
const MAX_CRITICAL_POINTS: usize = 8;

/// A polynomial `Σ c[k] s^k` on `s ∈ [0, 1]`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Poly {
    c: [f64; N_COEF],
    deg: usize,
}

impl Poly {
    fn new(c: [f64; N_COEF], deg: usize) -> Poly {
        Poly { c, deg }
    }

    /// Bounds of `|p''|` and `|p'''|` over [0, 1] (triangle inequality; the
    /// factor covers the rounding of the coefficients and of the sums).
    fn bounds(&self) -> [f64; 2] {
        let (mut m2, mut m3) = (0.0, 0.0);
        for k in 2..=self.deg {
            let kf = k as f64;
            let term = kf * (kf - 1.0) * self.c[k].abs();
            m2 += term;
            m3 += term * (kf - 2.0);
        }
        [m2 * (1.0 + 1e-12), m3 * (1.0 + 1e-12)]
    }

    /// `Σ_(k >= 1) |c_k| s^k`: a bound of `|p(σ) - p(0)|` over `[0, s]`.
    fn spread(&self, s: f64) -> f64 {
        let mut y = 0.0;
        for k in (1..=self.deg).rev() {
            y = (y + self.c[k].abs()) * s;
        }
        y
    }

    /// `sign p + offset`.
    fn affine(&self, sign: f64, offset: f64) -> Poly {
        let mut c = self.c.map(|x| sign * x);
        c[0] += offset;
        Poly::new(c, self.deg)
    }

    /// For a guard that is zero at `s = 0` up to rounding: `p / s^m`, `m`
    /// its leading coefficients at rounding level (at most three), which has
    /// the zeros of `p` in (0, 1]. `None` when the first coefficient left is
    /// negative: the guard does not grow from its zero.
    fn past_zero_start(&self) -> Option<Poly> {
        let scale: f64 = (1..=self.deg).map(|k| self.c[k].abs()).sum();
        let m = (0..=self.deg.min(3)).find(|&k| self.c[k].abs() > 1e-12 * scale)?;
        if self.c[m] < 0.0 {
            return None;
        }
        let mut c = [0.0; N_COEF];
        c[..=self.deg - m].copy_from_slice(&self.c[m..=self.deg]);
        Some(Poly::new(c, self.deg - m))
    }

    fn coefs(&self) -> &[f64] {
        &self.c[..=self.deg]
    }

    #[inline]
    fn eval(&self, s: f64) -> f64 {
        let mut y = self.c[self.deg];
        for k in (0..self.deg).rev() {
            y = y * s + self.c[k];
        }
        y
    }

    /// Value and derivative at `s`.
    #[inline]
    fn eval_d(&self, s: f64) -> (f64, f64) {
        let (mut y, mut d) = (self.c[self.deg], 0.0);
        for k in (0..self.deg).rev() {
            d = d * s + y;
            y = y * s + self.c[k];
        }
        (y, d)
    }

    fn derivative(&self) -> Poly {
        let mut c = [0.0; N_COEF];
        for k in 1..=self.deg {
            c[k - 1] = k as f64 * self.c[k];
        }
        Poly::new(c, self.deg.max(1) - 1)
    }
}

/// Why a guard or a peak could not be decided within the budget.
#[derive(Debug, PartialEq)]
pub(super) struct Undecided;

/// Whether `g > 0` over `(0, l]` follows from its ends (values `g0`, `g1`,
/// rates `d0`, `d1`) and `|g''| <= m2`: Taylor's bound from the start is
/// positive up to its root, the one from the end back to its own, and the
/// two reaches cover the stretch (admits a `g0 = 0` that grows).
fn stays_positive([g0, d0, g1, d1]: [f64; 4], l: f64, m2: f64) -> bool {
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
    g1 > 0.0 && reach(g0, d0) + reach(g1, -d1) > l
}

/// The first zero of `g` in `(a, e]`, where `g(a) = ga >= 0` with rate `da`
/// (`ga = 0` only for a guard that grows from a zero): `None` when `g > 0`
/// over `(a, e]` is proved. `tol` is the width below which a stretch is
/// not split further: a sign change there is the zero, and a dip below zero
/// and back inside it is not seen (a graze).
pub(super) fn first_zero(
    g: &Poly,
    [mut a, mut ga, mut da]: [f64; 3],
    e: f64,
    tol: f64,
) -> Result<Option<f64>, Undecided> {
    let [m2, m3] = g.bounds();
    let mut width = e - a;
    let mut evaluations = 0;
    while a < e {
        evaluations += 1;
        if evaluations > EVALUATION_BUDGET {
            return Err(Undecided);
        }
        let b = if a + width >= e { e } else { a + width };
        let l = b - a;
        let (gb, db) = g.eval_d(b);
        if gb > 0.0 {
            if l <= tol || stays_positive([ga, da, gb, db], l, m2) {
                (a, ga, da) = (b, gb, db);
                width = 2.0 * l;
                continue;
            }
        } else {
            // g' < 0 over the stretch (it stays within l²/8 sup|g'''| of its
            // linear interpolation): a single crossing.
            let falling = -da.max(db) > 0.125 * l * l * m3;
            if l <= tol || falling {
                return Ok(Some(refine(g, [a, ga], [b, gb], tol)));
            }
        }
        width = 0.5 * l;
    }
    Ok(None)
}

/// The zero of `g` between `a` (g > 0) and `b` (g <= 0), where it is the
/// only one: Newton's method kept inside the bracket (bisection when it
/// leaves it), to well below `tol`.
fn refine(g: &Poly, [mut a, ga]: [f64; 2], [mut b, gb]: [f64; 2], tol: f64) -> f64 {
    let mut x = a + ga / (ga - gb) * (b - a);
    for _ in 0..100 {
        if b - a <= tol {
            return b;
        }
        let (gx, dx) = g.eval_d(x);
        if gx > 0.0 {
            a = x;
        } else if gx < 0.0 {
            b = x;
        } else {
            return x;
        }
        let mut next = x - gx / dx;
        if !(next > a && next < b) {
            next = 0.5 * (a + b);
        }
        if (next - x).abs() <= 1e-3 * tol {
            return next;
        }
        x = next;
    }
    b
}

/// Raises `peak` to the largest `|y|` over `[0, e]`: at the ends, or where
/// `y'` changes sign.
fn raise_peak_exact(peak: &mut f64, y: &Poly, e: f64, tol: f64) -> Result<(), Undecided> {
    let ends = y.c[0].abs().max(y.eval(e).abs());
    if ends > *peak {
        *peak = ends;
    }
    if y.c[0].abs() + y.spread(e) <= *peak {
        return Ok(());
    }
    let dy = y.derivative();
    // The sign of y' just after 0 (y' may start at zero).
    let scale: f64 = dy.coefs().iter().map(|x| x.abs()).sum();
    let Some(&lead) = dy.coefs().iter().find(|x| x.abs() > 1e-12 * scale) else {
        return Ok(()); // y is constant
    };
    let mut sign = if lead < 0.0 { -1.0 } else { 1.0 };
    let mut a = 0.0;
    for _ in 0..MAX_CRITICAL_POINTS {
        // The first sign change of y' after `a`.
        let g = dy.affine(sign, 0.0);
        let r = if a == 0.0 {
            let g = g.past_zero_start().unwrap_or(g);
            let (g0, d0) = g.eval_d(0.0);
            first_zero(&g, [0.0, g0.max(0.0), d0], e, tol)?
        } else {
            let (ga, da) = g.eval_d(a);
            first_zero(&g, [a, ga.max(0.0), da], e, tol)?
        };
        let Some(r) = r else {
            return Ok(());
        };
        let at = y.eval(r).abs();
        if at > *peak {
            *peak = at;
        }
        (a, sign) = (r, -sign);
    }
    Err(Undecided)
}

/// The structure's cluster over the rest of a substep, of length `h`, from
/// the current state in the current mode: `u`, `v` and the absolute
/// acceleration as polynomials in `s = τ / h`.
struct Flow {
    h: f64,
    u: Poly,
    v: Poly,
    accel: Poly,
    /// `accel.spread(1)`: how far it can move from its start.
    accel_spread: f64,
    ag0: f64,
    ag_rate: f64,
    /// The forcing per unit mass that does input work (`Fext / m - ag`)
    /// at the start, and its rate.
    q0: f64,
    p1: f64,
}

impl Flow {
    fn new(sim: &Simulator, exc: &Excitation, t_ref: f64, h: f64) -> Flow {
        let (sys, d) = (&sim.sys, &sim.dynamics);
        let inv_mass = d.inv_mass0;
        let (w2, cm) = (sys.k * inv_mass, sys.c * inv_mass);
        let dt = sim.t - t_ref;
        let ag0 = exc.ag + exc.ag_rate * dt;
        let fext0 = exc.fext + exc.fext_rate * dt;
        let q0 = fext0 * inv_mass - ag0;
        let p0 = d.slip_load[0] * inv_mass + q0;
        let p1 = exc.fext_rate * inv_mass - exc.ag_rate;
        // Taylor terms (A h)^k z / k!: their u and v parts are the
        // coefficients in s.
        let deg = degree(h, w2, cm);
        let (mut u, mut v, mut accel) = ([0.0; N_COEF], [0.0; N_COEF], [0.0; N_COEF]);
        let mut y = [sim.u[0], sim.v[0], p0, p1];
        (u[0], v[0]) = (y[0], y[1]);
        for k in 1..=deg {
            let f = h * INV[k - 1];
            y = [f * y[1], f * (y[2] - w2 * y[0] - cm * y[1]), f * y[3], 0.0];
            (u[k], v[k]) = (y[0], y[1]);
        }
        // A0 = p - w2 u - cm v + ag.
        for k in 0..=deg {
            accel[k] = -w2 * u[k] - cm * v[k];
        }
        accel[0] += p0 + ag0;
        accel[1] += (p1 + exc.ag_rate) * h;
        let accel = Poly::new(accel, deg);
        Flow {
            h,
            u: Poly::new(u, deg),
            v: Poly::new(v, deg),
            accel_spread: accel.spread(1.0),
            accel,
            ag0,
            ag_rate: exc.ag_rate,
            q0,
            p1,
        }
    }

    /// Velocity of cluster `c` (relative to the support) as a polynomial.
    fn velocity(&self, sim: &Simulator, c: usize) -> Poly {
        if c == 0 {
            return self.v;
        }
        let d = &sim.dynamics;
        let mut k = [0.0; N_COEF];
        k[0] = sim.v[d.bottom[c]];
        k[1] = (d.accel_const[c] - self.ag0) * self.h;
        k[2] = -0.5 * self.ag_rate * self.h * self.h;
        Poly::new(k, 2)
    }

    /// The guard `g` as polynomials (a stick band has two sides), `None`
    /// where it is proved positive over the whole stretch from its
    /// coefficients alone.
    fn guard_polys(&self, sim: &Simulator, g: &Guard) -> [Option<Poly>; 2] {
        match *g {
            Guard::Slip { hi, lo, sign } => {
                let (vh, vl) = (self.velocity(sim, hi), self.velocity(sim, lo));
                let deg = vh.deg.max(vl.deg);
                let mut c = [0.0; N_COEF];
                for k in 0..=deg {
                    c[k] = sign * (vh.c[k] - vl.c[k]);
                }
                let p = Poly::new(c, deg);
                [(c[0] <= p.spread(1.0)).then_some(p), None]
            }
            Guard::Stuck {
                mass_above,
                f_top,
                cap,
            } => {
                // cap - |mass_above A0 + f_top| >= 0: A0 within [lo, hi].
                let lo = (-cap - f_top) / mass_above;
                let hi = (cap - f_top) / mass_above;
                let (a0, spread) = (self.accel.c[0], self.accel_spread);
                [
                    (a0 - spread <= lo).then(|| self.accel.affine(1.0, -lo)),
                    (a0 + spread >= hi).then(|| self.accel.affine(-1.0, hi)),
                ]
            }
        }
    }
}

/// What the search of a stretch found.
enum Next {
    /// Guards violated from the start with no positive stretch after it.
    AtOnce(u32),
    /// The first zero (fraction of the stretch) and its interface; `None`:
    /// no guard reaches zero before the substep's end.
    Event(Option<(f64, usize)>),
}

impl Simulator {
    /// The rest of the current substep, to `t1` within `piece`, on the exact
    /// motion with switches located on it (see the module's text); a stretch
    /// whose guards or peaks cannot be decided within the budget goes to
    /// fine RK4 steps.
    pub(super) fn exact_substep(&mut self, t1: f64, piece: &Piece) {
        let (exc, t_ref) = (&piece.exc, piece.t_ref);
        let all: u32 = (1..=self.sys.n).fold(0, |m, j| m | (1 << j));
        let mut muted: u32 = 0;
        let mut fired_at_once: u32 = 0;
        let mut events = 0;
        while self.t < t1 {
            let h = t1 - self.t;
            let flow = Flow::new(self, exc, t_ref, h);
            let tol = EVENT_TIME_TOL / h;
            let next = match self.next_event(&flow, muted, tol) {
                Ok(next) => next,
                Err(Undecided) => return self.fine_steps(t1, piece),
            };
            match next {
                Next::AtOnce(at_once) => {
                    // Fired once already in this substep: muted instead.
                    muted |= at_once & fired_at_once;
                    let fire = at_once & !fired_at_once;
                    fired_at_once |= fire;
                    if fire != 0 {
                        self.fire_violated(exc, t_ref, 0, fire);
                    }
                }
                Next::Event(None) => {
                    if self.take_exact(&flow, 1.0, tol).is_err() {
                        return self.fine_steps(t1, piece);
                    }
                    self.t = t1;
                }
                Next::Event(Some((s, j))) => {
                    if self.take_exact(&flow, s, tol).is_err() {
                        return self.fine_steps(t1, piece);
                    }
                    if s >= 1.0 {
                        self.t = t1;
                    }
                    // The located guard fires whatever its sign after
                    // rounding; others fire if they have reached zero too.
                    self.fire_violated(exc, t_ref, all & !muted, 1 << j);
                    events += 1;
                    if events >= MAX_EVENTS_PER_STEP {
                        muted = all;
                    }
                }
            }
        }
        if muted != 0 {
            self.stats.muted += u64::from(muted.count_ones());
            self.fire_violated(exc, t_ref, muted, 0);
        }
    }

    /// The first zero over the stretch of `flow` among the guards of the
    /// mode that are not `muted`, or the guards to fire at once.
    fn next_event(&self, flow: &Flow, muted: u32, tol: f64) -> Result<Next, Undecided> {
        let d = &self.dynamics;
        let mut ifaces = d.changing_guards;
        let mut earliest: Option<(f64, usize)> = None;
        let mut at_once = 0u32;
        for g in &d.guards[..d.n_guards] {
            let j = ifaces.trailing_zeros() as usize;
            ifaces &= ifaces - 1;
            if muted & (1 << j) != 0 {
                continue;
            }
            for poly in flow.guard_polys(self, g).iter().flatten() {
                // A guard at zero (a contact that has just switched) must
                // grow from it, or it fires at once.
                let scale = poly.spread(1.0);
                let grown;
                let poly = if poly.c[0] > 1e-12 * scale {
                    poly
                } else if let Some(p) = poly.past_zero_start() {
                    grown = p;
                    &grown
                } else {
                    at_once |= 1 << j;
                    continue;
                };
                let (g0, d0) = poly.eval_d(0.0);
                // Only zeros before the earliest one found so far matter.
                let end = earliest.map_or(1.0, |(s, _)| s);
                if let Some(s) = first_zero(poly, [0.0, g0.max(0.0), d0], end, tol)? {
                    if earliest.is_none_or(|(e, _)| s < e) {
                        earliest = Some((s, j));
                    }
                }
            }
        }
        Ok(if at_once != 0 {
            Next::AtOnce(at_once)
        } else {
            Next::Event(earliest)
        })
    }

    /// Takes the stretch of `flow` up to `s` (a fraction of it): every body
    /// moves with its cluster, the work terms are added in closed form, and
    /// the peaks are raised to their largest values over it. Fails, changing
    /// nothing, when a peak cannot be decided.
    fn take_exact(&mut self, flow: &Flow, s: f64, tol: f64) -> Result<(), Undecided> {
        let n = self.sys.n;
        let d = &self.dynamics;
        let tau = if s >= 1.0 { flow.h } else { s * flow.h };
        let (u0_start, u0) = (self.u[0], flow.u.eval(s));
        let v0 = flow.v.eval(s);

        // Peaks first (they can fail): |u0|, the absolute acceleration, and
        // the slip of the interface on top of the structure's cluster;
        // between two upper clusters a slip is quadratic in time and the
        // cubic through the ends is exact.
        let (mut peak_u0, mut peak_a0) = (self.peak_u0, self.peak_a0);
        raise_peak_exact(&mut peak_u0, &flow.u, s, tol)?;
        raise_peak_exact(&mut peak_a0, &flow.accel, s, tol)?;
        let mut peak_slip = self.peak_slip;
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
        for m in &d.moving[..d.n_moving] {
            let (j, hi, lo) = (m.j, m.hi, m.lo);
            let slip0 = self.u[j] - self.u[j - 1];
            if lo == 0 {
                // slip(s) = slip0 + (cluster hi's displacement) - (u0(s) - u0(0)).
                let (h, rel) = (flow.h, d.accel_const[hi] - flow.ag0);
                let mut c = flow.u.c.map(|x| -x);
                c[0] = slip0;
                c[1] += self.v[d.bottom[hi]] * h;
                c[2] += 0.5 * rel * h * h;
                c[3] -= flow.ag_rate * h * h * h / 6.0;
                let slip = Poly::new(c, flow.u.deg.max(3));
                raise_peak_exact(&mut peak_slip[j], &slip, s, tol)?;
            } else {
                let (vrel0, vrel1) = (self.v[j] - self.v[j - 1], v_end[hi] - v_end[lo]);
                let slip1 = slip0 + du[hi] - du[lo];
                hermite::raise_peak(&mut peak_slip[j], slip0, vrel0, slip1, vrel1, tau);
            }
        }

        // Work: input `∫ (Fext - m ag) v = m (q0 Δu + p' (τ u(τ) - ∫u))`,
        // viscous `c ∫ v²`, friction the constant force times the slip.
        let int_u = flow.h * integral(&flow.u, s);
        let mass = d.mass[0];
        let input = mass * (flow.q0 * (u0 - u0_start) + flow.p1 * (tau * u0 - int_u));
        let viscous = self.sys.c * flow.h * integral_of_square(&flow.v, s);
        for m in &d.moving[..d.n_moving] {
            self.e_friction[m.j] -= d.slip_force[m.j] * (du[m.hi] - du[m.lo]);
        }
        move_bodies(&mut self.u, &mut self.v, d, n, u0, &du, &v_end);
        self.e_input += input + upper_work;
        self.e_viscous += viscous;
        self.peak_u0 = peak_u0;
        self.peak_a0 = peak_a0;
        self.peak_slip = peak_slip;
        self.t += tau;
        self.stats.steps += 1;
        Ok(())
    }
}

/// `1 / (k + 1)` for k = 0.., to take the integrals' and the Taylor
/// terms' divisions as products.
const INV: [f64; N_COEF + 1] = {
    let mut inv = [0.0; N_COEF + 1];
    let mut k = 0;
    while k <= N_COEF {
        inv[k] = 1.0 / (k + 1) as f64;
        k += 1;
    }
    inv
};

/// `∫_0^s p(σ) dσ`.
fn integral(p: &Poly, s: f64) -> f64 {
    let mut total = 0.0;
    for k in (0..=p.deg).rev() {
        total = total * s + p.c[k] * INV[k];
    }
    total * s
}

/// Gauss–Legendre nodes and weights on [0, 1], 8 points: exact for
/// polynomials of degree 15.
const GAUSS_NODES: [f64; 8] = [
    0.019855071751231912,
    0.10166676129318664,
    0.2372337950418355,
    0.4082826787521751,
    0.5917173212478248,
    0.7627662049581645,
    0.8983332387068134,
    0.9801449282487681,
];
const GAUSS_WEIGHTS: [f64; 8] = [
    0.05061426814518853,
    0.11119051722668721,
    0.15685332293894344,
    0.18134189168918083,
    0.18134189168918083,
    0.15685332293894344,
    0.11119051722668721,
    0.05061426814518853,
];

/// `∫_0^s p(σ)² dσ` for a Taylor polynomial of the motion, by the 8-point
/// Gauss rule (the eight evaluations run side by side): exact for the
/// square's terms up to degree 15; those above fall as `(2ρ)^k / k!` with
/// `ρ <= 0.25 (1 + 2ζ)`, below 1e-18 of the first from degree 16.
fn integral_of_square(p: &Poly, s: f64) -> f64 {
    let x = GAUSS_NODES.map(|x| x * s);
    let mut y = [0.0; 8];
    for &c in p.coefs().iter().rev() {
        for i in 0..8 {
            y[i] = y[i] * x[i] + c;
        }
    }
    let mut total = 0.0;
    for i in 0..8 {
        total += GAUSS_WEIGHTS[i] * y[i] * y[i];
    }
    total * s
}
