//! Synthetic ground motions: the deterministic broadband generator (the seed
//! of the embedded default record, and a test signal), and the embedded
//! default record itself, so that the demo needs no file.

use crate::ground::record::GroundMotion;
use std::f64::consts::PI;

/// A square wave of amplitude `a` (m/s²) and frequency `f` (Hz) over
/// `duration` s: each half period held, the jump between halves over 1 µs
/// (the shortest step of a record). A chattering load for the work bound.
pub fn square_wave(duration: f64, f: f64, a: f64) -> GroundMotion {
    let half = 0.5 / f;
    let n = (duration / half).ceil() as usize;
    let mut gm = GroundMotion {
        time: Vec::with_capacity(2 * n),
        accel: Vec::with_capacity(2 * n),
    };
    for k in 0..n {
        let value = if k % 2 == 0 { a } else { -a };
        let t0 = k as f64 * half;
        gm.time.extend([t0, t0 + half - 1e-6]);
        gm.accel.extend([value, value]);
    }
    gm
}

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

/// The embedded default record (`resources/default_record.csv`, m/s2): the
/// broadband seed (20 s at 0.005 s) matched to the IS 1893 (Part 1):2016 Zone V
/// hard-soil DBE spectrum by `scripts/ground_motions.py default`.
pub fn default_record() -> GroundMotion {
    const CSV: &str = include_str!("../../resources/default_record.csv");
    GroundMotion::from_csv_text(CSV, "resources/default_record.csv")
        .expect("the embedded record is valid")
}

#[cfg(test)]
mod tests {
    #[test]
    fn broadband_is_deterministic_and_scaled() {
        let a = super::broadband(20.0, 0.005, 3.0);
        assert_eq!(a, super::broadband(20.0, 0.005, 3.0));
        assert_eq!(a.time.len(), 4001);
        assert!((a.pga() - 3.0).abs() < 1e-12);
    }

    #[test]
    fn the_embedded_default_record_reads() {
        let gm = super::default_record();
        assert!(gm.time.len() > 4000 && (gm.time[1] - 0.005).abs() < 1e-12);
        assert!(gm.duration() >= 20.0);
        // Matched to Zone V DBE (ZPA 0.18 g): a PGA of about 0.2 g.
        assert!(
            (0.15 * 9.81..0.3 * 9.81).contains(&gm.pga()),
            "{}",
            gm.pga()
        );
    }
}
