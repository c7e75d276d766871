//! The processor's instruction sets, for the engine's hot functions: each is
//! compiled twice (`twice!`), for the baseline x86-64 and for AVX-512,
//! whose 32 vector registers spare its loops most of their spills, and the
//! one to run is chosen at each call. Both do the same IEEE operations in the
//! same order (Rust fuses no multiply-add), so their results are the same
//! bit for bit; elsewhere than on x86-64 there is one.

use crate::physics::engine::{Excitation, Piece, PieceSource, Scratch, Simulator};
use std::sync::atomic::{AtomicBool, Ordering::Relaxed};

static WIDE_ALLOWED: AtomicBool = AtomicBool::new(true);

/// Whether this processor has AVX-512 (F and VL; std caches the detection).
#[inline]
pub fn wide_registers_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    let available =
        std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("avx512vl");
    #[cfg(not(target_arch = "x86_64"))]
    let available = false;
    available
}

/// Lets the engine use AVX-512 where the processor has it (the default), or
/// not: for tests and benchmarks of the baseline code on such a processor.
/// The results are the same either way.
pub fn allow_wide_registers(allowed: bool) {
    WIDE_ALLOWED.store(allowed, Relaxed);
}

/// Whether the AVX-512 copies run (allowed, and the processor has it).
#[inline(always)]
pub fn wide_registers() -> bool {
    WIDE_ALLOWED.load(Relaxed) && wide_registers_available()
}

/// `twice!(fn name / wide / body (&mut self, args) -> R)` defines the method
/// `name`, which runs the method `body` (`#[inline(always)]`, written out
/// elsewhere) compiled for AVX-512 as `wide` where the processor has it,
/// else as it is; `twice!(fn name / wide / path::to::body (args) -> R)` the
/// same for a function.
macro_rules! twice {
    (
        $(#[$attr:meta])*
        $vis:vis fn $name:ident / $wide:ident / $body:ident
        $(<$(const $cg:ident : $cty:ty),*>)?
        (&mut self $(, $arg:ident : $aty:ty)*) $(-> $ret:ty)?
    ) => {
        $(#[$attr])*
        #[inline(never)]
        $vis fn $name $(<$(const $cg: $cty),*>)? (&mut self $(, $arg: $aty)*) $(-> $ret)? {
            #[cfg(target_arch = "x86_64")]
            if $crate::isa::wide_registers() {
                // SAFETY: the processor has the features (just checked).
                return unsafe { self.$wide $(::<$($cg),*>)? ($($arg),*) };
            }
            self.$body $(::<$($cg),*>)? ($($arg),*)
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f,avx512vl")]
        #[inline(never)]
        unsafe fn $wide $(<$(const $cg: $cty),*>)? (&mut self $(, $arg: $aty)*) $(-> $ret)? {
            self.$body $(::<$($cg),*>)? ($($arg),*)
        }
    };
    (
        $(#[$attr:meta])*
        $vis:vis fn $name:ident / $wide:ident / $($body:ident)::+ ($($arg:ident : $aty:ty),*) -> $ret:ty
    ) => {
        $(#[$attr])*
        #[inline(never)]
        $vis fn $name($($arg: $aty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            if $crate::isa::wide_registers() {
                // SAFETY: the processor has the features (just checked).
                return unsafe { $wide($($arg),*) };
            }
            $($body)::+($($arg),*)
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f,avx512vl")]
        #[inline(never)]
        unsafe fn $wide($($arg: $aty),*) -> $ret {
            $($body)::+($($arg),*)
        }
    };
}
pub(crate) use twice;

// The engine's two hottest functions (with everything they inline): the
// driver's runs of substeps and the event path's stretches. Their callees
// out of line (a new mode's resolution, a stretch's Taylor series) are not:
// a second dispatch in each cost more than it gave (measured,
// docs/accuracy-speed.md, session 15).
impl Simulator {
    twice! {
        /// [`Simulator::sweep_run`], compiled twice.
        pub(crate) fn sweep_clusters / sweep_wide / sweep_run
            <const NC: usize, const AG: bool, const RUNS: u8>
            (&mut self, piece: &mut Piece, pieces: &mut impl PieceSource)
            -> Option<(f64, Excitation)>
    }

    twice! {
        /// [`Simulator::stretch_run`], compiled twice.
        pub(crate) fn exact_stretch / stretch_wide / stretch_run(
            &mut self, t1: f64, piece: &Piece, depth: u32, work: &mut Scratch
        )
    }
}
