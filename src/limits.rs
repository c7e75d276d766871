//! The limits that keep an instance safe inside its importer's process:
//! bounded record files, bounded work per call, no non-finite value behind
//! fmi2OK, and messages that quote only a few characters of a file.
//! `docs/robustness.md` lists them with what each bad input gets.

use crate::physics::engine::Outputs;
use crate::physics::params::MAX_BLOCKS;
use std::fmt;

/// A number in a message: the shortest digits that read back the same, in
/// exponent form where plain decimals would run long (`1e300` would take
/// 301 characters, `5e-324` 326).
#[derive(Clone, Copy, Debug)]
pub struct Num(pub f64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.0.abs();
        if a.is_finite() && a != 0.0 && !(1e-6..1e9).contains(&a) {
            write!(f, "{:e}", self.0)
        } else {
            write!(f, "{}", self.0)
        }
    }
}

/// Largest record file read (bytes): 10 million CSV samples fit with room.
pub const MAX_RECORD_BYTES: u64 = 512 << 20;
/// Longest line of a record file (bytes, without its end of line).
pub const MAX_RECORD_LINE: usize = 4096;
/// Most samples in a record: 2.8 hours at 1 kHz (160 MB in memory).
pub const MAX_RECORD_SAMPLES: usize = 10_000_000;
/// Shortest sample interval of a record (s): a 1 MHz record.
pub const MIN_RECORD_DT: f64 = 1e-6;
/// Largest absolute sample time of a CSV record and largest AT2 `DT` (s):
/// about 11.6 days, far beyond any record.
pub const MAX_RECORD_TIME: f64 = 1e6;
/// Largest absolute acceleration in a record (m/s^2, after the AT2
/// conversion from g): 100 000 g.
pub const MAX_RECORD_ACCEL: f64 = 1e6;
/// Largest absolute start and stop time (s): about 31 years, where a double
/// still resolves 0.1 µs (at 1e16 s, `t + 1` would round back to `t`).
pub const MAX_TIME: f64 = 1e9;
/// Longest `recordFile` string (bytes), as the usual `PATH_MAX`.
pub const MAX_PATH_BYTES: usize = 4096;
/// Most characters of a file's content a message quotes.
pub const MAX_QUOTE_CHARS: usize = 24;
/// Most work one call may do (one `fmi2DoStep`, one `sllRunBatch`), in
/// units of one internal step of the exact engine (30-70 ns): a few seconds.
/// Counted up front, where it can be known: the internal steps of the
/// interval and the record samples inside it (a step of solver 2 counts as
/// 3, one of solver 3 as [`regularized_step_weight`]); counted as it
/// happens: every internal step, [`SWITCH_WORK`] per stick/slip switch and
/// [`TRY_WORK`] per mode the resolver tries (the engine's work budget).
pub const MAX_STEPS_PER_CALL: f64 = 1e8;

/// The work of one stick/slip switch beyond the resolver's tries, in
/// internal steps: locating it, rebuilding the mode's dynamics and the
/// substep around it (measured about 3 µs with 1 to 8 blocks, where an
/// internal step takes about 50 ns: `examples/work_bound.rs`).
pub const SWITCH_WORK: u64 = 64;

/// The work of one assignment the mode resolver tries, in internal steps
/// (measured about 0.1 µs with 8 blocks).
pub const TRY_WORK: u64 = 2;

/// The distance from `x` to the next double away from zero (the unit in
/// the last place; the smallest subnormal at 0).
pub fn ulp(x: f64) -> f64 {
    let a = x.abs();
    if !a.is_finite() {
        return f64::NAN;
    }
    f64::from_bits(a.to_bits() + 1) - a
}

/// How far a master's `currentCommunicationPoint` may be from the FMU's
/// time: the rounding of two clocks that added the same `steps` step sizes
/// in a different order or frame, `steps + 4` units in the last place of the
/// larger of the time and the start time, and never more than 1e-9 of it.
pub fn time_tolerance(time: f64, start: f64, steps: u64) -> f64 {
    let scale = time.abs().max(start.abs());
    ((steps as f64 + 4.0) * ulp(scale)).min(1e-9 * scale)
}

/// Whether time `t` is at most `stop`, up to 1e-9 of it (fmpy takes a
/// communication point within that of the stop time as the stop time).
pub fn within_stop(t: f64, stop: f64) -> bool {
    t <= stop + 1e-9 * stop.abs().max(1.0)
}

/// Whether `dt`, the step of a record between samples near time `t` (as read
/// from a file), is at least [`MIN_RECORD_DT`] up to the rounding of the
/// file's decimal times: 1e-9 of the step, and 4 units in the last place of
/// `t` (a CSV written every microsecond up to 10 s has steps 2e-15 s short).
/// The one rule of every reader.
pub fn record_step_allowed(dt: f64, t: f64) -> bool {
    dt >= MIN_RECORD_DT * (1.0 - 1e-9) - 4.0 * ulp(t)
}

/// What one internal step of solver 3 costs in steps of the exact engine:
/// it evaluates every interface's `tanh` 6 times a step (four RK4 stages and
/// the peaks); measured about 260 ns a step with 1 block, 2.4 us with 8.
pub fn regularized_step_weight(n_blocks: usize) -> f64 {
    6.0 * (n_blocks + 1) as f64
}

/// At most [`MAX_QUOTE_CHARS`] characters of `text` between backquotes,
/// control characters shown as `?`, `...` when cut.
pub fn quote(text: &str) -> String {
    let mut out: String = text
        .chars()
        .take(MAX_QUOTE_CHARS)
        .map(|c| if c.is_control() { '?' } else { c })
        .collect();
    if text.chars().nth(MAX_QUOTE_CHARS).is_some() {
        out.push_str("...");
    }
    format!("`{out}`")
}

/// The work of covering `length` (s) in internal steps of at most `h_max`
/// with `samples` record samples inside, each step weighing `weight`: what
/// is counted up front.
pub fn work_estimate(length: f64, h_max: f64, samples: usize, weight: f64) -> f64 {
    (length / h_max + samples as f64) * weight
}

/// The error of a call that would need more than [`MAX_STEPS_PER_CALL`]
/// internal steps, or `None` when it fits. `length` is the interval (s),
/// `h_max` the largest internal step, `samples` the record samples inside,
/// `weight` the cost of one internal step in exact-engine steps.
pub fn work_error(length: f64, h_max: f64, samples: usize, weight: f64) -> Option<String> {
    let steps = work_estimate(length, h_max, samples, 1.0);
    (steps * weight > MAX_STEPS_PER_CALL).then(|| {
        let counted = if weight == 1.0 {
            String::new()
        } else {
            format!(", each counted as {weight} for its solver's cost")
        };
        format!(
            "stepping {} s would take about {steps:.3e} internal steps \
             (internal step {h_max:.3e} s, {samples} record samples{counted}), more than \
             the limit of {MAX_STEPS_PER_CALL:e} per call: split it into shorter \
             communication steps, or raise maxStep",
            Num(length)
        )
    })
}

/// The first output that is NaN or infinite, by its FMU name, with its value.
pub fn first_non_finite(o: &Outputs) -> Option<(String, f64)> {
    let scalars = [
        ("up", o.up),
        ("vp", o.vp),
        ("apAbs", o.ap_abs),
        ("baseShear", o.base_shear),
        ("peakUp", o.peak_up),
        ("peakApAbs", o.peak_ap_abs),
        ("Einput", o.e_input),
        ("Ekinetic", o.e_kinetic),
        ("Estrain", o.e_strain),
        ("Eviscous", o.e_viscous),
        ("Efriction", o.e_friction),
    ];
    if let Some((name, x)) = scalars.iter().find(|(_, x)| !x.is_finite()) {
        return Some((name.to_string(), *x));
    }
    let arrays: [(&str, &[f64; MAX_BLOCKS]); 6] = [
        ("ub", &o.ub),
        ("vb", &o.vb),
        ("slip", &o.slip),
        ("abAbs", &o.ab_abs),
        ("F", &o.force),
        ("peakSlip", &o.peak_slip),
    ];
    for j in 0..MAX_BLOCKS {
        for (name, xs) in arrays {
            if !xs[j].is_finite() {
                return Some((format!("{name}[{}]", j + 1), xs[j]));
            }
        }
    }
    None
}

/// The error for outputs holding a NaN or an infinity: the first such
/// variable, its value and the time.
pub fn non_finite_message(o: &Outputs, start_time: f64) -> Option<String> {
    first_non_finite(o).map(|(name, x)| {
        format!(
            "{name} = {} at t = {} s: the state or an output left the finite numbers \
             (inputs or parameters too large for this scene)",
            Num(x),
            Num(start_time + o.t)
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quotes_are_short_and_printable() {
        assert_eq!(quote("abc"), "`abc`");
        let long = "root:x:0:0:root:/root:/bin/bash";
        let q = quote(long);
        assert_eq!(q, "`root:x:0:0:root:/root:/b...`");
        assert_eq!(quote("a\u{1b}[2Jb"), "`a?[2Jb`");
    }

    #[test]
    fn work_beyond_the_limit_is_named() {
        assert!(work_error(20.0, 1e-3, 4000, 1.0).is_none());
        let e = work_error(1.0, 1e-12, 0, 1.0).unwrap();
        assert!(e.contains("1.000e12 internal steps"), "{e}");
        assert!(work_error(0.0, 1e-3, MAX_RECORD_SAMPLES, 1.0).is_none());
        // Solver 3 with 8 blocks: 54 times the cost of a step.
        assert!(work_error(1000.0, 1e-4, 0, 1.0).is_none());
        let e = work_error(1000.0, 1e-4, 0, regularized_step_weight(8)).unwrap();
        assert!(e.contains("each counted as 54 for its solver"), "{e}");
    }

    #[test]
    fn the_first_non_finite_output_is_named() {
        let mut o = Outputs::default();
        assert_eq!(first_non_finite(&o), None);
        o.slip[2] = f64::NAN;
        o.peak_slip[1] = f64::INFINITY;
        let (name, x) = first_non_finite(&o).unwrap();
        assert_eq!(name, "peakSlip[2]");
        assert!(x.is_infinite());
        o.e_input = f64::NEG_INFINITY;
        assert_eq!(first_non_finite(&o).unwrap().0, "Einput");
    }
}
