//! `vlab host` refuses wrong input with the flag, its unit and its range,
//! exits non-zero and leaves no output folder behind.

#![cfg(all(feature = "cli", feature = "plot"))]

use crate::common;

use common::{Scratch, stderr, vlab};

#[test]
fn wrong_host_input_is_refused_and_leaves_nothing() {
    let dir = Scratch::new("host-cli");
    let cases: [(&[&str], &str); 19] = [
        (
            &["host", "decay", "--damper", "dashpot:-1", "--out", "out"],
            "damper dashpot = -1 N s/m: must be in (0, 1000000]",
        ),
        (
            &["host", "decay", "--damper", "sand", "--out", "out"],
            "particles, empty, solid or dashpot:N_S_PER_M",
        ),
        (
            &["host", "decay", "--x0-m", "0.2", "--out", "out"],
            "--x0-m = 0.2 m: must be in [-0.05, 0.05]",
        ),
        (
            &["host", "frf", "--freq", "50:40:1", "--out", "out"],
            "STEP must be positive and TO at least FROM",
        ),
        (
            &[
                "host",
                "frf",
                "--freq",
                "40",
                "--record-cycles",
                "2",
                "--out",
                "out",
            ],
            "--record-cycles = 2 cycles: must be",
        ),
        (
            &["host", "run", "--excitation", "sine:40", "--out", "out"],
            "sine:freq_hz:force_n",
        ),
        (
            &["host", "decay", "--beds", "0", "--out", "out"],
            "beds = 0: must be from 1 to 64",
        ),
        (
            &["host", "decay", "--host", "no-such-host", "--out", "out"],
            "no built-in rig 'no-such-host'",
        ),
        // The host commands set their own length (--duration-s, the
        // stepped sine's cycles): the shaker's drive length is not offered.
        (
            &[
                "host", "frf", "--freq", "40", "--cycles", "30", "--out", "out",
            ],
            "unexpected argument '--cycles'",
        ),
        // The stepped sine in one run carries one bed's state.
        (
            &[
                "host",
                "frf",
                "--freq",
                "39,40",
                "--up-down",
                "--beds",
                "2",
                "--out",
                "out",
            ],
            "--beds = 2: --up-down runs one bed",
        ),
        (
            &["host", "frf", "--freq", "40", "--up-down", "--out", "out"],
            "--freq = 1 frequencies: must be at least 2 to come back down",
        ),
        // A swept sine needs silence after it, and its own three numbers.
        (
            &[
                "host",
                "frf",
                "--swept",
                "30:50:2",
                "--duration-s",
                "2",
                "--out",
                "out",
            ],
            "--duration-s = 2 s: must be longer than the sweep (2 s)",
        ),
        (
            &["host", "frf", "--swept", "30:50", "--out", "out"],
            "--swept = '30:50': must be START_HZ:END_HZ:SWEEP_S",
        ),
        // Force levels: ascending, and for the plain stepped sine.
        (
            &[
                "host",
                "frf",
                "--freq",
                "40",
                "--force-n",
                "5,3",
                "--out",
                "out",
            ],
            "--force-n = 3 after 5 N: force levels must be ascending",
        ),
        (
            &[
                "host",
                "frf",
                "--freq",
                "39,40",
                "--force-n",
                "3,5",
                "--up-down",
                "--out",
                "out",
            ],
            "several force levels are for the stepped sine",
        ),
        // True and burst random: a block that holds the band, a test that
        // holds two blocks.
        (
            &[
                "host",
                "frf",
                "--noise",
                "20:60:1:4",
                "--block-s",
                "0.1",
                "--out",
                "out",
            ],
            "--block-s = 0.1 s: must be at least 0.2 s: 4 cycles of the band's lowest frequency (20 Hz)",
        ),
        (
            &[
                "host",
                "frf",
                "--burst",
                "20:60:1:2:0.5:4",
                "--duration-s",
                "3",
                "--out",
                "out",
            ],
            "--duration-s = 3 s: must be at least 4 s",
        ),
        // A table carries a one-mode host only, at a positive acceleration.
        (
            &[
                "host",
                "base",
                "--host",
                "beam-2mode",
                "--freq",
                "40",
                "--out",
                "out",
            ],
            "--host beam-2mode: host modes = 2 modes: must be 1 (a host on a table must be one mode",
        ),
        (
            &[
                "host",
                "base",
                "--freq",
                "40",
                "--accel-mps2",
                "0",
                "--out",
                "out",
            ],
            "--accel-mps2 = 0 m/s^2: must be in (0, 490]",
        ),
    ];
    for (args, wanted) in cases {
        let out = vlab(&dir.0, args);
        let err = stderr(&out);
        assert!(!out.status.success(), "{args:?} passed");
        assert!(err.contains(wanted), "{args:?}: {err}");
        assert!(!dir.path("out").exists(), "{args:?} left its folder");
    }
}

#[test]
fn a_dashpot_decay_writes_its_record_and_recovers_its_loss_factor() {
    // The command a reader runs first (docs/host.md, section 2): its
    // decay.json's first log-decrement point within 1 % of 2 zeta.
    let dir = Scratch::new("host-cli-decay");
    let out = vlab(
        &dir.0,
        &[
            "--quiet",
            "host",
            "decay",
            "--damper",
            "dashpot:15",
            "--duration-s",
            "0.3",
            "--out",
            "d",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    for f in [
        "trace.csv",
        "trace.wav",
        "record.csv",
        "decay.csv",
        "decay.json",
        "loss-factor.svg",
    ] {
        assert!(dir.path(&format!("d/{f}")).is_file(), "{f}");
    }
    let j = common::json(&dir.path("d/decay.json"));
    let eta = j["analysis"]["log_decrement"][0]["loss_factor"]
        .as_f64()
        .expect("eta");
    let want = 2.0 * (0.003 + 15.0 / (2.0 * (31_582.734_f64 * 0.5).sqrt()));
    assert!((eta / want - 1.0).abs() < 0.01, "{eta} against {want}");
}

#[test]
fn beds_decay_alike_and_their_mean_is_each_cycles_figure() {
    // `--beds 2` decays two beds (seeds 1 and 1 000 001) and gives each
    // cycle's mean with the error of their spread (Student's t on 1 degree
    // of freedom: |a - b| / 2 * 1.8125, or the readings' errors if larger);
    // the second bed alone (`--seed 1000001`) reads what it read in the
    // ensemble, to the bit, and a dashpot asked for beds decays once.
    let dir = Scratch::new("host-cli-decay-beds");
    let decay = |extra: &[&str], out: &str| {
        let mut args = vec!["--quiet", "host", "decay", "--duration-s", "0.2"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", out]);
        let o = vlab(&dir.0, &args);
        assert!(o.status.success(), "{}", stderr(&o));
        common::json(&dir.path(&format!("{out}/decay.json")))
    };
    let both = decay(&["--beds", "2"], "both");
    let second = decay(&["--seed", "1000001"], "second");
    let e = &both["ensemble"];
    assert_eq!(e["beds"], 2);
    assert_eq!(e["seeds"][1], 1_000_001);
    let eta = |j: &serde_json::Value, c: usize| {
        j["analysis"]["log_decrement"][c]["loss_factor"]
            .as_f64()
            .expect("eta")
    };
    let points = e["log_decrement"].as_array().expect("points");
    assert!(points.len() >= 5, "{e}");
    for (c, p) in points.iter().enumerate() {
        let (a, b) = (eta(&both, c), eta(&second, c));
        let mean = p["loss_factor"].as_f64().expect("mean");
        assert!((mean - 0.5 * (a + b)).abs() < 1e-12, "cycle {c}: {p}");
        let spread = (a - b).abs() / 2.0 * 1.8125;
        let err = p["loss_factor_stderr"].as_f64().expect("error");
        assert!(
            err >= spread * (1.0 - 1e-9),
            "cycle {c}: {err} below {spread}"
        );
    }
    let csv = std::fs::read_to_string(dir.path("both/decay-beds.csv")).expect("decay-beds.csv");
    assert!(csv.starts_with("method,cycle,"), "{csv}");
    let dashpot = decay(&["--damper", "dashpot:15", "--beds", "3"], "dashpot");
    assert!(dashpot["ensemble"].is_null(), "{}", dashpot["ensemble"]);
}

#[test]
fn a_prediction_outside_the_map_says_so() {
    // The reference map (signals/reference/host-map) reaches Gamma 30 at
    // 36-44 Hz: 5 N on plate-40hz stays inside it (Gamma 4.6-16.6), 8 N
    // drives 39 Hz to Gamma 32.7, above it.
    let dir = Scratch::new("host-cli-predict");
    let map = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/signals/reference/host-map/sweep.csv"
    );
    let run = |force: &str| {
        let args = [
            "host",
            "predict",
            "--map",
            map,
            "--freq",
            "36,39,40",
            "--force-n",
            force,
            "--out",
            force,
        ];
        let out = vlab(&dir.0, &args);
        assert!(out.status.success(), "{}", stderr(&out));
        let j = common::json(&dir.path(&format!("{force}/predict.json")));
        (
            stderr(&out),
            j["warnings"].as_array().expect("warnings").len(),
        )
    };
    let (err, n) = run("5");
    assert!(n == 0 && !err.contains("warning"), "{err}");
    let (err, n) = run("8");
    assert_eq!(n, 1, "{err}");
    assert!(
        err.contains("warning: Gamma 32.7 lies above the map's highest point at 39 Hz, Gamma 30"),
        "{err}"
    );
}

/// The stepped sine up and down in one run, on the dashpot host: every
/// step within 1 % of the single mode's exact receptance, the branches not
/// apart, its three files written.
#[test]
fn a_dashpot_up_and_down_reads_one_receptance_and_says_so() {
    let dir = Scratch::new("host-cli-updown");
    let out = vlab(
        &dir.0,
        &[
            "--quiet",
            "host",
            "frf",
            "--damper",
            "dashpot:10",
            "--freq",
            "39:41:1",
            "--force-n",
            "2",
            "--up-down",
            "--out",
            "u",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("the branches do not stand apart"), "{text}");
    for f in ["updown.csv", "updown.json", "updown.svg"] {
        assert!(dir.path(&format!("u/{f}")).is_file(), "{f}");
    }
    let csv = std::fs::read_to_string(dir.path("u/updown.csv")).expect("csv");
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let branches: Vec<(&str, &str)> = rows.iter().map(|r| (r[1], r[2])).collect();
    assert_eq!(
        branches,
        [
            ("up", "39"),
            ("up", "40"),
            ("up", "41"),
            ("down", "40"),
            ("down", "39")
        ]
    );
    // plate-40hz: modal mass 0.5 kg, stiffness 31 582.734 N/m, zeta 0.003,
    // the dashpot at the damper (the drive point).
    let (m, k, c) = (
        0.5_f64,
        31_582.734_f64,
        10.0 + 2.0 * 0.003 * (31_582.734_f64 * 0.5).sqrt(),
    );
    for r in &rows {
        let f: f64 = r[2].parse().expect("freq");
        let w = std::f64::consts::TAU * f;
        let want = 1.0 / ((k - m * w * w).powi(2) + (c * w).powi(2)).sqrt();
        let (re, im): (f64, f64) = (r[3].parse().expect("re"), r[4].parse().expect("im"));
        assert!((re.hypot(im) / want - 1.0).abs() < 0.01, "{r:?}: {want}");
    }
}

/// A swept sine on the dashpot host: the half-power loss factor read off
/// the whole record's DFTs within 1 % of 2 zeta (0.0860 against 0.0856
/// when written), the peak at 40 Hz, no warning of a response left at the
/// end; cut the silence and the warning comes.
/// The host on the shaker's table with a dashpot to the table: the
/// transmissibility read from the two accelerometers is the exact
/// `(k + i w c) / (k - w^2 m + i w c)` of plate-40hz's numbers (computed
/// here, apart from vlab: m 0.5 kg, 40 Hz, zeta 0.003, plus 20 N s/m)
/// within 0.05 % both ways (the docs' run of nine frequencies: 0.0054 % at
/// most), and the power the table put in (Yang's method through its
/// transducer) what the host's damping and the dashpot dissipated within
/// 0.5 % (the docs' run: 0.21 % at most).
#[test]
fn a_dashpot_on_the_table_reads_its_exact_transmissibility() {
    let dir = Scratch::new("host-cli-base");
    let out = vlab(
        &dir.0,
        &[
            "--quiet",
            "host",
            "base",
            "--damper",
            "dashpot:20",
            "--freq",
            "30,38,40,42,52",
            "--down",
            "--out",
            "t",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let csv = std::fs::read_to_string(dir.path("t/transmissibility.csv")).expect("csv");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let (m, k) = (0.5, 0.5 * (std::f64::consts::TAU * 40.0_f64).powi(2));
    let c = 2.0 * 0.003 * (k * m).sqrt() + 20.0;
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            l.split(',')
                .map(|v| v.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), 9, "5 up, 4 down");
    for r in &rows {
        let w = std::f64::consts::TAU * r[col("freq_hz")];
        let exact = (k.powi(2) + (w * c).powi(2)).sqrt()
            / ((k - w * w * m).powi(2) + (w * c).powi(2)).sqrt();
        let mag = r[col("magnitude")];
        assert!(
            (mag / exact - 1.0).abs() < 5e-4,
            "{r:?}: |T| {mag} against {exact}"
        );
        let power = r[col("power_in_w")] / r[col("true_dissipated_w")] - 1.0;
        assert!(power.abs() < 5e-3, "{r:?}: power in off by {power}");
    }
    for f in ["transmissibility.json", "transmissibility.svg"] {
        assert!(dir.path(&format!("t/{f}")).is_file(), "{f}");
    }
}

#[test]
fn a_dashpot_swept_sine_reads_its_loss_factor() {
    let dir = Scratch::new("host-cli-swept");
    let run = |duration: &str, out: &str| {
        vlab(
            &dir.0,
            &[
                "--quiet",
                "host",
                "frf",
                "--damper",
                "dashpot:10",
                "--swept",
                "30:50:2",
                "--force-n",
                "2",
                "--duration-s",
                duration,
                "--out",
                out,
            ],
        )
    };
    let out = run("3", "s");
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    let eta: f64 = text
        .split("half-power loss factor ")
        .nth(1)
        .and_then(|t| t.split_whitespace().next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("no loss factor in {text}"));
    let two_zeta = 2.0 * (0.003 + 10.0 / (2.0 * (31_582.734_f64 * 0.5).sqrt()));
    assert!(
        (eta / two_zeta - 1.0).abs() < 0.01,
        "{eta} against {two_zeta}"
    );
    assert!(text.contains("peak 0.3700 mm/N at 40.00 Hz"), "{text}");
    assert!(
        !stderr(&out).contains("had not died out"),
        "{}",
        stderr(&out)
    );
    for f in ["frf.csv", "frf-magnitude.svg", "trace.csv", "record.csv"] {
        assert!(dir.path(&format!("s/{f}")).is_file(), "{f}");
    }
    let cut = run("2.05", "cut");
    assert!(cut.status.success(), "{}", stderr(&cut));
    assert!(
        stderr(&cut).contains("had not died out"),
        "{}",
        stderr(&cut)
    );
}

/// Stepped sines at three forces in one command: on the dashpot host (a
/// linear one) the levels' receptances coincide within 0.1 % at every
/// frequency (measured: 0.005 % at most, the channels' noise weighing more
/// at 1 N), each level in its folder.
#[test]
fn a_linear_host_reads_one_receptance_at_every_force() {
    let dir = Scratch::new("host-cli-levels");
    let out = vlab(
        &dir.0,
        &[
            "--quiet",
            "host",
            "frf",
            "--damper",
            "dashpot:10",
            "--freq",
            "39:41:1",
            "--force-n",
            "1,2,4",
            "--settle-cycles",
            "20",
            "--out",
            "l",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    for f in [
        "levels.csv",
        "levels.svg",
        "force-1N/frf.csv",
        "force-4N/frf.json",
    ] {
        assert!(dir.path(&format!("l/{f}")).is_file(), "{f}");
    }
    let csv = std::fs::read_to_string(dir.path("l/levels.csv")).expect("csv");
    let rows: Vec<(f64, f64, f64)> = csv
        .lines()
        .skip(1)
        .map(|l| {
            let c: Vec<f64> = l.split(',').map(|x| x.parse().expect("number")).collect();
            (c[0], c[1], c[2])
        })
        .collect();
    assert_eq!(rows.len(), 9);
    for f in [39.0, 40.0, 41.0] {
        let at: Vec<f64> = rows.iter().filter(|r| r.0 == f).map(|r| r.2).collect();
        assert_eq!(at.len(), 3);
        for h in &at {
            assert!((h / at[0] - 1.0).abs() < 1e-3, "{f} Hz: {at:?}");
        }
    }
}

/// A reader that stops reading ends the command quietly: with its
/// standard output closed before it prints (`vlab ... | head` does this),
/// the stepped sine exits by the closed pipe's signal, not with a panic
/// and a backtrace from its first line of output.
#[cfg(unix)]
#[test]
fn a_closed_pipe_ends_the_command_without_a_panic() {
    use std::os::unix::process::ExitStatusExt;
    use std::process::{Command, Stdio};
    let dir = Scratch::new("host-cli-pipe");
    let mut child = Command::new(env!("CARGO_BIN_EXE_vlab"))
        .args([
            "--quiet",
            "host",
            "frf",
            "--damper",
            "dashpot:10",
            "--freq",
            "39:41:1",
            "--force-n",
            "2",
            "--out",
            "p",
        ])
        .current_dir(&dir.0)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run vlab");
    // The stepped sine takes a tenth of a second before its first line:
    // the pipe is closed long before.
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("wait");
    let err = stderr(&out);
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(out.status.signal(), Some(13), "{:?}: {err}", out.status);
}
