//! Runtime choice of a vector extension for the batched kernels ([`super::soa`],
//! `material`'s batch module) and the scalar entry points ([`super::material`]).
//!
//! A baseline x86-64 build may only assume SSE2, so the kernels' loops over lanes compile to
//! 4-wide code. The same source compiled inside a function marked `#[target_feature]` becomes
//! AVX2 or AVX-512 code. A batched entry point therefore comes in three versions, made by
//! `widest_versions!`: its body (`#[inline(always)]`, so that it and the kernels it calls
//! are compiled into each version), an AVX2 wrapper and an AVX-512 wrapper. The entry point
//! picks one with [`level`], which asks the CPU once.
//!
//! The scalar entry points (one point's prepare, one direction's eval) come in the same
//! three versions and run at [`SCALAR_LEVEL`]: there the gain is the VEX encoding (three
//! operands, so fewer register copies) and 256-bit block copies, not wider lanes.
//!
//! Results do not depend on the version that runs: each does the same IEEE operations per
//! lane in the same order (Rust never fuses `a * b + c` into one rounding, and lanes do not
//! interact), so the outputs are bit-identical; `tests/interp/soa.rs` and
//! `tests/interp/levels.rs` check this.
//!
//! Why not only `-C target-cpu=native`: a build for distribution cannot assume AVX-512, and on
//! Intel server cores LLVM's tuning for `native` prefers 256-bit vectors, while these kernels,
//! limited by the divide/square-root unit, run fastest 512 bits wide.

/// The vector extensions an entry point can be run with (batched or scalar), narrowest
/// first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
#[repr(u8)]
pub enum Level {
    /// Whatever the build targets (SSE2 for a baseline x86-64 build).
    Baseline,
    /// AVX2 with FMA.
    Avx2,
    /// AVX-512 (F, VL, DQ, BW) with AVX2 and FMA.
    Avx512,
}

impl Level {
    /// Lower-case name, for reports.
    #[cfg(feature = "testkit")]
    pub fn name(self) -> &'static str {
        match self {
            Level::Avx512 => "avx512",
            Level::Avx2 => "avx2",
            Level::Baseline => "baseline",
        }
    }
}

/// The level the scalar entry points run at ([`crate::interp::Material::prepare_into`],
/// [`crate::interp::Prepared::eval`] and their kin) when the CPU has it. AVX2, not AVX-512:
/// for one point at a time the AVX-512 build was the slowest of the three (its wider
/// registers buy nothing there, and its start-up costs are paid per call).
pub const SCALAR_LEVEL: Level = Level::Avx2;

/// The widest [`Level`] this CPU supports, asked once and then read from a static (the
/// scalar entry points ask at every call).
#[inline]
pub fn level() -> Level {
    use std::sync::atomic::{AtomicU8, Ordering};
    // 0 until the first call; then the level's index + 1.
    static LEVEL: AtomicU8 = AtomicU8::new(0);
    match LEVEL.load(Ordering::Relaxed) {
        1 => Level::Baseline,
        2 => Level::Avx2,
        3 => Level::Avx512,
        _ => {
            let found = detect();
            LEVEL.store(found as u8 + 1, Ordering::Relaxed);
            found
        }
    }
}

/// [`level`]'s question to the CPU.
#[cold]
fn detect() -> Level {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::is_x86_feature_detected as has;
        let avx2 = has!("avx2") && has!("fma");
        if avx2 && has!("avx512f") && has!("avx512vl") && has!("avx512dq") && has!("avx512bw") {
            return Level::Avx512;
        }
        if avx2 {
            return Level::Avx2;
        }
    }
    Level::Baseline
}

/// Inside an `impl` block: defines `unsafe fn $avx512(&self, ..)` and `unsafe fn $avx2(&self,
/// ..)` (x86-64 only) that run `self.$body(..)` with AVX-512 or AVX2 enabled. `$body` must be
/// `#[inline(always)]`; a generic body lists its generic parameters in brackets first
/// (`[const W: usize] body(..)`). Callers check [`level`] first: calling a version the CPU
/// lacks is undefined behaviour.
macro_rules! widest_versions {
    ($([$($gen:tt)*])? $body:ident($($arg:ident: $ty:ty),*) -> $ret:ty, $avx512:ident, $avx2:ident) => {
        /// The body compiled with AVX-512. Safety: the CPU must support AVX-512 F, VL, DQ
        /// and BW, AVX2 and FMA.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")]
        unsafe fn $avx512$(<$($gen)*>)?(&self, $($arg: $ty),*) -> $ret {
            self.$body($($arg),*)
        }

        /// The body compiled with AVX2. Safety: the CPU must support AVX2 and FMA.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2,fma")]
        unsafe fn $avx2$(<$($gen)*>)?(&self, $($arg: $ty),*) -> $ret {
            self.$body($($arg),*)
        }
    };
}

/// Calls the version of a [`widest_versions!`] entry point for `$at` (a [`Level`]), or for
/// the widest level the CPU has if that is narrower.
macro_rules! call_widest {
    ($at:expr, $self:ident.$body:ident($($arg:expr),*), $avx512:ident, $avx2:ident) => {{
        #[cfg(target_arch = "x86_64")]
        match Ord::min($at, $crate::interp::simd::level()) {
            // SAFETY: `level` found every feature the version is compiled with.
            $crate::interp::simd::Level::Avx512 => unsafe { $self.$avx512($($arg),*) },
            // SAFETY: as above.
            $crate::interp::simd::Level::Avx2 => unsafe { $self.$avx2($($arg),*) },
            $crate::interp::simd::Level::Baseline => $self.$body($($arg),*),
        }
        #[cfg(not(target_arch = "x86_64"))]
        $self.$body($($arg),*)
    }};
}

pub(super) use {call_widest, widest_versions};
