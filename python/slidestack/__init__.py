"""slidestack from Python: the same library code as the ``slidestack`` command line.

Seismic response of a structure (one storey or a shear building) carrying stacks of sliding rigid
blocks with Coulomb friction, exact event-driven simulation, response spectra, spectral matching,
and the staged T_new study (motions -> sweep -> tnew -> fit -> report, ida, floors, design).

>>> import slidestack
>>> r = slidestack.simulate(period=1.0, alpha=[0.5, 0.5], mu=[0.2, 0.1])
>>> r["peak_displacement_m"]  # the numbers of ``slidestack simulate --json``
>>> ds = slidestack.simulate_many([dict(mu=[m, 0.1]) for m in (0.1, 0.2, 0.3)])
>>> ds["peak_displacement_m"]  # an xarray DataArray over ``case``, the same numbers

Every function releases the GIL while it works. Errors carry the message the command line
prints and the attributes ``kind``, ``file``, ``key`` and ``line``: bad input raises
``ValueError``, a missing file ``FileNotFoundError``, other I/O ``OSError``, Ctrl-C
``KeyboardInterrupt``, and a damaged file or a failed run ``slidestack.Error`` (a
``RuntimeError``).
"""

from ._native import (
    Error,
    __version__,
    design,
    export_edp,
    export_frame_edp,
    fit,
    floors,
    ida,
    match,
    merge,
    motions,
    read_record,
    report,
    run,
    simulate,
    spectrum,
    status,
    sweep,
    tnew,
)
from ._batch import simulate_many, spectra
from ._study import open_study

__all__ = [
    "Error",
    "__version__",
    "design",
    "export_edp",
    "export_frame_edp",
    "fit",
    "floors",
    "ida",
    "match",
    "merge",
    "motions",
    "open_study",
    "read_record",
    "report",
    "run",
    "simulate",
    "simulate_many",
    "spectra",
    "spectrum",
    "status",
    "sweep",
    "tnew",
]
