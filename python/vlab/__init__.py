"""vlab in Python: the virtual granular-damper laboratory's shake as a function.

    >>> import vlab
    >>> r = vlab.shake(freq_hz=40, gamma=20)          # about 63 s on an idle 2-core machine
    >>> r.efficiency                                  # (value, one-sigma error)
    >>> acc = r.channel("acceleration")               # numpy array, m/s^2
    >>> r.summary["ensemble"]["beds"]

`shake` plans and runs what `vlab shake` runs (the same checks, the same
numbers for the same scene and seed; the thesis damper of Terzioglu's PhD
thesis, University of Sheffield, 2023, driven through the thesis rig and
measured by Yang's method). Its keyword arguments are the command's flags:
`beds`, `seed`, `scene` (a scene file), `orientation`, `cycles`,
`steady_cycles`, `rig`, `noise_seed`, `calibration` (a table from
`vlab calibrate`), and `threads`, `cache` (the command line's bed cache) and
`progress`. Bad values raise `ValueError` naming the value, its unit and its
range, before any work is done.

The other experiments and studies are functions alike: `sweep` (and
`read_sweep`), `analyze`, `cor`, `drop`, `calibrate`, `host_predict`,
`scene`.

Long runs (`shake`, `sweep`) release the GIL and report progress: to
`progress=` when it is a callable, on tqdm bars when it is left out and tqdm
is installed, nowhere with `progress=False`.
"""

import json

import numpy as np

from . import _vlab

__all__ = [
    "shake",
    "sweep",
    "read_sweep",
    "Sweep",
    "read_record",
    "Record",
    "analyze",
    "cor",
    "drop",
    "host_predict",
    "host_run",
    "host_decay",
    "host_frf",
    "host_base",
    "HostRun",
    "HostDecay",
    "HostFrf",
    "HostBase",
    "calibrate",
    "Calibration",
    "scene",
    "Shake",
    "Drop",
    "HostPrediction",
    "DEFAULT_BEDS",
]

DEFAULT_BEDS = _vlab.DEFAULT_BEDS


class _Bars:
    """tqdm bars for a run's progress, one per stage, closed when the run
    ends. A drive run until steady has no known end, so its bar counts
    cycles; every other stage shows how much of it is done."""

    def __init__(self, tqdm):
        self._tqdm = tqdm
        self._stage = None
        self._bar = None

    def _open(self, stage, total, unit):
        if stage != self._stage:
            self.close()
            self._stage = stage
            self._bar = self._tqdm(total=total, desc=stage, unit=unit, leave=False)

    def shake(self, phase, fraction, cycle):
        """A shake's call: its phase, the fraction of it done, the cycle."""
        if phase == "driving":
            self._open(phase, None, "cycle")
            self._bar.update(cycle - self._bar.n)
        else:
            self._open(phase, 100, "%")
            self._bar.update(round(100 * fraction) - self._bar.n)

    def sweep(self, what, done, total):
        """A count's call (a sweep's, a stepped sine's): "bed", "condition"
        or "frequency", how many are done of how many."""
        names = {"bed": "settling beds", "condition": "conditions", "frequency": "frequencies"}
        self._open(names.get(what, what), total, what)
        self._bar.update(done - self._bar.n)

    def close(self):
        if self._bar is not None:
            self._bar.close()
        self._bar = None
        self._stage = None


def _run_with_progress(run, options, kind):
    """Runs `run(**options)` with its `progress` option resolved: a callable
    is called, `False` is nothing, and none given is tqdm bars when tqdm is
    installed."""
    progress = options.pop("progress", None)
    if progress is False:
        return run(**options)
    if progress is not None:
        return run(progress=progress, **options)
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return run(**options)
    bars = _Bars(tqdm)
    try:
        return run(progress=getattr(bars, kind), **options)
    finally:
        bars.close()


class _Channels:
    """A record's channels on one clock, for the classes that hold one."""

    sample_rate_hz = property(lambda self: self._inner.sample_rate_hz)

    @property
    def channels(self):
        """The record's channels, `{name: unit}`."""
        return dict(self._inner.channels)

    def channel(self, name):
        """The samples of channel `name` in its unit (numpy array)."""
        return self._inner.channel(name)


class Shake(_Channels):
    """A finished shake: its figures, the rig's record and the DEM's truth.

    `efficiency`, `measured_efficiency`, `energy_per_cycle_j` and
    `measured_energy_per_cycle_j` are `(value, one-sigma error)` pairs, the
    error `None` where it is not known: the ensemble's for several beds, the
    bed's own window's for one (which says nothing of another packing).
    """

    def __init__(self, inner):
        self._inner = inner

    @property
    def summary(self):
        """What summary.json holds, as a dict (read anew: `write` adds the
        files it wrote)."""
        return json.loads(self._inner.summary_json)

    efficiency = property(lambda self: self._inner.efficiency)
    measured_efficiency = property(lambda self: self._inner.measured_efficiency)
    energy_per_cycle_j = property(lambda self: self._inner.energy_per_cycle_j)
    measured_energy_per_cycle_j = property(
        lambda self: self._inner.measured_energy_per_cycle_j
    )
    longer_drive_rel = property(
        lambda self: self._inner.longer_drive_rel,
        doc="""One sigma more, relative, for where the same beds driven hundreds
        more cycles would read (0.21 over the root of the window's cycles);
        not in the errors above. `None` for one bed.""",
    )
    warnings = property(lambda self: self._inner.warnings)

    def time_s(self):
        """Each sample's time from the drive's start, s (numpy array): the
        record starts summary["steady_start_s"] after the drive does."""
        return self._inner.time_s()

    def dissipated_per_cycle_j(self):
        """The first bed's dissipation in each drive cycle, J (numpy array)."""
        return self._inner.dissipated_per_cycle_j()

    def write(self, out):
        """Writes what `vlab shake` writes into folder `out`."""
        self._inner.write(out)

    def __repr__(self):
        return repr(self._inner)


def shake(freq_hz=40.0, gamma=20.0, **options):
    """Drives the damper at `freq_hz` (Hz) and `gamma` (peak acceleration / g)
    and measures it, as `vlab shake --freq F --gamma G` does; returns a Shake.

    `progress`: a callable given `(phase, fraction, cycle)` as the run goes
    (`fraction` of the phase; of the 400-cycle cap while driving until
    steady), `False` for none; left out, tqdm bars when tqdm is installed.
    """
    run = lambda **o: _vlab.shake(freq_hz, gamma, **o)
    return Shake(_run_with_progress(run, options, "shake"))


class Record(_Channels):
    """A record read from its file: its channels as numpy arrays on one
    clock, its metadata as a dict."""

    def __init__(self, inner):
        self._inner = inner


    def time_s(self):
        """Each sample's time on the record's clock, s (numpy array)."""
        return self._inner.time_s()

    @property
    def metadata(self):
        """Who made the record, the rig, the drive (drive_freq_hz, gamma),
        the transducers' sensitivities and the rest ("extra"), as a dict."""
        return json.loads(self._inner.metadata_json)

    def __repr__(self):
        names = ", ".join(f"{n} [{u}]" for n, u in self._inner.channels)
        return f"<vlab.Record of {names} at {self.sample_rate_hz:g} Hz>"


def read_record(path):
    """Reads a record file as `vlab analyze` reads it (CSV, WAV with its
    .json sidecar, TDMS); returns a Record."""
    return Record(_vlab.read_record(str(path)))


def analyze(record=None, **options):
    """Yang's method on a record, as `vlab analyze --json` does it; returns
    the analysis as a dict (power_w, energy_per_cycle_j, efficiency, each with
    its one-sigma error or None, the phase correction, the per-harmonic
    powers, the warnings).

    `record` is a file (CSV, WAV with its .json sidecar, TDMS); or pass
    `acceleration` (m/s^2), `force` (N) and `sample_rate_hz` (Hz) as arrays,
    with `freq_hz` (Hz). `calibration` is a phase-error table (a file from
    `vlab calibrate` or a run's calibration.json); `gamma` and
    `particle_mass_kg` give the efficiency where the record's metadata does
    not. `force_freq`, `force_calibration`, `as_recorded`, `force_channel`
    and `accel_channel` are the command's flags of the same names.
    """
    for key in ("acceleration", "force"):
        if options.get(key) is not None:
            options[key] = np.ascontiguousarray(options[key], dtype=np.float64)
    return json.loads(_vlab.analyze(record, **options))


def cor(record=None, **options):
    """The drop-test restitution estimator (thesis eq. 7.3-7.5) on a force
    record, as `vlab cor --json` does it; returns the report as a dict (the
    impacts' onsets and peaks, the gaps, the speeds, the restitution of each
    triple, their mean and spread, the warnings).

    `record` is a file (CSV with the time first, WAV with its .json sidecar,
    TDMS); or pass `force` (N) as an array with `sample_rate_hz` (Hz).
    `channel`, `g_mps2`, `threshold_n` and `holdoff_s` are the command's
    flags of the same names.
    """
    if options.get("force") is not None:
        options["force"] = np.ascontiguousarray(options["force"], dtype=np.float64)
    return json.loads(_vlab.cor(record, **options))


class Sweep:
    """A sweep's rows, run by `sweep` or read back by `read_sweep`: what
    sweep.csv holds, as columns and as the report `vlab sweep --json` prints.
    """

    def __init__(self, inner):
        self._inner = inner

    @property
    def report(self):
        """What `vlab sweep --json` prints, as a dict: "rows" (every row),
        "by_condition" (each condition's efficiency over its seeds with its
        +- and where that comes from), "peaks" (where each series' DEM
        efficiency peaks against Gamma), "sweep_id", "shard"."""
        return json.loads(self._inner.report_json)

    @property
    def columns(self):
        """sweep.csv's columns by name, cell for cell as the file holds
        them: float64 arrays (units in the names, NaN where a row has none),
        int64 arrays for seed, beds, cycles, steady_cycles and steps, lists
        of str for orientation, status, se_from, steady, phase and note.
        `pandas.DataFrame(s.columns, copy=False)` takes the arrays as they
        are, without copying."""
        return self._inner.columns

    @property
    def header(self):
        """The scene, rig, shaker, drive and identity the file's header
        names, as a dict."""
        return self._inner.header

    @property
    def down(self):
        """The down branch (a Sweep) of a sweep run with `up_down=True`,
        whose own rows are the up branch; None for any other sweep."""
        down = self._inner.down
        return None if down is None else Sweep(down)

    @property
    def branches(self):
        """updown.csv of a sweep run with `up_down=True` as columns: each
        condition both branches ran (fill_ratio, orientation, freq_hz,
        gamma, seed), each branch's efficiency, error and phase
        (`efficiency_up`, `efficiency_up_se`, `phase_up`, the same `_down`),
        `difference` (down less up), `z` (over their errors in quadrature)
        and `apart` ("true" beyond 3 sigma); None for any other sweep."""
        text = self._inner.up_down_csv
        return None if text is None else _csv_columns(text)

    def write(self, out):
        """Writes sweep.csv and the sweep's plots (efficiency and map, PNG
        and SVG) into folder `out`; returns the paths written."""
        return [str(p) for p in self._inner.write(str(out))]

    def __len__(self):
        return len(self._inner)

    def __repr__(self):
        return repr(self._inner)


def sweep(freqs_hz, gammas, **options):
    """A sweep as `vlab sweep` runs it: every condition (each of `freqs_hz`
    (Hz) x `gammas` (peak acceleration / g) x `seeds` x `fill_ratios` x
    `orientations`) of the damper driven through the rig and measured;
    returns a Sweep.

    Keyword arguments are the command's flags: `seeds` (default [1]),
    `fill_ratios` and `orientations` (default: the scene's), `scene`,
    `cycles`, `steady_cycles` (default: each condition until steady),
    `dt_s`, `rig`, `shaker`, `beds` (an ensemble per condition), `out` (the
    folder sweep.csv and the plots go to, kept up to date as conditions
    finish; none: a temporary folder, removed), `resume` (go on with the
    sweep in `out`), `up_down` (each chain of Gamma run up and back down
    with the bed carried from each condition to the next, as `vlab sweep
    --up-down`: the Sweep returned is the up branch, its `down` the down
    branch and its `branches` the two side by side; one bed a condition,
    not resumable), `cache`, `threads`, and `progress`: a callable given
    `("bed", settled, beds)` and `("condition", done, conditions)`, `False`
    for none; left out, tqdm bars when tqdm is installed. Bad values raise
    `ValueError` naming the keyword, its unit and its range, before any work.
    """
    listed = lambda v: [v] if isinstance(v, (int, float)) else list(v)
    for key in ("seeds", "fill_ratios", "orientations"):
        if key in options:
            options[key] = listed(options[key])
    for key in ("scene", "out"):
        if options.get(key) is not None:
            options[key] = str(options[key])
    freqs = [float(f) for f in listed(freqs_hz)]
    amplitudes = [float(g) for g in listed(gammas)]
    run = lambda **o: _vlab.sweep(freqs, amplitudes, **o)
    return Sweep(_run_with_progress(run, options, "sweep"))


def read_sweep(path):
    """A sweep.csv read back (the file, or the folder holding it); returns a
    Sweep."""
    return Sweep(_vlab.read_sweep(str(path)))


class Drop:
    """A finished drop test: its summary (what drop.json holds) and each
    height's force record."""

    def __init__(self, inner):
        self._inner = inner

    @property
    def summary(self):
        """What drop.json holds, as a dict: each height's impacts, the
        restitution of each triple with the model's realised one, their mean
        and spread, the warnings."""
        return json.loads(self._inner.summary_json)

    heights_m = property(lambda self: list(self._inner.heights_m))
    sample_rate_hz = property(lambda self: self._inner.sample_rate_hz)

    @property
    def cor(self):
        """The restitution over every triple: (mean, standard deviation)."""
        s = self.summary
        return (s["cor_mean"], s["cor_std"])

    def force(self, height_m):
        """The force record of the drop from `height_m` (N, numpy array)."""
        return self._inner.force(height_m)

    def write(self, out):
        """Writes what `vlab drop` writes into folder `out`."""
        self._inner.write(out)

    def __repr__(self):
        return repr(self._inner)


def drop(heights_m=(0.05,), **options):
    """The drop test of `vlab drop` (thesis Section 7.3): a preset sphere
    dropped on the drop rig's plate from each height (m), its force recorded
    and the lab's estimator (eq. 7.3-7.5) turning the gaps between impacts
    into restitution, beside what the DEM contact realised; returns a Drop.

    Keyword arguments are the command's flags: `particle`
    ("acrylic-smooth", "acrylic-printed" or "steel"), `cor` (instead of the
    preset's restitution), `diameter_m`, `sample_rate_hz`, `rig` (a drop rig
    file), `threshold_n`, `holdoff_s`, `seed`. Bad values raise `ValueError`
    naming the keyword, its unit and its range, before any drop.
    """
    if isinstance(heights_m, (int, float)):
        heights_m = [heights_m]
    return Drop(_vlab.drop_test([float(h) for h in heights_m], **options))


class HostPrediction:
    """A host's predicted response to a stepped sine: what predict.json and
    predict.csv hold."""

    def __init__(self, inner):
        self._inner = inner

    @property
    def summary(self):
        """What predict.json holds, as a dict: the host, the map, the force,
        the time taken, the warnings and every response."""
        return json.loads(self._inner.summary_json)

    @property
    def columns(self):
        """What predict.csv holds, as a dict of numpy arrays (units in the
        names; `extrapolated` bool, `roots` int): `pandas.DataFrame(p.columns)`
        takes it as it is."""
        return self._inner.columns

    warnings = property(lambda self: list(self._inner.warnings))

    def write(self, out):
        """Writes predict.csv and predict.json into folder `out`."""
        self._inner.write(out)

    def __repr__(self):
        return repr(self._inner)


def _map_files(map):
    """A `map` keyword as the library takes it: a path, or a list of paths
    (the first refined by the later ones)."""
    if isinstance(map, (list, tuple)):
        return [str(m) for m in map]
    return str(map)


def host_predict(map, freqs_hz, force_n, **options):
    """The host's steady response to a stepped sine of `force_n` (N) at each
    of `freqs_hz` (Hz, ascending), predicted in milliseconds from the
    dissipation map of the sweep `map` (its sweep.csv) by describing function
    and harmonic balance, as `vlab host predict` does; returns a
    HostPrediction. `map` may be a list of sweep files: the first refined by
    the later ones (each replaces the conditions it holds, as `--map` given
    again), e.g. the map with sweeps of a finer Γ grid at the onset.

    Keyword arguments are the command's flags: `host` (a built-in name,
    plate-40hz or beam-2mode, or a host file), `orientation` (the sweep's,
    when it has both), `yang` (model the damper on Yang's measured
    efficiency instead of the DEM's). Bad values raise `ValueError` naming
    the keyword, before any work.
    """
    if isinstance(freqs_hz, (int, float)):
        freqs_hz = [freqs_hz]
    return HostPrediction(
        _vlab.host_predict(_map_files(map), [float(f) for f in freqs_hz], float(force_n), **options)
    )


class HostRun(_Channels):
    """A finished test of the damper on a host: the lab's record (the
    acceleration at the damper, the force at the drive point), what the
    simulator knows at each sample, and where the energy went."""

    def __init__(self, inner):
        self._inner = inner

    warnings = property(lambda self: list(self._inner.warnings))

    @property
    def truth(self):
        """What record.csv holds, as numpy arrays named with their units:
        time_s, damper_displacement_m, damper_velocity_mps,
        damper_acceleration_mps2, drive_force_n, drive_velocity_mps,
        damper_force_n, host_energy_j and the running energies
        damper_dissipated_j, damper_work_in_j, host_dissipated_j,
        dashpot_dissipated_j, excitation_work_j."""
        return self._inner.truth

    @property
    def energy(self):
        """Where the host's energy went over the test (J): "host" (the
        excitation's work, the host's own damping, a dashpot's, the work on
        the damper, the host's energy at the end), "damper_dissipated_j"
        and, with particles, the bed's ledger ("bed")."""
        return json.loads(self._inner.energy_json)

    @property
    def steps(self):
        """(steps, step length s, wall time s) of the run."""
        return self._inner.steps

    def write(self, out):
        """Writes trace.csv, trace.wav, record.csv and record.svg into
        folder `out`, as `vlab host run --out` does."""
        self._inner.write(str(out))


def host_run(excitation, **options):
    """Drives the host with `excitation` and records it, as `vlab host run
    --excitation KEY` does; returns a HostRun. `excitation` is the command's
    key: "sine:F_HZ:FORCE_N", "sweep:F0_HZ:F1_HZ:DURATION_S:FORCE_N",
    "multisine:F1_HZ:N1,F2_HZ:N2,...", "random:LOW_HZ:HIGH_HZ:RMS_N:PERIOD_S:SEED",
    "hammer:IMPULSE_N_S" or "release:X0_M".

    Keyword arguments are the command's flags: `duration_s`, `host` (a
    built-in name, plate-40hz or beam-2mode, or a host file), `damper`
    ("particles", "empty", "solid" or "dashpot:N_S_PER_M"), `scene`,
    `seed`, `orientation`, `rig`, `noise_seed`, `cache`, `threads` and
    `progress` (as `shake`'s). Bad values raise `ValueError` naming the
    keyword, before any work.
    """
    for key in ("scene",):
        if options.get(key) is not None:
            options[key] = str(options[key])
    run = lambda **o: _vlab.host_run(excitation, **o)
    return HostRun(_run_with_progress(run, options, "shake"))


class HostDecay:
    """A finished free decay: the loss factor against amplitude by the
    logarithmic decrement and by the Hilbert envelope, each beside the
    DEM's own energies (what decay.csv and decay.json hold)."""

    def __init__(self, inner):
        self._inner = inner

    @property
    def summary(self):
        """What decay.json holds, as a dict."""
        return json.loads(self._inner.summary_json)

    @property
    def columns(self):
        """What decay.csv holds: "method" a list of str, every other column
        a float64 numpy array named with its unit."""
        return _csv_columns(self._inner.csv)

    @property
    def beds_columns(self):
        """What decay-beds.csv holds with several beds (as `columns`), else None."""
        text = self._inner.beds_csv
        return None if text is None else _csv_columns(text)

    @property
    def run(self):
        """The first bed's run (a HostRun)."""
        return HostRun(self._inner.run)

    def write(self, out):
        """Writes what `vlab host decay --out` writes into folder `out`."""
        self._inner.write(str(out))


def _csv_columns(text):
    """A CSV text's columns: numbers as float64 arrays, words as lists."""
    lines = text.splitlines()
    names = lines[0].split(",")
    cells = [line.split(",") for line in lines[1:]]
    columns = {}
    for k, name in enumerate(names):
        values = [row[k] for row in cells]
        try:
            columns[name] = np.array([float(v) for v in values])
        except ValueError:
            columns[name] = values
    return columns


def host_decay(**options):
    """The host released (`x0_m`, m at the damper, default 0.003) or struck
    by a hammer (`hammer_n_s`, N s) and left to ring down for `duration_s`,
    measured as `vlab host decay` measures it: the loss factor against
    amplitude by the logarithmic decrement and by the Hilbert envelope, each
    against the DEM's energies; returns a HostDecay. `map` (a sweep.csv)
    adds Yang's structure-independent energy at each point; `beds` > 1
    decays several beds and gives their mean with the error of their
    spread. The other keywords are `host_run`'s.
    """
    if options.get("scene") is not None:
        options["scene"] = str(options["scene"])
    if options.get("map") is not None:
        options["map"] = _map_files(options["map"])
    return HostDecay(_run_with_progress(_vlab.host_decay, options, "shake"))


class HostFrf:
    """A finished frequency response of the host with the damper: a stepped
    sine's (the receptance at each frequency beside the host without
    particles, with their mass as a solid and, with a map, the model's), a
    stepped sine's up and back down in one run (each step's receptance and
    branch), a swept sine's (the receptance over its band) or a random
    force's, periodic, true or burst (H1, H2, coherence)."""

    def __init__(self, inner):
        self._inner = inner

    kind = property(lambda self: self._inner.kind,
                    doc='"stepped sine", "stepped sine up and down", "swept sine", "periodic random", '
                        '"true random (Hann, 50 % overlap)" or "burst random".')
    warnings = property(lambda self: list(self._inner.warnings),
                        doc="What the test warns of, as `vlab host frf` prints it: a channel clipped "
                            "or too faint, a map outside its range, lines too coarse for the "
                            "resonance, a swept or burst response that had not died out.")

    @property
    def columns(self):
        """What frf.csv holds: float64 numpy arrays named with their units."""
        return _csv_columns(self._inner.csv)

    @property
    def summary(self):
        """What frf.json (updown.json) holds, as a dict; None for a random
        force, which writes none."""
        text = self._inner.summary_json
        return None if text is None else json.loads(text)

    def write(self, out):
        """Writes what `vlab host frf --out` writes into folder `out`."""
        self._inner.write(str(out))


def host_frf(freqs_hz=None, **options):
    """The host's frequency response with the damper, as `vlab host frf`
    measures it: a stepped sine at each of `freqs_hz` (Hz, ascending) of
    `force_n` (N, default 5), `settle_cycles` (30) and `record_cycles` (20)
    at each, `beds` at each; `map` (a sweep.csv) adds the map-based model's
    prediction; `up_down=True` runs the frequencies in one run, up and back
    down, the state carried from step to step. Or a swept sine (`swept`,
    "START_HZ:END_HZ:SWEEP_S" at `force_n`, then silence until
    `duration_s`), or a random force over `duration_s` (default 8): `random`
    ("LOW_HZ:HIGH_HZ:RMS_N:PERIOD_S:SEED", periodic), `noise`
    ("LOW_HZ:HIGH_HZ:RMS_N:SEED", true random in Hann blocks of `block_s`)
    or `burst` ("LOW_HZ:HIGH_HZ:RMS_N:PERIOD_S:ON_FRACTION:SEED"): H1, H2,
    coherence. Returns a HostFrf. The other keywords are `host_run`'s; `progress` is
    called with ("frequency", done, frequencies) for a stepped sine.
    """
    if isinstance(freqs_hz, (int, float)):
        freqs_hz = [freqs_hz]
    if freqs_hz is not None:
        freqs_hz = [float(f) for f in freqs_hz]
    if options.get("scene") is not None:
        options["scene"] = str(options["scene"])
    if options.get("map") is not None:
        options["map"] = _map_files(options["map"])
    runs_once = any(options.get(k) for k in ("random", "noise", "burst", "swept", "up_down"))
    kind = "shake" if runs_once else "sweep"
    run = lambda **o: _vlab.host_frf(freqs_hz, **o)
    return HostFrf(_run_with_progress(run, options, kind))


class HostBase:
    """A finished test of the host on the shaker's table: each step's
    transmissibility (the damper's acceleration over the table's), the
    exact one for a linear payload, the power the table put in against what
    was dissipated, and whether the step was steady."""

    def __init__(self, inner):
        self._inner = inner

    @property
    def columns(self):
        """What transmissibility.csv holds: numpy arrays named with their
        units (the branch and the flags as lists)."""
        return _csv_columns(self._inner.csv)

    def write(self, out):
        """Writes what `vlab host base --out` writes into folder `out`."""
        self._inner.write(str(out))


def host_base(freqs_hz, **options):
    """The host on the rig's shaker table, as `vlab host base` measures it:
    a stepped sine of the table's acceleration `accel_mps2` (m/s^2, default
    10) at each of `freqs_hz` (Hz, ascending), `settle_cycles` (30) and
    `record_cycles` (20) at each, in one run; `down=True` comes back down.
    The host must have one mode (a mass on its spring and dashpot to the
    table). Returns a HostBase. The other keywords are `host_run`'s.
    """
    if isinstance(freqs_hz, (int, float)):
        freqs_hz = [freqs_hz]
    freqs_hz = [float(f) for f in freqs_hz]
    if options.get("scene") is not None:
        options["scene"] = str(options["scene"])
    run = lambda **o: _vlab.host_base(freqs_hz, **o)
    return HostBase(_run_with_progress(run, options, "shake"))


def scene(path=None):
    """A scene as `vlab scene` reads it: the file at `path` merged over the
    built-in thesis damper, or the damper itself. Returns a dict: "toml",
    the resolved scene as TOML (what `vlab scene --print` writes of a file),
    and "figures", what `vlab scene --json` prints (the particles' count,
    shape, mass and, for a body, its sub-spheres, volume, inertia, sphericity
    and the multi-sphere errors; the fill ratio; the time steps). A bad file
    raises `ValueError` naming its key.
    """
    return json.loads(_vlab.scene_json(None if path is None else str(path)))


class Calibration:
    """A rig's phase error measured on the empty enclosure: each frequency's
    row and the table that `shake(calibration=...)` and
    `analyze(calibration=...)` read once written."""

    def __init__(self, inner):
        self._inner = inner

    @property
    def rows(self):
        """Each frequency's phase error (rad), its spread over the amplitudes
        (rad), the amplitudes averaged and the rig model's own phase error
        (rad), as `vlab calibrate --json` prints them: a list of dicts."""
        return json.loads(self._inner.rows_json)

    @property
    def columns(self):
        """The rows as numpy arrays, one per field, units in the names."""
        rows = self.rows
        return {k: np.array([r[k] for r in rows]) for k in (rows[0] if rows else {})}

    @property
    def table(self):
        """The table as a dict (what the written file holds)."""
        return json.loads(self._inner.table_json)

    def write(self, path):
        """Writes the table to the file `path`, as `vlab calibrate --out`."""
        self._inner.write(str(path))

    def __repr__(self):
        return "<vlab.Calibration at {} Hz>".format(
            ", ".join(f"{r['freq_hz']:g}" for r in self.rows)
        )


def calibrate(freqs_hz, **options):
    """The rig's phase error measured on the empty enclosure (thesis Section
    7.4.2, Fig. 7.9) at each of `freqs_hz` (Hz), as `vlab calibrate` does;
    returns a Calibration. Keyword arguments are the command's flags:
    `gammas` (amplitudes averaged, default 2, 5, 10), `rig`, `shaker`
    ("prescribed" or "electrodynamic"), `cycles`, `record_cycles`, `dt_s`.
    Bad values raise `ValueError` naming the keyword, before any work.
    """
    if isinstance(freqs_hz, (int, float)):
        freqs_hz = [freqs_hz]
    if "gammas" in options:
        options["gammas"] = [float(g) for g in options["gammas"]]
    return Calibration(_vlab.calibrate([float(f) for f in freqs_hz], **options))
