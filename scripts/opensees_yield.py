#!/usr/bin/env python3
"""A yielding structure, no blocks, side by side: OpenSees (Steel01) against slidestack.

Usage
    LD_LIBRARY_PATH=.venv-peers/lib/python3.11/site-packages/openseespylinux/lib \\
        .venv-peers/bin/python scripts/opensees_yield.py [--slidestack PATH] [--markdown FILE]

    ``scripts/bench-peers`` makes ``.venv-peers/`` with openseespy (or ``python -m venv
    .venv-peers && .venv-peers/bin/pip install openseespy``); the LD_LIBRARY_PATH is needed
    because the wheel bundles BLAS/LAPACK without telling the loader (scripts/opensees_stack.py
    explains). Without openseespy the script exits with code 3 and says so.

The system (docs/model.md, "Yielding structure")
    A bare SDOF, m = 1 kg, k = (2π/T_p)², c = 2ζ·sqrt(k), ζ of the bare structure, with a
    bilinear restoring force with kinematic hardening: yield force F_y = C_y·g, post-yield
    stiffness r·k (r = 0: elastic–perfectly plastic), under a base acceleration linear between
    the record's samples; displacements relative to the ground.

The OpenSees model
    ``model basic -ndm 1 -ndf 1``; node 0 fixed, node 1 with mass 1. Two ``zeroLength``
    elements between them: ``uniaxialMaterial Steel01 F_y k r`` (no isotropic hardening: a1..a4
    at their defaults 0, 1, 0, 1; with b = r it is exactly this bilinear law, including r = 0)
    and ``uniaxialMaterial Viscous c 1`` (force c·u̇). Ground motion as in
    scripts/opensees_stack.py (``Path`` series, ``UniformExcitation``, consistent initial
    acceleration −a_g(0)). ``Newmark 0.5 0.25`` (average acceleration), ``Newton``,
    ``NormDispIncr 1e-12``, h = dt/steps_per_sample. The hysteretic energy is
    ``Σ ½(F_{k−1} + F_k)(u_k − u_{k−1}) − F_end²/(2k)`` over the steps, F from ``eleForce``.

slidestack side
    ``slidestack simulate --structure epp|bilinear`` with one frictionless block (μ = 0: it never
    loads the structure, which responds alone; tests/limits.rs) and ``--damping-basis
    structure``; displacement at every sample from ``--history``, ``residual_displacement_m``,
    ``energy.hysteretic`` and the exact peak from ``--json``.

Output
    A markdown table per case: for each steps_per_sample, |peak/peak_ss − 1| (peaks over the
    samples for both), max_k |u(t_k) − u_ss(t_k)| / peak_ss, |residual − residual_ss| / peak_ss,
    |E_h/E_h,ss − 1| and the time of one OpenSees analysis; and the observed order of the
    history difference. Newmark is second order, so the difference should fall about 100-fold
    per tenfold refinement where slidestack is exact; where it stalls, the reference has stopped
    converging.

Numbers (docs/opensees-yield.md, OpenSees 3.7.1): on all four cases the history difference
falls at order 1.7–2.2 from 1 to 1000 steps per sample, to 3e-9–6e-8 of the peak at 1000 (peak,
residual drift and hysteretic energy likewise, 1e-10–4e-8): OpenSees converges to slidestack's
exact answer. At 1 step per sample it is off by 3e-3–4e-2 in the history.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import opensees_stack as oss  # noqa: E402  (same directory; imports openseespy only when asked)

G = oss.G
REPO = oss.REPO

# (record, T_p s, ζ, structure, C_y, r)
CASES = [
    ("RSN960_NORTHR_LOS270.AT2", 1.0, 0.05, "epp", 0.1, 0.0),
    ("RSN960_NORTHR_LOS270.AT2", 0.5, 0.05, "bilinear", 0.15, 0.05),
    ("RSN829_CAPEMEND_RIO360.AT2", 0.3, 0.02, "bilinear", 0.2, 0.1),
    ("RSN1633_MANJIL_ABBAR--L.AT2", 2.0, 0.05, "epp", 0.03, 0.0),
]
STEPS = [1, 10, 100, 1000]


def opensees_run(ops, dt, accel_g, period_s, zeta, cy, r, steps_per_sample):
    """u at every sample, the hysteretic energy (J/kg) and the analysis time (s)."""
    k = (2 * math.pi / period_s) ** 2
    c = 2 * zeta * math.sqrt(k)
    fy = cy * G
    t0 = time.perf_counter()
    ops.wipe()
    ops.model("basic", "-ndm", 1, "-ndf", 1)
    ops.node(0, 0.0)
    ops.fix(0, 1)
    ops.node(1, 0.0, "-mass", 1.0)
    ops.uniaxialMaterial("Steel01", 1, fy, k, r)
    ops.uniaxialMaterial("Viscous", 2, c, 1.0)
    ops.element("zeroLength", 1, 0, 1, "-mat", 1, "-dir", 1)
    ops.element("zeroLength", 2, 0, 1, "-mat", 2, "-dir", 1)
    ops.timeSeries("Path", 1, "-dt", dt, "-values", *map(float, accel_g), "-factor", G,
                   "-useLast")
    ops.pattern("UniformExcitation", 1, 1, "-accel", 1)
    ops.constraints("Plain")
    ops.numberer("Plain")
    ops.system("FullGeneral")
    ops.test("NormDispIncr", 1e-12, 50)
    ops.algorithm("Newton")
    ops.integrator("Newmark", 0.5, 0.25)
    ops.analysis("Transient")
    ops.setNodeAccel(1, 1, -G * float(accel_g[0]), "-commit")
    h = dt / steps_per_sample
    u = [0.0]
    u_prev, f_prev, work = 0.0, 0.0, 0.0
    for _ in range(1, len(accel_g)):
        for _ in range(steps_per_sample):
            if ops.analyze(1, h) != 0:
                raise RuntimeError(f"Newton does not converge at t = {ops.getTime():.6g} s")
            un = ops.nodeDisp(1, 1)
            fn = ops.eleForce(1, 2)
            work += 0.5 * (f_prev + fn) * (un - u_prev)
            u_prev, f_prev = un, fn
        u.append(u_prev)
    elapsed = time.perf_counter() - t0
    ops.wipe()
    return u, work - f_prev * f_prev / (2 * k), elapsed


def slidestack_run(slidestack, record, period_s, zeta, kind, cy, r):
    with tempfile.TemporaryDirectory() as d:
        hist = Path(d) / "h.csv"
        cmd = [slidestack, "simulate", "--record", str(record), "--period", repr(period_s),
               "--damping", repr(zeta), "--damping-basis", "structure", "--alpha", "0.5",
               "--mu", "0", "--structure", kind, "--yield-strength-ratio", repr(cy),
               "--json", "--history", str(hist)]
        if kind == "bilinear":
            cmd += ["--post-yield-ratio", repr(r)]
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"opensees_yield: slidestack simulate failed ({p.returncode}): "
                     f"{p.stderr.strip()}")
        with open(hist, newline="") as f:
            u = [float(row["ps_disp_m"]) for row in csv.DictReader(f)]
    return u, json.loads(p.stdout)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--slidestack", default=str(REPO / "target/release/slidestack"))
    ap.add_argument("--markdown", type=Path, help="also write the tables to this file")
    args = ap.parse_args()
    try:
        ops = oss.import_opensees()
    except ImportError as e:
        print(f"opensees_yield: {e}", file=sys.stderr)
        sys.exit(oss.EXIT_NO_OPENSEES)
    out = [f"# A yielding SDOF: OpenSees Steel01 vs slidestack\n\nOpenSees "
           f"{oss.opensees_version(ops)}; slidestack `{args.slidestack}`. Cells: differences "
           f"from slidestack's exact integrator (peaks over the samples for both; u, residual "
           f"over slidestack's peak; E_h relative).\n"]
    for rec, tp, zeta, kind, cy, r in CASES:
        path = REPO / "tests/fixtures/records" / rec
        accel, dt = oss.read_at2(path)
        ref, js = slidestack_run(args.slidestack, path, tp, zeta, kind, cy, r)
        peak_ss = max(abs(x) for x in ref)
        eh_ss = js["energy"]["hysteretic"]
        out.append(f"## {rec}, T_p = {tp} s, ζ = {zeta}, {kind} C_y = {cy}"
                   + (f", r = {r}" if kind == "bilinear" else "") + "\n\n"
                   f"slidestack: ductility {js['ductility']:.4f}, exact peak "
                   f"{js['peak_displacement_m']:.6g} m, residual "
                   f"{js['residual_displacement_m']:.6g} m, E_h {eh_ss:.6g} J/kg, "
                   f"{js['yield_events']} yield/unloading events\n\n"
                   "| steps/sample | peak | history | residual | E_h | OpenSees time (s) |\n"
                   "|---|---|---|---|---|---|")
        hist_errs = []
        for sps in STEPS:
            try:
                u, eh, elapsed = opensees_run(ops, dt, accel, tp, zeta, cy, r, sps)
            except Exception as e:  # noqa: BLE001 - reported, never made up
                out.append(f"| {sps} | failed: {e} | | | | |")
                continue
            e_peak = abs(max(abs(x) for x in u) / peak_ss - 1)
            e_hist = max(abs(a - b) for a, b in zip(u, ref, strict=True)) / peak_ss
            e_res = abs(u[-1] - ref[-1]) / peak_ss
            e_eh = abs(eh / eh_ss - 1)
            hist_errs.append((sps, e_hist))
            out.append(f"| {sps} | {e_peak:.1e} | {e_hist:.1e} | {e_res:.1e} | {e_eh:.1e} | "
                       f"{elapsed:.3g} |")
        orders = [f"{a}→{b}: {math.log(ea / eb) / math.log(b / a):.2f}"
                  for (a, ea), (b, eb) in zip(hist_errs, hist_errs[1:])]
        out.append("\nobserved order of the history difference: " + ", ".join(orders) + "\n")
        print("\n".join(out[-(len(STEPS) + 4):]), flush=True)
    if args.markdown:
        args.markdown.write_text("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
