//! Exact response of a linear SDOF oscillator to a piecewise-linear load
//! (Nigam & Jennings, BSSA 59, 1969; Chopra, *Dynamics of Structures*,
//! Table 5.2.1). Used as an oracle for the engine and for response spectra.

/// The exact recurrence of one step `dt` for `u'' + 2 ζ ω u' + ω² u = p(t)`
/// with `p` linear over the step: `[u1, v1] = [[a, b, c, d], [a1, b1, c1,
/// d1]] · [u, v, p0, p1]`. Requires `0 <= ζ < 1`, `ω > 0`, `dt > 0`.
#[derive(Clone, Copy, Debug)]
pub struct Recurrence {
    u: [f64; 4],
    v: [f64; 4],
}

impl Recurrence {
    /// The coefficients for `ω`, `ζ` and the step `dt`.
    pub fn new(omega: f64, zeta: f64, dt: f64) -> Recurrence {
        let k = omega * omega;
        let sq = (1.0 - zeta * zeta).sqrt();
        let wd = omega * sq;
        let e = (-zeta * omega * dt).exp();
        let (s, c) = (wd * dt).sin_cos();
        let a = e * (zeta / sq * s + c);
        let b = e * s / wd;
        let cc = (2.0 * zeta / (omega * dt)
            + e * (((1.0 - 2.0 * zeta * zeta) / (wd * dt) - zeta / sq) * s
                - (1.0 + 2.0 * zeta / (omega * dt)) * c))
            / k;
        let d = (1.0 - 2.0 * zeta / (omega * dt)
            + e * ((2.0 * zeta * zeta - 1.0) / (wd * dt) * s + 2.0 * zeta / (omega * dt) * c))
            / k;
        let a1 = -e * (omega / sq * s);
        let b1 = e * (c - zeta / sq * s);
        let c1 = (-1.0 / dt + e * ((omega / sq + zeta / (dt * sq)) * s + c / dt)) / k;
        let d1 = (1.0 - e * (zeta / sq * s + c)) / (k * dt);
        Recurrence {
            u: [a, b, cc, d],
            v: [a1, b1, c1, d1],
        }
    }

    /// `(u, v)` at the step's end from `(u, v)` at its start, the load
    /// going from `p0` to `p1`.
    #[inline(always)]
    pub fn step(&self, (u, v): (f64, f64), p0: f64, p1: f64) -> (f64, f64) {
        let (r, q) = (&self.u, &self.v);
        (
            r[0] * u + r[1] * v + r[2] * p0 + r[3] * p1,
            q[0] * u + q[1] * v + q[2] * p0 + q[3] * p1,
        )
    }
}

/// One step of the exact recurrence (see [`Recurrence`]), its coefficients
/// built for this step. Returns `(u, v)` at the end.
pub fn step(omega: f64, zeta: f64, dt: f64, state: (f64, f64), p0: f64, p1: f64) -> (f64, f64) {
    Recurrence::new(omega, zeta, dt).step(state, p0, p1)
}

/// Response to ground acceleration samples `ag` (every `dt`, linear between
/// them) from rest: returns the relative displacement at every sample.
///
/// This is the benchmarks' physical floor, so it is written to compile to
/// the plain recurrence whatever the rest of the crate does: coefficients
/// once, the output written into place (no call inside the loop, so the
/// state stays in registers; a `Vec::push` there, with its growth path,
/// compiled in some builds to a loop that kept the state in memory, 1.7x
/// slower).
pub fn response(omega: f64, zeta: f64, dt: f64, ag: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; ag.len()];
    let rec = Recurrence::new(omega, zeta, dt);
    let mut state = (0.0, 0.0);
    for (u, w) in out.iter_mut().skip(1).zip(ag.windows(2)) {
        state = rec.step(state, -w[0], -w[1]);
        *u = state.0;
    }
    out
}
