//! The processor's instruction sets, for the engine's hot functions: each is
//! compiled three times (`copies!`), for the baseline x86-64, for AVX2 (x86-64-v3:
//! three-operand instructions, 16 registers) and for AVX-512 (32 vector registers,
//! which spare its loops most of their spills), and the one to run is chosen at
//! each call. All do the same IEEE operations in the same order (Rust fuses no
//! multiply-add, and no copy enables FMA), so their results are the same bit for
//! bit; elsewhere than on x86-64 there is one.

use crate::physics::engine::{Excitation, Piece, PieceSource, Scratch, Simulator};
use std::sync::atomic::{AtomicU8, Ordering::Relaxed};

/// An instruction set the hot functions are compiled for, from the narrowest.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Isa {
    /// Baseline x86-64 (SSE2), and every other architecture.
    Baseline,
    /// AVX2 with BMI1/2, LZCNT and POPCNT (x86-64-v3 less FMA).
    Avx2,
    /// AVX-512 F and VL.
    Avx512,
}

/// The widest set the engine may use (tests and benchmarks lower it).
static LIMIT: AtomicU8 = AtomicU8::new(Isa::Avx512 as u8);

/// [`available`], once detected (`u8::MAX` before).
static DETECTED: AtomicU8 = AtomicU8::new(u8::MAX);

impl Isa {
    /// The set stored as `code` (`isa as u8`) in [`LIMIT`] or [`DETECTED`].
    #[inline(always)]
    fn from_code(code: u8) -> Option<Isa> {
        [Isa::Baseline, Isa::Avx2, Isa::Avx512]
            .get(usize::from(code))
            .copied()
    }
}

/// The widest set this processor has (std's checks, combined once).
#[inline]
pub fn available() -> Isa {
    Isa::from_code(DETECTED.load(Relaxed)).unwrap_or_else(|| {
        let isa = detect();
        DETECTED.store(isa as u8, Relaxed);
        isa
    })
}

#[cold]
fn detect() -> Isa {
    #[cfg(target_arch = "x86_64")]
    {
        use std::is_x86_feature_detected as has;
        let v3 = has!("avx2") && has!("bmi1") && has!("bmi2") && has!("lzcnt") && has!("popcnt");
        if v3 && has!("avx512f") && has!("avx512vl") {
            return Isa::Avx512;
        }
        if v3 {
            return Isa::Avx2;
        }
    }
    Isa::Baseline
}

/// Lets the engine use the sets up to `limit` where the processor has them
/// (the default: all), for tests and benchmarks of the narrower copies. The
/// results are the same either way.
pub fn allow_up_to(limit: Isa) {
    LIMIT.store(limit as u8, Relaxed);
}

/// The copy that runs: the widest available and allowed.
#[inline(always)]
pub fn chosen() -> Isa {
    match Isa::from_code(LIMIT.load(Relaxed)) {
        Some(Isa::Baseline) => Isa::Baseline,
        limit => available().min(limit.unwrap_or(Isa::Avx512)),
    }
}

/// `copies!(fn name / avx2, avx512 / body (&mut self, args) -> R)` defines the
/// method `name`, which runs the method `body` (`#[inline(always)]`, written
/// out elsewhere) compiled as `avx2` or `avx512` where [`chosen`] says so, else
/// as it is; `copies!(fn name / avx2, avx512 / path::to::body (args) -> R)` the
/// same for a function.
macro_rules! copies {
    (
        $(#[$attr:meta])*
        $vis:vis fn $name:ident / $avx2:ident, $avx512:ident / $body:ident
        $(<$(const $cg:ident : $cty:ty),*>)?
        (&mut self $(, $arg:ident : $aty:ty)*) $(-> $ret:ty)?
    ) => {
        $(#[$attr])*
        #[inline(never)]
        $vis fn $name $(<$(const $cg: $cty),*>)? (&mut self $(, $arg: $aty)*) $(-> $ret)? {
            #[cfg(target_arch = "x86_64")]
            match $crate::isa::chosen() {
                // SAFETY: the processor has the features (`chosen`).
                $crate::isa::Isa::Avx512 => {
                    return unsafe { self.$avx512 $(::<$($cg),*>)? ($($arg),*) };
                }
                // SAFETY: as above.
                $crate::isa::Isa::Avx2 => {
                    return unsafe { self.$avx2 $(::<$($cg),*>)? ($($arg),*) };
                }
                $crate::isa::Isa::Baseline => {}
            }
            self.$body $(::<$($cg),*>)? ($($arg),*)
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
        #[inline(never)]
        unsafe fn $avx2 $(<$(const $cg: $cty),*>)? (&mut self $(, $arg: $aty)*) $(-> $ret)? {
            self.$body $(::<$($cg),*>)? ($($arg),*)
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f,avx512vl")]
        #[inline(never)]
        unsafe fn $avx512 $(<$(const $cg: $cty),*>)? (&mut self $(, $arg: $aty)*) $(-> $ret)? {
            self.$body $(::<$($cg),*>)? ($($arg),*)
        }
    };
    (
        $(#[$attr:meta])*
        $vis:vis fn $name:ident / $avx2:ident, $avx512:ident / $($body:ident)::+ ($($arg:ident : $aty:ty),*) -> $ret:ty
    ) => {
        $(#[$attr])*
        #[inline(never)]
        $vis fn $name($($arg: $aty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            match $crate::isa::chosen() {
                // SAFETY: the processor has the features (`chosen`).
                $crate::isa::Isa::Avx512 => return unsafe { $avx512($($arg),*) },
                // SAFETY: as above.
                $crate::isa::Isa::Avx2 => return unsafe { $avx2($($arg),*) },
                $crate::isa::Isa::Baseline => {}
            }
            $($body)::+($($arg),*)
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
        #[inline(never)]
        unsafe fn $avx2($($arg: $aty),*) -> $ret {
            $($body)::+($($arg),*)
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f,avx512vl")]
        #[inline(never)]
        unsafe fn $avx512($($arg: $aty),*) -> $ret {
            $($body)::+($($arg),*)
        }
    };
}
pub(crate) use copies;

// The engine's two hottest functions (with everything they inline): the
// driver's runs of substeps and the event path's stretches. Their callees
// out of line (a new mode's resolution, a stretch's Taylor series) are not:
// a second dispatch in each cost more than it gave (measured,
// docs/accuracy-speed.md, session 15).
impl Simulator {
    copies! {
        /// [`Simulator::sweep_run`], compiled three times.
        pub(crate) fn sweep_clusters / sweep_avx2, sweep_avx512 / sweep_run
            <const NC: usize, const AG: bool, const RUNS: u8>
            (&mut self, piece: &mut Piece, pieces: &mut impl PieceSource)
            -> Option<(f64, Excitation)>
    }

    copies! {
        /// [`Simulator::stretch_run`], compiled three times.
        pub(crate) fn exact_stretch / stretch_avx2, stretch_avx512 / stretch_run(
            &mut self, t1: f64, piece: &Piece, depth: u32, work: &mut Scratch
        )
    }
}
