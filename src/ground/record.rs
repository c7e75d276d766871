//! Ground-motion records: the [`GroundMotion`] table, and driving a
//! simulator through one. The file readers (PEER `.AT2`, CSV, single
//! column) are in `formats.rs`, as `GroundMotion` constructors.
//!
//! A record is a table of samples; between samples the acceleration is
//! linear, before the first and after the last it is zero.

use crate::physics::engine::{Excitation, Samples, SimError};
use crate::physics::solver::Stepper;
use std::fmt;

/// A tabulated ground acceleration (m/s^2) at increasing times (s).
#[derive(Clone, Debug, PartialEq)]
pub struct GroundMotion {
    /// Sample times (s), increasing.
    pub time: Vec<f64>,
    /// Accelerations at those times (m/s2).
    pub accel: Vec<f64>,
}

/// A record that could not be read: which file, which line, what was wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordError {
    /// The file's name as given.
    pub file: String,
    /// 1-based line number, 0 when the problem is not on one line.
    pub line: usize,
    /// What was wrong.
    pub message: String,
}

impl fmt::Display for RecordError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(f, "{}:{}: {}", self.file, self.line, self.message)
        } else {
            write!(f, "{}: {}", self.file, self.message)
        }
    }
}

impl std::error::Error for RecordError {}

impl GroundMotion {
    /// Samples every `dt` from t = 0.
    pub fn uniform(dt: f64, accel: Vec<f64>) -> GroundMotion {
        let time = (0..accel.len()).map(|i| i as f64 * dt).collect();
        GroundMotion { time, accel }
    }

    /// Duration covered by the samples (time of the last one).
    pub fn duration(&self) -> f64 {
        self.time.last().copied().unwrap_or(0.0)
    }

    /// Number of samples at times in `(t0, t1]`.
    pub fn samples_in(&self, t0: f64, t1: f64) -> usize {
        let after = |t: f64| self.time.partition_point(|&x| x <= t);
        after(t1).saturating_sub(after(t0))
    }

    /// Largest absolute acceleration.
    pub fn pga(&self) -> f64 {
        self.accel.iter().fold(0.0, |m, a| m.max(a.abs()))
    }

    /// Index of the first sample strictly after `t`: guessed from the mean
    /// spacing (exact for uniform records), checked, else binary search.
    fn first_after(&self, t: f64) -> usize {
        let n = self.time.len();
        if n >= 2 {
            let span = self.time[n - 1] - self.time[0];
            let guess = ((t - self.time[0]) / span * (n - 1) as f64).floor() + 1.0;
            if guess >= 1.0 && guess < n as f64 {
                let i = guess as usize;
                if self.time[i - 1] <= t && t < self.time[i] {
                    return i;
                }
            }
        }
        self.time.partition_point(|&x| x <= t)
    }

    /// The linear piece that holds at `t` (looking forward): its value at
    /// `t`, its slope, and where it ends (the next sample, or infinity).
    pub fn piece_at(&self, t: f64) -> (f64, f64, f64) {
        self.piece_before(self.first_after(t), t)
    }

    /// The piece that holds at `t` when `i` is the first sample after `t`.
    #[inline]
    fn piece_before(&self, i: usize, t: f64) -> (f64, f64, f64) {
        let n = self.time.len();
        if i == 0 {
            let end = self.time.first().copied().unwrap_or(f64::INFINITY);
            return (0.0, 0.0, end);
        }
        if i >= n {
            return (0.0, 0.0, f64::INFINITY);
        }
        let (t0, t1) = (self.time[i - 1], self.time[i]);
        let slope = (self.accel[i] - self.accel[i - 1]) / (t1 - t0);
        (self.accel[i - 1] + slope * (t - t0), slope, t1)
    }
}

/// Drives `sim` from its current time to `t_end` under `scale * record`
/// plus `extra` (linear from the current time), splitting at every sample
/// so that each piece is linear.
pub fn advance_with_record<S: Stepper>(
    sim: &mut S,
    t_end: f64,
    record: &GroundMotion,
    scale: f64,
    extra: &Excitation,
) -> Result<(), SimError> {
    if sim.takes_samples(extra) && t_end > sim.time() && record.time.len() >= 2 {
        return advance_by_samples(sim, t_end, record, scale, extra);
    }
    advance_by_pieces(sim, t_end, record, scale, extra)
}

/// As [`advance_with_record`], one linear piece per sample interval.
fn advance_by_pieces<S: Stepper>(
    sim: &mut S,
    t_end: f64,
    record: &GroundMotion,
    scale: f64,
    extra: &Excitation,
) -> Result<(), SimError> {
    let t_start = sim.time();
    let mut t = t_start;
    let mut done = false;
    // First sample after `t`, carried from piece to piece.
    let mut next_sample = record.first_after(t);
    let pieces = std::iter::from_fn(move || {
        if done {
            return None;
        }
        while next_sample < record.time.len() && record.time[next_sample] <= t {
            next_sample += 1;
        }
        let (a, slope, piece_end) = record.piece_before(next_sample, t);
        let t1 = piece_end.min(t_end);
        let dt = t - t_start;
        let exc = Excitation {
            ag: scale * a + extra.ag + extra.ag_rate * dt,
            ag_rate: scale * slope + extra.ag_rate,
            fext: extra.fext + extra.fext_rate * dt,
            fext_rate: extra.fext_rate,
        };
        t = t1;
        done = t1 >= t_end;
        Some((t1, exc))
    });
    sim.advance_pieces(pieces)
}

/// As [`advance_with_record`] for a stepper with a path of its own for
/// whole samples (held inputs): the samples from one at the current time to
/// the last before `t_end` go to it in one call, the partial intervals at
/// either end to [`advance_by_pieces`].
fn advance_by_samples<S: Stepper>(
    sim: &mut S,
    t_end: f64,
    record: &GroundMotion,
    scale: f64,
    extra: &Excitation,
) -> Result<(), SimError> {
    let n = record.time.len();
    let dt = record.time[1] - record.time[0];
    loop {
        let t = sim.time();
        if t >= t_end {
            return Ok(());
        }
        let i = record.first_after(t);
        if i >= 1 && i < n && record.time[i - 1] == t && record.time[i] <= t_end {
            let last = record.time.partition_point(|&x| x <= t_end) - 1;
            sim.advance_samples(&Samples {
                time: &record.time[i - 1..=last],
                accel: &record.accel[i - 1..=last],
                scale,
                ag_offset: extra.ag,
                fext: extra.fext,
                dt,
            })?;
            continue;
        }
        let next_sample = record.time.get(i).copied().unwrap_or(f64::INFINITY);
        advance_by_pieces(sim, next_sample.min(t_end), record, scale, extra)?;
    }
}

/// Runs a whole record from the simulator's current time to the record's end.
pub fn run<S: Stepper>(sim: &mut S, record: &GroundMotion, scale: f64) -> Result<(), SimError> {
    advance_with_record(
        sim,
        record.duration(),
        record,
        scale,
        &Excitation::default(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Collects the pieces it is given.
    struct Recorder {
        t: f64,
        pieces: Vec<(f64, f64, f64)>,
    }

    impl crate::physics::solver::Stepper for Recorder {
        fn time(&self) -> f64 {
            self.t
        }
        fn advance(&mut self, t_end: f64, exc: &Excitation) -> Result<(), SimError> {
            self.pieces.push((t_end, exc.ag, exc.ag_rate));
            self.t = t_end;
            Ok(())
        }
    }

    #[test]
    fn a_record_is_fed_piece_by_piece_as_piece_at_gives_it() {
        // Expected values: `piece_at` (the lookup from scratch) at each
        // piece's start, from a start between samples to an end past them.
        let gm = GroundMotion {
            time: vec![0.0, 0.1, 0.25, 0.3, 0.5],
            accel: vec![1.0, -2.0, 0.5, 4.0, 0.0],
        };
        let mut rec = Recorder {
            t: 0.05,
            pieces: Vec::new(),
        };
        advance_with_record(&mut rec, 0.7, &gm, 2.0, &Excitation::default()).unwrap();
        let mut t = 0.05;
        let mut expected = Vec::new();
        while t < 0.7 {
            let (a, slope, end) = gm.piece_at(t);
            let end = end.min(0.7);
            expected.push((end, 2.0 * a, 2.0 * slope));
            t = end;
        }
        assert_eq!(rec.pieces, expected);
        assert_eq!(rec.pieces.len(), 5);
    }
}
