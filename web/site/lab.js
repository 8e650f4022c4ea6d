// The browser lab's page: the form, the worker, the drawings and Yang's
// method step by step (docs/browser-lab.md). The URL may carry the form's
// values (?freq=40&gamma=20&orientation=vertical&seed=1&cycles=8&steady=5
// &rig=thesis-shaker), autorun=1 to start at once, and report=1 to POST the
// result to /result when done (the headless-browser test reads it there).
"use strict";

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
const fields = { freq: "freq", gamma: "gamma", orientation: "orientation", seed: "seed",
  cycles: "cycles", steady: "steady", rig: "rig" };
for (const [key, id] of Object.entries(fields)) {
  if (params.has(key)) $(id).value = params.get(key);
}

let worker = null;
let setup = null;
let trace = [];          // [t_s, accel, force] from the frames while running
let frames = [];         // every frame of the run, for the replay
let playing = null;      // the replay's timer
let startedAt = 0;
let lastPaint = 0;
let pendingFrame = null;

function request() {
  return {
    freq_hz: Number($("freq").value),
    gamma: Number($("gamma").value),
    orientation: $("orientation").value,
    seed: Math.round(Number($("seed").value)),
    cycles: Math.round(Number($("cycles").value)),
    steady_cycles: Math.round(Number($("steady").value)),
    rig: $("rig").value,
  };
}

function status(text, isError) {
  $("status").textContent = text;
  $("status").className = isError ? "error" : "";
}

function run() {
  if (worker === null) {
    worker = new Worker("lab-worker.js");
    worker.onmessage = (m) => onWorker(m.data);
  }
  setup = null;
  trace = [];
  frames = [];
  window.labResult = undefined;
  window.labWallSeconds = undefined;
  stopReplay();
  $("play").disabled = true;
  $("scrub").disabled = true;
  $("method").hidden = true;
  $("results").hidden = true;
  $("run").disabled = true;
  startedAt = performance.now();
  status("loading the lab ...");
  worker.postMessage(request());
}

$("controls").addEventListener("submit", (e) => {
  e.preventDefault();
  run();
});

function onWorker(m) {
  if (m.kind === "event") {
    const e = JSON.parse(m.text);
    if (e.kind === "setup") {
      setup = e;
    } else if (e.kind === "progress") {
      const s = ((performance.now() - startedAt) / 1000).toFixed(1);
      const what = e.phase === "driving" ? `driving, cycle ${e.cycle}` : e.phase;
      status(`${what}: ${(100 * e.fraction).toFixed(0)} %, ${s} s`);
    } else if (e.kind === "frame") {
      trace.push([e.t_s, e.accel_mps2, e.force_n]);
      frames.push(e);
      pendingFrame = e;
      const now = performance.now();
      if (now - lastPaint > 30) {
        lastPaint = now;
        requestAnimationFrame(() => {
          if (pendingFrame) drawBed(pendingFrame);
          drawLiveChannels();
        });
      }
    }
  } else if (m.kind === "result") {
    const result = JSON.parse(m.text);
    showResult(result);
  } else if (m.kind === "error") {
    status(`refused: ${m.text}`, true);
  } else if (m.kind === "done") {
    $("run").disabled = false;
    window.labWallSeconds = m.wall_s;
    if ($("status").className !== "error") {
      status(`done in ${m.wall_s.toFixed(1)} s (pouring, settling, driving and measuring).`);
    }
    if (window.labResult) addSpeed(window.labResult, m.wall_s);
    if (frames.length > 0) {
      $("scrub").max = frames.length - 1;
      $("scrub").value = frames.length - 1;
      $("scrub").disabled = false;
      $("play").disabled = false;
    }
    report();
  }
}

// ---- the replay ------------------------------------------------------

function stopReplay() {
  if (playing !== null) clearInterval(playing);
  playing = null;
  $("play").textContent = "▶ replay";
}

$("scrub").addEventListener("input", () => {
  stopReplay();
  drawBed(frames[Number($("scrub").value)]);
});

$("play").addEventListener("click", () => {
  if (playing !== null) { stopReplay(); return; }
  $("play").textContent = "❚❚ pause";
  playing = setInterval(() => {
    const k = (Number($("scrub").value) + 1) % frames.length;
    $("scrub").value = k;
    drawBed(frames[k]);
  }, 80);
});

// ---- drawing -------------------------------------------------------------

/// Blue (0) through green to red (1 and above).
function colour(x) {
  const t = Math.max(0, Math.min(1, x));
  const r = Math.round(255 * Math.min(1, Math.max(0, 2 * t - 0.3)));
  const g = Math.round(200 * (1 - Math.abs(2 * t - 1)));
  const b = Math.round(255 * Math.min(1, Math.max(0, 1.3 - 2 * t)));
  return `rgb(${r},${g},${b})`;
}

function drawBed(f) {
  const c = $("bed");
  const ctx = c.getContext("2d");
  ctx.clearRect(0, 0, c.width, c.height);
  if (!setup) return;
  const vertical = setup.orientation === "vertical";
  const R = setup.radius_mm, L = setup.length_mm, A = setup.stroke_mm;
  // view: across x up, mm; the enclosure over its whole stroke fits
  const xr = vertical ? [-R * 1.1, R * 1.1] : [-A - 0.05 * L, L + A + 0.05 * L];
  const yr = vertical ? [-A - 0.05 * L, L + A + 0.05 * L] : [-R * 1.1, R * 1.1];
  const scale = Math.min((c.width - 20) / (xr[1] - xr[0]), (c.height - 40) / (yr[1] - yr[0]));
  const px = (x) => 10 + (x - xr[0]) * scale;
  const py = (y) => c.height - 30 - (y - yr[0]) * scale;
  const u = f.enclosure_mm;
  ctx.strokeStyle = "#333";
  ctx.lineWidth = 2;
  if (vertical) ctx.strokeRect(px(-R), py(u + L), 2 * R * scale, L * scale);
  else ctx.strokeRect(px(u), py(R), L * scale, 2 * R * scale);
  const s = f.spheres;
  for (let i = 0; i < s.length; i += 4) {
    ctx.beginPath();
    ctx.arc(px(s[i]), py(s[i + 1]), s[i + 2] * scale, 0, 2 * Math.PI);
    ctx.fillStyle = colour(s[i + 3] / (2 * setup.peak_speed_mps));
    ctx.fill();
    ctx.strokeStyle = "rgba(0,0,0,0.35)";
    ctx.lineWidth = 0.5;
    ctx.stroke();
  }
  ctx.fillStyle = "#222";
  ctx.font = "13px sans-serif";
  ctx.fillText(`t = ${(1000 * f.t_s).toFixed(1)} ms, enclosure at ${u.toFixed(2)} mm`, 10, c.height - 10);
}

/// Plots series [[x...], [y...], colour, label] in a box of the canvas.
function plot(canvas, box, series, xLabel, yLabel) {
  const ctx = canvas.getContext("2d");
  const [x0, y0, w, h] = box;
  let xs = [], ys = [];
  for (const s of series) { xs = xs.concat(s[0]); ys = ys.concat(s[1]); }
  if (xs.length < 2) return;
  let [xmin, xmax] = [Math.min(...xs), Math.max(...xs)];
  let [ymin, ymax] = [Math.min(...ys), Math.max(...ys)];
  if (xmax === xmin) xmax = xmin + 1;
  if (ymax === ymin) { ymax += 1; ymin -= 1; }
  const pad = 0.05 * (ymax - ymin);
  ymin -= pad; ymax += pad;
  const px = (x) => x0 + 50 + (x - xmin) / (xmax - xmin) * (w - 60);
  const py = (y) => y0 + h - 30 - (y - ymin) / (ymax - ymin) * (h - 45);
  ctx.strokeStyle = "#999";
  ctx.lineWidth = 1;
  ctx.strokeRect(px(xmin), py(ymax), w - 60, h - 45);
  if (ymin < 0 && ymax > 0) {
    ctx.beginPath(); ctx.moveTo(px(xmin), py(0)); ctx.lineTo(px(xmax), py(0));
    ctx.strokeStyle = "#ddd"; ctx.stroke();
  }
  ctx.fillStyle = "#333";
  ctx.font = "12px sans-serif";
  ctx.fillText(fmt(ymax), x0 + 2, py(ymax) + 10);
  ctx.fillText(fmt(ymin), x0 + 2, py(ymin));
  ctx.fillText(fmt(xmin), px(xmin), y0 + h - 14);
  const right = fmt(xmax);
  ctx.fillText(right, px(xmax) - ctx.measureText(right).width, y0 + h - 14);
  ctx.fillText(xLabel, x0 + w / 2 - ctx.measureText(xLabel).width / 2, y0 + h - 2);
  ctx.fillText(yLabel, x0 + 52, y0 + 12);
  let ly = y0 + 12;
  for (const [sx, sy, col, label] of series) {
    ctx.strokeStyle = col;
    ctx.lineWidth = 1.4;
    ctx.beginPath();
    for (let i = 0; i < sx.length; i++) {
      if (i === 0) ctx.moveTo(px(sx[i]), py(sy[i])); else ctx.lineTo(px(sx[i]), py(sy[i]));
    }
    ctx.stroke();
    if (label) {
      ctx.fillStyle = col;
      ctx.fillText(label, x0 + w - 12 - ctx.measureText(label).width, ly);
      ly += 14;
    }
  }
}

function fmt(v) {
  const a = Math.abs(v);
  if (a !== 0 && (a < 0.01 || a >= 1e4)) return v.toExponential(2);
  return v.toPrecision(3);
}

function drawLiveChannels() {
  const c = $("channels");
  c.getContext("2d").clearRect(0, 0, c.width, c.height);
  const t = trace.map((p) => 1000 * p[0]);
  plot(c, [0, 0, c.width, c.height / 2], [[t, trace.map((p) => p[1]), "#1f5fbf", "enclosure acceleration"]], "time (ms)", "m/s²");
  plot(c, [0, c.height / 2, c.width, c.height / 2], [[t, trace.map((p) => p[2]), "#c0392b", "particles' force on the enclosure"]], "time (ms)", "N");
}

function drawRecord(rec) {
  const c = $("channels");
  c.getContext("2d").clearRect(0, 0, c.width, c.height);
  const t = rec.accel_mps2.map((_, i) => 1000 * i * rec.dt_s);
  plot(c, [0, 0, c.width, c.height / 2], [[t, rec.accel_mps2, "#1f5fbf", "recorded acceleration"]], "time in the measured window (ms)", "m/s²");
  plot(c, [0, c.height / 2, c.width, c.height / 2], [[t, rec.force_n, "#c0392b", "recorded force (static weight removed)"]], "time in the measured window (ms)", "N");
  $("channels-caption").textContent = "The rig's record of the measured cycles (40 kHz, shown thinned): what Yang's method reads.";
  const l = $("loop");
  l.getContext("2d").clearRect(0, 0, l.width, l.height);
  plot(l, [0, 0, l.width, l.height], [[rec.displacement_mm, rec.force_n, "#6c3483", ""]], "enclosure displacement (mm)", "force (N)");
}

// ---- the result ----------------------------------------------------------

function pm(value, err, digits) {
  const v = value.toFixed(digits);
  return err == null ? `${v} (± not known)` : `${v} ± ${err.toFixed(digits)}`;
}

function showResult(r) {
  window.labResult = r;
  const s = r.summary, y = r.yang, d = s.dem, m = s.measured;
  drawRecord(r.record);
  const w = 2 * Math.PI * y.drive_freq_hz;
  const steps = [
    `The record: ${y.n_samples} samples at ${(y.sample_rate_hz / 1000).toFixed(0)} kHz, ${y.n_periods} whole periods of ${y.drive_freq_hz} Hz (the last ${s.steady_cycles} cycles of ${s.cycles}).`,
    `Discrete Fourier transform of force and acceleration over whole periods; at each harmonic k the velocity is V<sub>k</sub> = A<sub>k</sub> / (j ω<sub>k</sub>), ω<sub>1</sub> = ${w.toFixed(1)} rad/s.`,
    `Complex power P = ½ Σ Re(F<sub>k</sub> V<sub>k</sub>*), each harmonic in the table below${y.force_polarity_reversed ? " (the force read as the gauge's reaction and was negated)" : ""}.`,
    `The rig's phase error, ${(1000 * y.phase_correction_rad).toFixed(2)} mrad at the drive (measured on the empty enclosure), is subtracted from each phase: P = ${y.power_w.toFixed(4)} W.`,
    `Energy per cycle E = P / f = ${y.energy_per_cycle_j.toFixed(5)} J; the scale E<sub>max</sub> = 4 M (Γ g / ω)² = ${y.e_max_j.toFixed(5)} J (thesis eq. 6.10: the particles' mass M meeting the enclosure fully plastically twice a cycle at a relative speed of twice its peak speed; a scale, not a bound), so the efficiency is E / E<sub>max</sub> = ${y.efficiency.toFixed(4)}.`,
    `Check: the force-displacement loop encloses ${y.loop_energy_per_cycle_j.toFixed(5)} J per cycle, the same sum before the phase correction (${m.uncorrected_energy_per_cycle_j.toFixed(5)} J).`,
  ];
  $("steps").innerHTML = steps.map((t) => `<li>${t}</li>`).join("");
  $("harmonics").tBodies[0].innerHTML = y.per_harmonic.map((h) =>
    `<tr><td>${h.harmonic}</td><td>${h.freq_hz.toFixed(0)}</td><td>${h.force_amp_n.toFixed(4)}</td>` +
    `<td>${h.velocity_amp_mps.toExponential(3)}</td><td>${(h.phase_rad * 180 / Math.PI).toFixed(2)}</td><td>${h.power_w.toExponential(3)}</td></tr>`).join("") +
    `<tr><td colspan="5">every other bin up to ${(y.sample_rate_hz / 2000).toFixed(0)} kHz (noise, leakage)</td><td>${y.other_bins_power_w.toExponential(3)}</td></tr>` +
    `<tr><td colspan="5"><b>P, the sum</b> (a negative entry: that harmonic gave energy back over the window)</td><td><b>${y.power_w.toExponential(4)}</b></td></tr>`;
  const rows = [
    ["", "DEM truth", "measured (Yang)"],
    ["energy per cycle (J)", pm(d.energy_per_cycle_j, d.energy_per_cycle_stderr_j, 5), pm(m.energy_per_cycle_j, m.energy_per_cycle_stderr_j, 5)],
    ["efficiency E / E_max", pm(d.efficiency, d.efficiency_stderr, 4), pm(m.efficiency, m.efficiency_stderr, 4)],
    ["measured vs DEM", "", `${(100 * m.error_vs_dem_rel).toFixed(2)} %`],
    ["without the phase correction", "", `${m.uncorrected_energy_per_cycle_j.toFixed(5)} J (${(100 * m.uncorrected_error_vs_dem_rel).toFixed(2)} %)`],
    ["leak the phase error predicts", "", `${(100 * m.predicted_leak_per_cycle_j / d.energy_per_cycle_j).toFixed(2)} % of the DEM's energy`],
    ["spheres, time step, steps", `${s.n_particles}, ${s.dt_s.toExponential(3)} s, ${s.steps}`, ""],
    ["state hash", s.state_hash, "the final DEM state: vlab shake --beds 1 prints the same for this scene and seed"],
  ];
  $("result-table").tBodies[0].innerHTML = rows.map((row, i) =>
    `<tr>${row.map((cell) => i === 0 ? `<th>${cell}</th>` : `<td>${cell}</td>`).join("")}</tr>`).join("");
  $("notes").textContent = "± is one standard error of this bed's window, from the spread of its measured cycles; it leaves out how far another packing of the same damper lies, which vlab shake --beds 6 measures (docs/accuracy.md). Under 16 cycles it is not known. The first cycles are a transient and are not measured.";
  $("method").hidden = false;
  $("results").hidden = false;
  $("result-json").textContent = JSON.stringify({
    freq_hz: s.freq_hz, gamma: s.gamma, orientation: s.orientation, seed: s.seed,
    cycles: s.cycles, steady_cycles: s.steady_cycles, rig: s.rig, n_particles: s.n_particles,
    dt_s: s.dt_s, steps: s.steps, particle_mass_kg: s.particle_mass_kg, e_max_j: d.e_max_j,
    state_hash: s.state_hash,
    dem_efficiency: d.efficiency, dem_energy_per_cycle_j: d.energy_per_cycle_j,
    measured_efficiency: m.efficiency, measured_energy_per_cycle_j: m.energy_per_cycle_j,
    rig_phase_error_rad: m.rig_phase_error_rad, phase_correction_rad: m.phase_correction_rad,
    yang_efficiency: y.efficiency, loop_energy_per_cycle_j: y.loop_energy_per_cycle_j,
    uncorrected_energy_per_cycle_j: m.uncorrected_energy_per_cycle_j,
  });
}

function addSpeed(r, wallS) {
  const s = r.summary;
  const rate = s.n_particles * s.steps / wallS;
  $("notes").textContent += ` This run: ${wallS.toFixed(1)} s in the browser for pouring, settling and ${s.steps} drive steps (${(rate / 1e6).toFixed(1)} M particle-steps/s counting the drive's steps over the whole time).`;
}

function report() {
  if (params.get("report") !== "1") return;
  const body = window.labResult
    ? JSON.stringify({ ok: true, wall_s: window.labWallSeconds, result: JSON.parse($("result-json").textContent) })
    : JSON.stringify({ ok: false, error: $("status").textContent });
  fetch("/result", { method: "POST", body, headers: { "Content-Type": "application/json" } });
}

if (params.get("autorun") === "1") run();
