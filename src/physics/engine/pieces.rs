//! The excitation over an interval, its linear pieces cut into equal
//! substeps, and the default's step constants.

use super::*;

/// Excitation over one interval, linear in time from the interval start:
/// `ag(t) = ag + ag_rate (t - t_start)`, and likewise the external force.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Excitation {
    /// Ground (support) acceleration at the interval start (m/s^2).
    pub ag: f64,
    /// Its slope over the interval (m/s^3); 0 holds it constant.
    pub ag_rate: f64,
    /// External force on the structure at the interval start (N).
    pub fext: f64,
    /// Its slope (N/s).
    pub fext_rate: f64,
}

impl Excitation {
    /// `(ag, Fext)` at `dt` after the piece's start.
    #[inline(always)]
    pub fn at(&self, dt: f64) -> (f64, f64) {
        (self.ag + self.ag_rate * dt, self.fext + self.fext_rate * dt)
    }

    /// Checks that a step from `now` to `t_end` under this piece is possible:
    /// every value finite and time not going back.
    #[inline]
    pub fn check(&self, now: f64, t_end: f64) -> Result<(), SimError> {
        // A sum that is not finite (a bad value, or finite ones
        // overflowing) goes to the detailed check.
        let sum = self.ag + self.ag_rate + self.fext + self.fext_rate + t_end;
        if finite_terms(sum) && t_end >= now {
            return Ok(());
        }
        self.check_each(now, t_end)
    }

    #[cold]
    pub(super) fn check_each(&self, now: f64, t_end: f64) -> Result<(), SimError> {
        for (name, value) in [
            ("ag", self.ag),
            ("der(ag)", self.ag_rate),
            ("Fext", self.fext),
            ("der(Fext)", self.fext_rate),
            ("t_end", t_end),
        ] {
            if !value.is_finite() {
                return Err(SimError::BadInput { name, value });
            }
        }
        if t_end < now {
            return Err(SimError::BadTime { now, t_end });
        }
        Ok(())
    }
}

/// A source of consecutive linear pieces of excitation, each given by its end time and its
/// excitation (values at its start). Any iterator of pieces is a source through [`Plain`].
pub trait PieceSource {
    /// The next piece, or `None` at the end.
    fn next_piece(&mut self) -> Option<(f64, Excitation)>;

    /// How many of the next pieces the source may promise to continue the one it gave last, as a
    /// record's next samples do (each as long as the last up to the rounding of the times, 1e-15
    /// relative, `Fext` held with a zero rate, every value finite): the driver takes them with
    /// [`PieceSource::continuing`], keeping its substeps without checking them again, and then
    /// tells the source with [`PieceSource::skip`]. Lean methods of their own, so that the common
    /// piece is built in registers, its place counted by the driver.
    #[inline(always)]
    fn promised(&self) -> usize {
        0
    }

    /// Promised piece `k` (`k < promised()`): its end, `ag` and `ag_rate` (`Fext` and its zero rate
    /// stay as they were), if it keeps the promise; `None` takes nothing (the driver calls `skip`
    /// with the pieces taken and asks `next_piece`), and asked again before that answers `None`
    /// again. A source may move on as it gives a piece, or leave that to `skip`.
    #[inline(always)]
    fn continuing(&mut self, _k: usize) -> Option<(f64, f64, f64)> {
        None
    }

    /// The driver took the first `k` promised pieces.
    #[inline(always)]
    fn skip(&mut self, _k: usize) {}
}

/// An iterator of pieces as a [`PieceSource`] that promises nothing (one
/// piece: `Simulator::advance`).
pub struct Plain<I>(pub I);

impl<I: Iterator<Item = (f64, Excitation)>> PieceSource for Plain<I> {
    #[inline(always)]
    fn next_piece(&mut self) -> Option<(f64, Excitation)> {
        self.0.next()
    }
}

/// An iterator of pieces as a [`PieceSource`] that promises each next piece and checks the promise
/// as it gives it (the checks a record makes once for a stretch of samples): a piece that breaks it
/// waits for `next_piece`, which the driver checks in full.
pub struct CheckedPieces<I> {
    pieces: std::iter::Fuse<I>,
    waiting: Option<(f64, Excitation)>,
    /// A jump of `ag` breaks the promise (it moves a prescribed support).
    ag_continuous: bool,
    /// The end of the last piece given, the length of the last given by `next_piece` (NaN before
    /// the second: no promise), `Fext` if held (NaN if not: no promise) and `ag` at that end.
    end: f64,
    length: f64,
    fext: f64,
    ag_end: f64,
}

impl<I: Iterator> CheckedPieces<I> {
    /// The pieces of `pieces` up to its first `None` for a scene of `sys`, the first to be checked
    /// in full; on a prescribed support a jump of `ag` breaks the promise (it moves the support).
    pub fn new(pieces: I, sys: &System) -> CheckedPieces<I> {
        CheckedPieces {
            pieces: pieces.fuse(),
            waiting: None,
            ag_continuous: sys.prescribed(),
            end: f64::NAN,
            length: f64::NAN,
            fext: f64::NAN,
            ag_end: f64::NAN,
        }
    }
}

impl<I: Iterator<Item = (f64, Excitation)>> PieceSource for CheckedPieces<I> {
    #[inline(always)]
    fn next_piece(&mut self) -> Option<(f64, Excitation)> {
        let (t_end, exc) = self.waiting.take().or_else(|| self.pieces.next())?;
        let length = t_end - self.end;
        self.length = length;
        self.end = t_end;
        self.fext = if exc.fext_rate == 0.0 {
            exc.fext
        } else {
            f64::NAN
        };
        self.ag_end = exc.at(length).0;
        Some((t_end, exc))
    }

    #[inline(always)]
    fn promised(&self) -> usize {
        if self.length > 0.0 && !self.fext.is_nan() {
            usize::MAX
        } else {
            0
        }
    }

    #[inline(always)]
    fn continuing(&mut self, _k: usize) -> Option<(f64, f64, f64)> {
        if self.waiting.is_some() {
            return None;
        }
        let (t_end, exc) = self.pieces.next()?;
        // As long as the last up to rounding, Fext held (bit for bit; a -0.0
        // goes to `next_piece`'s full check), every value finite (`sum * 0` is 0 then, else NaN, which
        // fails the length's test), and where it matters `ag` without a jump.
        let sum = exc.ag + exc.ag_rate + t_end;
        if exc.fext_rate.to_bits() == 0
            && exc.fext.to_bits() == self.fext.to_bits()
            && continues_as_long(self.end, t_end + sum * 0.0, self.length)
            && !(self.ag_continuous && is_jump(exc.ag, self.ag_end))
        {
            if self.ag_continuous {
                self.ag_end = exc.at(t_end - self.end).0;
            }
            self.end = t_end;
            return Some((t_end, exc.ag, exc.ag_rate));
        }
        self.waiting = Some((t_end, exc));
        None
    }
}

/// One linear piece of excitation from `t_ref` to `t_end`, cut into `n`
/// equal substeps of `h`; `i` is the next substep to take (1-based).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Piece {
    pub(super) exc: Excitation,
    pub(super) t_ref: f64,
    pub(super) t_end: f64,
    pub(super) n: usize,
    pub(super) h: f64,
    pub(super) i: usize,
}

impl Piece {
    pub(super) fn new(t_ref: f64, t_end: f64, exc: &Excitation, h_max: f64) -> Piece {
        let length = t_end - t_ref;
        // One substep without a division: most of a record's samples.
        let (n, h) = if length > 0.0 && length <= h_max {
            (1, length)
        } else if length > 0.0 {
            let n = substeps(length, h_max);
            (n as usize, length / n)
        } else {
            (0, 0.0)
        };
        Piece {
            exc: *exc,
            t_ref,
            t_end,
            n,
            h,
            i: 1,
        }
    }

    /// A copy read one field at a time: a caller has just written the piece field by field, and a
    /// wider load across two such stores waits for them to reach the cache (a store-forwarding
    /// stall: 6-8 % of a one-substep call, measured; the bare structure's record path +2 %).
    #[inline(always)]
    pub(super) fn read_by_field(&self) -> Piece {
        // SAFETY: fields of a live reference (volatile: never merged wider).
        let x = |field: &f64| unsafe { std::ptr::read_volatile(field) };
        let k = |field: &usize| unsafe { std::ptr::read_volatile(field) };
        let e = &self.exc;
        Piece {
            exc: Excitation {
                ag: x(&e.ag),
                ag_rate: x(&e.ag_rate),
                fext: x(&e.fext),
                fext_rate: x(&e.fext_rate),
            },
            t_ref: x(&self.t_ref),
            t_end: x(&self.t_end),
            n: k(&self.n),
            h: x(&self.h),
            i: k(&self.i),
        }
    }

    /// Whether a piece from `t_ref` to `t_end` is as long as this one up to the rounding of their
    /// times (a record's next sample): it then keeps this one's substeps.
    #[inline(always)]
    pub(super) fn same_length(&self, t_ref: f64, t_end: f64) -> bool {
        self.n > 0 && continues_as_long(t_ref, t_end, self.t_end - self.t_ref)
    }

    /// End time of substep `i` (the last one ends exactly at `t_end`).
    #[inline]
    pub(super) fn end_of(&self, i: usize) -> f64 {
        if i == self.n {
            self.t_end
        } else {
            self.t_ref + i as f64 * self.h
        }
    }
}

/// The default's fine stretches where the exact event path (`exact_events`) cannot decide a substep
/// within its budget (a guard hovering at rounding level): `h ω_p <= 0.01` and `h <= 0.625 ms`, so
/// that such a substep stays below 1e-9 of the peaks (docs/accuracy-speed.md, "Accuracy").
pub const FINE_H_OMEGA: f64 = 0.01;
/// See [`FINE_H_OMEGA`].
pub const FINE_MAX_STEP: f64 = 0.000625;
/// Event tolerance on time (s).
pub const EVENT_TIME_TOL: f64 = 1e-12;
/// Chatter guard: at most this many located events in one internal step;
/// past it the rest of the step switches at its end only.
pub const MAX_EVENTS_PER_STEP: u32 = 64;

/// Whether an interval of `length` ending at `t_end` is as long as one of
/// `other` up to the rounding of the times (1e-15 of the time): a
/// record's next sample, which keeps the previous one's substeps and map.
#[inline(always)]
pub fn same_up_to_rounding(length: f64, other: f64, t_end: f64) -> bool {
    (length - other).abs() <= 1e-15 * (t_end.abs() + other)
}

/// Whether the terms of `sum` were all finite (a sum that is not: a bad value, or finite ones
/// overflowing): `x - x` is 0 exactly where `x` is finite, one subtraction.
#[inline(always)]
#[allow(clippy::eq_op)]
pub fn finite_terms(sum: f64) -> bool {
    sum - sum == 0.0
}

/// Whether a piece from `t_start` to `t_end` goes forward and is as long as
/// `other` up to the rounding of the times (a piece of a few ulps must not
/// pass for the next when it is empty or goes back).
#[inline(always)]
fn continues_as_long(t_start: f64, t_end: f64, other: f64) -> bool {
    t_end > t_start && same_up_to_rounding(t_end - t_start, other, t_end)
}

/// Whether `Fext` moving from `before` to `after` at an instant is a jump (which can break a
/// stick), not the rounding of a ramp carried across pieces.
#[inline(always)]
pub(super) fn is_jump(after: f64, before: f64) -> bool {
    (after - before).abs() > 1e-12 * after.abs().max(before.abs())
}

/// Number of equal substeps of at most `h_max` in an interval of `length`.
/// A ratio within 1e-9 of an integer is that integer: the interval is a
/// difference of times carrying rounding, and must not cost an extra step.
pub fn substeps(length: f64, h_max: f64) -> f64 {
    let x = length / h_max * (1.0 - 1e-9);
    // `ceil` without a libm call on the baseline x86-64 target.
    if x < 1.0 {
        return 1.0;
    }
    if x >= 4.5e15 {
        return x.ceil();
    }
    let floor = x as i64 as f64;
    if floor < x {
        floor + 1.0
    } else {
        floor
    }
}
