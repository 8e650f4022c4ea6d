"""vlab.sweep and vlab.read_sweep against `vlab sweep` and its files."""

import csv
import json
import os
import subprocess

import numpy as np
import pandas as pd
import pytest

import vlab

# Two conditions of the thesis damper on one bed: 40 Hz at Gamma 10 and 20,
# 4 cycles of which the last 2 are kept, through the ideal rig, not cached.
GRID = dict(freqs_hz=[40], gammas=[10, 20])
SHORT = dict(cycles=4, steady_cycles=2, rig="ideal", cache=False)
FLAGS = ["--freq", "40", "--gamma", "10,20", "--cycles", "4", "--steady-cycles", "2",
         "--rig", "ideal", "--no-cache"]
REFERENCE = os.path.join(
    os.path.dirname(__file__), "..", "..", "signals", "reference", "sweep-steady", "sweep.csv"
)


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    """The short sweep run into a folder, and what `progress` was told."""
    out = tmp_path_factory.mktemp("sweep") / "py"
    told = []
    s = vlab.sweep(**GRID, **SHORT, out=out, progress=lambda *p: told.append(p))
    return s, out, told


def rows_without_wall_times(path):
    """sweep.csv's header lines and rows, the wall-time cells blanked (they
    are the one column two runs of the same sweep differ in)."""
    with open(path) as f:
        lines = f.read().splitlines()
    head = [l for l in lines if l.startswith("#")]
    body = list(csv.reader(l for l in lines if not l.startswith("#")))
    wall = body[0].index("wall_time_s")
    for row in body[1:]:
        row[wall] = ""
    return head, body


def test_the_sweep_is_the_commands_row_for_row(small, cli, tmp_path):
    s, out, _ = small
    made = tmp_path / "cli"
    said = subprocess.run([cli, "--quiet", "sweep", *FLAGS, "--out", str(made), "--json"],
                          capture_output=True, text=True, check=True)
    assert rows_without_wall_times(out / "sweep.csv") == rows_without_wall_times(made / "sweep.csv")
    report = json.loads(said.stdout)
    ours = s.report
    for r in report["rows"] + ours["rows"]:
        r.pop("wall_time_s")
    assert ours == report
    # The plots are drawn from the rows alone: the same bytes.
    for name in ["efficiency.svg", "map.svg"]:
        assert (out / name).read_bytes() == (made / name).read_bytes(), name


def test_the_columns_are_the_files_cells_as_numpy_arrays(small):
    s, out, _ = small
    columns = s.columns
    assert len(s) == 2
    with open(out / "sweep.csv") as f:
        rows = list(csv.DictReader(l for l in f if not l.startswith("#")))
    assert list(columns) == list(rows[0])
    for name, values in columns.items():
        cells = [r[name] for r in rows]
        if isinstance(values, list):
            assert values == cells, name
        elif values.dtype == np.int64:
            assert values.tolist() == [int(c) for c in cells], name
        else:
            assert values.dtype == np.float64, name
            # Every number reads back to the very bits the file holds.
            expect = np.array([float(c) for c in cells])
            assert np.array_equal(values, expect, equal_nan=True), name
    assert columns["gamma"].tolist() == [10.0, 20.0]
    assert columns["status"] == ["ok", "ok"]
    assert 0 < columns["efficiency"][1] < 1.5


def test_a_dataframe_takes_the_columns_without_copying(small):
    s, _, _ = small
    columns = s.columns
    frame = pd.DataFrame(columns, copy=False)
    assert frame.shape == (2, len(columns))
    for name in ["efficiency", "energy_per_cycle_j", "steps"]:
        assert np.shares_memory(frame[name].to_numpy(), columns[name]), name


def test_progress_counts_the_beds_then_the_conditions(small):
    _, _, told = small
    assert told[0] == ("bed", 1, 1)
    conditions = [t for t in told if t[0] == "condition"]
    assert [t[1] for t in conditions] == [1, 2] and all(t[2] == 2 for t in conditions)


def test_tqdm_shows_the_progress_when_none_is_given(capfd):
    pytest.importorskip("tqdm", reason="tqdm is in python/requirements-test.txt")
    vlab.sweep(freqs_hz=40, gammas=20, **SHORT)
    said = capfd.readouterr().err
    assert "settling beds" in said and "conditions" in said, said
    vlab.sweep(freqs_hz=40, gammas=20, progress=False, **SHORT)
    assert capfd.readouterr().err == ""


def test_a_sweep_read_back_is_the_file(small):
    s, out, _ = small
    back = vlab.read_sweep(out)
    assert back.report == s.report
    reference = vlab.read_sweep(REFERENCE)
    assert len(reference) == len(reference.columns["gamma"]) > 20
    assert reference.header["rig"] == "thesis-shaker"


def test_write_draws_the_plots_the_command_draws(small, tmp_path):
    s, out, _ = small
    written = s.write(tmp_path / "again")
    names = sorted(os.path.basename(p) for p in written)
    assert names == ["efficiency.png", "efficiency.svg", "map.png", "map.svg", "sweep.csv"]
    for name in names:
        assert (tmp_path / "again" / name).read_bytes() == (out / name).read_bytes(), name


@pytest.mark.parametrize(
    "args, said",
    [
        (dict(gammas=[-1]), ["gammas", "-1", "positive"]),
        (dict(freqs_hz=[]), ["freqs_hz", "at least one"]),
        (dict(beds=0), ["beds", "1 to 64"]),
        (dict(orientations=["sideways"]), ["sideways", "vertical"]),
        (dict(fill_ratios=[0.9]), ["fill_ratios", "0.9"]),
        (dict(shaker="hydraulic"), ["shaker", "hydraulic"]),
        (dict(rig="no-such-rig"), ["rig", "no-such-rig"]),
        (dict(cycles=3, steady_cycles=5), ["steady_cycles"]),
    ],
)
def test_a_bad_value_is_refused_with_its_keyword_before_any_work(args, said):
    call = dict(GRID, **SHORT)
    call.update(args)
    with pytest.raises(ValueError) as refused:
        vlab.sweep(**call)
    for part in said:
        assert part in str(refused.value), str(refused.value)


def test_a_folder_with_a_sweep_is_not_overwritten(small):
    _, out, _ = small
    before = (out / "sweep.csv").read_bytes()
    with pytest.raises(ValueError, match="resume=True"):
        vlab.sweep(**GRID, **SHORT, out=out)
    assert (out / "sweep.csv").read_bytes() == before


def test_a_sweep_up_and_down_is_the_commands_and_carries_the_bed(small, cli, tmp_path):
    s, _, _ = small
    assert s.down is None and s.branches is None
    out = tmp_path / "py"
    up = vlab.sweep(**GRID, **SHORT, up_down=True, out=out, progress=False)
    made = tmp_path / "cli"
    subprocess.run([cli, "--quiet", "sweep", *FLAGS, "--up-down", "--out", str(made)],
                   capture_output=True, text=True, check=True)
    for branch in ["up", "down"]:
        assert (rows_without_wall_times(out / branch / "sweep.csv")
                == rows_without_wall_times(made / branch / "sweep.csv")), branch
    assert (out / "updown.csv").read_text() == (made / "updown.csv").read_text()
    down = up.down
    # The first condition up starts from the settled bed, as the plain
    # sweep's does; the top is one run on both branches; coming down, Gamma
    # 10 starts from where Gamma 20 left the bed.
    assert up.columns["efficiency"][0] == s.columns["efficiency"][0]
    assert up.columns["efficiency"][1] == down.columns["efficiency"][0]
    assert down.columns["gamma"].tolist() == [20.0, 10.0]
    assert down.columns["efficiency"][1] != up.columns["efficiency"][0]
    side = up.branches
    assert side["gamma"].tolist() == [10.0, 20.0]
    assert side["difference"][1] == 0.0
    with pytest.raises(ValueError, match="beds"):
        vlab.sweep(**GRID, **SHORT, up_down=True, beds=2)
    with pytest.raises(ValueError, match="resume"):
        vlab.sweep(**GRID, **SHORT, up_down=True, resume=True, out=tmp_path / "again")
    assert not (tmp_path / "again").exists()
