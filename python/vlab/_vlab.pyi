"""Type stubs of the compiled half of vlab (python/src/)."""

from os import PathLike
from typing import Any, Callable, Optional, Union

import numpy as np
import numpy.typing as npt

DEFAULT_BEDS: int

Figure = tuple[float, Optional[float]]

class Shake:
    @property
    def summary_json(self) -> str: ...
    @property
    def efficiency(self) -> Figure: ...
    @property
    def measured_efficiency(self) -> Figure: ...
    @property
    def energy_per_cycle_j(self) -> Figure: ...
    @property
    def measured_energy_per_cycle_j(self) -> Figure: ...
    @property
    def longer_drive_rel(self) -> Optional[float]: ...
    @property
    def warnings(self) -> list[str]: ...
    @property
    def sample_rate_hz(self) -> float: ...
    @property
    def channels(self) -> list[tuple[str, str]]: ...
    def channel(self, name: str) -> npt.NDArray[np.float64]: ...
    def time_s(self) -> npt.NDArray[np.float64]: ...
    def dissipated_per_cycle_j(self) -> npt.NDArray[np.float64]: ...
    def write(self, out: Union[str, PathLike[str]]) -> None: ...

def shake(
    freq_hz: float = 40.0,
    gamma: float = 20.0,
    *,
    beds: int = ...,
    seed: Optional[int] = None,
    scene: Union[str, PathLike[str], None] = None,
    orientation: Optional[str] = None,
    cycles: Optional[int] = None,
    steady_cycles: Optional[int] = None,
    rig: str = "thesis-shaker",
    noise_seed: Optional[int] = None,
    calibration: Union[str, PathLike[str], None] = None,
    threads: Optional[int] = None,
    cache: bool = True,
    progress: Optional[Callable[[str, float, int], object]] = None,
) -> Shake: ...

class Record:
    @property
    def sample_rate_hz(self) -> float: ...
    @property
    def channels(self) -> list[tuple[str, str]]: ...
    def channel(self, name: str) -> npt.NDArray[np.float64]: ...
    def time_s(self) -> npt.NDArray[np.float64]: ...
    @property
    def metadata_json(self) -> str: ...

def read_record(path: Union[str, PathLike[str]]) -> Record: ...

def analyze(
    record: Union[str, PathLike[str], None] = None,
    *,
    acceleration: Optional[npt.NDArray[np.float64]] = None,
    force: Optional[npt.NDArray[np.float64]] = None,
    sample_rate_hz: Optional[float] = None,
    freq_hz: Optional[float] = None,
    gamma: Optional[float] = None,
    particle_mass_kg: Optional[float] = None,
    calibration: Union[str, PathLike[str], None] = None,
    force_freq: bool = False,
    force_calibration: bool = False,
    as_recorded: bool = False,
    force_channel: str = "force",
    accel_channel: str = "acceleration",
) -> str: ...

def cor(
    record: Union[str, PathLike[str], None] = None,
    *,
    force: Optional[npt.NDArray[np.float64]] = None,
    sample_rate_hz: Optional[float] = None,
    channel: Optional[str] = None,
    g_mps2: float = 9.81,
    threshold_n: Optional[float] = None,
    holdoff_s: Optional[float] = None,
) -> str: ...

class Drop:
    @property
    def summary_json(self) -> str: ...
    @property
    def heights_m(self) -> list[float]: ...
    @property
    def sample_rate_hz(self) -> float: ...
    def force(self, height_m: float) -> npt.NDArray[np.float64]: ...
    def write(self, out: Union[str, PathLike[str]]) -> None: ...

def drop_test(
    heights_m: list[float] = ...,
    *,
    particle: str = "acrylic-smooth",
    cor: Optional[float] = None,
    diameter_m: float = 0.005,
    sample_rate_hz: Optional[float] = None,
    rig: Union[str, PathLike[str], None] = None,
    threshold_n: Optional[float] = None,
    holdoff_s: Optional[float] = None,
    seed: int = 1,
) -> Drop: ...

class HostPredict:
    @property
    def summary_json(self) -> str: ...
    @property
    def columns(self) -> dict[str, npt.NDArray[Any]]: ...
    @property
    def warnings(self) -> list[str]: ...
    def write(self, out: Union[str, PathLike[str]]) -> None: ...

def host_predict(
    map: Union[str, PathLike[str], list[Union[str, PathLike[str]]]],
    freqs_hz: list[float],
    force_n: float,
    *,
    host: str = "plate-40hz",
    orientation: Optional[str] = None,
    yang: bool = False,
) -> HostPredict: ...

def scene_json(scene: Union[str, PathLike[str], None] = None) -> str: ...

class Calibration:
    @property
    def rows_json(self) -> str: ...
    @property
    def table_json(self) -> str: ...
    def write(self, path: Union[str, PathLike[str]]) -> None: ...

def calibrate(
    freqs_hz: list[float],
    *,
    gammas: list[float] = ...,
    rig: str = "thesis-shaker",
    shaker: Optional[str] = None,
    cycles: int = 8,
    record_cycles: int = 5,
    dt_s: float = 1e-6,
) -> Calibration: ...

class Sweep:
    @property
    def report_json(self) -> str: ...
    @property
    def columns(self) -> dict[str, Union[npt.NDArray[np.float64], npt.NDArray[np.int64], list[str]]]: ...
    @property
    def header(self) -> dict[str, Union[str, int]]: ...
    @property
    def down(self) -> Optional[Sweep]: ...
    @property
    def up_down_csv(self) -> Optional[str]: ...
    def write(self, out: Union[str, PathLike[str]]) -> list[str]: ...
    def __len__(self) -> int: ...

def sweep(
    freqs_hz: list[float],
    gammas: list[float],
    *,
    seeds: list[int] = ...,
    fill_ratios: list[float] = ...,
    orientations: list[str] = ...,
    scene: Union[str, PathLike[str], None] = None,
    cycles: Optional[int] = None,
    steady_cycles: Optional[int] = None,
    dt_s: Optional[float] = None,
    rig: str = "thesis-shaker",
    shaker: Optional[str] = None,
    beds: int = 1,
    out: Union[str, PathLike[str], None] = None,
    resume: bool = False,
    up_down: bool = False,
    cache: bool = True,
    threads: Optional[int] = None,
    progress: Optional[Callable[[str, int, int], object]] = None,
) -> Sweep: ...

def read_sweep(path: Union[str, PathLike[str]]) -> Sweep: ...

class HostRun:
    @property
    def sample_rate_hz(self) -> float: ...
    @property
    def channels(self) -> list[tuple[str, str]]: ...
    def channel(self, name: str) -> npt.NDArray[np.float64]: ...
    @property
    def truth(self) -> dict[str, npt.NDArray[np.float64]]: ...
    @property
    def energy_json(self) -> str: ...
    @property
    def steps(self) -> tuple[int, float, float]: ...
    @property
    def warnings(self) -> list[str]: ...
    def write(self, out: Union[str, PathLike[str]]) -> None: ...

def host_run(
    excitation: str,
    *,
    duration_s: float = 1.0,
    host: str = "plate-40hz",
    damper: str = "particles",
    scene: Union[str, PathLike[str], None] = None,
    seed: Optional[int] = None,
    orientation: Optional[str] = None,
    rig: str = "thesis-shaker",
    noise_seed: Optional[int] = None,
    cache: bool = True,
    threads: Optional[int] = None,
    progress: Optional[Callable[[str, float, int], object]] = None,
) -> HostRun: ...

class HostDecay:
    @property
    def summary_json(self) -> str: ...
    @property
    def csv(self) -> str: ...
    @property
    def beds_csv(self) -> Optional[str]: ...
    @property
    def run(self) -> HostRun: ...
    def write(self, out: Union[str, PathLike[str]]) -> None: ...

def host_decay(
    *,
    x0_m: float = 0.003,
    hammer_n_s: Optional[float] = None,
    duration_s: float = 1.0,
    beds: int = 1,
    map: Union[str, PathLike[str], list[Union[str, PathLike[str]]], None] = None,
    host: str = "plate-40hz",
    damper: str = "particles",
    scene: Union[str, PathLike[str], None] = None,
    seed: Optional[int] = None,
    orientation: Optional[str] = None,
    rig: str = "thesis-shaker",
    noise_seed: Optional[int] = None,
    cache: bool = True,
    threads: Optional[int] = None,
    progress: Optional[Callable[[str, float, int], object]] = None,
) -> HostDecay: ...

class HostFrf:
    @property
    def kind(self) -> str: ...
    @property
    def csv(self) -> str: ...
    @property
    def summary_json(self) -> Optional[str]: ...
    @property
    def warnings(self) -> list[str]: ...
    def write(self, out: Union[str, PathLike[str]]) -> None: ...

def host_frf(
    freqs_hz: Optional[list[float]] = None,
    *,
    force_n: float = 5.0,
    settle_cycles: int = 30,
    record_cycles: int = 20,
    beds: int = 1,
    up_down: bool = False,
    swept: Optional[str] = None,
    random: Optional[str] = None,
    noise: Optional[str] = None,
    block_s: float = 2.0,
    burst: Optional[str] = None,
    duration_s: float = 8.0,
    map: Union[str, PathLike[str], list[Union[str, PathLike[str]]], None] = None,
    host: str = "plate-40hz",
    damper: str = "particles",
    scene: Union[str, PathLike[str], None] = None,
    seed: Optional[int] = None,
    orientation: Optional[str] = None,
    rig: str = "thesis-shaker",
    noise_seed: Optional[int] = None,
    cache: bool = True,
    threads: Optional[int] = None,
    progress: Optional[Callable[..., object]] = None,
) -> HostFrf: ...

class HostBase:
    @property
    def csv(self) -> str: ...
    def write(self, out: Union[str, PathLike[str]]) -> None: ...

def host_base(
    freqs_hz: list[float],
    *,
    accel_mps2: float = 10.0,
    settle_cycles: int = 30,
    record_cycles: int = 20,
    down: bool = False,
    host: str = "plate-40hz",
    damper: str = "particles",
    scene: Union[str, PathLike[str], None] = None,
    seed: Optional[int] = None,
    orientation: Optional[str] = None,
    rig: str = "thesis-shaker",
    noise_seed: Optional[int] = None,
    cache: bool = True,
    threads: Optional[int] = None,
    progress: Optional[Callable[[str, float, int], object]] = None,
) -> HostBase: ...
