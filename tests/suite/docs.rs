//! The documentation cannot rot: the `vlab` commands of `docs/tutorial.md` and
//! of `README.md` run, every relative link of `README.md` and `docs/*.md`
//! points to a file (and heading) that exists, CI runs the test command
//! the README gives, and the figures the pages show are what their commands
//! draw, byte for byte (the rest of them: `tests/suite/figures.rs`). Command lines
//! marked `# takes minutes` are skipped.

#![cfg(all(feature = "cli", feature = "plot"))]

use crate::common;

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::process::Command;

use common::Scratch;

/// The repository's root.
fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Text of the repository file `name`.
fn read(name: &str) -> String {
    std::fs::read_to_string(root().join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The lines of the fenced blocks tagged `sh` in `text`.
fn sh_lines(text: &str) -> Vec<&str> {
    let mut in_block = false;
    let mut lines = Vec::new();
    for line in text.lines() {
        if line.starts_with("```") {
            in_block = line == "```sh";
            continue;
        }
        if in_block {
            lines.push(line);
        }
    }
    lines
}

/// The `vlab ...` command lines of the `sh` blocks of `text`, without the
/// ones marked `# takes minutes`.
fn vlab_commands(text: &str) -> Vec<String> {
    sh_lines(text)
        .into_iter()
        .filter(|l| l.starts_with("vlab ") && !l.contains("# takes minutes"))
        .map(str::to_string)
        .collect()
}

/// How a `vlab sweep` of the docs is run by the tests: each condition
/// driven a fixed 12 cycles (the last 6 measured), not until steady. The
/// command's flags, its conditions and its files are checked; its minutes
/// are not (the tutorial's took 4 minutes of the docs' tests' 6; the rule
/// that stops a sweep's shakes is `cli_sweep`'s to check).
const SWEEP_IN_TESTS: &str = "--cycles 12 --steady-cycles 6";

/// `cmd` as the tests run it: a `vlab sweep` of conditions (not `merge`
/// or `optimum`) that names no cycle count shortened by [`SWEEP_IN_TESTS`],
/// before any comment.
fn as_tested(cmd: &str) -> String {
    let is_sweep = cmd.starts_with("vlab sweep ")
        && !cmd.starts_with("vlab sweep merge")
        && !cmd.starts_with("vlab sweep optimum");
    if !is_sweep || cmd.contains("--cycles") {
        return cmd.to_string();
    }
    match cmd.split_once('#') {
        Some((run, comment)) => format!("{} {SWEEP_IN_TESTS}   #{comment}", run.trim_end()),
        None => format!("{cmd} {SWEEP_IN_TESTS}"),
    }
}

/// Runs `commands` in order with `sh` in a scratch folder that holds a copy of
/// the reference records (as a reader's checkout does), the test build's
/// `vlab` first on the `PATH` and a scratch cache of settled beds; a sweep
/// shortened ([`as_tested`]).
fn run_in_order(tag: &str, doc: &str, commands: &[String]) -> Scratch {
    let bin_dir = Path::new(env!("CARGO_BIN_EXE_vlab"))
        .parent()
        .expect("binary folder")
        .to_path_buf();
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let dir = Scratch::new(tag);
    copy_dir(
        &root().join("signals/reference"),
        &dir.path("signals/reference"),
    );
    for cmd in commands.iter().map(|c| as_tested(c)) {
        let out = Command::new("sh")
            .args(["-c", &format!("set -e; {cmd}")])
            .env("PATH", &path)
            .env("VLAB_CACHE_DIR", dir.path(".vlab-cache"))
            .current_dir(&dir.0)
            .output()
            .expect("run sh");
        assert!(
            out.status.success(),
            "{doc} command failed: {cmd}\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    dir
}

#[test]
fn only_a_sweep_of_conditions_is_shortened() {
    assert_eq!(
        as_tested("vlab sweep --freq 40 --gamma 3,10 --seeds 1,2   # about 3 minutes"),
        "vlab sweep --freq 40 --gamma 3,10 --seeds 1,2 --cycles 12 --steady-cycles 6   # about 3 minutes"
    );
    for kept in [
        "vlab sweep --freq 40 --gamma 3 --cycles 8 --out x",
        "vlab sweep merge a b --out c",
        "vlab shake --freq 40 --gamma 20",
    ] {
        assert_eq!(as_tested(kept), kept);
    }
}

/// The README's commands, then the tutorial's, in one scratch folder: a
/// tutorial line the README ran already (the main job, step 5) is not run
/// again (its files are there as the reader's run leaves them). The main
/// job is the suite's longest command; run twice it was a third of the
/// docs' tests.
#[test]
fn readme_and_tutorial_commands_run() {
    let readme_text = read("README.md");
    let readme = vlab_commands(&readme_text);
    assert!(
        readme.len() >= 4,
        "found only {} README commands: {readme:?}",
        readme.len()
    );
    let tutorial = vlab_commands(&read("docs/tutorial.md"));
    assert!(
        tutorial.len() >= 10,
        "found only {} tutorial commands",
        tutorial.len()
    );
    let main_job = "vlab shake --freq 40 --gamma 20";
    for (page, commands) in [("README", &readme), ("tutorial", &tutorial)] {
        assert!(
            commands.iter().any(|c| c == main_job),
            "the {page} no longer runs the main job as `{main_job}`"
        );
    }
    let mut commands = readme.clone();
    commands.extend(tutorial.iter().filter(|c| !readme.contains(c)).cloned());
    let dir = run_in_order("readme-tutorial", "README or tutorial", &commands);
    // The sample output's run wrote where the README says it did.
    assert!(
        readme_text.contains("wrote signals/thesis-40Hz-G20"),
        "README's sample output no longer names its folder"
    );
    assert!(
        dir.path("signals/thesis-40Hz-G20/summary.json").is_file(),
        "the README's shake wrote no signals/thesis-40Hz-G20/summary.json"
    );
    // Step 7's claim: the mis-calibrated rig reads off, the right one does not.
    let read = |p: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.path(p)).expect(p)).expect("json")
    };
    let good = read("signals/thesis-40Hz-G20/summary.json")["measured"]["error_vs_dem_rel"]
        .as_f64()
        .expect("error");
    let wrong = read("wrong/summary.json")["measured"]["error_vs_dem_rel"]
        .as_f64()
        .expect("error");
    assert!(good.abs() < 0.01, "calibrated run off by {good}");
    assert!(wrong.abs() > 0.02, "mis-calibrated run only off by {wrong}");
    // The snapshots docs/maps.md and this tutorial show are step 8's.
    for name in ["snapshots.png", "snapshots.svg"] {
        common::same_figure(
            &dir.path(&format!("bb/{name}")),
            &format!("docs/figures/{name}"),
            &format!(
                "vlab shake --freq 40 --gamma 20 --beds 1 --snapshots --out bb; cp bb/{name} docs/figures/"
            ),
        );
    }
    tutorial_numbers_are_the_runs(&dir);
}

/// Runs `vlab args` in the tutorial's scratch folder (its bed cache) and
/// gives its standard output.
fn vlab_output(dir: &Scratch, args: &[&str]) -> String {
    let out = common::vlab(&dir.0, args);
    assert!(
        out.status.success(),
        "vlab {args:?}: {}",
        common::stderr(&out)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn json_output(dir: &Scratch, args: &[&str]) -> serde_json::Value {
    serde_json::from_str(&vlab_output(dir, args)).unwrap_or_else(|e| panic!("{args:?}: {e}"))
}

fn json_file(dir: &Scratch, name: &str) -> serde_json::Value {
    common::json(&dir.path(name))
}

fn num(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("{v} is not a number"))
}

/// The number after `label` on the line of `text` that holds it.
fn number_after(text: &str, label: &str) -> f64 {
    let line = text
        .lines()
        .find(|l| l.contains(label))
        .unwrap_or_else(|| panic!("no line with {label:?} in\n{text}"));
    let rest = &line[line.find(label).map_or(0, |i| i + label.len())..];
    let word: String = rest
        .trim_start_matches(|c: char| !(c.is_ascii_digit() || c == '-'))
        .chars()
        .take_while(|c| c.is_ascii_digit() || matches!(c, '.' | '-' | 'e'))
        .collect();
    word.parse()
        .unwrap_or_else(|e| panic!("{label:?} in {line:?}: {e}"))
}

/// One condition of a reference sweep, its efficiencies the mean over its
/// seeds.
struct Condition {
    orientation: String,
    freq_hz: f64,
    gamma: f64,
    dem: f64,
    measured: f64,
}

/// The conditions of the reference sweep `name`.
fn seed_means(name: &str) -> Vec<Condition> {
    let text = read(name);
    let body: String = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| format!("{l}\n"))
        .collect();
    let mut reader = csv::Reader::from_reader(body.as_bytes());
    let headers = reader.headers().expect("header").clone();
    let column = |key: &str| headers.iter().position(|h| h == key).expect(key);
    let (o, f, g, st, e, m) = (
        column("orientation"),
        column("freq_hz"),
        column("gamma"),
        column("status"),
        column("efficiency"),
        column("efficiency_measured"),
    );
    let mut sums: Vec<(Condition, f64)> = Vec::new();
    for row in reader.records() {
        let row = row.expect("row");
        if &row[st] != "ok" {
            continue;
        }
        let value = |i: usize| row[i].parse::<f64>().expect("number");
        let (freq_hz, gamma) = (value(f), value(g));
        let same =
            |c: &Condition| c.orientation == row[o] && c.freq_hz == freq_hz && c.gamma == gamma;
        match sums.iter_mut().find(|(c, _)| same(c)) {
            Some((c, n)) => {
                c.dem += value(e);
                c.measured += value(m);
                *n += 1.0;
            }
            None => sums.push((
                Condition {
                    orientation: row[o].to_string(),
                    freq_hz,
                    gamma,
                    dem: value(e),
                    measured: value(m),
                },
                1.0,
            )),
        }
    }
    sums.into_iter()
        .map(|(c, n)| Condition {
            dem: c.dem / n,
            measured: c.measured / n,
            ..c
        })
        .collect()
}

/// The DEM efficiency of one condition of `conditions`.
fn efficiency_at(conditions: &[Condition], orientation: &str, freq_hz: f64, gamma: f64) -> f64 {
    conditions
        .iter()
        .find(|c| c.orientation == orientation && c.freq_hz == freq_hz && c.gamma == gamma)
        .unwrap_or_else(|| panic!("no {orientation} {freq_hz} Hz, Gamma {gamma}"))
        .dem
}

/// The answer key's class map (exercise 3) quotes the reference class map.
#[test]
fn the_answers_quote_the_class_map() {
    let page = read("docs/answers.md")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    let map = seed_means("signals/reference/class-map/sweep.csv");
    let at = |o: &str, g: f64| efficiency_at(&map, o, 40.0, g);
    for sentence in [
        format!(
            "at {:.3} (the vertical one there: {:.3})",
            at("horizontal", 20.0),
            at("vertical", 20.0)
        ),
        format!(
            "still bounces at Γ 30 ({:.3}; vertical {:.3})",
            at("horizontal", 30.0),
            at("vertical", 30.0)
        ),
        format!(
            "at Γ 5 the horizontal damper dissipates {:.3}, more than twice the vertical {:.3}",
            at("horizontal", 5.0),
            at("vertical", 5.0)
        ),
        format!(
            "At Γ 10 both convect ({:.3} horizontal, {:.3} vertical)",
            at("horizontal", 10.0),
            at("vertical", 10.0)
        ),
    ] {
        assert!(
            page.contains(&sentence),
            "docs/answers.md should say: {sentence}"
        );
    }
    // Both halves peak on the grid at Gamma 20.
    for o in ["vertical", "horizontal"] {
        let best = [5.0, 10.0, 20.0, 30.0]
            .into_iter()
            .max_by(|a, b| at(o, *a).total_cmp(&at(o, *b)));
        assert_eq!(best, Some(20.0), "{o}");
    }
}

/// The words of the repository page `name`, one space apart, the quote
/// marks of boxes taken out: a sentence is found whatever its line breaks.
fn page_words(name: &str) -> String {
    read(name)
        .lines()
        .map(|l| l.trim_start().trim_start_matches('>'))
        .flat_map(str::split_whitespace)
        .collect::<Vec<_>>()
        .join(" ")
}

/// Every number the tutorial's steps 1–10 quote, against the runs of its
/// commands (and a few `--json` twins run in the same folder): the page
/// must still hold each sentence with the number as the run gives it,
/// rounded as the page rounds it. A change that moves a number fails here
/// with the sentence to edit.
fn tutorial_numbers_are_the_runs(dir: &Scratch) {
    let page = page_words("docs/tutorial.md");
    let mut wrong = Vec::new();
    let mut quote = |sentence: String| {
        if !page.contains(&sentence) {
            wrong.push(sentence);
        }
    };

    // 1. The damper.
    let scene = json_output(dir, &["scene", "--json"]);
    let scene_text = vlab_output(dir, &["scene"]);
    let drive = vlab::drive::Drive::new(40.0, 20.0, 9.81).expect("drive");
    quote(format!(
        "at 40 Hz Γ 20 is a stroke of ±{:.1} mm and a peak speed `Γ g / ω` of {:.2} m/s",
        drive.displacement_amplitude_m() * 1e3,
        drive.velocity_amplitude_mps()
    ));
    quote(format!("a volume fill of {:.3}", num(&scene["fill_ratio"])));
    quote(format!(
        "a time step of {:.1e} s at 40 Hz, Γ 20 (every collision resolved by {} steps",
        num(&scene["dt_s_at_40hz_gamma20"]),
        number_after(&scene_text, "Gamma 20 (")
    ));
    quote(format!(
        "against a Rayleigh limit of {:.1e} s",
        num(&scene["rayleigh_limit_s"])
    ));
    quote(format!(
        "eq. 5.26, {:.1} m/s between spheres",
        number_after(&scene_text, "yield velocity")
    ));

    // 2. One collision.
    let hertz = json_output(dir, &["impact", "--speed-mps", "1", "--json"]);
    let (d, h) = (
        num(&hertz["contact_duration_s"]),
        num(&hertz["hertz_contact_duration_s"]),
    );
    quote(format!(
        "The first collision lasts {d:.2e} s, against {h:.2e} s for a purely elastic"
    ));
    quote(format!("stretches it by {:.1} %)", 100.0 * (d / h - 1.0)));
    quote(format!(
        "comes back at e = {:.3}",
        num(&hertz["normal_restitution"])
    ));
    let thesis = json_output(
        dir,
        &[
            "impact",
            "--speed-mps",
            "1",
            "--cor",
            "0.57",
            "--restitution-mode",
            "thesis",
            "--json",
        ],
    );
    quote(format!(
        "the realised restitution is {:.2}, not the 0.57 asked for",
        num(&thesis["normal_restitution"])
    ));

    // 3. The drop test.
    let drop = json_file(dir, "drop/drop.json");
    quote(format!(
        "agrees with what the contact model realises to {:.3} % on average",
        100.0 * num(&drop["cor_error_rel"])
    ));

    // 4. The phase error.
    let cal = json_file(dir, "cal.json");
    let at_40 = cal["points"]
        .as_array()
        .and_then(|p| p.iter().find(|p| p["freq_hz"].as_f64() == Some(40.0)))
        .expect("cal.json has 40 Hz");
    quote(format!(
        "at 40 Hz, Γ 20 the {:.3}° error",
        num(&at_40["phase_error_rad"]).to_degrees()
    ));
    // The drawing of the signal chain and the leak by hand, from the rig file.
    let rig: toml::Table = toml::from_str(&vlab_output(dir, &["rig", "thesis-shaker", "--print"]))
        .expect("the printed rig is TOML");
    let key = |table: &str, name: &str| -> f64 {
        let v = &rig[table][name];
        v.as_float()
            .or_else(|| v.as_integer().map(|i| i as f64))
            .unwrap_or_else(|| panic!("{table}.{name} is not a number"))
    };
    let (force, accel) = (&rig["force"]["low_pass"], &rig["accelerometer"]["low_pass"]);
    for (what, low_pass) in [("force", force), ("acceleration", accel)] {
        let cutoff = low_pass["cutoff_hz"].as_float().expect("cutoff_hz");
        let order = low_pass["order"].as_integer().expect("order");
        assert_eq!(
            (cutoff, order),
            (10_000.0, 4),
            "the drawing's {what} filter"
        );
    }
    quote(format!("{} V/N", key("force", "sensitivity_v_per_n")));
    quote(format!("corner {} Hz", key("force", "high_pass_hz")));
    quote(format!(
        "{} V/(m/s²)",
        key("accelerometer", "sensitivity_v_per_mps2")
    ));
    quote(format!(
        "corner {} Hz",
        key("accelerometer", "high_pass_hz")
    ));
    assert_eq!(key("daq", "sample_rate_hz"), 40_000.0, "the drawing's ADC");
    quote(format!(
        "the ADC samples the force {:.0} µs late (the **inter-channel skew**",
        key("force", "sample_skew_s") * 1e6
    ));
    quote(format!("ADC, {} bit", key("daq", "bits")));
    let m_enc = key("enclosure", "mass_kg");
    let a_peak = drive.acceleration_amplitude_mps2();
    let v_peak = drive.velocity_amplitude_mps();
    quote(format!(
        "about ½ × {m_enc} kg × {a_peak:.0} m/s² × {v_peak:.2} m/s ≈ {:.0} var",
        0.5 * m_enc * a_peak * v_peak
    ));
    let run = json_file(dir, "signals/thesis-40Hz-G20/summary.json");
    let dem_j = num(&run["dem"]["energy_per_cycle_j"]);
    quote(format!(
        "is worth about {:.0} % of the damper's dissipation",
        -100.0 * num(&run["measured"]["predicted_leak_per_cycle_j"]) / dem_j
    ));
    let reference = json_output(
        dir,
        &[
            "analyze",
            "signals/reference/thesis-40Hz-G20/trace.csv",
            "--json",
        ],
    );
    let h1 = &reference["per_harmonic"][0];
    let q_var =
        0.5 * num(&h1["force_amp_n"]) * num(&h1["velocity_amp_mps"]) * num(&h1["phase_rad"]).sin();
    let corrected = json_output(
        dir,
        &[
            "analyze",
            "signals/reference/thesis-40Hz-G20/trace.csv",
            "--calibration",
            "signals/reference/thesis-40Hz-G20/calibration.json",
            "--json",
        ],
    );
    let power_w = num(&corrected["power_w"]);
    quote(format!(
        "({q_var:.1} var with the bed, on the reference record)"
    ));
    quote(format!(
        "0.005 rad × {q_var:.1} var ≈ {:.2} W, {:.1} % of the {power_w:.2} W the bed dissipates",
        0.005 * q_var,
        100.0 * 0.005 * q_var / power_w
    ));
    quote(format!(
        "`vlab analyze`'s correction {:.4} W",
        power_w - num(&reference["power_w"])
    ));
    quote(format!(
        "the same {:.2} W is {:.1} %, the answers' figure",
        0.005 * q_var,
        100.0 * 0.005 * q_var / num(&reference["power_w"])
    ));

    // 5. Shake, record, measure.
    let (m, dem) = (&run["measured"], &run["dem"]);
    quote(format!("steady ({} cycles here:", num(&run["cycles"])));
    // The six beds' figures: the ensemble's mean and its +-.
    let ensemble = &run["ensemble"];
    let (e, se) = (
        num(&ensemble["measured_energy_per_cycle_j"]["mean"]),
        num(&ensemble["measured_energy_per_cycle_j"]["stderr"]),
    );
    let eta = num(&ensemble["measured_efficiency"]["mean"]);
    quote(format!(
        "Yang's method gives {:.2}e-2 ± {:.2}e-2 J per cycle over the six beds, an efficiency of {eta:.3} ± {:.3}",
        e * 1e2,
        se * 1e2,
        num(&ensemble["measured_efficiency"]["stderr"])
    ));
    let error = num(&m["error_vs_dem_rel"]);
    assert!(
        error.abs() < 0.001,
        "step 5 says within 0.1 % of the DEM; the run reads {:+.3} %",
        100.0 * error
    );
    quote(format!(
        "(½ M (2V)² = 2 M V² a blow): {:.3} J here, so {e:.3} J is {eta:.2}.",
        num(&dem["e_max_j"]),
    ));

    // 6. Analyse the record yourself.
    let raw = json_output(
        dir,
        &["analyze", "signals/thesis-40Hz-G20/trace.csv", "--json"],
    );
    let low = -100.0 * (num(&raw["energy_per_cycle_j"]) / dem_j - 1.0);
    quote(format!(
        "Without the calibration the same record reads {low:.1} % low"
    ));
    quote(format!("your run of step 5 leaks {low:.1} % of its own"));

    // 7. Break it on purpose.
    let broken = json_file(dir, "wrong/summary.json");
    quote(format!(
        "the measurement reads about {:.0} % off",
        100.0 * num(&broken["measured"]["error_vs_dem_rel"]).abs()
    ));

    // 9. Records from your own lab.
    let reference_dir = "signals/reference/thesis-40Hz-G20";
    let tdms = json_output(
        dir,
        &[
            "analyze",
            &format!("{reference_dir}/trace.tdms"),
            "--calibration",
            &format!("{reference_dir}/calibration.json"),
            "--json",
        ],
    );
    quote(format!(
        "the third), they give the same {:.4} W, {:.4e} J per cycle",
        num(&tdms["power_w"]),
        num(&tdms["energy_per_cycle_j"])
    ));
    let uncalibrated = json_output(
        dir,
        &[
            "analyze",
            &format!("{reference_dir}/trace-semicolon.csv"),
            "--freq",
            "40",
            "--delimiter",
            ";",
            "--decimal-comma",
            "--json",
        ],
    );
    quote(format!(
        "the second, without `--calibration`, reads {:.4} W",
        num(&uncalibrated["power_w"])
    ));
    let cor = json_output(
        dir,
        &[
            "cor",
            "signals/reference/drop-acrylic-smooth/force-h2mm.csv",
            "--json",
        ],
    );
    let triples = cor["cor_per_triple"].as_array().map_or(0, Vec::len);
    let words = [
        "no", "one", "two", "three", "four", "five", "six", "seven", "eight",
    ];
    quote(format!(
        "COR {:.5} over {} triples",
        num(&cor["cor_mean"]),
        words.get(triples).copied().unwrap_or("many")
    ));

    // 10. Reading an efficiency curve and a map.
    let predict = json_output(dir, &["predict", "--freq", "20,40,80", "--json"]);
    let gammas = |key: &str| -> Vec<String> {
        predict[key]
            .as_array()
            .expect(key)
            .iter()
            .map(|g| format!("{:.1}", num(g)))
            .collect()
    };
    let (close, loose) = (gammas("close_packing_gamma"), gammas("loose_packing_gamma"));
    quote(format!(
        "Γ {}, {} and {} with close packing, {}, {} and {} with loose packing",
        close[0], close[1], close[2], loose[0], loose[1], loose[2]
    ));
    let steady = seed_means("signals/reference/sweep-steady/sweep.csv");
    let at = |f: f64, g: f64| efficiency_at(&steady, "vertical", f, g);
    quote(format!("fluidisation at Γ 3 ({:.2})", at(40.0, 3.0)));
    quote(format!("bouncing bed at Γ 20 ({:.2})", at(40.0, 20.0)));
    let (g5, g8) = (at(40.0, 5.0), at(40.0, 8.0));
    quote(format!(
        "the efficiency falls to {:.2}–{:.2}",
        g5.min(g8),
        g5.max(g8)
    ));
    let worst_dissipating = steady
        .iter()
        .filter(|c| c.dem > 0.1)
        .map(|c| (c.measured / c.dem - 1.0).abs())
        .fold(0.0, f64::max);
    assert!(
        worst_dissipating < 0.01,
        "step 10 says within 1 % wherever the damper dissipates; worst {:.2} %",
        100.0 * worst_dissipating
    );
    let thesis_80: Vec<f64> = seed_means("signals/reference/sweep-thesis/sweep.csv")
        .iter()
        .filter(|c| c.freq_hz == 80.0 && (1.5..=20.0).contains(&c.gamma))
        .map(|c| 100.0 * (1.0 - c.measured / c.dem))
        .collect();
    quote(format!(
        "at 80 Hz by {:.0}–{:.0} % from Γ 1.5 to 20",
        thesis_80.iter().copied().fold(f64::INFINITY, f64::min),
        thesis_80.iter().copied().fold(0.0, f64::max)
    ));

    assert!(
        wrong.is_empty(),
        "docs/tutorial.md no longer says what its commands give; it should say:\n{}",
        wrong.join("\n")
    );
}

/// The chapter on the damper on a structure: its commands run in order and
/// every number it quotes is what they give.
#[test]
fn host_chapter_commands_run() {
    let commands = vlab_commands(&read("docs/host.md"));
    assert!(
        commands.len() >= 8,
        "found only {} commands",
        commands.len()
    );
    let dir = run_in_order("host-chapter", "docs/host.md", &commands);
    for (drawn, shown, command) in [
        (
            "host/dashpot/loss-factor.svg",
            "host-dashpot-loss-factor.svg",
            "vlab host decay --damper dashpot:15 --duration-s 0.5 --out host/dashpot",
        ),
        (
            "host/frf-dashpot/frf-magnitude.svg",
            "host-dashpot-frf.svg",
            "vlab host frf --damper dashpot:10 --freq 36:44:0.25 --force-n 2 --settle-cycles 0 --out host/frf-dashpot",
        ),
        (
            "host/plate/loss-factor.svg",
            "host-loss-factor.svg",
            "vlab host decay --duration-s 0.8 --map signals/reference/host-map/sweep.csv --out host/plate",
        ),
    ] {
        common::same_figure(
            &dir.path(drawn),
            &format!("docs/figures/{shown}"),
            &format!("{command}; cp {drawn} docs/figures/{shown}"),
        );
    }
    let page = page_words("docs/host.md");
    let mut wrong = Vec::new();
    let mut quote = |sentence: String| {
        if !page.contains(&sentence) {
            wrong.push(sentence);
        }
    };
    let plate = vlab::host::HostSpec::sdof("plate", 40.0, 0.5, 0.003).expect("valid");
    let m = plate.modes[0];
    let zeta = |c: f64| m.damping_ratio + c / (2.0 * (m.stiffness() * m.modal_mass_kg).sqrt());

    // 2. The dashpot.
    let d = json_file(&dir, "host/dashpot/decay.json");
    let a = &d["analysis"];
    quote(format!("a loss factor η = 2ζ = {:.4}", 2.0 * zeta(15.0)));
    quote(format!(
        "logarithmic decrement reads {:.4} on the first cycle and the Hilbert envelope {:.4}",
        num(&a["log_decrement"][0]["loss_factor"]),
        num(&a["envelope"][0]["loss_factor"])
    ));
    quote(format!(
        "puts {:.4} J into the dashpot, which dissipated {:.4} J",
        num(&a["damper_energy_sum_j"]),
        num(&a["true_damper_dissipated_sum_j"])
    ));
    let swept = json_file(&dir, "host/swept-dashpot/frf.json");
    quote(format!(
        "Its {} lines read a half-power loss factor of {:.4} from the swept sine against the known {:.4}",
        swept["lines"].as_u64().unwrap_or(0),
        num(&swept["half_power"]["loss_factor"]),
        2.0 * zeta(10.0)
    ));
    quote(format!(
        "(`tail_fraction`: the largest acceleration over the record's last 5 % over the largest anywhere, {:.4} here",
        num(&swept["tail_fraction"])
    ));
    let f = json_file(&dir, "host/frf-dashpot/frf.json");
    quote(format!(
        "a loss factor of {:.4} against the known {:.4}",
        num(&f["measured"]["half_power"]["loss_factor"]),
        2.0 * zeta(10.0)
    ));
    let coherence = std::fs::read_to_string(dir.path("host/random-dashpot/frf.csv"))
        .expect("frf.csv")
        .lines()
        .skip(1)
        .filter_map(|l| l.split(',').nth(5)?.parse::<f64>().ok())
        .fold(f64::INFINITY, f64::min);
    quote(format!(
        "stays above {:.3}",
        (coherence * 1000.0).floor() / 1000.0
    ));

    // 5. The linear dashpot beside the damper's true random: its line at
    // 40 Hz (H1, H2 in mm/N, coherence).
    let line_40 = std::fs::read_to_string(dir.path("host/noise-dashpot2/frf.csv"))
        .expect("frf.csv")
        .lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .filter_map(|v| v.parse::<f64>().ok())
                .collect::<Vec<f64>>()
        })
        .find(|c| c.len() >= 6 && c[0] == 40.0)
        .expect("a line at 40 Hz");
    quote(format!(
        "reads H1 {:.2}, H2 {:.2} and a coherence of {:.3} there",
        line_40[1].hypot(line_40[2]) * 1e3,
        line_40[3].hypot(line_40[4]) * 1e3,
        line_40[5]
    ));

    // 3. and 4. The granular damper on both hosts.
    let sums = |name: &str| {
        let a = json_file(&dir, name)["analysis"].clone();
        (
            num(&a["damper_energy_sum_j"]),
            num(&a["true_damper_energy_sum_j"]),
            num(&a["true_damper_dissipated_sum_j"]),
            a,
        )
    };
    let (log, work, dissipated, plate_a) = sums("host/plate/decay.json");
    quote(format!(
        "the log decrement puts {log:.4} J into the damper, the host did {work:.4} J of work on the bed and the DEM dissipated {dissipated:.4} J"
    ));
    let first = &plate_a["log_decrement"][0];
    quote(format!(
        "at the start of the decay (Γ {:.1}) the log decrement's damper energy per cycle is {:.4} J",
        num(&first["gamma"]),
        num(&first["damper_energy_j"])
    ));
    let csv = std::fs::read_to_string(dir.path("host/plate/decay.csv")).expect("decay.csv");
    let yang_column = csv
        .lines()
        .next()
        .and_then(|h| h.split(',').position(|c| c == "yang_map_energy_j"))
        .expect("a Yang column");
    let yang0: f64 = csv
        .lines()
        .nth(1)
        .and_then(|l| l.split(',').nth(yang_column)?.parse().ok())
        .expect("a Yang value");
    quote(format!("and the map's steady figure {yang0:.4} J"));
    let (blog, bwork, bdissipated, beam_a) = sums("host/beam/decay.json");
    let beam_first = &beam_a["log_decrement"][0];
    quote(format!(
        "its first cycle's loss factor is {:.3} (Γ {:.1}) against the plate's {:.3}",
        num(&beam_first["loss_factor"]),
        num(&beam_first["gamma"]),
        num(&first["loss_factor"])
    ));
    quote(format!(
        "over the decay the log decrement puts {blog:.4} J into the damper, the host's work on the bed is {bwork:.4} J and the DEM dissipated {bdissipated:.4} J"
    ));

    // 5. The map-based model.
    let peak = |name: &str| {
        std::fs::read_to_string(dir.path(name))
            .expect("predict.csv")
            .lines()
            .skip(1)
            .filter_map(|l| {
                let c: Vec<f64> = l
                    .split(',')
                    .take(2)
                    .filter_map(|v| v.parse().ok())
                    .collect();
                (c.len() == 2).then(|| (c[0], c[1]))
            })
            .fold((0.0, 0.0), |b: (f64, f64), p| if p.1 > b.1 { p } else { b })
    };
    let (pf, px) = peak("host/predict/predict.csv");
    quote(format!(
        "predicts a flat top of {:.2} mm at {:.1} Hz",
        px * 1e3,
        pf
    ));
    let (bf, bx) = peak("host/predict-beam/predict.csv");
    quote(format!(
        "the beam's peak {:.2} mm at {:.1} Hz",
        bx * 1e3,
        bf
    ));

    // 6. On the shaker's table: the worst step against the exact answer,
    // rounded up to the page's digit.
    let table = json_file(&dir, "host/base-dashpot/transmissibility.json");
    let points = table["points"].as_array().expect("points");
    let worst = |f: &dyn Fn(&serde_json::Value) -> f64| {
        points.iter().map(f).fold(0.0_f64, |m, v| m.max(v.abs()))
    };
    let t_off = worst(&|p| {
        let exact = num(&p["exact_re"]).hypot(num(&p["exact_im"]));
        num(&p["magnitude"]) / exact - 1.0
    });
    let power_off = worst(&|p| num(&p["power_in_w"]) / num(&p["true_dissipated_w"]) - 1.0);
    quote(format!(
        "accelerometers read it within {:.3} % at every step both ways",
        (t_off * 1e5).ceil() / 1e3
    ));
    quote(format!(
        "reads the dissipation within {:.1} %",
        (power_off * 1e3).ceil() / 10.0
    ));

    assert!(
        wrong.is_empty(),
        "docs/host.md no longer says what its commands give; it should say:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn ci_runs_the_readme_test_command() {
    let readme = read("README.md");
    let ci = read(".ci/run");
    let readme_cargo: Vec<&str> = sh_lines(&readme)
        .into_iter()
        .filter(|l| l.starts_with("cargo test"))
        .collect();
    let ci_cargo: Vec<&str> = ci.lines().filter(|l| l.starts_with("cargo ")).collect();
    assert_eq!(
        readme_cargo,
        vec!["cargo test --workspace"],
        "the README gives one test command, for vlab and the browser lab's crate"
    );
    assert_eq!(ci_cargo, readme_cargo, ".ci/run and the README disagree");
}

#[test]
fn relative_links_resolve() {
    let mut files = vec![root().join("README.md")];
    for entry in std::fs::read_dir(root().join("docs")).expect("docs/") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "md") {
            files.push(path);
        }
    }
    assert!(
        files.len() >= 10,
        "found only {} Markdown files",
        files.len()
    );
    let mut broken = Vec::new();
    let mut checked = 0;
    for file in &files {
        let text = std::fs::read_to_string(file).expect("read Markdown");
        for target in link_targets(&text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            checked += 1;
            let (path_part, anchor) = match target.split_once('#') {
                Some((p, a)) => (p, Some(a)),
                None => (target.as_str(), None),
            };
            let linked: PathBuf = if path_part.is_empty() {
                file.clone()
            } else {
                file.parent().expect("folder").join(path_part)
            };
            let name = file.strip_prefix(root()).unwrap_or(file).display();
            if !linked.exists() {
                broken.push(format!("{name}: {target} (no such file)"));
                continue;
            }
            if let Some(anchor) = anchor {
                let is_md = linked.extension().is_some_and(|e| e == "md");
                let linked_text = std::fs::read_to_string(&linked).unwrap_or_default();
                if is_md && !heading_anchors(&linked_text).contains(anchor) {
                    broken.push(format!("{name}: {target} (no such heading)"));
                }
            }
        }
    }
    assert!(checked >= 20, "checked only {checked} links");
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

/// The targets of the inline links and images of `text`, outside fenced
/// blocks and code spans.
fn link_targets(text: &str) -> Vec<String> {
    let mut targets = Vec::new();
    let mut in_fence = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_fence = !in_fence;
            continue;
        }
        if in_fence {
            continue;
        }
        let prose = without_code_spans(line);
        let mut rest = prose.as_str();
        while let Some(i) = rest.find("](") {
            let after = &rest[i + 2..];
            let Some(end) = after.find(')') else { break };
            targets.push(after[..end].trim().to_string());
            rest = &after[end..];
        }
    }
    targets
}

/// `line` with its `code spans` removed.
fn without_code_spans(line: &str) -> String {
    line.split('`').step_by(2).collect::<Vec<_>>().join("")
}

/// The anchors the forge gives the headings of `text`: lower case, code
/// marks and punctuation dropped, spaces as hyphens.
fn heading_anchors(text: &str) -> HashSet<String> {
    let mut anchors = HashSet::new();
    let mut in_fence = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_fence = !in_fence;
            continue;
        }
        if in_fence || !line.starts_with('#') {
            continue;
        }
        let title = line.trim_start_matches('#').trim();
        let anchor: String = title
            .to_lowercase()
            .chars()
            .filter(|c| c.is_alphanumeric() || *c == ' ' || *c == '-' || *c == '_')
            .map(|c| if c == ' ' { '-' } else { c })
            .collect();
        anchors.insert(anchor);
    }
    anchors
}

#[test]
fn anchors_follow_the_forge() {
    let anchors = heading_anchors(
        "# Maps: where, and why\n## The drop test: `vlab drop`\n```sh\n# not a heading\n```\n",
    );
    assert!(anchors.contains("maps-where-and-why"), "{anchors:?}");
    assert!(anchors.contains("the-drop-test-vlab-drop"), "{anchors:?}");
    assert_eq!(anchors.len(), 2, "{anchors:?}");
    assert_eq!(
        link_targets("see [a](b.md#c) and `[x](not-a-link)` and ![f](g.png)"),
        vec!["b.md#c", "g.png"]
    );
}

/// Copies the folder `from` to `to`, recursively.
fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("create folder");
    for entry in std::fs::read_dir(from).expect("read folder") {
        let path = entry.expect("entry").path();
        let target = to.join(path.file_name().expect("name"));
        if path.is_dir() {
            copy_dir(&path, &target);
        } else {
            std::fs::copy(&path, &target).expect("copy");
        }
    }
}

/// The figures docs/maps.md shows are what its command draws today, byte
/// for byte (`vlab plot signals/reference/sweep-steady/sweep.csv --out
/// docs/figures`): a change to the plots fails here until the figures are
/// redrawn, so the chapter cannot show a plot vlab no longer makes.
#[test]
fn the_maps_figures_are_what_their_command_draws() {
    let dir = Scratch::new("figures");
    let sweep = root().join("signals/reference/sweep-steady/sweep.csv");
    let sweep = sweep.to_string_lossy();
    vlab_output(&dir, &["plot", &sweep, "--out", "drawn"]);
    for name in ["efficiency.png", "efficiency.svg", "map.png", "map.svg"] {
        let drawn = std::fs::read(dir.path(&format!("drawn/{name}"))).expect("drawn");
        let shown = std::fs::read(root().join("docs/figures").join(name)).expect("shown");
        assert!(
            drawn == shown,
            "docs/figures/{name} is not what `vlab plot` draws now: redraw it with `vlab plot signals/reference/sweep-steady/sweep.csv --out docs/figures`"
        );
    }
}
