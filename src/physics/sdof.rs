//! Exact response of a linear SDOF oscillator to a piecewise-linear load
//! (Nigam & Jennings, BSSA 59, 1969; Chopra, *Dynamics of Structures*,
//! Table 5.2.1). Used as an oracle for the engine and for response spectra.

/// One step of the exact recurrence for `u'' + 2 ζ ω u' + ω² u = p(t)`
/// with `p` linear from `p0` to `p1` over `dt`. Returns `(u, v)` at the end.
/// Requires `0 <= ζ < 1`, `ω > 0`, `dt > 0`.
pub fn step(omega: f64, zeta: f64, dt: f64, (u, v): (f64, f64), p0: f64, p1: f64) -> (f64, f64) {
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
    (
        a * u + b * v + cc * p0 + d * p1,
        a1 * u + b1 * v + c1 * p0 + d1 * p1,
    )
}

/// Response to ground acceleration samples `ag` (every `dt`, linear between
/// them) from rest: returns the relative displacement at every sample.
pub fn response(omega: f64, zeta: f64, dt: f64, ag: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(ag.len());
    let mut state = (0.0, 0.0);
    out.push(0.0);
    for w in ag.windows(2) {
        state = step(omega, zeta, dt, state, -w[0], -w[1]);
        out.push(state.0);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_closed_forms() {
        // Step load p = 1 from rest: u = (1 - e^{-ζωt}(cos ωd t + ζ/√(1-ζ²) sin ωd t)) / ω².
        let (w, z) = (3.0, 0.05);
        let wd = w * (1.0f64 - z * z).sqrt();
        let mut s = (0.0, 0.0);
        let dt = 0.37;
        for i in 1..=20 {
            s = step(w, z, dt, s, 1.0, 1.0);
            let t = i as f64 * dt;
            let exact = (1.0
                - (-z * w * t).exp()
                    * ((wd * t).cos() + z / (1.0 - z * z).sqrt() * (wd * t).sin()))
                / (w * w);
            assert!((s.0 - exact).abs() < 1e-14, "step load at t = {t}");
        }
        // Ramp p = t on an undamped oscillator: u = (t - sin(ωt)/ω) / ω².
        let mut s = (0.0, 0.0);
        for i in 0..30 {
            s = step(w, 0.0, dt, s, i as f64 * dt, (i + 1) as f64 * dt);
        }
        let t = 30.0 * dt;
        assert!((s.0 - (t - (w * t).sin() / w) / (w * w)).abs() < 1e-13);
    }
}
