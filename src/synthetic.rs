//! The embedded default ground motion: a deterministic broadband record, so
//! that the demo and the tests need no file.

use crate::record::GroundMotion;
use std::f64::consts::PI;

/// A sum of 40 sines log-spaced from 0.2 to 20 Hz, amplitudes falling as
/// 1/sqrt(f), phases from a fixed-seed generator, under a 2 s build-up and an
/// exponential decay after mid-record; scaled to peak `pga` (m/s^2).
/// Sampled every `dt` from t = 0 to `duration`.
pub fn broadband(duration: f64, dt: f64, pga: f64) -> GroundMotion {
    let mut seed: u64 = 0x2545F4914F6CDD1D;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let components: Vec<(f64, f64)> = (0..40)
        .map(|i| (0.2 * 100f64.powf(i as f64 / 39.0), 2.0 * PI * next()))
        .collect();
    let n = (duration / dt).round() as usize + 1;
    let raw: Vec<f64> = (0..n)
        .map(|i| {
            let t = i as f64 * dt;
            let envelope =
                (t / 2.0).min(1.0) * (-(t - 0.5 * duration).max(0.0) / (0.2 * duration)).exp();
            envelope
                * components
                    .iter()
                    .map(|(f, phase)| (2.0 * PI * f * t + phase).sin() / f.sqrt())
                    .sum::<f64>()
        })
        .collect();
    let peak = raw.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    GroundMotion::uniform(dt, raw.iter().map(|a| a * pga / peak).collect())
}

/// The demo's record: 20 s at 0.005 s, PGA 0.36 g (IS 1893 Zone V, Z = 0.36).
pub fn default_record(g: f64) -> GroundMotion {
    broadband(20.0, 0.005, 0.36 * g)
}

#[cfg(test)]
mod tests {
    #[test]
    fn is_deterministic_and_scaled() {
        let a = super::default_record(9.81);
        let b = super::default_record(9.81);
        assert_eq!(a, b);
        assert_eq!(a.time.len(), 4001);
        assert!((a.pga() - 0.36 * 9.81).abs() < 1e-12);
    }
}
