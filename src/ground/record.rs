//! Ground-motion records: the [`GroundMotion`] table, and driving a
//! simulator through one. The file readers (PEER `.AT2`, CSV, single
//! column) are in `formats.rs`, as `GroundMotion` constructors.
//!
//! A record is a table of samples; between samples the acceleration is
//! linear, before the first and after the last it is zero.

use crate::physics::engine::{Excitation, SimError};
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
    let t = sim.time();
    let dt = if record.time.len() >= 2 {
        record.time[1] - record.time[0]
    } else {
        f64::INFINITY
    };
    let pieces = RecordPieces {
        dt,
        inv_dt: 1.0 / dt,
        record,
        scale,
        extra: *extra,
        t_start: t,
        t,
        t_end,
        next_sample: record.first_after(t),
        done: false,
    };
    sim.advance_pieces(pieces)
}

/// The linear pieces of `scale * record + extra` from `t` to `t_end`, one
/// per sample interval (the first and last may be partial).
struct RecordPieces<'a> {
    record: &'a GroundMotion,
    /// The record's first interval and its reciprocal: an interval as long
    /// up to the rounding of its times takes its slope by a product (a
    /// division per sample would sit on the engine's critical path).
    dt: f64,
    inv_dt: f64,
    scale: f64,
    extra: Excitation,
    t_start: f64,
    t: f64,
    t_end: f64,
    /// First sample after `t`.
    next_sample: usize,
    done: bool,
}

impl RecordPieces<'_> {
    /// The piece from `self.t` given its value, slope and end, and the
    /// iterator moved past it.
    #[inline(always)]
    fn piece(&mut self, a: f64, slope: f64, piece_end: f64, i: usize) -> (f64, Excitation) {
        let t1 = if piece_end < self.t_end {
            piece_end
        } else {
            self.t_end
        };
        let (e, dt) = (&self.extra, self.t - self.t_start);
        let exc = Excitation {
            ag: self.scale * a + e.ag + e.ag_rate * dt,
            ag_rate: self.scale * slope + e.ag_rate,
            fext: e.fext + e.fext_rate * dt,
            fext_rate: e.fext_rate,
        };
        self.t = t1;
        self.done = t1 >= self.t_end;
        if piece_end <= t1 {
            self.next_sample = i + 1;
        }
        (t1, exc)
    }

    /// A partial interval, or one before the first or after the last sample.
    #[cold]
    #[inline(never)]
    fn partial(&mut self) -> (f64, Excitation) {
        let i = self.next_sample;
        let (a, slope, piece_end) = self.record.piece_before(i, self.t);
        let (t1, exc) = self.piece(a, slope, piece_end, i);
        if i >= self.record.time.len() {
            self.next_sample = i;
        }
        (t1, exc)
    }
}

impl Iterator for RecordPieces<'_> {
    type Item = (f64, Excitation);

    #[inline(always)]
    fn next(&mut self) -> Option<(f64, Excitation)> {
        if self.done {
            return None;
        }
        let (time, accel, i) = (
            &self.record.time[..],
            &self.record.accel[..],
            self.next_sample,
        );
        if i == 0 || i >= time.len() || i >= accel.len() || time[i - 1] != self.t {
            return Some(self.partial());
        }
        // A whole sample interval from its first sample (the usual case).
        let (t0, t1) = (time[i - 1], time[i]);
        let rise = accel[i] - accel[i - 1];
        let slope = if ((t1 - t0) - self.dt).abs() <= 1e-15 * (t1.abs() + self.dt) {
            rise * self.inv_dt
        } else {
            rise / (t1 - t0)
        };
        Some(self.piece(accel[i - 1], slope, t1, i))
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
