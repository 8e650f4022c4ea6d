//! The step's hot loops for the processor it runs on: on x86-64 they are
//! compiled twice, for the baseline every x86-64 has (SSE2) and for the
//! x86-64-v3 level most have had since 2013 (AVX2 and its three-operand
//! instructions, BMI), and the second runs wherever the processor has it.
//!
//! **The same bits either way.** The loops use only the operations IEEE
//! 754 rounds exactly (add, multiply, divide, square root, comparisons),
//! which every instruction set gives alike; fused multiply-add, which
//! rounds once where the baseline rounds twice, is not among the features
//! enabled, and Rust never fuses on its own. A test steps the thesis bed
//! both ways and compares every particle's state bit for bit
//! ([`set_baseline_only`]); `vlab bench` reports which ran.
//!
//! Measured on the thesis drive, one thread (docs/performance.md): a
//! 10-cycle shake takes 0.94 of the baseline loops' time (`VLAB_ISA=baseline`
//! asks for those). What the wider loops need is inlined into them
//! (`#[inline(always)]` down to the contact law): a loop they call is
//! compiled for the baseline.

use std::sync::atomic::{AtomicU8, Ordering};

/// Not yet asked, the baseline, the wider loops.
const UNKNOWN: u8 = 0;
const BASELINE: u8 = 1;
const WIDE: u8 = 2;

static CHOICE: AtomicU8 = AtomicU8::new(UNKNOWN);

/// `VLAB_ISA=baseline` in the environment runs the baseline loops only
/// (read once, at the first step), to time one against the other.
pub const BASELINE_ENV: &str = "VLAB_ISA";

/// True when the wider loops run: the processor has x86-64-v3 and the
/// baseline was not asked for.
#[inline]
pub fn wide() -> bool {
    match CHOICE.load(Ordering::Relaxed) {
        UNKNOWN => {
            let asked_baseline = std::env::var_os(BASELINE_ENV).is_some_and(|v| v == "baseline");
            let choice = if has_v3() && !asked_baseline {
                WIDE
            } else {
                BASELINE
            };
            CHOICE.store(choice, Ordering::Relaxed);
            choice == WIDE
        }
        c => c == WIDE,
    }
}

/// Runs the baseline loops only (`true`), or whichever the processor allows
/// (`false`), for the rest of the process: for the test that the two give
/// the same bits, and for timing one against the other.
pub fn set_baseline_only(only: bool) {
    let choice = if !only && has_v3() { WIDE } else { BASELINE };
    CHOICE.store(choice, Ordering::Relaxed);
}

/// The processor has what [`run`]'s wider instance was compiled for.
fn has_v3() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("avx2")
            && std::is_x86_feature_detected!("avx")
            && std::is_x86_feature_detected!("bmi1")
            && std::is_x86_feature_detected!("bmi2")
            && std::is_x86_feature_detected!("lzcnt")
            && std::is_x86_feature_detected!("popcnt")
            && std::is_x86_feature_detected!("sse3")
            && std::is_x86_feature_detected!("ssse3")
            && std::is_x86_feature_detected!("sse4.1")
            && std::is_x86_feature_detected!("sse4.2")
            && std::is_x86_feature_detected!("movbe")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Runs `f`, a hot loop of the step, compiled for the widest instructions
/// the processor has ([`wide`]).
#[inline(always)]
pub fn run<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if wide() {
        // SAFETY: `wide` is true only where the processor has every
        // feature `v3` is compiled with.
        return unsafe { v3(f) };
    }
    f()
}

/// `f` compiled with the features of x86-64-v3 but fused multiply-add.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2,bmi1,bmi2,lzcnt,popcnt,sse3,ssse3,sse4.1,sse4.2,movbe")]
unsafe fn v3<R>(f: impl FnOnce() -> R) -> R {
    f()
}
