"""vlab.host_run and vlab.host_decay against `vlab host run` / `decay` and
the single-degree-of-freedom answer."""

import json
import math
import os
import subprocess

import numpy as np
import pytest

import vlab

# The built-in plate (one mode at 40 Hz, 0.5 kg, 0.3 % damping) with a
# linear dashpot of 15 N s/m in the enclosure, released from 3 mm: no DEM,
# so a run takes a fraction of a second.
DASHPOT = dict(damper="dashpot:15", duration_s=0.3, rig="ideal", cache=False)


@pytest.fixture(scope="module")
def released():
    return vlab.host_run("release:0.003", **DASHPOT)


@pytest.fixture(scope="module")
def decay():
    return vlab.host_decay(x0_m=0.003, **DASHPOT)


def test_the_run_writes_the_commands_files(released, cli, tmp_path):
    released.write(tmp_path / "py")
    subprocess.run([cli, "--quiet", "host", "run", "--excitation", "release:0.003",
                    "--damper", "dashpot:15", "--duration-s", "0.3", "--rig", "ideal",
                    "--no-cache", "--out", str(tmp_path / "cli")],
                   check=True, capture_output=True)
    for name in ["trace.csv", "record.csv", "trace.wav", "record.svg"]:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name


def test_the_release_rings_down_as_one_damped_mode(released):
    truth = released.truth
    t, x = truth["time_s"], truth["damper_displacement_m"]
    # One mode, 0.5 kg at 40 Hz; its own 0.3 % plus the dashpot's c / (2 m wn).
    m, wn = 0.5, 2 * math.pi * 40.0
    zeta = 0.003 + 15.0 / (2 * m * wn)
    wd = wn * math.sqrt(1 - zeta**2)
    expect = 0.003 * np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * t))
    # The host's linear step is exact for a mode and a dashpot: to a part
    # in a million of the release.
    assert np.max(np.abs(x - expect)) < 1e-6 * 0.003, np.max(np.abs(x - expect))


def test_the_energy_books_close(released):
    e = released.energy["host"]
    energy0 = 0.5 * 0.5 * (2 * math.pi * 40.0) ** 2 * 0.003**2
    # Each term integrated on its own: what the host held at the start went
    # into its damping and the dashpot, or is still there.
    spent = e["host_dissipated_j"] + e["dashpot_dissipated_j"] + released.truth["host_energy_j"][-1]
    assert spent == pytest.approx(energy0 + e["excitation_work_j"], rel=1e-3)
    assert released.truth["dashpot_dissipated_j"][-1] > 0.9 * energy0 * (1 - math.exp(-2))


def test_the_decay_is_the_commands(decay, cli, tmp_path):
    decay.write(tmp_path / "py")
    said = subprocess.run([cli, "--quiet", "host", "decay", "--x0-m", "0.003",
                           "--damper", "dashpot:15", "--duration-s", "0.3", "--rig", "ideal",
                           "--no-cache", "--out", str(tmp_path / "cli")],
                          check=True, capture_output=True, text=True)
    assert said.returncode == 0
    for name in ["decay.csv", "trace.csv", "record.csv", "loss-factor.svg"]:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    ours = json.loads((tmp_path / "py" / "decay.json").read_text())
    theirs = json.loads((tmp_path / "cli" / "decay.json").read_text())
    for d in (ours, theirs):
        d.pop("wall_time_s")
    assert ours == theirs


def test_the_log_decrement_reads_the_modes_damping(decay):
    c = decay.columns
    log = [i for i, m in enumerate(c["method"]) if m == "log-decrement"]
    assert len(log) >= 5
    # Loss factor 2 zeta of the mode with its dashpot, to 1 %.
    m, wn = 0.5, 2 * math.pi * 40.0
    eta = 2 * (0.003 + 15.0 / (2 * m * wn))
    assert np.allclose(c["loss_factor"][log], eta, rtol=1e-2), c["loss_factor"][log]
    assert decay.beds_columns is None


@pytest.mark.parametrize(
    "call, said",
    [
        (lambda: vlab.host_run("banana:3", **DASHPOT), ["excitation", "banana"]),
        (lambda: vlab.host_run("release:0.003", **dict(DASHPOT, damper="foam")), ["damper", "foam"]),
        (lambda: vlab.host_run("release:0.003", **dict(DASHPOT, host="no-such-host")), ["host", "no-such-host"]),
        (lambda: vlab.host_run("release:0.003", **dict(DASHPOT, rig="no-such-rig")), ["rig", "no-such-rig"]),
        (lambda: vlab.host_decay(x0_m=float("nan"), **DASHPOT), ["x0_m"]),
        (lambda: vlab.host_decay(hammer_n_s=-1, **DASHPOT), ["hammer_n_s"]),
        (lambda: vlab.host_decay(beds=0, **DASHPOT), ["beds", "1 to 64"]),
        (lambda: vlab.host_decay(map="no-such.csv", **DASHPOT), ["map", "no-such.csv"]),
    ],
)
def test_a_bad_value_is_refused_with_its_keyword(call, said):
    with pytest.raises(ValueError) as refused:
        call()
    for part in said:
        assert part in str(refused.value), str(refused.value)


# A stepped sine of the dashpot host: three frequencies around the plate's
# 40 Hz, 10 cycles to settle and 8 recorded at each.
STEPPED = dict(damper="dashpot:15", rig="ideal", cache=False, settle_cycles=10, record_cycles=8)


@pytest.fixture(scope="module")
def stepped():
    told = []
    frf = vlab.host_frf([38, 40, 42], force_n=2.0, progress=lambda *p: told.append(p), **STEPPED)
    return frf, told


def test_the_stepped_sine_is_the_commands(stepped, cli, tmp_path):
    frf, told = stepped
    assert frf.kind == "stepped sine"
    assert told == [("frequency", 1, 3), ("frequency", 2, 3), ("frequency", 3, 3)]
    frf.write(tmp_path / "py")
    subprocess.run([cli, "--quiet", "host", "frf", "--freq", "38,40,42", "--force-n", "2",
                    "--damper", "dashpot:15", "--rig", "ideal", "--settle-cycles", "10",
                    "--record-cycles", "8", "--no-cache", "--out", str(tmp_path / "cli")],
                   check=True, capture_output=True)
    names = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert sorted(p.name for p in (tmp_path / "py").iterdir()) == names
    for name in names:
        if name.endswith(".json"):
            continue
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name


def test_the_stepped_sine_reads_the_modes_receptance(stepped):
    frf, _ = stepped
    c = frf.columns
    # One mode with its dashpot: |X/F| = 1 / |k - m w^2 + j c w|, to 1 %
    # (10 settling cycles leave the transient at e^(-2 pi zeta 10) ~ 2e-2
    # of the start, which starts steady).
    m, wn = 0.5, 2 * math.pi * 40.0
    c_total = 2 * 0.003 * m * wn + 15.0
    w = 2 * math.pi * c["freq_hz"]
    exact = 1 / np.abs(m * wn**2 - m * w**2 + 1j * c_total * w)
    measured = np.hypot(c["receptance_re_m_per_n"], c["receptance_im_m_per_n"])
    assert np.allclose(measured, exact, rtol=1e-2), (measured, exact)


def test_a_periodic_random_force_gives_h1_and_h2():
    frf = vlab.host_frf(random="30:50:2:0.5:1", duration_s=1.5, damper="dashpot:15", rig="ideal",
                        cache=False)
    assert frf.kind == "periodic random" and frf.summary is None
    c = frf.columns
    assert np.all(c["coherence"] > 0.99)
    h1 = np.hypot(c["h1_re_m_per_n"], c["h1_im_m_per_n"])
    m, wn = 0.5, 2 * math.pi * 40.0
    w = 2 * math.pi * c["freq_hz"]
    exact = 1 / np.abs(m * wn**2 - m * w**2 + 1j * (2 * 0.003 * m * wn + 15.0) * w)
    assert np.allclose(h1, exact, rtol=1e-2)


def test_up_and_down_is_the_commands_and_one_answer_on_a_linear_host(cli, tmp_path):
    frf = vlab.host_frf([39, 40, 41], force_n=2.0, up_down=True, **STEPPED)
    assert frf.kind == "stepped sine up and down"
    c = frf.columns
    assert c["branch"] == ["up", "up", "up", "down", "down"]
    assert list(c["freq_hz"]) == [39.0, 40.0, 41.0, 40.0, 39.0]
    # A linear host has one answer: the branches agree to 1 % (10 settling
    # cycles at zeta 0.063 leave e^-4 of the step's transient: 0.22 %).
    assert abs(c["amplitude_m"][0] / c["amplitude_m"][4] - 1) < 1e-2
    assert all(not p["apart"] for p in frf.summary["pairs"])
    frf.write(tmp_path / "py")
    subprocess.run([cli, "--quiet", "host", "frf", "--freq", "39,40,41", "--force-n", "2",
                    "--up-down", "--damper", "dashpot:15", "--rig", "ideal", "--settle-cycles",
                    "10", "--record-cycles", "8", "--no-cache", "--out", str(tmp_path / "cli")],
                   check=True, capture_output=True)
    for name in ["updown.csv", "updown.svg"]:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name


def test_a_swept_sine_and_the_random_forces_read_the_modes_receptance():
    m, wn = 0.5, 2 * math.pi * 40.0
    common = dict(damper="dashpot:15", rig="ideal", cache=False)

    def exact(f):
        w = 2 * math.pi * f
        return 1 / np.abs(m * wn**2 - m * w**2 + 1j * (2 * 0.003 * m * wn + 15.0) * w)

    swept = vlab.host_frf(swept="30:50:2", force_n=2.0, duration_s=3.0, **common)
    assert swept.kind == "swept sine" and swept.summary["tail_fraction"] < 0.01
    c = swept.columns
    band = (c["freq_hz"] >= 32) & (c["freq_hz"] <= 48)
    assert np.allclose(c["magnitude_m_per_n"][band], exact(c["freq_hz"][band]), rtol=3e-3)
    burst = vlab.host_frf(burst="20:60:1:2:0.5:4", duration_s=10.0, **common)
    assert burst.kind == "burst random" and burst.warnings == []
    noise = vlab.host_frf(noise="20:60:1:4", block_s=4.0, duration_s=24.0, **common)
    assert noise.kind.startswith("true random")
    for frf, rtol in [(burst, 0.015), (noise, 0.05)]:
        c = frf.columns
        band = (c["freq_hz"] >= 30) & (c["freq_hz"] <= 50)
        h1 = np.hypot(c["h1_re_m_per_n"], c["h1_im_m_per_n"])[band]
        assert np.allclose(h1, exact(c["freq_hz"][band]), rtol=rtol), frf.kind


def test_a_burst_and_a_sweep_that_outlast_their_block_say_so():
    # 2 N s/m leaves the plate a damping ratio of 0.011: over a burst's
    # second off its ringing falls by e^-2.8 only, and 0.1 s after a sweep
    # it is still ringing; both blocks cut a response that had not died.
    common = dict(damper="dashpot:2", cache=False)
    burst = vlab.host_frf(burst="20:60:1:2:0.5:4", duration_s=10.0, **common)
    swept = vlab.host_frf(swept="30:50:2", force_n=2.0, duration_s=2.1, **common)
    for frf in (burst, swept):
        said = [w for w in frf.warnings if "had not died out" in w]
        assert len(said) == 1, (frf.kind, frf.warnings)
    assert "--burst" in [w for w in burst.warnings if "died" in w][0]


@pytest.mark.parametrize(
    "args, said",
    [
        (dict(freqs_hz=[40], swept="30:50:2"), ["freqs_hz and swept", "give one"]),
        (dict(noise="20:60:1:4", block_s=0.1), ["block_s = 0.1 s", "4 cycles"]),
        (dict(burst="20:60:1:2:1.5:4"), ["burst on_fraction"]),
        (dict(swept="30:50:2", duration_s=2.0), ["duration_s", "longer than the sweep"]),
        (dict(freqs_hz=[39, 40], up_down=True, beds=2), ["beds = 2", "one bed"]),
        (dict(freqs_hz=[40, 39]), ["freqs_hz", "ascending"]),
        (dict(freqs_hz=None), ["freqs_hz", "random"]),
        (dict(freqs_hz=[40], force_n=-1), ["force_n"]),
        (dict(freqs_hz=[40], record_cycles=1), ["record_cycles"]),
        (dict(random="30:50:2"), ["random"]),
        (dict(random="30:50:2:0.5:1", duration_s=1.0), ["duration_s", "three periods"]),
        (dict(freqs_hz=[40], duration_s=-1), ["duration_s"]),
    ],
)
def test_a_bad_frf_value_is_refused_with_its_keyword(args, said):
    call = dict(damper="dashpot:15", rig="ideal", cache=False)
    call.update(args)
    with pytest.raises(ValueError) as refused:
        vlab.host_frf(**call)
    for part in said:
        assert part in str(refused.value), str(refused.value)


def test_the_host_on_the_table_is_the_commands_and_its_exact_transmissibility(cli, tmp_path):
    freqs = [36, 40, 44]
    base = vlab.host_base(freqs, accel_mps2=10.0, damper="dashpot:20", settle_cycles=20,
                          record_cycles=10, down=True, cache=False)
    c = base.columns
    assert c["branch"] == ["up", "up", "up", "down", "down"]
    # The mass on its spring and dashpot to the table, computed here.
    m, k = 0.5, 0.5 * (2 * math.pi * 40.0) ** 2
    ct = 2 * 0.003 * math.sqrt(k * m) + 20.0
    w = 2 * math.pi * c["freq_hz"]
    exact = np.abs((k + 1j * w * ct) / (k - w**2 * m + 1j * w * ct))
    assert np.max(np.abs(c["magnitude"] / exact - 1)) < 5e-4
    assert np.max(np.abs(c["power_in_w"] / c["true_dissipated_w"] - 1)) < 5e-3
    base.write(tmp_path / "py")
    subprocess.run([cli, "--quiet", "host", "base", "--freq", "36,40,44", "--accel-mps2", "10",
                    "--damper", "dashpot:20", "--settle-cycles", "20", "--record-cycles", "10",
                    "--down", "--no-cache", "--out", str(tmp_path / "cli")],
                   check=True, capture_output=True)
    for name in ["transmissibility.csv", "transmissibility.svg"]:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name


@pytest.mark.parametrize(
    "args, said",
    [
        (dict(host="beam-2mode"), ["participation factors"]),
        (dict(accel_mps2=0.0), ["accel_mps2", "m/s^2"]),
        (dict(record_cycles=1), ["record_cycles"]),
    ],
)
def test_a_bad_table_value_is_refused_with_its_keyword(args, said):
    call = dict(damper="dashpot:20", cache=False)
    call.update(args)
    with pytest.raises(ValueError) as refused:
        vlab.host_base([40], **call)
    for part in said:
        assert part in str(refused.value), str(refused.value)
