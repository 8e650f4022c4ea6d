//! What drives the host: a force at its drive point, as a lab applies it with
//! a shaker on a stinger or an instrumented hammer (thesis Section 2.3.1, and
//! 9.4 v: multi-harmonic, random and transient loading).
//!
//! Each excitation is one documented key, as the command line writes it:
//!
//! | key | force at the drive point |
//! |---|---|
//! | `sine:F_HZ:FORCE_N` | `F sin 2π f t` |
//! | `sweep:F0_HZ:F1_HZ:DURATION_S:FORCE_N` | linear chirp, `F sin 2π (f0 t + (f1 − f0) t² / 2T)`, then nothing |
//! | `multisine:F1_HZ:N1,F2_HZ:N2,...` | `Σ F_k sin 2π f_k t` |
//! | `random:LOW_HZ:HIGH_HZ:RMS_N:PERIOD_S:SEED` | periodic random: every line `k / PERIOD` in the band at one amplitude, phases drawn from SEED, `RMS_N` in all |
//! | `hammer:IMPULSE_N_S` | a half-sine pulse of 0.5 ms carrying the impulse, at t = 0 |
//! | `release:X0_M` | nothing: the host starts deflected by `X0_M` at the damper and is let go |
//!
//! A stepped sine whose steps follow one another in one run (the bed's and
//! the host's state carried from each frequency to the next, as a lab's
//! sine controller steps) has no key: `vlab host frf --up-down` makes it
//! ([`Excitation::Stepped`]).

use std::f64::consts::{PI, TAU};

use rand_core::Rng;
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;
use realfft::num_complex::Complex64;
use serde::Serialize;

use crate::maths;
use crate::validation::{Bound, InvalidParameter, in_range, positive};

/// Width of the hammer's half-sine pulse, s: a steel tip on a steel host.
pub const HAMMER_PULSE_S: f64 = 5e-4;

/// One sine of a multi-sine, or a line of a periodic random force.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Line {
    pub freq_hz: f64,
    pub force_n: f64,
    pub phase_rad: f64,
}

/// The largest force an excitation may ask of the shaker at the drive point
/// (N): a stepped sine's `force_n` is held to the same.
pub const MAX_FORCE_N: f64 = 1e4;

/// A force at the host's drive point.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Excitation {
    /// `F sin 2π f t`.
    Sine { freq_hz: f64, force_n: f64 },
    /// Linear chirp from `start_hz` to `end_hz` over `duration_s`, then zero.
    Sweep {
        start_hz: f64,
        end_hz: f64,
        duration_s: f64,
        force_n: f64,
    },
    /// A sum of sines (multi-harmonic loading), and a periodic random force
    /// (its lines at random phases).
    Lines { lines: Vec<Line>, random: bool },
    /// Half-sine pulse of [`HAMMER_PULSE_S`] carrying `impulse_n_s`.
    Hammer { impulse_n_s: f64 },
    /// No force: the host is released from `x0_m` at the damper.
    Release { x0_m: f64 },
    /// A force given by its samples at `rate_hz` from t = 0, linearly
    /// interpolated, nothing after the last: a true or burst random force
    /// ([`RandomNoise`]) that no formula of a few numbers repeats.
    Sampled {
        rate_hz: f64,
        #[serde(skip)]
        samples_n: Vec<f64>,
    },
    /// A stepped sine in one run: `F sin 2π f_k (t − t_k)` over `cycles`
    /// whole cycles of each `f_k` in turn, `t_k` the step's start, so the
    /// force is continuous at every step (it is zero there); then nothing.
    Stepped {
        freqs_hz: Vec<f64>,
        cycles: u32,
        force_n: f64,
    },
}

/// Most frequencies a stepped sine takes, predicted or measured.
pub const MAX_FREQUENCIES: usize = 1000;

/// Checks the frequencies of a stepped sine, predicted or measured: each in
/// (0, 5000] Hz, ascending, 1 to [`MAX_FREQUENCIES`] of them, naming
/// `freqs_hz`.
pub fn check_frequencies(freqs_hz: &[f64]) -> Result<(), InvalidParameter> {
    if freqs_hz.is_empty() || freqs_hz.len() > MAX_FREQUENCIES {
        return Err(InvalidParameter::new(
            "freqs_hz",
            format!("{} frequencies", freqs_hz.len()),
            "",
            format!("between 1 and {MAX_FREQUENCIES} frequencies"),
        ));
    }
    for &f in freqs_hz {
        in_range(
            "freqs_hz",
            f,
            "Hz",
            Bound::Open(0.0),
            Bound::Closed(5_000.0),
        )?;
    }
    if let Some(w) = freqs_hz.windows(2).find(|w| w[1] <= w[0]) {
        return Err(InvalidParameter::new(
            "freqs_hz",
            format!("{} after {}", w[1], w[0]),
            "Hz",
            "ascending",
        ));
    }
    Ok(())
}

/// Samples a cycle of a random force's highest frequency: linear
/// interpolation between them is within 0.4 % of the band-limited force
/// (the force transducer measures what is applied, so the FRF does not
/// see even that).
pub const NOISE_RATE_PER_HZ: f64 = 20.0;

/// Longest random force made, s.
pub const MAX_NOISE_S: f64 = 600.0;

/// A random force that does not repeat within a test: band-limited noise
/// (every line `k / span` in the band at one amplitude, phases drawn from
/// `seed`, `span` the whole force's length: over any block shorter than
/// the test it is true random, and an FRF of it leaks unless windowed),
/// or, with `burst`, that noise switched on for the first `on_fraction` of
/// every `period_s` and off for the rest (burst random: a block of one
/// period holds a whole response when it has died out in the silence, so
/// needs no window).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RandomNoise {
    pub low_hz: f64,
    pub high_hz: f64,
    /// The rms while on (N).
    pub rms_n: f64,
    pub seed: u64,
    /// `(period_s, on_fraction)` of a burst random force.
    pub burst: Option<(f64, f64)>,
}

impl RandomNoise {
    /// Parses `noise:LOW_HZ:HIGH_HZ:RMS_N:SEED` or
    /// `burst:LOW_HZ:HIGH_HZ:RMS_N:PERIOD_S:ON_FRACTION:SEED`.
    pub fn parse(key: &str) -> Result<Self, InvalidParameter> {
        let refuse = || {
            InvalidParameter::new(
                "excitation",
                format!("'{key}'"),
                "",
                "noise:LOW_HZ:HIGH_HZ:RMS_N:SEED or burst:LOW_HZ:HIGH_HZ:RMS_N:PERIOD_S:ON_FRACTION:SEED",
            )
        };
        let parts: Vec<&str> = key.split(':').collect();
        let names: &[(&str, &str)] = match parts.first() {
            Some(&"noise") => &[
                ("low_hz", "Hz"),
                ("high_hz", "Hz"),
                ("rms_n", "N"),
                ("seed", ""),
            ],
            Some(&"burst") => &[
                ("low_hz", "Hz"),
                ("high_hz", "Hz"),
                ("rms_n", "N"),
                ("period_s", "s"),
                ("on_fraction", ""),
                ("seed", ""),
            ],
            _ => return Err(refuse()),
        };
        if parts.len() != names.len() + 1 {
            return Err(refuse());
        }
        let v = parts[1..]
            .iter()
            .zip(names)
            .map(|(p, (name, unit))| {
                p.trim()
                    .parse::<f64>()
                    .map_err(|_| InvalidParameter::new(*name, format!("'{p}'"), unit, "a number"))
            })
            .collect::<Result<Vec<f64>, _>>()?;
        let seed = v[v.len() - 1];
        in_range(
            "seed",
            seed,
            "",
            Bound::Closed(0.0),
            Bound::Closed(u32::MAX.into()),
        )?;
        let noise = RandomNoise {
            low_hz: v[0],
            high_hz: v[1],
            rms_n: v[2],
            seed: seed as u64,
            burst: (v.len() == 6).then(|| (v[3], v[4])),
        };
        noise.validate()?;
        Ok(noise)
    }

    /// Checks the band (0 < low < high <= 5 kHz), the rms (at most
    /// [`MAX_FORCE_N`]) and a burst's on-fraction (in (0, 1)) and period
    /// (holding a cycle of the lowest frequency while on, at most
    /// [`MAX_NOISE_S`]).
    pub fn validate(&self) -> Result<(), InvalidParameter> {
        positive("low_hz", self.low_hz, "Hz")?;
        in_range(
            "high_hz",
            self.high_hz,
            "Hz",
            Bound::Open(self.low_hz),
            Bound::Closed(5_000.0),
        )?;
        in_range(
            "rms_n",
            self.rms_n,
            "N",
            Bound::Open(0.0),
            Bound::Closed(MAX_FORCE_N),
        )?;
        if let Some((period_s, on)) = self.burst {
            in_range("on_fraction", on, "", Bound::Open(0.0), Bound::Open(1.0))?;
            in_range(
                "period_s",
                period_s,
                "s",
                Bound::Closed(1.0 / (on * self.low_hz)),
                Bound::Closed(MAX_NOISE_S),
            )
            .map_err(|e| e.because("a burst holds a cycle of the lowest frequency"))?;
        }
        Ok(())
    }

    /// The force over `duration_s` (at most [`MAX_NOISE_S`]), sampled at
    /// [`NOISE_RATE_PER_HZ`] times the band's top.
    pub fn excitation(&self, duration_s: f64) -> Result<Excitation, InvalidParameter> {
        self.validate()?;
        in_range(
            "duration_s",
            duration_s,
            "s",
            Bound::Open(0.0),
            Bound::Closed(MAX_NOISE_S),
        )?;
        let rate_hz = NOISE_RATE_PER_HZ * self.high_hz;
        let n = ((duration_s * rate_hz).ceil() as usize + 2).max(8);
        let span_s = n as f64 / rate_hz;
        let first = ((self.low_hz * span_s).ceil() as usize).max(1);
        let last = ((self.high_hz * span_s).floor() as usize).min(n / 2 - 1);
        if last < first {
            return Err(InvalidParameter::new(
                "duration_s",
                duration_s,
                "s",
                format!(
                    "long enough to hold a line in [{}, {}] Hz",
                    self.low_hz, self.high_hz
                ),
            ));
        }
        // Each line of amplitude A carries A^2 / 2 of the mean square; the
        // inverse transform sums each bin with its conjugate and does not
        // divide by n, so the bin A / 2 gives a cosine of amplitude A.
        let amplitude = self.rms_n * (2.0 / (last - first + 1) as f64).sqrt();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(self.seed);
        let mut spectrum = vec![Complex64::new(0.0, 0.0); n / 2 + 1];
        for bin in spectrum.iter_mut().take(last + 1).skip(first) {
            let phase = TAU * (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
            *bin = Complex64::from_polar(0.5 * amplitude, phase);
        }
        let mut samples_n = vec![0.0; n];
        realfft::RealFftPlanner::<f64>::new()
            .plan_fft_inverse(n)
            .process(&mut spectrum, &mut samples_n)
            .map_err(|e| InvalidParameter::new("noise", n as f64, "samples", e.to_string()))?;
        if let Some((period_s, on)) = self.burst {
            // The force is interpolated between samples, so a burst whose
            // first sample were on would ramp up from the sample before the
            // period began, the end of the previous block (0.8 ms early at
            // 60 Hz x 20): the first sample of each period stays off, and
            // the ramp starts inside the period.
            let samples_per_period = period_s * rate_hz;
            for (k, f) in samples_n.iter_mut().enumerate() {
                let phase = (k as f64 / samples_per_period).fract();
                if phase >= on || phase * samples_per_period < 1.0 - 1e-9 {
                    *f = 0.0;
                }
            }
        }
        Ok(Excitation::Sampled { rate_hz, samples_n })
    }
}

/// A periodic random force as its key gives it
/// (`random:LOW_HZ:HIGH_HZ:RMS_N:PERIOD_S:SEED`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PeriodicRandom {
    pub low_hz: f64,
    pub high_hz: f64,
    pub rms_n: f64,
    /// Its period (s): the block of an FRF without leakage.
    pub period_s: f64,
    pub seed: u64,
}

impl PeriodicRandom {
    /// Parses `LOW_HZ:HIGH_HZ:RMS_N:PERIOD_S:SEED` (the key without its
    /// `random:`), refusing what [`Excitation::parse`] refuses.
    pub fn parse(values: &str) -> Result<Self, InvalidParameter> {
        let key = format!("random:{values}");
        let (_, force) = Excitation::parse_with_random(&key)?;
        force.ok_or_else(|| InvalidParameter::new("excitation", key, "", "a random key"))
    }

    /// The force itself ([`Excitation::periodic_random`]).
    pub fn excitation(&self) -> Result<Excitation, InvalidParameter> {
        Excitation::periodic_random(
            self.low_hz,
            self.high_hz,
            self.rms_n,
            self.period_s,
            self.seed,
        )
    }
}

impl Excitation {
    /// The force at `t_s` from the start, N.
    pub fn force_n(&self, t_s: f64) -> f64 {
        match self {
            Excitation::Sine { freq_hz, force_n } => force_n * maths::sin(TAU * freq_hz * t_s),
            Excitation::Sweep {
                start_hz,
                end_hz,
                duration_s,
                force_n,
            } => {
                if t_s > *duration_s || t_s < 0.0 {
                    0.0
                } else {
                    let cycles =
                        start_hz * t_s + (end_hz - start_hz) * t_s * t_s / (2.0 * duration_s);
                    force_n * maths::sin(TAU * cycles)
                }
            }
            Excitation::Lines { lines, .. } => lines
                .iter()
                .map(|l| l.force_n * maths::sin(TAU * l.freq_hz * t_s + l.phase_rad))
                .sum(),
            Excitation::Hammer { impulse_n_s } => {
                if (0.0..=HAMMER_PULSE_S).contains(&t_s) {
                    // Peak F0 with integral F0 2 w / pi = J.
                    let peak = PI * impulse_n_s / (2.0 * HAMMER_PULSE_S);
                    peak * maths::sin(PI * t_s / HAMMER_PULSE_S)
                } else {
                    0.0
                }
            }
            Excitation::Release { .. } => 0.0,
            Excitation::Sampled { rate_hz, samples_n } => {
                let x = t_s * rate_hz;
                if x.is_nan() || x < 0.0 {
                    return 0.0;
                }
                let k = x.floor() as usize;
                match (samples_n.get(k), samples_n.get(k + 1)) {
                    (Some(a), Some(b)) => a + (x - k as f64) * (b - a),
                    (Some(a), None) if x == k as f64 => *a,
                    _ => 0.0,
                }
            }
            Excitation::Stepped {
                freqs_hz,
                cycles,
                force_n,
            } => {
                let mut start_s = 0.0;
                for f in freqs_hz {
                    let end_s = start_s + f64::from(*cycles) / f;
                    if t_s < end_s {
                        return match t_s >= start_s {
                            true => force_n * maths::sin(TAU * f * (t_s - start_s)),
                            false => 0.0,
                        };
                    }
                    start_s = end_s;
                }
                0.0
            }
        }
    }

    /// A stepped sine's steps, each as its frequency (Hz) and its start
    /// and end (s); empty for the other excitations.
    pub fn steps(&self) -> Vec<(f64, f64, f64)> {
        let Excitation::Stepped {
            freqs_hz, cycles, ..
        } = self
        else {
            return Vec::new();
        };
        let mut start_s = 0.0;
        freqs_hz
            .iter()
            .map(|f| {
                let end_s = start_s + f64::from(*cycles) / f;
                let step = (*f, start_s, end_s);
                start_s = end_s;
                step
            })
            .collect()
    }

    /// A sine's frequency (Hz) and amplitude, or a stepped sine's first;
    /// `None` for the other excitations.
    pub fn first_sine(&self) -> Option<(f64, f64)> {
        match self {
            Excitation::Sine { freq_hz, force_n } => Some((*freq_hz, *force_n)),
            Excitation::Stepped {
                freqs_hz, force_n, ..
            } => freqs_hz.first().map(|f| (*f, *force_n)),
            _ => None,
        }
    }

    /// The displacement at the damper the host starts from, m.
    pub fn initial_displacement_m(&self) -> f64 {
        match self {
            Excitation::Release { x0_m } => *x0_m,
            _ => 0.0,
        }
    }

    /// The highest frequency the force holds, Hz (for the step and the record).
    pub fn highest_freq_hz(&self) -> f64 {
        match self {
            Excitation::Sine { freq_hz, .. } => *freq_hz,
            Excitation::Sweep {
                start_hz, end_hz, ..
            } => start_hz.max(*end_hz),
            Excitation::Lines { lines, .. } => lines.iter().map(|l| l.freq_hz).fold(0.0, f64::max),
            Excitation::Hammer { .. } => 1.0 / HAMMER_PULSE_S,
            Excitation::Release { .. } => 0.0,
            Excitation::Stepped { freqs_hz, .. } => freqs_hz.iter().copied().fold(0.0, f64::max),
            // Made with [`NOISE_RATE_PER_HZ`] samples a cycle of its top.
            Excitation::Sampled { rate_hz, .. } => rate_hz / NOISE_RATE_PER_HZ,
        }
    }

    /// A periodic random force: every line `k / period_s` in
    /// `[low_hz, high_hz]` at one amplitude and a phase drawn from `seed`,
    /// `rms_n` in all. A whole period of it has no leakage in an FRF whose
    /// block is the period.
    pub fn periodic_random(
        low_hz: f64,
        high_hz: f64,
        rms_n: f64,
        period_s: f64,
        seed: u64,
    ) -> Result<Self, InvalidParameter> {
        positive("period_s", period_s, "s")?;
        positive("low_hz", low_hz, "Hz")?;
        in_range(
            "high_hz",
            high_hz,
            "Hz",
            Bound::Open(low_hz),
            Bound::Closed(5_000.0),
        )?;
        positive("rms_n", rms_n, "N")?;
        let first = (low_hz * period_s).ceil() as u64;
        let last = (high_hz * period_s).floor() as u64;
        if last < first {
            return Err(InvalidParameter::new(
                "period_s",
                period_s,
                "s",
                format!("long enough to put a line k / period_s in [{low_hz}, {high_hz}] Hz"),
            ));
        }
        let count = (last - first + 1) as f64;
        // Each line of amplitude A carries A^2 / 2 of the mean square.
        let amplitude = rms_n * (2.0 / count).sqrt();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let lines = (first..=last)
            .map(|k| Line {
                freq_hz: k as f64 / period_s,
                force_n: amplitude,
                phase_rad: TAU * (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64,
            })
            .collect();
        Ok(Excitation::Lines {
            lines,
            random: true,
        })
    }

    /// Parses a key of the table in the module docs.
    pub fn parse(key: &str) -> Result<Self, InvalidParameter> {
        Self::parse_with_random(key).map(|(excitation, _)| excitation)
    }

    /// [`Self::parse`], and of a `random:` key the periodic random force's
    /// values as given (its period is what an FRF's block is).
    ///
    /// Over 80 lines: one match over the keys of the module's table, a short
    /// arm each; split per key it reads no easier.
    pub fn parse_with_random(
        key: &str,
    ) -> Result<(Self, Option<PeriodicRandom>), InvalidParameter> {
        let refuse =
            |valid: &str| InvalidParameter::new("excitation", format!("'{key}'"), "", valid);
        let (kind, rest) = key.split_once(':').ok_or_else(|| {
            refuse("KIND:VALUES, KIND one of sine, sweep, multisine, random, hammer, release")
        })?;
        let numbers =
            |text: &str, names: &[&str], units: &[&str]| -> Result<Vec<f64>, InvalidParameter> {
                let parts: Vec<&str> = text.split(':').collect();
                if parts.len() != names.len() {
                    return Err(refuse(&format!("{kind}:{}", names.join(":"))));
                }
                parts
                    .iter()
                    .zip(names.iter().zip(units))
                    .map(|(p, (name, unit))| {
                        p.trim().parse::<f64>().map_err(|_| {
                            InvalidParameter::new(*name, format!("'{p}'"), unit, "a number")
                        })
                    })
                    .collect()
            };
        let excitation = match kind {
            "sine" => {
                let v = numbers(rest, &["freq_hz", "force_n"], &["Hz", "N"])?;
                Excitation::Sine {
                    freq_hz: v[0],
                    force_n: v[1],
                }
            }
            "sweep" => {
                let v = numbers(
                    rest,
                    &["start_hz", "end_hz", "duration_s", "force_n"],
                    &["Hz", "Hz", "s", "N"],
                )?;
                Excitation::Sweep {
                    start_hz: v[0],
                    end_hz: v[1],
                    duration_s: v[2],
                    force_n: v[3],
                }
            }
            "multisine" => {
                let lines = rest
                    .split(',')
                    .map(|pair| {
                        let v = numbers(pair, &["freq_hz", "force_n"], &["Hz", "N"])?;
                        Ok(Line {
                            freq_hz: v[0],
                            force_n: v[1],
                            phase_rad: 0.0,
                        })
                    })
                    .collect::<Result<Vec<_>, InvalidParameter>>()?;
                Excitation::Lines {
                    lines,
                    random: false,
                }
            }
            "random" => {
                let v = numbers(
                    rest,
                    &["low_hz", "high_hz", "rms_n", "period_s", "seed"],
                    &["Hz", "Hz", "N", "s", ""],
                )?;
                in_range(
                    "seed",
                    v[4],
                    "",
                    Bound::Closed(0.0),
                    Bound::Closed(u32::MAX.into()),
                )?;
                in_range(
                    "rms_n",
                    v[2],
                    "N",
                    Bound::Open(0.0),
                    Bound::Closed(MAX_FORCE_N),
                )?;
                let force = PeriodicRandom {
                    low_hz: v[0],
                    high_hz: v[1],
                    rms_n: v[2],
                    period_s: v[3],
                    seed: v[4] as u64,
                };
                let excitation = force.excitation()?;
                excitation.validate()?;
                return Ok((excitation, Some(force)));
            }
            "hammer" => {
                let v = numbers(rest, &["impulse_n_s"], &["N s"])?;
                Excitation::Hammer { impulse_n_s: v[0] }
            }
            "release" => {
                let v = numbers(rest, &["x0_m"], &["m"])?;
                Excitation::Release { x0_m: v[0] }
            }
            _ => {
                return Err(refuse(
                    "KIND:VALUES, KIND one of sine, sweep, multisine, random, hammer, release",
                ));
            }
        };
        excitation.validate()?;
        Ok((excitation, None))
    }

    /// Checks every value (frequencies positive and at most 5 kHz, forces
    /// positive and at most [`MAX_FORCE_N`], a release within 50 mm).
    pub fn validate(&self) -> Result<(), InvalidParameter> {
        let freq =
            |key: &str, f: f64| in_range(key, f, "Hz", Bound::Open(0.0), Bound::Closed(5_000.0));
        let force =
            |key: &str, f: f64| in_range(key, f, "N", Bound::Open(0.0), Bound::Closed(MAX_FORCE_N));
        match self {
            Excitation::Sine { freq_hz, force_n } => {
                freq("freq_hz", *freq_hz)?;
                force("force_n", *force_n)?;
            }
            Excitation::Sweep {
                start_hz,
                end_hz,
                duration_s,
                force_n,
            } => {
                freq("start_hz", *start_hz)?;
                freq("end_hz", *end_hz)?;
                positive("duration_s", *duration_s, "s")?;
                force("force_n", *force_n)?;
            }
            Excitation::Lines { lines, random } => {
                if lines.is_empty() {
                    return Err(InvalidParameter::new("lines", "none", "", "at least one"));
                }
                for l in lines {
                    freq("freq_hz", l.freq_hz)?;
                    // A random force is bounded by its RMS (checked as it
                    // is parsed), not line by line.
                    match random {
                        true => positive("force_n", l.force_n, "N").map(|_| ())?,
                        false => force("force_n", l.force_n).map(|_| ())?,
                    }
                }
            }
            Excitation::Hammer { impulse_n_s } => {
                positive("impulse_n_s", *impulse_n_s, "N s")?;
            }
            Excitation::Release { x0_m } => {
                in_range(
                    "x0_m",
                    *x0_m,
                    "m",
                    Bound::Closed(-0.05),
                    Bound::Closed(0.05),
                )
                .map_err(|e| e.because("a release within the enclosure's stroke"))?;
                if *x0_m == 0.0 {
                    return Err(InvalidParameter::new(
                        "x0_m",
                        0,
                        "m",
                        "non-zero (a release from rest decays nothing)",
                    ));
                }
            }
            Excitation::Sampled { rate_hz, samples_n } => {
                positive("rate_hz", *rate_hz, "Hz")?;
                if let Some(k) = samples_n.iter().position(|f| !f.is_finite()) {
                    return Err(InvalidParameter::new(
                        "samples_n",
                        format!("sample {k} = {}", samples_n[k]),
                        "N",
                        "finite",
                    ));
                }
            }
            Excitation::Stepped {
                freqs_hz,
                cycles,
                force_n,
            } => {
                if freqs_hz.is_empty() {
                    return Err(InvalidParameter::new(
                        "freqs_hz",
                        "none",
                        "",
                        "at least one",
                    ));
                }
                for f in freqs_hz {
                    freq("freq_hz", *f)?;
                }
                if *cycles == 0 {
                    return Err(InvalidParameter::new("cycles", 0, "", "at least 1 a step"));
                }
                force("force_n", *force_n)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_key_parses_to_its_force() {
        let sine = Excitation::parse("sine:40:5").expect("valid");
        assert!((sine.force_n(1.0 / 160.0) - 5.0).abs() < 1e-12);
        // The chirp's instantaneous frequency is f0 + (f1 - f0) t / T: its
        // zero crossings at t where the phase is a whole half cycle.
        let sweep = Excitation::parse("sweep:10:30:2:1").expect("valid");
        let t_half = {
            // phase(t) = 10 t + 5 t^2 = 0.5 -> t = (-10 + sqrt(100 + 10)) / 10.
            (-10.0 + 110.0_f64.sqrt()) / 10.0
        };
        assert!(sweep.force_n(t_half).abs() < 1e-12);
        assert_eq!(sweep.force_n(2.5), 0.0);
        // The hammer's pulse carries its impulse (midpoint sum, 1e-6).
        let hammer = Excitation::parse("hammer:0.02").expect("valid");
        let dt = 1e-7;
        let impulse: f64 = (0..10_000)
            .map(|k| hammer.force_n((f64::from(k) + 0.5) * dt) * dt)
            .sum();
        assert!((impulse - 0.02).abs() < 1e-6 * 0.02 + 1e-12, "{impulse}");
        let multi = Excitation::parse("multisine:40:5,120:2").expect("valid");
        assert!((multi.force_n(1.0 / 160.0) - (5.0 + 2.0 * (TAU * 0.75).sin())).abs() < 1e-12);
        assert_eq!(
            Excitation::parse("release:0.003")
                .expect("valid")
                .initial_displacement_m(),
            0.003
        );
    }

    #[test]
    fn the_periodic_random_force_has_its_rms_its_band_and_its_seed() {
        let f = Excitation::parse("random:20:80:2:1:7").expect("valid");
        let Excitation::Lines { lines, random } = &f else {
            panic!("{f:?}")
        };
        assert!(random);
        assert_eq!(lines.len(), 61, "lines 20..=80 Hz at 1 Hz");
        // Mean square over one period, 1e-9.
        let n = 40_000;
        let ms: f64 = (0..n)
            .map(|k| f.force_n(f64::from(k) / f64::from(n)).powi(2))
            .sum::<f64>()
            / f64::from(n);
        assert!((ms.sqrt() - 2.0).abs() < 1e-9, "{}", ms.sqrt());
        // Periodic, and another seed draws other phases.
        assert!((f.force_n(0.123) - f.force_n(1.123)).abs() < 1e-9);
        let other = Excitation::parse("random:20:80:2:1:8").expect("valid");
        assert!((f.force_n(0.123) - other.force_n(0.123)).abs() > 1e-6);
    }

    /// A stepped sine in one run: each step whole cycles of its sine from
    /// a zero, so the force is continuous (zero) at every step; the steps
    /// follow one another without a gap; nothing after the last.
    #[test]
    fn a_stepped_sine_in_one_run_steps_at_zeros_of_its_force() {
        let e = Excitation::Stepped {
            freqs_hz: vec![40.0, 41.0, 40.0],
            cycles: 3,
            force_n: 2.0,
        };
        let steps = e.steps();
        assert_eq!(steps.len(), 3);
        assert_eq!(steps[0], (40.0, 0.0, 3.0 / 40.0));
        for w in steps.windows(2) {
            assert_eq!(w[0].2, w[1].1);
        }
        for &(f, start, end) in &steps {
            for t in [start, end] {
                for side in [-1e-9, 1e-9] {
                    assert!(e.force_n(t + side).abs() < 2.0 * TAU * 41.0 * 2e-9, "{t}");
                }
            }
            // A quarter cycle in, the step's own sine at its crest.
            assert!((e.force_n(start + 0.25 / f) - 2.0).abs() < 1e-9);
        }
        assert_eq!(e.force_n(steps[2].2 + 1e-3), 0.0);
        assert_eq!(e.highest_freq_hz(), 41.0);
        for bad in [
            Excitation::Stepped {
                freqs_hz: vec![],
                cycles: 3,
                force_n: 2.0,
            },
            Excitation::Stepped {
                freqs_hz: vec![40.0],
                cycles: 0,
                force_n: 2.0,
            },
            Excitation::Stepped {
                freqs_hz: vec![40.0],
                cycles: 3,
                force_n: 2e4,
            },
        ] {
            assert!(bad.validate().is_err(), "{bad:?}");
        }
    }

    /// Noise: its rms is the asked one to rounding (Parseval over the
    /// whole force), its spectrum holds the band only, two seeds differ; a
    /// burst is zero while off; wrong keys are refused by field.
    #[test]
    fn random_noise_has_its_rms_its_band_and_its_bursts() {
        let noise = RandomNoise::parse("noise:20:60:2:7").expect("a key");
        let Excitation::Sampled { rate_hz, samples_n } = noise.excitation(3.0).expect("made")
        else {
            panic!("not sampled")
        };
        assert_eq!(rate_hz, 1200.0);
        let ms = samples_n.iter().map(|f| f * f).sum::<f64>() / samples_n.len() as f64;
        assert!((ms.sqrt() / 2.0 - 1.0).abs() < 1e-12, "{}", ms.sqrt());
        let n = samples_n.len();
        let mut input = samples_n.clone();
        let mut spectrum = vec![Complex64::new(0.0, 0.0); n / 2 + 1];
        realfft::RealFftPlanner::<f64>::new()
            .plan_fft_forward(n)
            .process(&mut input, &mut spectrum)
            .expect("a spectrum");
        for (k, bin) in spectrum.iter().enumerate() {
            let f = k as f64 * rate_hz / n as f64;
            let amplitude = 2.0 * bin.norm() / n as f64;
            if !(19.9..=60.1).contains(&f) {
                assert!(amplitude < 1e-9, "{f} Hz: {amplitude}");
            }
        }
        let other = RandomNoise::parse("noise:20:60:2:8").expect("a key");
        assert_ne!(other.excitation(3.0), noise.excitation(3.0));
        let burst = RandomNoise::parse("burst:20:60:2:0.5:0.25:7").expect("a key");
        let e = burst.excitation(2.0).expect("made");
        for t in [0.2, 0.3, 0.45, 0.8, 1.4] {
            assert_eq!(e.force_n(t), 0.0, "{t} s is off");
        }
        // Each burst starts inside its period: the interpolation does not
        // ramp it up over the previous period's last sample interval (it
        // did, 0.8 ms early, before the period's first sample was kept
        // off).
        for m in 1..4 {
            let t = 0.5 * f64::from(m) - 2e-4;
            assert_eq!(e.force_n(t), 0.0, "{t} s is in the period before");
        }
        assert!((0..100).any(|k| e.force_n(f64::from(k) * 1e-3) != 0.0));
        for (key, field) in [
            ("noise:60:20:2:7", "high_hz"),
            ("noise:20:60:0:7", "rms_n"),
            ("noise:20:60:2", "excitation"),
            ("burst:20:60:2:0.5:1.5:7", "on_fraction"),
            ("burst:20:60:2:0.01:0.5:7", "period_s"),
            ("noise:20:x:2:7", "high_hz"),
        ] {
            assert_eq!(RandomNoise::parse(key).expect_err(key).key, field, "{key}");
        }
    }

    #[test]
    fn a_wrong_key_says_what_it_wanted() {
        let msg = |k: &str| Excitation::parse(k).expect_err(k).to_string();
        assert!(
            msg("sine:40").contains("sine:freq_hz:force_n"),
            "{}",
            msg("sine:40")
        );
        assert_eq!(msg("sine:-40:5"), "freq_hz = -40 Hz: must be in (0, 5000]");
        assert_eq!(msg("sine:40:x"), "force_n = 'x' N: must be a number");
        assert!(msg("tap:1").contains("KIND one of"), "{}", msg("tap:1"));
        assert!(msg("release:0.2").contains("x0_m = 0.2 m: must be in [-0.05, 0.05]"));
        assert!(
            msg("random:20.2:20.7:1:1:1").contains("period_s = 1 s"),
            "{}",
            msg("random:20.2:20.7:1:1:1")
        );
        assert!(msg("random:20:80:1:1:-1").contains("seed = -1"));
    }
}
