//! Ground-motion records: the [`GroundMotion`] table, and driving a
//! simulator through one. The file readers (PEER `.AT2`, CSV, single
//! column) are in `formats.rs`, as `GroundMotion` constructors.
//!
//! A record is a table of samples; between samples the acceleration is
//! linear, before the first and after the last it is zero.

use crate::physics::engine::{same_up_to_rounding, Excitation, PieceSource, SimError};
use crate::solver::Stepper;
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
    let n = record.time.len().min(record.accel.len());
    let mut pieces = RecordPieces {
        dt,
        inv_dt: 1.0 / dt,
        time: &record.time[..n],
        accel: &record.accel[..n],
        record,
        scale,
        extra: *extra,
        t_start: t,
        t,
        t_end,
        next_sample: record.first_after(t),
        stop: 0,
        after_end: record.first_after(t_end).min(n),
        promise: extra.fext_rate == 0.0 && extra.fext.is_finite() && dt > 0.0 && dt.is_finite(),
        continue_stop: 0,
        uniform_end: 0,
        steady: extra.ag_rate == 0.0 && extra.fext_rate == 0.0,
        yielded: false,
        done: false,
    };
    pieces.align();
    sim.advance_source(pieces)
}

/// The linear pieces of `scale * record + extra` from `t` to `t_end`, one
/// per sample interval (the first and last may be partial).
struct RecordPieces<'a> {
    record: &'a GroundMotion,
    /// The samples (as many times as accelerations).
    time: &'a [f64],
    accel: &'a [f64],
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
    /// While `next_sample < stop`, the next piece is a whole sample
    /// interval ending at or before `t_end` (0 while `t` is not on a sample).
    stop: usize,
    /// First sample after `t_end` (at most the number of samples).
    after_end: usize,
    /// `Fext` constant and finite (it cannot jump between pieces), and the
    /// first interval positive and finite: a whole interval as long as it
    /// may be promised to continue the last one.
    promise: bool,
    /// While the piece yielded last was a whole interval as long as the
    /// first (and `promise`), the end of the whole intervals as long as the
    /// first that follow it ([`RecordPieces::uniform_from`]); else 0. The
    /// intervals before it may be promised to continue the last one.
    continue_stop: usize,
    /// The intervals that end at samples from the last one looked at up
    /// to this one (excluded) are as long as the first up to rounding
    /// (looked for once per stretch, [`RecordPieces::uniform_from`]).
    uniform_end: usize,
    /// `extra` is constant (no rates).
    steady: bool,
    /// A piece was yielded (or the lean path will yield one next): the
    /// pieces end once `t` reaches `t_end`.
    yielded: bool,
    done: bool,
}

impl RecordPieces<'_> {
    /// Where `t` is on a sample, the whole intervals that follow it up to
    /// `t_end` take the lean path.
    fn align(&mut self) {
        let i = self.next_sample;
        self.stop = if i >= 1 && i < self.time.len() && self.time[i - 1] == self.t {
            self.after_end
        } else {
            0
        };
        // The lean path yields next (it does not mark its pieces).
        self.yielded |= i < self.stop;
        self.uniform_end = 0;
    }

    /// The piece from `self.t` given its value, slope and end, and the
    /// iterator moved past it.
    #[inline(always)]
    fn piece(&mut self, a: f64, slope: f64, piece_end: f64, i: usize) -> (f64, Excitation) {
        let t1 = if piece_end < self.t_end {
            piece_end
        } else {
            self.t_end
        };
        let exc = self.excitation(self.t, a, slope);
        self.t = t1;
        self.done = t1 >= self.t_end;
        if piece_end <= t1 {
            self.next_sample = i + 1;
        }
        (t1, exc)
    }

    /// The whole sample interval that ends at sample `i` (its start at
    /// `self.t`): its start value, slope, and whether it is as long as the
    /// first interval up to rounding.
    #[inline(always)]
    fn whole(&self, i: usize) -> (f64, f64, bool) {
        let ([t0, t1], [a0, a1]) = (pair(self.time, i), pair(self.accel, i));
        let rise = a1 - a0;
        let uniform = same_up_to_rounding(t1 - t0, self.dt, t1);
        let slope = if uniform {
            rise * self.inv_dt
        } else {
            rise / (t1 - t0)
        };
        (a0, slope, uniform)
    }

    /// The first sample from `k >= 1` on (`stop` at most) whose interval is
    /// not as long as the first up to the rounding of the times.
    fn uniform_from(&mut self, k: usize) -> usize {
        if k < self.uniform_end {
            return self.uniform_end;
        }
        self.uniform_end = uniform_end(self.time, self.dt, self.stop, k);
        self.uniform_end
    }

    /// A partial interval, one before the first or after the last sample,
    /// or a whole one that `t_end` cuts.
    #[cold]
    #[inline(never)]
    fn partial(&mut self) -> Option<(f64, Excitation)> {
        if self.done || (self.yielded && self.t >= self.t_end) {
            return None;
        }
        let i = self.next_sample;
        let (t1, exc) = if i >= 1 && i < self.time.len() && self.time[i - 1] == self.t {
            let (a, slope, _) = self.whole(i);
            self.piece(a, slope, self.time[i], i)
        } else {
            let (a, slope, piece_end) = self.record.piece_before(i, self.t);
            let piece = self.piece(a, slope, piece_end, i);
            if i >= self.record.time.len() {
                self.next_sample = i;
            }
            piece
        };
        self.continue_stop = 0;
        self.yielded = true;
        self.align();
        Some((t1, exc))
    }
}

crate::isa::copies! {
    /// The first sample from `k >= 1` on (`stop` at most) whose interval is not `dt` long up to
    /// the rounding of the times; compiled per instruction set (`crate::isa`: eight samples to a
    /// register on AVX-512), the same comparisons in each.
    fn uniform_end / uniform_end_avx2, uniform_end_avx512 / uniform_end_of
        (time: &[f64], dt: f64, stop: usize, k: usize) -> usize
}

#[inline(always)]
fn uniform_end_of(time: &[f64], dt: f64, stop: usize, k: usize) -> usize {
    let uniform = |t0: f64, t1: f64| same_up_to_rounding(t1 - t0, dt, t1);
    let mut j = k;
    // Eight at a time, each eight checked whole (no branch per sample,
    // and no bounds checks: the chunks of the times from `k - 1` and
    // from `k`).
    let t = &time[k - 1..stop];
    for (t0, t1) in t.chunks_exact(8).zip(t[1..].chunks_exact(8)) {
        if !t0
            .iter()
            .zip(t1)
            .fold(true, |all, (&a, &b)| all & uniform(a, b))
        {
            break;
        }
        j += 8;
    }
    while j < stop && uniform(time[j - 1], time[j]) {
        j += 1;
    }
    j
}

/// Samples `i - 1` and `i` (one bounds check).
#[inline(always)]
fn pair(x: &[f64], i: usize) -> [f64; 2] {
    let p = &x[i - 1..i + 1];
    [p[0], p[1]]
}

impl PieceSource for RecordPieces<'_> {
    #[inline]
    fn next_piece(&mut self) -> Option<(f64, Excitation)> {
        let i = self.next_sample;
        if i >= self.stop {
            return self.partial();
        }
        let (a, slope, uniform) = self.whole(i);
        self.continue_stop = if uniform & self.promise {
            self.uniform_from(i + 1)
        } else {
            0
        };
        let (t1, exc) = self.lean(i, a, slope);
        (self.t, self.next_sample) = (t1, i + 1);
        Some((t1, exc))
    }

    #[inline(always)]
    fn promised(&self) -> usize {
        self.continue_stop.saturating_sub(self.next_sample)
    }

    #[inline(always)]
    #[allow(clippy::eq_op)] // `sum - sum`: the finiteness test below
    fn continuing(&mut self, k: usize) -> Option<(f64, f64, f64)> {
        // A whole sample interval from its first sample, ending at or
        // before `t_end` (the usual case), as long as the last (looked
        // for once, `uniform_from`): its slope by the product (the
        // division only where `whole` needs it).
        let i = self.next_sample + k;
        let ([t0, t1], [a0, a1]) = (pair(self.time, i), pair(self.accel, i));
        let exc = self.excitation(t0, a0, (a1 - a0) * self.inv_dt);
        // `engine::finite_terms` (Fext is finite by the promise), written
        // out: calling it moved the sample loop's code, +1.7 % instructions
        // on the bare structure.
        let sum = exc.ag + exc.ag_rate + t1;
        if sum - sum != 0.0 {
            return None;
        }
        Some((t1, exc.ag, exc.ag_rate))
    }

    #[inline(always)]
    fn skip(&mut self, k: usize) {
        if k > 0 {
            self.next_sample += k;
            self.t = self.time[self.next_sample - 1];
        }
    }
}

impl RecordPieces<'_> {
    /// The whole interval that ends at sample `i <= t_end` (from `self.t`,
    /// its start): `piece` without its cuts, and without moving on.
    #[inline(always)]
    fn lean(&self, i: usize, a: f64, slope: f64) -> (f64, Excitation) {
        (pair(self.time, i)[1], self.excitation(self.t, a, slope))
    }

    /// `scale * record + extra` from `t`, where the record is `a` with
    /// slope `slope`.
    #[inline(always)]
    fn excitation(&self, t: f64, a: f64, slope: f64) -> Excitation {
        let (e, dt) = (&self.extra, t - self.t_start);
        if self.steady {
            // `extra` constant: its rates' terms are zeros.
            return Excitation {
                ag: self.scale * a + e.ag,
                ag_rate: self.scale * slope,
                fext: e.fext,
                fext_rate: 0.0,
            };
        }
        Excitation {
            ag: self.scale * a + e.ag + e.ag_rate * dt,
            ag_rate: self.scale * slope + e.ag_rate,
            fext: e.fext + e.fext_rate * dt,
            fext_rate: e.fext_rate,
        }
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

    impl crate::solver::Stepper for Recorder {
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
