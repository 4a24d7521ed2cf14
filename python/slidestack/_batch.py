"""Many runs in one call, answered as labelled xarray Datasets: ``simulate_many`` (cases under
records) and ``spectra`` (records at damping ratios)."""

from __future__ import annotations

import math
import numbers
import os
from typing import TYPE_CHECKING, Any, Dict, List, Optional, Sequence, Tuple

from . import _native

if TYPE_CHECKING:
    import xarray

#: The dimension of each list in ``simulate``'s dict (a tuple for nested lists; nested keys
#: joined by ``_``; a building's ``stacks`` lists under ``stacks_``, with ``stack`` before this
#: one). Every list key is here: tests/test_batch.py checks that none of ``simulate``'s keys is
#: left out.
LIST_DIMS: Dict[str, Any] = {
    # one storey
    "alpha": "block",
    "mu": "interface",
    "mu_static": "interface",
    "peak_abs_accel_g": "body",
    "peak_abs_velocity_mps": "body",
    "peak_slip_m": "interface",
    "residual_slip_m": "interface",
    "slip_time_s": "interface",
    "energy_friction_per_interface": "interface",
    # building
    "building_floor_masses": "floor",
    "building_storey_stiffnesses": "storey",
    "building_yield_strength_ratios": "storey",
    "building_stiffness_n_per_m": "storey",
    "building_yield_drift_m": "storey",
    "building_storey_heights_m": "storey",
    "modes_s": "mode",
    "floor_peak_displacement_m": "floor",
    "floor_peak_abs_accel_g": "floor",
    "floor_peak_abs_velocity_mps": "floor",
    "storey_peak_drift_m": "storey",
    "storey_peak_drift_ratio": "storey",
    "storey_ductility": "storey",
    "storey_residual_drift_m": "storey",
    "stacks_alpha": "block",
    "stacks_mu": "interface",
    "stacks_mu_static": "interface",
    "stacks_peak_slip_m": "interface",
    "stacks_residual_slip_m": "interface",
    "stacks_peak_abs_accel_g": "block",
    "stacks_peak_abs_velocity_mps": "block",
    # the rocking check (aspect given): a ratio per block
    "aspect": "block",
    # floor response spectra (floor_spectra asked for): psa_g[damping][floor][period]; the
    # oscillator's damping ratio is not the structure's (`damping`, a variable)
    "floor_spectra_periods_s": "period",
    "floor_spectra_damping": "oscillator_damping",
    "floor_spectra_psa_g": ("oscillator_damping", "floor", "period"),
}

#: simulate's mappings that may be null (``rocking_onset``: null when the stack never rocks),
#: with their fields: flattened to one variable per field, NaN where null.
NULLABLE: Dict[str, Tuple[str, ...]] = {"rocking_onset": ("block", "time_s")}

#: simulate's lists that label a dimension (the floor spectra's periods and damping ratios)
#: when every run has the same.
LABELLING = (("floor_spectra_periods_s", "period"), ("floor_spectra_damping", "oscillator_damping"))

#: Units by the end of a name (the names carry them: docs/python.md).
_UNIT_SUFFIXES = (
    ("_n_per_m", "N/m"),
    ("_mps2", "m/s^2"),
    ("_ratio", "1"),
    ("_m", "m"),
    ("_g", "g"),
    ("_s", "s"),
)


def _units(name: str) -> Optional[str]:
    if name.startswith("energy_") and "error" not in name:
        return "J/kg"
    for suffix, unit in _UNIT_SUFFIXES:
        if name.endswith(suffix):
            return unit
    return None


def _is_one_record(record: Any) -> bool:
    """A path, or an ``(accel_g, dt_s)`` pair, rather than a list of records."""
    if isinstance(record, (str, os.PathLike)):
        return True
    if isinstance(record, (list, tuple)) and len(record) == 2:
        first, second = record
        return isinstance(second, numbers.Real) and not isinstance(first, (str, os.PathLike))
    return False


def _missing(v: Any) -> bool:
    return v is None or (isinstance(v, float) and math.isnan(v))


def _plain(v: Any) -> Any:
    """A numpy scalar or array as a Python number or list; NaN as not given."""
    if hasattr(v, "tolist"):
        v = v.tolist()
    if isinstance(v, list):
        while v and _missing(v[-1]):
            v.pop()
        return v
    return None if _missing(v) else v


def _case_dicts(cases: Any) -> List[Dict[str, Any]]:
    """The cases as dicts of ``simulate``'s keywords: a list of dicts, a pandas DataFrame (a row
    a case, a column a keyword) or an xarray Dataset (dimension ``case``; a variable without it
    applies to every case). In a DataFrame or Dataset, NaN means "not given" (the default), and
    a list value's trailing NaN are left off (cases with fewer blocks than others)."""
    if hasattr(cases, "columns") and hasattr(cases, "to_dict"):
        rows = cases.to_dict("records")
        plain = [{k: _plain(v) for k, v in row.items()} for row in rows]
        return [{k: v for k, v in row.items() if not _missing(v)} for row in plain]
    if hasattr(cases, "data_vars") and hasattr(cases, "sizes"):
        if "case" not in cases.sizes:
            raise ValueError("a Dataset of cases needs the dimension `case`")
        out = []
        for i in range(cases.sizes["case"]):
            row = {}
            for name, var in cases.data_vars.items():
                v = _plain(var.isel(case=i).values if "case" in var.dims else var.values)
                if not _missing(v):
                    row[str(name)] = v
            out.append(row)
        return out
    if isinstance(cases, dict):
        raise ValueError("`cases` is a list of dicts (one case each), not one dict")
    return list(cases)


def _flatten(d: Dict[str, Any]) -> Dict[str, Any]:
    """``simulate``'s dict with nested mappings joined by ``_``; a building's ``stacks`` as lists
    over the stacks (``stacks_alpha[stack][block]``), and its friction energy per interface
    split by stack."""
    flat: Dict[str, Any] = {}
    for key, value in d.items():
        if key in NULLABLE:
            for f in NULLABLE[key]:
                flat[f"{key}_{f}"] = None if value is None else value[f]
        elif isinstance(value, dict):
            for k, v in _flatten(value).items():
                flat[f"{key}_{k}"] = v
        elif key == "stacks":
            keys = [k for s in value for k in s]
            for k in dict.fromkeys(keys):  # every stack's keys, in order
                if k in NULLABLE:
                    for f in NULLABLE[k]:
                        flat[f"stacks_{k}_{f}"] = [
                            None if s.get(k) is None else s[k][f] for s in value
                        ]
                else:
                    flat[f"stacks_{k}"] = [s.get(k) for s in value]
        else:
            flat[key] = value
    if "stacks_mu" in flat:
        per = flat.pop("energy_friction_per_interface")
        split, start = [], 0
        for mu in flat["stacks_mu"]:
            split.append(per[start : start + len(mu)])
            start += len(mu)
        flat["stacks_energy_friction_per_interface"] = split
    return flat


def _dims_of(key: str, value: Any) -> Tuple[str, ...]:
    if key.startswith("stacks_"):
        inner = LIST_DIMS.get(key) or LIST_DIMS.get(key[len("stacks_") :])
        return ("stack",) if inner is None else ("stack", inner)
    if key in LIST_DIMS:
        dims = LIST_DIMS[key]
        return dims if isinstance(dims, tuple) else (dims,)
    if isinstance(value, list):
        raise RuntimeError(f"internal: simulate's `{key}` is a list with no dimension in LIST_DIMS")
    return ()


def _array(values: List[List[Any]], dims: Tuple[str, ...], sizes: Dict[str, int]) -> Any:
    """``values[case][record]`` (each a scalar or a nested list) as one array, lists padded with
    NaN to ``sizes``; None as NaN (numbers) or "" (strings)."""
    import numpy as np

    shape = (len(values), len(values[0])) + tuple(sizes[d] for d in dims)
    try:
        whole = np.array(values)
    except ValueError:  # ragged: some lists shorter
        whole = None
    if whole is not None and whole.shape == shape and whole.dtype in (np.float64, np.int64):
        return whole
    leaves = []

    def walk(v: Any, depth: int) -> None:
        if depth == len(dims):
            leaves.append(v)
        elif v is not None:
            for x in v:
                walk(x, depth + 1)

    for row in values:
        for v in row:
            walk(v, 0)
    present = [x for x in leaves if x is not None]
    if present and all(isinstance(x, str) for x in present):
        fill: Any = ""
        dtype: Any = object
    elif len(present) == math.prod(shape) and all(isinstance(x, int) for x in present):
        fill, dtype = 0, np.int64
    else:
        fill, dtype = np.nan, np.float64
    out = np.full(shape, fill, dtype=dtype)

    def put(v: Any, index: Tuple[int, ...]) -> None:
        if v is None:
            return
        if len(index) == len(shape):
            out[index] = v
            return
        for k, x in enumerate(v):
            put(x, index + (k,))

    for c, row in enumerate(values):
        for r, v in enumerate(row):
            put(v, (c, r))
    return out


def _labels(names: List[str]) -> List[str]:
    """Record names as coordinate labels: as they are when distinct, else each with ``#index``."""
    return names if len(set(names)) == len(names) else [f"{n}#{j}" for j, n in enumerate(names)]


def _dataset(outcomes: List[List[Dict[str, Any]]], one_record: bool) -> "xarray.Dataset":
    import numpy as np
    import xarray as xr

    flat = [[_flatten(o) for o in row] for row in outcomes]
    labels = _labels([o["record"] for o in flat[0]])
    keys: List[str] = []
    for row in flat:
        for o in row:
            keys.extend(k for k in o if k not in keys and k != "record")
    sizes: Dict[str, int] = {}
    dims_of: Dict[str, Tuple[str, ...]] = {}
    for key in keys:
        values: List[Any] = [o.get(key) for row in flat for o in row]
        dims = _dims_of(key, next((v for v in values if v is not None), None))
        dims_of[key] = dims
        level: List[Any] = values
        for d in dims:  # the longest list at each nesting level
            level = [x for x in level if x is not None]
            sizes[d] = max([sizes.get(d, 0)] + [len(x) for x in level])
            level = [y for x in level for y in x]
    data = {}
    for key in keys:
        dims = dims_of[key]
        grid = [[o.get(key) for o in row] for row in flat]
        var = xr.Variable(("case", "record") + dims, _array(grid, dims, sizes))
        unit = _units(key)
        if unit is not None:
            var.attrs["units"] = unit
        data[key] = var
    coords: Dict[str, Any] = {"case": np.arange(len(flat)), "record": labels}
    for d, n in sizes.items():
        # body 0 is the structure, 1… the blocks; every other dimension counts from 1 (floor 1,
        # interface 1 = structure–block 1, mode 1, …), as simulate's lists do.
        coords[d] = np.arange(n) if d == "body" else np.arange(1, n + 1)
    # LABELLING's lists as coordinates where every run has the same; else they stay variables.
    for key, dim in LABELLING:
        if key in data:
            table = data[key].values.reshape(-1, sizes[dim])
            if (table == table[0]).all():
                coords[dim] = xr.Variable(dim, table[0], attrs=data.pop(key).attrs)
    ds = xr.Dataset(data, coords=coords)
    if one_record:
        ds = ds.isel(record=0)
    return ds


def simulate_many(
    cases: Any,
    record: Any = None,
    *,
    threads: Optional[int] = None,
    config: Optional[Any] = None,
) -> "xarray.Dataset":
    """Every case under every record in one call, on the library's threads with the GIL released,
    as an xarray Dataset with dimensions ``case`` (and ``record`` when ``record`` is a list).

    ``cases``: a list of dicts of ``simulate``'s keywords (``period``, ``alpha``, ``mu``, …,
    ``building``, ``stacks``), a pandas DataFrame (a row a case) or an xarray Dataset (dimension
    ``case``); one-storey cases or building cases, not both in one call. ``record``: a path, an
    ``(accel_g, dt_s)`` pair, or a list of them (None: the built-in record). ``threads``: how many
    threads (None: the library's default, ``RAYON_NUM_THREADS`` or every core). ``config``: a case
    file whose keys every case's keywords override.

    Each variable is a key of ``simulate``'s dict (nested keys joined by ``_``: ``energy_input``,
    ``building_storeys``; a building's stacks as ``stacks_*`` over ``stack``), its numbers those
    of one ``simulate`` call per case and record, bit for bit, whatever ``threads``. Lists are
    labelled by ``interface``, ``block``, ``body`` (0 the structure), ``floor``, ``storey``,
    ``mode`` and ``stack`` (each counted from 1 but ``body``), padded with NaN where a case has
    fewer. A bad case raises ``ValueError`` naming its index and key before any run; Ctrl-C
    raises ``KeyboardInterrupt`` within one run of each thread."""
    rows = _case_dicts(cases)
    one = record is None or _is_one_record(record)
    records = None if record is None else ([record] if one else list(record))
    outcomes = _native.simulate_many(rows, records, threads, config)
    return _dataset(outcomes, one)


#: The lists of ``spectrum``'s answer that are spectra (over ``period``).
_SPECTRA = ("sd_m", "psv_mps", "psa_g", "peak_time_s")


def spectra(
    records: Sequence[Any],
    periods: Any = None,
    damping: Any = None,
) -> "xarray.Dataset":
    """Elastic response spectra of many records at one or more damping ratios in one call (the
    command line's ``spectrum`` batch underneath, on the library's threads with the GIL
    released), as an xarray Dataset with dimensions ``record``, ``damping`` and ``period``:
    ``sd_m``, ``psv_mps``, ``psa_g`` and ``peak_time_s``, the numbers of ``spectrum`` of each
    record, bit for bit.

    ``records``: a list of paths or ``(accel_g, dt_s)`` pairs. ``periods``: a SPEC string as
    ``slidestack spectrum --periods`` reads it or a list (default ``0.05:4:0.01``). ``damping``:
    a ratio or a list (default 0.05)."""
    import numpy as np
    import xarray as xr

    if _is_one_record(records):
        raise ValueError("`records` is a list of records (paths or (accel_g, dt_s) pairs)")
    records = list(records)
    if not records:
        raise ValueError("`records` is empty: give at least one record")
    found = _native.spectra(records, periods, damping)
    n_damping = len(found) // len(records)
    first = found[0]
    data = {}
    for key in _SPECTRA:
        values = np.array([s[key] for s in found]).reshape(len(records), n_damping, -1)
        data[key] = xr.Variable(("record", "damping", "period"), values,
                                attrs={"units": _units(key)})
    coords = {
        "record": _labels([found[k * n_damping]["record"] for k in range(len(records))]),
        "damping": [s["damping"] for s in found[:n_damping]],
        "period": xr.Variable("period", np.array(first["periods_s"]), attrs={"units": "s"}),
    }
    return xr.Dataset(data, coords=coords)
