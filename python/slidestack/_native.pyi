"""Types of the compiled half of slidestack (python/src/lib.rs)."""

import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

class Error(RuntimeError):
    """A stored file that fails its checks, or a run that could not produce its result."""

    kind: str
    file: Optional[str]
    key: Optional[str]
    line: Optional[int]

_Path = Union[str, os.PathLike[str]]
_Floats = Union[Sequence[float], npt.NDArray[np.floating[Any]]]
_Record = Union[_Path, Tuple[_Floats, float]]
_Config = Union[_Path, Mapping[str, Any]]

def simulate(
    record: Optional[_Record] = None,
    period: Optional[float] = None,
    alpha: Optional[_Floats] = None,
    mu: Optional[_Floats] = None,
    mu_static: Optional[_Floats] = None,
    damping: Optional[float] = None,
    damping_basis: Optional[str] = None,
    scale: Optional[float] = None,
    structure: Optional[str] = None,
    yield_strength_ratio: Optional[float] = None,
    post_yield_ratio: Optional[float] = None,
    aspect: Optional[_Floats] = None,
    integrator: Optional[str] = None,
    rk4_substeps: Optional[int] = None,
    building: Optional[Mapping[str, Any]] = None,
    stacks: Optional[Sequence[Mapping[str, Any]]] = None,
    floor_spectra: Optional[Mapping[str, Any]] = None,
    history: bool = False,
    config: Optional[_Path] = None,
) -> Dict[str, Any]:
    """One case under one ground motion: the dict ``slidestack simulate --json`` prints (same
    keys, bit-identical numbers), plus ``history`` (numpy arrays) with ``history=True``.

    Keywords are the case file's keys; None means the default (period 1.0 s, alpha [0.5, 0.5],
    mu [0.2, 0.1], damping 0.05 on the ``rigid`` basis, scale 1, elastic structure, exact
    integrator, the built-in Northridge record). ``record`` is a path or ``(accel_g, dt_s)``;
    ``building``/``stacks`` take the case file's mappings; ``aspect`` (width over height per block,
    bottom first) asks for the rocking check (``rocking_onset``); ``floor_spectra`` (``{"periods": SPEC
    or list, "damping": list}``) asks for each floor's response spectra; ``config`` a case file
    whose keys the keywords override."""

def simulate_many(
    cases: Sequence[Mapping[str, Any]],
    records: Optional[Sequence[_Record]] = None,
    threads: Optional[int] = None,
    config: Optional[_Path] = None,
) -> List[List[Dict[str, Any]]]:
    """Every case under every record: ``simulate``'s dicts, ``[case][record]``
    (slidestack.simulate_many labels them as an xarray Dataset)."""

def read_record(
    path: _Path, units: Optional[str] = None, dt: Optional[float] = None
) -> Tuple[npt.NDArray[np.float64], float]:
    """A record file (PEER .AT2, two- or one-column text) as ``(accel_g, dt_s)``."""

def spectrum(
    accel_g: _Floats,
    dt: float,
    periods: Union[str, _Floats, None] = None,
    damping: Union[float, _Floats, None] = None,
    ductility: Union[float, _Floats, None] = None,
    post_yield_ratio: Optional[float] = None,
) -> Any:
    """Response spectrum of one record (``slidestack spectrum --json``'s object with numpy arrays:
    ``sd_m``, ``psv_mps``, ``psa_g``, ``peak_time_s``); a list of them for several damping
    ratios; constant-ductility spectra with ``ductility``. ``periods`` is a SPEC string
    (default ``0.05:4:0.01``) or numbers; ``damping`` defaults to 0.05."""

def spectra(
    records: Sequence[_Record],
    periods: Union[str, _Floats, None] = None,
    damping: Union[float, _Floats, None] = None,
) -> List[Dict[str, Any]]:
    """Elastic spectra of every record at every damping ratio: ``spectrum``'s dicts,
    record-major (slidestack.spectra labels them as an xarray Dataset)."""

def match(
    record: _Record, target: str, settings: Optional[Mapping[str, Any]] = None
) -> Dict[str, Any]:
    """One record matched to the target SPEC (``is1893:zone=V,soil=I``, ``asce7:…``,
    ``table:FILE``): ``record``, ``accel_g`` (numpy), ``dt_s`` and ``report``."""

def design(
    study: _Path,
    zone: str,
    period: float,
    alpha: _Floats,
    mu: _Floats,
    extrapolate: bool = False,
    storeys: Optional[int] = None,
    floor: Union[int, str, None] = None,
) -> Dict[str, Any]:
    """T_new of one structure from a finished study: the dict ``slidestack design --json``
    prints. In a building study, ``storeys`` and ``floor`` (a number, ``"roof"``, ``"mid"`` or ``"all"``)
    name the building, and ``period`` is its bare first-mode period T_1."""

def export_edp(
    config: _Path, records: Sequence[_Record], out: _Path, attached: bool = False
) -> _Path:
    """A building case's FEMA P-58 demands under ``records`` in pelicun's demand-sample format
    (one row per record: PFA and PFV per floor, the ground as floor 0, PID and RID per storey,
    a ``Units`` row), written to ``out`` (CSV): what ``slidestack export edp`` writes; with
    ``attached``, the stacks rigidly attached. Returns ``out``."""

def export_frame_edp(
    study: _Path,
    zone: str,
    storeys: int,
    stack_floor: Union[int, str],
    period: float,
    alpha: _Floats,
    mu: _Floats,
    out: _Path,
    attached: bool = False,
) -> _Path:
    """One case of a finished building study (its output directory), its FEMA P-58 demands
    under its zone's motions written to ``out`` as pelicun's demand sample: what ``slidestack
    export edp --study`` writes. Returns ``out``."""

def run(
    config: _Config, out: Optional[_Path] = None, force: bool = False, wait: bool = True
) -> Dict[str, Dict[str, Any]]:
    """Every stage in order (``slidestack run``); what each did, by stage name. Ctrl-C stops it
    at the next work unit, leaving the output directory resumable."""

def motions(
    config: _Config, out: Optional[_Path] = None, force: bool = False, wait: bool = True
) -> Dict[str, Any]: ...
def sweep(
    config: _Config,
    out: Optional[_Path] = None,
    force: bool = False,
    wait: bool = True,
    shard: Optional[Tuple[int, int]] = None,
) -> Dict[str, Any]: ...
def tnew(
    config: _Config,
    out: Optional[_Path] = None,
    force: bool = False,
    wait: bool = True,
    shard: Optional[Tuple[int, int]] = None,
) -> Dict[str, Any]: ...
def fit(
    config: _Config, out: Optional[_Path] = None, force: bool = False, wait: bool = True
) -> Dict[str, Any]: ...
def ida(
    config: _Config,
    out: Optional[_Path] = None,
    force: bool = False,
    wait: bool = True,
    shard: Optional[Tuple[int, int]] = None,
) -> Dict[str, Any]: ...
def floors(
    config: _Config, out: Optional[_Path] = None, force: bool = False, wait: bool = True
) -> Dict[str, Any]: ...
def report(
    config: _Config, out: Optional[_Path] = None, force: bool = False, wait: bool = True
) -> Dict[str, Any]: ...
def merge(config: _Config, out: Optional[_Path] = None, wait: bool = True) -> Dict[str, Any]: ...
def status(config: _Config, out: Optional[_Path] = None) -> Dict[str, Any]:
    """What is on disk for every stage (``slidestack status --format env`` as a dict)."""
