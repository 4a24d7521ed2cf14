"""A finished (or partial) study's files as xarray Datasets."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Dict, Union

if TYPE_CHECKING:
    import xarray

#: The stage files open_study reads, in the order the stages write them.
STAGE_FILES = ("motions", "sweep", "tnew", "fit", "ida", "floors")


def _decode_flags(ds: "xarray.Dataset") -> "xarray.Dataset":
    """Adds ``NAME_meaning`` (strings) beside each CF flag variable (``flag_values`` and
    ``flag_meanings`` attributes), keeping the integer codes."""
    import numpy as np

    for name in list(ds.data_vars):
        var = ds[name]
        values = var.attrs.get("flag_values")
        meanings = var.attrs.get("flag_meanings")
        if values is None or meanings is None:
            continue
        if isinstance(meanings, bytes):
            meanings = meanings.decode()
        words = str(meanings).split()
        codes = np.atleast_1d(np.asarray(values))
        if len(words) != len(codes):
            continue
        lookup = dict(zip(codes.tolist(), words))
        flat = [lookup.get(c, "") for c in np.asarray(var.values).ravel().tolist()]
        decoded = np.array(flat, dtype=object).reshape(var.shape)
        ds[f"{name}_meaning"] = (var.dims, decoded)
    return ds


def open_study(out: Union[str, "os.PathLike[str]"]) -> Dict[str, Dict[str, "xarray.Dataset"]]:
    """The study in output directory ``out`` as ``{file: {zone: Dataset}}``.

    ``file`` is the stage (``motions``, ``sweep``, ``tnew``, ``fit``, ``ida``, ``floors``; those
    present),
    ``zone`` the zone's name (group ``zone_NAME``; ``""`` for a file's root variables). The
    Datasets have the files' labelled dimensions and units, with CF conventions decoded and each
    CF flag variable ``X`` given a ``X_meaning`` of strings. Needs xarray, h5netcdf and h5py
    (``pip install slidestack[study]``; h5netcdf >= 1.8 no longer installs h5py, its backend);
    imported here, so the rest of the module needs only numpy.
    Raises FileNotFoundError when ``out`` holds none of the files.
    """
    try:
        import h5netcdf  # type: ignore[import-untyped]
        import h5py  # type: ignore[import-untyped]  # noqa: F401 (h5netcdf's backend)
        import xarray as xr
    except ImportError as e:
        raise ImportError(
            f"open_study needs xarray, h5netcdf and h5py ({e}): pip install xarray h5netcdf h5py"
        ) from e

    out = os.fspath(out)
    study: Dict[str, Dict[str, xr.Dataset]] = {}
    for stage in STAGE_FILES:
        path = os.path.join(out, f"{stage}.h5")
        if not os.path.exists(path):
            continue
        with h5netcdf.File(path, "r") as f:
            groups = list(f.groups)
            root_vars = len(f.variables) > 0
        zones: Dict[str, xr.Dataset] = {}
        if root_vars:
            zones[""] = _decode_flags(xr.load_dataset(path, engine="h5netcdf", phony_dims="sort"))
        for g in groups:
            zone = g[len("zone_"):] if g.startswith("zone_") else g
            zones[zone] = _decode_flags(xr.load_dataset(path, engine="h5netcdf", group=g, phony_dims="sort"))
        study[stage] = zones
    if not study:
        raise FileNotFoundError(
            f"{out}: no study files ({', '.join(s + '.h5' for s in STAGE_FILES)})"
        )
    return study
