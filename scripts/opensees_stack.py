#!/usr/bin/env python3
"""slidestack's system as an OpenSees model (OpenSeesPy), a peer for benchmarks.

Usage
    python scripts/opensees_stack.py IN.json OUT.json
    python scripts/opensees_stack.py --check [--slidestack PATH] [--quick]

    Run it with a Python that has ``openseespy`` (``scripts/bench-peers`` installs it into
    ``.venv-peers/``). On Linux the OpenSeesPy wheel bundles BLAS/LAPACK/gfortran in
    ``<site-packages>/openseespylinux/lib`` but does not tell the dynamic loader, which reads
    ``LD_LIBRARY_PATH`` only when the process starts; so whoever starts Python must set it:

        LD_LIBRARY_PATH=.venv-peers/lib/python3.11/site-packages/openseespylinux/lib \\
            .venv-peers/bin/python scripts/opensees_stack.py IN.json OUT.json

    (``scripts/bench-peers`` does this itself when it re-runs inside its venv.) Without
    openseespy, or without that path, the script exits with code 3 and says so on stderr.

The system (src/dynamics/model.rs)
    A linear SDOF structure of mass m_p = 1, stiffness k = 4π²/T_p²·m_p and viscous damping
    c = 2ζ·sqrt(k·m_p) between it and the ground, carrying n rigid blocks of masses α_i·m_p
    (bottom first) with Coulomb friction μ_i at interface i (interface 1: structure-block 1),
    normal force g·Σ_{j≥i} α_j·m_p, g = 9.80665 m/s², under a base acceleration that is linear
    between the record's samples. Displacements are relative to the ground.

The OpenSees model
    ``model basic -ndm 1 -ndf 1``. Node 0 is the ground (fixed), node 1 the structure (mass
    m_p), node i+1 block i (mass α_i), all at x = 0.
    * Structure: ``zeroLength`` 0-1 with ``uniaxialMaterial Elastic k c``: the material's
      stress is k·ε + η·dε/dt, and for a zeroLength element ε and dε/dt are the relative
      displacement and velocity, so the force is exactly k·u + c·u̇ (the element also adds η
      to the damping matrix it gives the integrator).
    * Interface i: ``zeroLength`` i-(i+1) with ``uniaxialMaterial ElasticPP (s·k) (F_i/(s·k))``,
      an elastic-perfectly-plastic spring of initial stiffness s·k (s = ``stick_stiffness``)
      that yields at F_i = μ_i·g·Σ_{j≥i} α_j: regularised Coulomb friction. It sticks with an
      elastic slip of up to F_i/(s·k) instead of not at all, so it converges to the rigid stick
      only as s → ∞. EPP has one yield force, so static friction equals kinetic here: a case
      with μ_s > μ_k cannot be modelled this way. μ_i = 0 means no element.
    * Ground motion: ``timeSeries Path -dt dt -values a_0 … a_{N-1} -factor g -useLast``
      (linear between samples; ``-useLast`` because at the last sample time the series would
      otherwise read past its end and return 0) and ``pattern UniformExcitation 1 1 -accel``,
      which loads each mass with −m·a_g and solves for displacements relative to the ground
      (checked against slidestack by ``--check``, including the sign).
    * Analysis: ``Newmark 0.5 0.25`` (average acceleration: unconditionally stable, second
      order, no numerical damping; started from the consistent acceleration −a_g(0))
      with step h = dt/steps_per_sample, ``Plain`` constraints and numberer, ``FullGeneral``
      system (n+1 unknowns), ``NormDispIncr 1e-12`` (m), at most 20 iterations, ``Newton``.
      Why Newton: within a step each EPP spring is piecewise linear (stick, or slip at ±F_i),
      so once Newton has every spring's state right its next correction is zero to round-off;
      it takes 2-4 iterations on almost every step. Why it sometimes fails: the stick range of
      a spring is only 2·F_i/(s·k) wide, and when h is long compared with the stick mode
      (h ≳ 1/ω_stick, ω_stick ~ ω·sqrt(s)) a slip iterate jumps across it, so near a stop
      Newton can alternate between slip at +F_i and at −F_i for ever. NewtonLineSearch,
      KrylovNewton and ModifiedNewton -initial (which converges only linearly, at a rate of
      about 1 − m/(h²·s·k)) were tried as retries at the same h: they rescue some of those
      steps, but left 11 of the 170 runs of ``--check`` failing when tried. What works is the
      usual remedy, halving a failed step (recursively, at most 10 times) until Newton
      converges. The run's message counts such steps; they make that part of the run more
      accurate, not less. A run that still fails is ``ok: false`` with the time and the end
      of OpenSees's log; no number is made up.
    * Output: node 1's displacement at every record sample (``nodeDisp`` after each group of
      steps_per_sample steps), starting with 0 at t = 0.

Protocol
    IN.json:  {"clock": "wall" | "cpu" (optional, default "wall"),
               "cases": [{"id": str, "dt_s": float, "accel_g": [float, ...],
                          "period_s": float, "damping_ratio": float,
                          "alpha": [float, ...], "mu": [float, ...],
                          "runs": [{"steps_per_sample": int, "stick_stiffness": float}],
                          "repeats": int}]}
    OUT.json: {"opensees_version": str,
               "cases": [{"id": str,
                          "runs": [{"steps_per_sample": int, "stick_stiffness": float,
                                    "ok": bool, "message": str, "time_s": float,
                                    "u_m": [float, ...], "peak_m": float}]}]}
    ``time_s`` is the median time of one analysis (model build + analysis, no JSON I/O) over
    ``repeats``: wall time (``time.perf_counter``) or, with ``"clock": "cpu"``, the CPU time of
    the thread that runs OpenSees (``time.thread_time``), which other load on the machine barely
    changes; ``u_m`` has one value per record sample, ``peak_m`` = max |u_m|. A failed
    run has ``ok: false``, its message, and null ``time_s``, ``u_m`` and ``peak_m``.

--check
    Compares the model with ``slidestack simulate`` (its exact integrator; the structure's
    displacement at every sample from ``--history``) for steps_per_sample 1, 2, 5, 10, 20 and
    stick stiffness 1e2-1e5 (and 1e7 for the case that never slides) on a case that never
    slides (μ = 5: a linear SDOF of mass 1 + Σα, to which Newmark converges at second order)
    and on sliding cases with 1, 2 and 3 blocks on two fixture records. Prints markdown
    tables of |peak/peak_ss − 1| and max_k |u(t_k) − u_ss(t_k)| / peak_ss, with peaks taken
    over the samples for both. ``--quick`` checks only RSN960. slidestack: ``--slidestack``,
    else $SLIDESTACK, else target/release/slidestack.
"""

from __future__ import annotations

import argparse
import atexit
import csv
import itertools
import json
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

G = 9.80665
REPO = Path(__file__).resolve().parent.parent
EXIT_NO_OPENSEES = 3
MAX_HALVINGS = 10


_LOG: Path | None = None


def import_opensees():
    """The ``openseespy.opensees`` module, or ImportError with what to do. OpenSees's messages
    (a warning for every step on which Newton fails) go to a temporary log file instead of
    stderr; a failed run quotes the end of it."""
    global _LOG
    try:
        import openseespy.opensees as ops  # noqa: PLC0415
    except Exception as e:  # noqa: BLE001 - openseespy raises RuntimeError when a lib is missing
        hint = ""
        try:  # where the wheel's libraries are, found without importing the package
            import importlib.util  # noqa: PLC0415
            spec = importlib.util.find_spec("openseespylinux")
            if spec and spec.submodule_search_locations:
                lib = Path(list(spec.submodule_search_locations)[0]) / "lib"
                if lib.is_dir():
                    hint = f" (here: LD_LIBRARY_PATH={lib})"
        except (ImportError, ValueError):
            pass
        raise ImportError(
            f"cannot import openseespy.opensees ({type(e).__name__}: {e}). Install it with "
            f"`pip install openseespy` into the Python that runs this script ({sys.executable}), "
            f"and on Linux start that Python with LD_LIBRARY_PATH containing "
            f"<site-packages>/openseespylinux/lib{hint}: the wheel's BLAS/LAPACK/gfortran, and "
            f"the loader reads LD_LIBRARY_PATH only at process start. scripts/bench-peers does "
            f"both."
        ) from e
    if _LOG is None:
        fd, name = tempfile.mkstemp(prefix="opensees_stack-", suffix=".log")
        os.close(fd)
        _LOG = Path(name)
        atexit.register(_LOG.unlink, missing_ok=True)
        ops.logFile(name, "-noEcho")
    return ops


def log_size() -> int:
    return _LOG.stat().st_size if _LOG else 0


def log_tail(since: int, lines: int = 3) -> str:
    """The last `lines` lines OpenSees logged after byte `since`, joined by " | "."""
    if not _LOG:
        return ""
    with open(_LOG, "rb") as f:
        f.seek(since)
        text = f.read().decode(errors="replace")
    return " | ".join([x.strip() for x in text.splitlines() if x.strip()][-lines:])


def opensees_version(ops) -> str:
    try:
        return str(ops.version())
    except Exception:  # noqa: BLE001 - older builds have no version()
        from importlib.metadata import version  # noqa: PLC0415
        return f"openseespy {version('openseespy')}"


# --------------------------------------------------------------------------- the model

def build(ops, dt: float, accel_g, period_s: float, damping_ratio: float, alpha, mu,
          stick_stiffness: float) -> None:
    """Defines the model, ground motion and analysis in a wiped OpenSees domain."""
    n = len(alpha)
    if len(mu) != n:
        raise ValueError(f"{len(mu)} friction coefficients for {n} blocks")
    bad = [f"{name} = {v!r}" for name, v, ok in [
        ("dt_s", dt, dt > 0), ("period_s", period_s, period_s > 0),
        ("damping_ratio", damping_ratio, 0 <= damping_ratio < 1),
        ("stick_stiffness", stick_stiffness, stick_stiffness > 0),
        *((f"alpha_{i}", a, a > 0) for i, a in enumerate(alpha, 1)),
        *((f"mu_{i}", m, m >= 0) for i, m in enumerate(mu, 1))]
        if not (math.isfinite(v) and ok)]
    if bad or len(accel_g) < 2:
        raise ValueError("invalid input: " + ", ".join(bad or ["fewer than 2 samples"]))
    k = (2 * math.pi / period_s) ** 2  # m_p = 1
    c = 2 * damping_ratio * math.sqrt(k)
    ops.wipe()
    ops.model("basic", "-ndm", 1, "-ndf", 1)
    ops.node(0, 0.0)
    ops.fix(0, 1)
    ops.node(1, 0.0, "-mass", 1.0)
    for i, a in enumerate(alpha, start=1):
        ops.node(i + 1, 0.0, "-mass", float(a))
    ops.uniaxialMaterial("Elastic", 1, k, c)
    ops.element("zeroLength", 1, 0, 1, "-mat", 1, "-dir", 1)
    ks = stick_stiffness * k
    for i in range(1, n + 1):
        f_yield = mu[i - 1] * G * sum(alpha[i - 1:])
        if f_yield == 0.0:
            continue  # frictionless: the block is free
        ops.uniaxialMaterial("ElasticPP", i + 1, ks, f_yield / ks)
        ops.element("zeroLength", i + 1, i, i + 1, "-mat", i + 1, "-dir", 1)
    ops.timeSeries("Path", 1, "-dt", dt, "-values", *map(float, accel_g), "-factor", G,
                   "-useLast")
    ops.pattern("UniformExcitation", 1, 1, "-accel", 1)
    ops.constraints("Plain")
    ops.numberer("Plain")
    ops.system("FullGeneral")
    ops.test("NormDispIncr", 1e-12, 20)
    ops.algorithm("Newton")
    ops.integrator("Newmark", 0.5, 0.25)
    ops.analysis("Transient")
    # At t = 0 every spring and damper force is zero, so every mass accelerates at −a_g(0)
    # relative to the ground. Newmark would otherwise start from zero acceleration, a
    # velocity error of h·a_g(0)/2 that lasts: first order in h.
    for node in range(1, n + 2):
        ops.setNodeAccel(node, 1, -G * float(accel_g[0]), "-commit")


def analyse(ops, n_samples: int, dt: float, steps_per_sample: int):
    """Runs the built model over the record; (u at every sample, split steps, finest step)."""
    if steps_per_sample < 1:
        raise ValueError(f"steps_per_sample must be >= 1, got {steps_per_sample}")
    h = dt / steps_per_sample
    u = [0.0]
    split = 0
    finest = h

    def step(size: float, depth: int, whole: bool = True) -> None:
        nonlocal split, finest
        if whole and ops.analyze(1, size) == 0:
            finest = min(finest, size)
            return
        if depth == MAX_HALVINGS:
            raise RuntimeError(f"Newton does not converge at t = {ops.getTime() + size:.6g} s "
                               f"even with the step halved {MAX_HALVINGS} times "
                               f"({size:.3g} s)")
        if depth == 0:
            split += 1
        step(size / 2, depth + 1)
        step(size / 2, depth + 1)

    for k in range(1, n_samples):
        if ops.analyze(steps_per_sample, h) != 0:
            # Newton failed on a step of this interval and the domain is back at the last
            # converged step. Finish the interval, halving the failed step and any other that
            # fails (the failed one would fail again whole: Newton is deterministic).
            done = round((ops.getTime() - (k - 1) * dt) / h)
            step(h, 0, whole=False)
            for _ in range(done + 1, steps_per_sample):
                step(h, 0)
        u.append(ops.nodeDisp(1, 1))
    return u, split, finest


CLOCKS = {"wall": time.perf_counter, "cpu": time.thread_time}


def simulate(ops, dt: float, accel_g, period_s: float, damping_ratio: float, alpha, mu,
             steps_per_sample: int, stick_stiffness: float, clock=time.perf_counter) -> dict:
    """One analysis: {"ok", "message", "time_s", "u_m", "peak_m"} (time of build + analysis)."""
    logged = log_size()
    t0 = clock()
    try:
        build(ops, dt, accel_g, period_s, damping_ratio, alpha, mu, stick_stiffness)
        u, split, finest = analyse(ops, len(accel_g), dt, steps_per_sample)
    except Exception as e:  # noqa: BLE001 - OpenSeesError, bad input: reported, not raised
        ops.wipe()
        tail = log_tail(logged)
        return {"ok": False, "message": f"{type(e).__name__}: {e}"
                + (f" (OpenSees log: {tail})" if tail else ""),
                "time_s": None, "u_m": None, "peak_m": None}
    elapsed = clock() - t0
    ops.wipe()
    if not all(math.isfinite(x) for x in u):
        return {"ok": False, "message": "non-finite displacement", "time_s": None,
                "u_m": None, "peak_m": None}
    msg = "converged" + (f"; {split} of {(len(u) - 1) * steps_per_sample} steps split "
                         f"(finest {finest:.3g} s)" if split else "")
    return {"ok": True, "message": msg, "time_s": elapsed, "u_m": u,
            "peak_m": max(abs(x) for x in u)}


def run_case(ops, case: dict, clock=time.perf_counter) -> dict:
    """All runs of one protocol case; time_s is the median over ``repeats`` analyses."""
    repeats = max(1, int(case.get("repeats", 1)))
    runs = []
    for r in case["runs"]:
        sps, s = int(r["steps_per_sample"]), float(r["stick_stiffness"])
        times, res = [], None
        for _ in range(repeats):
            res = simulate(ops, float(case["dt_s"]), case["accel_g"], float(case["period_s"]),
                           float(case["damping_ratio"]), case["alpha"], case["mu"], sps, s,
                           clock)
            if not res["ok"]:
                break
            times.append(res["time_s"])
        if res["ok"]:
            res["time_s"] = statistics.median(times)
        runs.append({"steps_per_sample": sps, "stick_stiffness": s, **res})
    return {"id": case["id"], "runs": runs}


# --------------------------------------------------------------------------- --check

def read_at2(path: Path):
    """PEER .AT2 (either header style): (values in g, dt)."""
    lines = path.read_text().splitlines()
    m = re.search(r"NPTS\s*=\s*(\d+)\s*,?\s*DT\s*=\s*([0-9.Ee+-]+)", lines[3], re.I)
    if m:
        npts, dt = int(m.group(1)), float(m.group(2))
    else:
        f = lines[3].split()
        npts, dt = int(f[0]), float(f[1])
    values = [float(x) for x in " ".join(lines[4:]).split()]
    if len(values) < npts:
        sys.exit(f"opensees_stack: {path}: {len(values)} values, NPTS says {npts}")
    return values[:npts], dt


def slidestack_history(slidestack: str, record: Path, period_s: float, damping_ratio: float,
                       alpha, mu) -> tuple[list[float], dict]:
    """Structure displacement at every sample by ``slidestack simulate``, and its JSON. The
    damping ratio is taken on the bare structure (``--damping-basis structure``), as this
    model's ``c = 2ζ√(k·m_p)``; slidestack's default basis is the structure with its load."""
    with tempfile.TemporaryDirectory() as d:
        hist = Path(d) / "h.csv"
        r = subprocess.run([slidestack, "simulate", "--record", str(record),
                            "--period", repr(period_s), "--damping", repr(damping_ratio),
                            "--damping-basis", "structure",
                            "--alpha", ",".join(map(repr, alpha)),
                            "--mu", ",".join(map(repr, mu)), "--json", "--history", str(hist)],
                           capture_output=True, text=True)
        if r.returncode != 0:
            raise RuntimeError(f"slidestack simulate failed ({r.returncode}): "
                               f"{r.stderr.strip()}")
        with open(hist, newline="") as f:
            u = [float(row["ps_disp_m"]) for row in csv.DictReader(f)]
    return u, json.loads(r.stdout)


def compare(u, ref) -> tuple[float, float]:
    """(|peak/peak_ref − 1|, max |u − ref| / peak_ref), peaks over the samples."""
    peak_ref = max(abs(x) for x in ref)
    peak = max(abs(x) for x in u)
    return abs(peak / peak_ref - 1), max(abs(a - b) for a, b in zip(u, ref, strict=True)) / peak_ref


def check(args) -> None:
    ops = import_opensees_or_exit()
    slidestack = (args.slidestack or os.environ.get("SLIDESTACK")
                  or str(REPO / "target/release/slidestack"))
    recs = REPO / "tests/fixtures/records"
    records = ["RSN960_NORTHR_LOS270.AT2"] + ([] if args.quick else ["RSN829_CAPEMEND_RIO360.AT2"])
    sps_list = [1, 2, 5, 10, 20]
    zeta, period = 0.05, 1.0
    cases = []
    for rec in records:
        cases.append((rec, [0.5, 0.5], [5.0, 5.0], [1e2, 1e3, 1e4, 1e5, 1e7]))
        cases.append((rec, [0.5], [0.1], [1e2, 1e3, 1e4, 1e5]))
        cases.append((rec, [0.5, 0.5], [0.2, 0.1], [1e2, 1e3, 1e4, 1e5]))
        cases.append((rec, [0.3, 0.3, 0.3], [0.15, 0.1, 0.05], [1e2, 1e3, 1e4, 1e5]))
    print(f"# OpenSees model vs slidestack simulate\n\nOpenSees {opensees_version(ops)}; "
          f"slidestack `{slidestack}`; T_p = {period} s, ζ = {zeta}; static = kinetic "
          f"friction. Cell: |peak/peak_ss − 1| / max |u − u_ss| / peak_ss, peaks over the "
          f"samples; steps/sample down, stick stiffness (× k) across.\n", flush=True)
    for rec, alpha, mu, stiffs in cases:
        accel, dt = read_at2(recs / rec)
        try:
            ref, js = slidestack_history(slidestack, recs / rec, period, zeta, alpha, mu)
        except (RuntimeError, OSError) as e:
            sys.exit(f"opensees_stack: {e}")
        if len(ref) != len(accel):
            sys.exit(f"opensees_stack: slidestack gives {len(ref)} samples, the record has "
                     f"{len(accel)}")
        slip = ", ".join(f"{s:.3g}" for s in js["slip_time_s"])
        print(f"## {rec} (dt {dt} s, {len(accel)} samples), α = {alpha}, μ = {mu}\n\n"
              f"slidestack: peak over samples {max(map(abs, ref)):.6g} m (exact peak "
              f"{js['peak_displacement_m']:.6g} m), time slipping per interface {slip} s\n",
              flush=True)
        print("| steps/sample | " + " | ".join(f"{s:.0e}" for s in stiffs) + " |")
        print("|---" * (len(stiffs) + 1) + "|")
        notes = []
        hist_err = {}
        for sps in sps_list:
            cells = []
            for s in stiffs:
                res = simulate(ops, dt, accel, period, zeta, alpha, mu, sps, s)
                if not res["ok"]:
                    cells.append("failed")
                    notes.append(f"- {sps} steps/sample, {s:.0e}: {res['message']}")
                    continue
                e_peak, e_hist = compare(res["u_m"], ref)
                cells.append(f"{e_peak:.1e} / {e_hist:.1e}")
                hist_err[sps, s] = e_hist
                if res["message"] != "converged":
                    notes.append(f"- {sps} steps/sample, {s:.0e}: {res['message']}")
            print(f"| {sps} | " + " | ".join(cells) + " |", flush=True)
        s = stiffs[-1]
        orders = [f"{a}→{b}: {math.log(hist_err[a, s] / hist_err[b, s]) / math.log(b / a):.2f}"
                  for a, b in itertools.pairwise(sps_list)
                  if (a, s) in hist_err and (b, s) in hist_err]
        if orders:
            notes.insert(0, f"- observed order of the history error in h at stick stiffness "
                            f"{stiffs[-1]:.0e}, steps/sample " + ", ".join(orders))
        print("\n".join([""] + notes + [""]) if notes else "", flush=True)


# --------------------------------------------------------------------------- main

def import_opensees_or_exit():
    try:
        return import_opensees()
    except ImportError as e:
        print(f"opensees_stack: {e}", file=sys.stderr)
        sys.exit(EXIT_NO_OPENSEES)


def main() -> None:
    p = argparse.ArgumentParser(description="slidestack's system in OpenSees (see the docstring).")
    p.add_argument("input", nargs="?", help="IN.json")
    p.add_argument("output", nargs="?", help="OUT.json")
    p.add_argument("--check", action="store_true", help="compare with slidestack simulate")
    p.add_argument("--slidestack", help="slidestack binary for --check")
    p.add_argument("--quick", action="store_true", help="--check on RSN960 only")
    args = p.parse_args()
    if args.check:
        check(args)
        return
    if not (args.input and args.output):
        p.error("IN.json and OUT.json are required (or --check)")
    spec = json.loads(Path(args.input).read_text())
    clock_name = spec.get("clock", "wall")
    if clock_name not in CLOCKS:
        sys.exit(f"{args.input}: clock must be one of {sorted(CLOCKS)}, got {clock_name!r}")
    ops = import_opensees_or_exit()
    out = {"opensees_version": opensees_version(ops),
           "cases": [run_case(ops, c, CLOCKS[clock_name]) for c in spec["cases"]]}
    Path(args.output).write_text(json.dumps(out))


if __name__ == "__main__":
    main()
