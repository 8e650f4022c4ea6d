//! Times Yang's power method on a thesis-sized record (5 s at 40 kHz, two
//! channels, 200 000 samples each). Run it optimised:
//!
//! ```text
//! cargo run --release --example yang_power_bench
//! ```

use vlab::signals::bench::bench_yang_power;

fn main() -> Result<(), vlab::signals::SignalsError> {
    let r = bench_yang_power(5.0, 40_000.0, 40.0, 20)?;
    println!(
        "yang_power, {} samples x 2 channels, {} runs each:\n  \
         fresh call (plans FFT): median {:.2} ms, min {:.2} ms\n  \
         reused plan:            median {:.2} ms, min {:.2} ms\n  \
         power = {:.6} W",
        r.n_samples,
        r.repeats,
        r.fresh_median_s * 1e3,
        r.fresh_min_s * 1e3,
        r.reused_median_s * 1e3,
        r.reused_min_s * 1e3,
        r.power_w
    );
    Ok(())
}
