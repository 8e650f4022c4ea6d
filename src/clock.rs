//! Wall-clock time for progress lines, speed reports and the per-step
//! thread choice, on every target the library builds for.
//!
//! `std::time::Instant` panics on `wasm32-unknown-unknown` (the browser lab's
//! target, docs/browser-lab.md): there is no clock without a host import. A
//! [`Stopwatch`] reads the monotonic clock where there is one and reads zero
//! elapsed time on that target, so a run in the browser reports no wall time
//! (the page times itself) and never switches threads it does not have. No
//! number of a run depends on it: wall time is only reported, and the thread
//! choice changes speed, never results.

use std::time::Duration;

/// A started stopwatch.
#[derive(Debug, Clone, Copy)]
pub struct Stopwatch {
    #[cfg(not(all(target_arch = "wasm32", target_os = "unknown")))]
    started: std::time::Instant,
}

impl Stopwatch {
    /// A stopwatch started now.
    pub fn start() -> Stopwatch {
        Stopwatch {
            #[cfg(not(all(target_arch = "wasm32", target_os = "unknown")))]
            started: std::time::Instant::now(),
        }
    }

    /// Time since [`Stopwatch::start`] (zero where there is no clock).
    pub fn elapsed(&self) -> Duration {
        #[cfg(not(all(target_arch = "wasm32", target_os = "unknown")))]
        return self.started.elapsed();
        #[cfg(all(target_arch = "wasm32", target_os = "unknown"))]
        return Duration::ZERO;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elapsed_time_grows_from_zero() {
        let watch = Stopwatch::start();
        let first = watch.elapsed();
        std::thread::sleep(Duration::from_millis(2));
        let second = watch.elapsed();
        assert!(
            second >= first + Duration::from_millis(2),
            "{first:?} then {second:?}"
        );
    }
}
