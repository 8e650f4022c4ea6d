"""vlab.read_record: a record file's channels as arrays, the file's numbers."""

import os

import numpy as np
import pytest

import vlab

REFERENCE = os.path.join(
    os.path.dirname(__file__), "..", "..", "signals", "reference", "thesis-40Hz-G20"
)


def test_a_csv_record_is_its_numbers_to_the_bit():
    rec = vlab.read_record(os.path.join(REFERENCE, "trace.csv"))
    assert rec.channels == {"acceleration": "m/s^2", "force": "N"}
    assert rec.sample_rate_hz == 40000
    with open(os.path.join(REFERENCE, "trace.csv")) as f:
        rows = [l for l in f if not l.startswith("#")][1:]
    table = np.array([[float(x) for x in r.split(",")] for r in rows])
    assert np.array_equal(rec.channel("acceleration"), table[:, 1])
    assert np.array_equal(rec.channel("force"), table[:, 2])
    assert np.allclose(rec.time_s(), table[:, 0], rtol=0, atol=1e-12)
    meta = rec.metadata
    assert meta["drive_freq_hz"] == 40.0 and meta["gamma"] == 20.0
    with pytest.raises(KeyError, match="acceleration, force"):
        rec.channel("velocity")


def test_every_format_holds_the_same_record():
    csv = vlab.read_record(os.path.join(REFERENCE, "trace.csv"))
    for name in ["trace.wav", "trace.tdms"]:
        other = vlab.read_record(os.path.join(REFERENCE, name))
        assert other.channels == csv.channels, name
        for ch in csv.channels:
            a, b = csv.channel(ch), other.channel(ch)
            # The WAV holds the ADC's 16-bit codes scaled back (the CSV's
            # numbers are those codes too): equal within a part in 1e9.
            assert np.allclose(a, b, rtol=0, atol=1e-9 * np.max(np.abs(a))), (name, ch)


def test_arrays_read_give_the_files_analysis():
    path = os.path.join(REFERENCE, "trace.csv")
    rec = vlab.read_record(path)
    of_file = vlab.analyze(path)
    of_arrays = vlab.analyze(
        acceleration=rec.channel("acceleration"),
        force=rec.channel("force"),
        sample_rate_hz=rec.sample_rate_hz,
        freq_hz=40.0,
    )
    assert of_arrays["power_w"] == of_file["power_w"]
    assert of_file["power_w"] == pytest.approx(2.1597, abs=5e-5)


def test_a_missing_file_is_named():
    with pytest.raises(ValueError, match="no-such.csv"):
        vlab.read_record("no-such.csv")
