#!/usr/bin/env python3
"""Prints the SHA-256 of the numbers a stage file stores: every dataset's name, type, shape and
values, and every attribute's name and value, in name order, leaving out what names the code
rather than the numbers (fingerprints, the program's version) and HDF5's own bookkeeping
(dimension-scale references). Used by tests/methods.rs, the guard of src/methods.rs.

    stage-hashes.py FILE.h5 [FILE.h5 ...]   # one line per file: NAME SHA256
"""

import hashlib
import sys

import h5py
import numpy as np

SKIP_ATTRS = {"DIMENSION_LIST", "REFERENCE_LIST", "CLASS", "NAME", "_Netcdf4Dimid",
              "_Netcdf4Coordinates", "slidestack_version"}


def value_bytes(v) -> bytes:
    a = np.asarray(v)
    if a.dtype.kind in "OSU":
        items = [x.decode() if isinstance(x, bytes) else str(x) for x in a.ravel()]
        return "\0".join(items).encode()
    return np.ascontiguousarray(a).tobytes()


def attrs(h, obj) -> None:
    for name in sorted(obj.attrs):
        if name in SKIP_ATTRS or "fingerprint" in name:
            continue
        v = obj.attrs[name]
        if isinstance(v, h5py.Reference) or getattr(np.asarray(v).dtype, "kind", "") == "O" and any(
            isinstance(x, h5py.Reference) for x in np.asarray(v).ravel()
        ):
            continue
        h.update(f"@{name}".encode())
        h.update(value_bytes(v))


def digest(path: str) -> str:
    h = hashlib.sha256()
    with h5py.File(path, "r") as f:
        attrs(h, f)
        names = []
        f.visit(names.append)
        for name in sorted(names):
            obj = f[name]
            h.update(f"/{name}".encode())
            attrs(h, obj)
            if isinstance(obj, h5py.Dataset):
                h.update(f"{obj.dtype.str}{obj.shape}".encode())
                h.update(value_bytes(obj[()]))
    return h.hexdigest()


if __name__ == "__main__":
    for p in sys.argv[1:]:
        print(p.rsplit("/", 1)[-1], digest(p))
