#!/usr/bin/env python3
"""slidestack's multi-storey building as an OpenSees model (OpenSeesPy), a peer for comparisons.

Usage
    python scripts/opensees_building.py IN.json OUT.json
    python scripts/opensees_building.py --check [--quick] [--slidestack PATH] [--markdown FILE]

    Run it with a Python that has ``openseespy`` and ``numpy`` and with the OpenSeesPy wheel's
    libraries on ``LD_LIBRARY_PATH`` (scripts/opensees_stack.py explains why):

        python3 -m venv .venv-peers && .venv-peers/bin/pip install openseespy numpy
        LD_LIBRARY_PATH=.venv-peers/lib/python3.11/site-packages/openseespylinux/lib \\
            .venv-peers/bin/python scripts/opensees_building.py IN.json OUT.json

    (``scripts/compare-opensees-building`` makes that venv and sets the path itself.) Without
    openseespy, or without that path, the script exits with code 3 and says so on stderr.

The system (docs/model.md, "A multi-storey building"; src/dynamics/building/model.rs)
    N floors of masses m_j (relative values taken as kg), floor 1 the lowest; storey i a spring
    k_i between floor i−1 (0: the ground) and floor i. The relative stiffnesses are scaled so
    that the bare building's first mode has the period ``period`` (modes of (K, M) by the
    symmetric eigenproblem of M^{-1/2}·K·M^{-1/2}, numpy). Damping: the constant matrix
    C = M_b·Φ·diag(2ζω_r)·Φᵀ·M_b, Φ the mass-normalised modes of (K, M_b), M_b the bare floor
    masses (``damping_basis: structure``) or each floor's mass plus the blocks of every stack
    on it (``rigid``, the default), acting on the floors' velocities relative to the ground.
    Stacks: chains of rigid blocks on floors, block masses α_b·m_floor, Coulomb friction μ_b at
    interface b (1: floor–bottom block), normal force g·Σ(masses above), g = 9.80665 m/s²;
    static = kinetic friction here (a stack with ``mu_static`` ≠ ``mu`` is refused). Storeys
    optionally yield: ``epp`` or ``bilinear`` with kinematic hardening, F_y,i = C_y,i·g·Σ_{j≥i}
    m_j (bare floor masses at and above storey i), post-yield stiffness r·k_i.

The OpenSees model
    ``model basic -ndm 1 -ndf 1``. Node 0 is the ground (fixed), node j floor j (mass m_j),
    then one node per block, stacks in the order given, each bottom-up (slidestack's body
    order), all at x = 0.
    * Storey i: ``zeroLength`` (i−1)-i with ``uniaxialMaterial Elastic k_i`` or, when the
      storeys yield, ``Steel01 F_y,i k_i r`` (kinematic hardening only; b = r is exactly the
      bilinear law, r = 0 the EPP one; scripts/opensees_yield.py checks it against slidestack).
    * Damping, exactly C: a symmetric matrix is a sum of pairwise dashpots,
      C = Σ_{i<j} c_ij·(e_i − e_j)(e_i − e_j)ᵀ + Σ_i d_i·e_i·e_iᵀ with c_ij = −C_ij and
      d_i = Σ_j C_ij (the row sum), so one ``zeroLength`` with ``uniaxialMaterial Elastic 0
      c_ij`` (force c·Δu̇, linear: no minimum velocity as in ``Viscous``) between every pair of
      floors, and one from every floor to the ground (node 0; displacements are relative to
      the ground, so these act on the relative velocities as in slidestack). Some c_ij are
      negative; nothing requires them to be positive, C is. ``--check`` reads the assembled
      matrix back (``printA`` at two step sizes) and compares it with numpy's C.
    * Interface b of a stack: ``zeroLength`` below-block with ``uniaxialMaterial ElasticPP
      k_s F_b/k_s``, elastic-perfectly-plastic, yield force F_b = μ_b·g·Σ(masses above), as in
      scripts/opensees_stack.py, with k_s = s·ω₁²·m_floor: s the ``stick_stiffness`` factor,
      ω₁ = 2π/period and m_floor the mass of the floor the stack stands on. For one storey
      this is opensees_stack.py's s·k exactly. Regularised Coulomb friction: it sticks with an
      elastic slip of up to F_b/k_s instead of none, so it converges only as s → ∞; the stick
      mode has a frequency of about ω₁·sqrt(s/α). μ_b = 0 means no element.
    * Or, with ``"friction": "flatslider"``, each interface is OpenSees's
      ``flatSliderBearing`` with ``frictionModel Coulomb μ_b`` and kInit = k_s, in a
      ``-ndm 2 -ndf 3`` model (rotations fixed, floors fixed vertically, blocks free
      vertically and massless there, the axial direction vertical via ``-orient 0 1 0 -1 0
      0``, axial ``Elastic`` stiffness 1e3·k_s): the normal force is the element's axial
      force, from the blocks' weights applied by a static gravity step (``loadConst``) before
      the ground motion. Same elastic-plastic law as ElasticPP, N from the model instead of
      given: on a single block the results agree with the ElasticPP model to 2e-13, but on a
      stack OpenSees 3.7.1's element commits the plastic slip of a rejected Newton iterate
      (slip that never happened; ``--check`` counts it, docs/opensees-building.md says why),
      so the comparison uses ElasticPP.
    * Ground motion: ``timeSeries Path -dt dt -values … -factor g·scale -useLast`` (linear
      between samples) and ``pattern UniformExcitation``: every mass loaded by −m·a_g,
      displacements relative to the ground.
    * Analysis: ``Newmark 0.5 0.25`` (average acceleration) from the consistent initial
      acceleration −a_g(0), step h = dt/steps_per_sample, ``Plain`` constraints and
      numberer, ``FullGeneral``, ``NormDispIncr 1e-12`` (m), at most 20 iterations,
      ``Newton``, and a failed step halved recursively (at most 10 times) until Newton
      converges, as in scripts/opensees_stack.py (which says why).
    * Outputs, read after every converged step (peaks over the steps, so a peak between steps
      is missed; slidestack's peaks are exact over time): floor displacement and absolute
      acceleration, storey drifts, each interface's slip (block minus body below, so including
      the spring's elastic part of at most F_b/k_s); residual drift and slip at the record's
      end; ``modes_s`` the bare building's periods (numpy). A floor's absolute acceleration is
      the mass-weighted mean of ``nodeAccel`` + a_g(t) over the floor and the blocks stuck to
      it (every interface between them below its friction limit after the step): the limit
      s → ∞ of "the floor and its stuck blocks move together". The floor node's own
      acceleration is not used for it: a sticking interface's spring rings at its stick
      frequency after every jump of the friction force above it (a block reversing), Newmark's
      average acceleration rule does not damp that ringing, and its amplitude is set by the
      force jump, not by s, so the node's peak converges to the exact peak plus the ringing
      (7.8 % high on the roof of the ``yielding`` comparison case; docs/opensees-building.md,
      "The roof's acceleration and the stick springs' ringing"). That node value is reported
      as ``floor_peak_node_abs_accel_g``.

Protocol
    IN.json:  {"cases": [{"id": str, "dt_s": float, "accel_g": [float, ...], "scale": float,
                          "damping": float, "damping_basis": "rigid" | "structure",
                          "building": {"storeys": int, "period": float,
                                       "floor_masses": [...], "storey_stiffnesses": [...],
                                       "structure": "elastic" | "epp" | "bilinear",
                                       "yield_strength_ratios": [...],
                                       "post_yield_ratio": float},
                          "stacks": [{"floor": int, "alpha": [...], "mu": [...]}],
                          "runs": [{"steps_per_sample": int, "stick_stiffness": float,
                                    "friction": "elasticpp" | "flatslider"}],
                          "repeats": int, "history": bool, "step_history": bool}]}
        Defaults as slidestack's: scale 1, damping 0.05, damping_basis rigid, floor_masses and
        storey_stiffnesses all 1, structure elastic, post_yield_ratio 0 (epp), no stacks,
        friction elasticpp, repeats 1. ``storeys`` may be left out (the lists' length).
    OUT.json: {"opensees_version": str,
               "cases": [{"id": str, "modes_s": [...], "storey_stiffness_n_per_m": [...],
                          "damping_matrix": [[...]],
                          "runs": [{"steps_per_sample", "stick_stiffness", "friction",
                                    "ok": bool, "message": str,
                                    "wall_s": float, "cpu_s": float,
                                    "modes_s": [...],
                                    "floor_peak_displacement_m": [...],
                                    "floor_peak_abs_accel_g": [...],
                                    "floor_peak_node_abs_accel_g": [...],
                                    "storey_peak_drift_m": [...],
                                    "storey_residual_drift_m": [...],
                                    "stacks": [{"floor": int, "peak_slip_m": [...],
                                                "residual_slip_m": [...]}],
                                    "steps": int, "split_steps": int,
                                    "floor_u_m": [[...], ...]  (with "history": true),
                                    "step_history": {"columns": [str, ...],
                                                     "rows": [[...], ...]}
                                        (with "step_history": true)}]}]}
    Lists are floor 1 / storey 1 / interface 1 first. ``wall_s`` and ``cpu_s`` are medians over
    ``repeats`` of one analysis (model build + analysis + reading the state after every step,
    no JSON I/O): ``time.perf_counter`` and the CPU time of the thread that runs OpenSees
    (``time.thread_time``), which other load on the machine barely changes. ``floor_u_m`` has
    one row per record sample (t = 0 first), one value per floor. ``step_history``, for
    debugging, has one row per converged step (after it; t = 0 not included) with the columns
    ``step_columns`` names: time, ground acceleration, per floor its displacement, its node's
    absolute acceleration and the reported one (with its stuck blocks), per block its slip,
    absolute acceleration, interface force (N) and 1/0 for sticking/slipping (large: 25 numbers
    per step for the comparison case). A failed run has ``ok: false``, its message and null
    values; no number is made up.

--check (docs/opensees-building.md, "Verification")
    1. The assembled damping matrix (``printA`` at two step sizes, K and M known) against
       numpy's C, both bases, with blocks on the floors.
    2. The bare building's periods by OpenSees ``eigen`` against numpy's.
    3. Bare elastic buildings against a numpy modal solution: each mode an SDOF
       q̈ + 2ζω q̇ + ω² q = −Γ·a_g solved exactly for a ground acceleration linear between
       samples (the SDOF's two complex modes, each e^{λh}y + h·φ₁(λh)·β₀ + h·φ₂(λh)·β₁),
       u = Σ φ_r·q_r, at 1-100 steps per sample: floor histories, peaks, drifts, absolute
       accelerations; the observed order.
    4. Stacks that cannot slide (μ = 5), damping in the ``structure`` basis (so C is not
       classical for the loaded building): against the exact state-space solution of the
       building with the blocks' masses added (2N complex modes, each exact as above), as the
       stick stiffness and steps per sample grow.
    5. The stacks of the comparison case (sliding): convergence as the stick stiffness grows
       at a fine step, and the grid of (s, steps per sample) against the finest run.
    6. One storey, one stack: this model against scripts/opensees_stack.py (the same OpenSees
       model built by another script) and, when a slidestack binary is found (``--slidestack``,
       $SLIDESTACK, target/release/slidestack), against ``slidestack simulate``.
    7. flatSliderBearing against ElasticPP, and a count of the steps after which a bearing's
       committed plastic slip changed while its force stayed below μN.
    ``--quick`` runs fewer settings.
"""

from __future__ import annotations

import argparse
import cmath
import json
import math
import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import opensees_stack as oss  # noqa: E402  (same directory; imports openseespy only when asked)

G = oss.G
REPO = oss.REPO
MAX_HALVINGS = oss.MAX_HALVINGS
EXIT_NO_OPENSEES = oss.EXIT_NO_OPENSEES
FRICTIONS = ("elasticpp", "flatslider")
STRUCTURES = ("elastic", "epp", "bilinear")


def import_numpy():
    try:
        import numpy as np  # noqa: PLC0415
    except ImportError:
        print(f"opensees_building: needs numpy in the Python that runs it ({sys.executable}): "
              f"pip install numpy", file=sys.stderr)
        sys.exit(EXIT_NO_OPENSEES)
    return np


np = import_numpy()


# --------------------------------------------------------------------------- the building

def stiffness_matrix(k):
    """Shear building: storey i (0-based) joins floor i−1 (the ground for i = 0) and floor i."""
    n = len(k)
    kk = np.zeros((n, n))
    for i in range(n):
        kk[i, i] += k[i]
        if i > 0:
            kk[i - 1, i - 1] += k[i]
            kk[i - 1, i] -= k[i]
            kk[i, i - 1] -= k[i]
    return kk


def modes(masses, k):
    """(ω_r², Φ) of K·φ = ω²·M·φ, M diagonal, ascending, Φᵀ·M·Φ = I (columns are modes), by the
    symmetric eigenproblem of M^{-1/2}·K·M^{-1/2} (as slidestack's ``modes``)."""
    s = 1.0 / np.sqrt(np.asarray(masses, dtype=float))
    w2, v = np.linalg.eigh(s[:, None] * stiffness_matrix(k) * s[None, :])
    return w2, s[:, None] * v


def modal_damping(basis_masses, k, zeta):
    """C = M_b·Φ·diag(2ζω_r)·Φᵀ·M_b from the modes of (K, M_b)."""
    w2, phi = modes(basis_masses, k)
    mp = np.asarray(basis_masses)[:, None] * phi
    return mp @ np.diag(2.0 * zeta * np.sqrt(np.maximum(w2, 0.0))) @ mp.T


class Building:
    """A case's building, validated, with everything OpenSees needs (SI units)."""

    def __init__(self, case: dict):
        b = case.get("building", {})
        fm = b.get("floor_masses")
        ks = b.get("storey_stiffnesses")
        n = int(b.get("storeys") or len(fm or ks or [1]))
        self.n = n
        fm = [1.0] * n if fm is None else [float(x) for x in fm]
        ks = [1.0] * n if ks is None else [float(x) for x in ks]
        self.period = float(b.get("period", 1.0))
        self.zeta = float(case.get("damping", 0.05))
        self.basis = case.get("damping_basis", "rigid")
        self.structure = b.get("structure", "elastic")
        self.scale = float(case.get("scale", 1.0))
        bad = []
        if n < 1:
            bad.append(f"building.storeys = {n}")
        for key, v in (("floor_masses", fm), ("storey_stiffnesses", ks)):
            if len(v) != n:
                bad.append(f"building.{key} lists {len(v)} values for {n} storeys")
            bad += [f"building.{key}[{i}] = {x!r}" for i, x in enumerate(v)
                    if not (math.isfinite(x) and x > 0)]
        if not (math.isfinite(self.period) and self.period > 0):
            bad.append(f"building.period = {self.period!r}")
        if not (math.isfinite(self.zeta) and 0 <= self.zeta < 1):
            bad.append(f"damping = {self.zeta!r}")
        if self.basis not in ("rigid", "structure"):
            bad.append(f"damping_basis = {self.basis!r}")
        if self.structure not in STRUCTURES:
            bad.append(f"building.structure = {self.structure!r}")
        if not math.isfinite(self.scale):
            bad.append(f"scale = {self.scale!r}")
        if bad:
            raise ValueError("invalid case: " + "; ".join(bad))
        self.floor_m = fm
        # Blocks: masses, the node below, the friction limit; stacks in order, bottom-up.
        self.stacks = []  # per stack: {"floor": 1-based, "blocks": [block indices]}
        self.block_m, self.block_below, self.block_mu, self.block_limit = [], [], [], []
        self.block_floor = []
        load = [0.0] * n
        for si, s in enumerate(case.get("stacks", [])):
            floor = int(s["floor"])
            alpha = [float(a) for a in s["alpha"]]
            mu = [float(m) for m in s["mu"]]
            if not 1 <= floor <= n:
                raise ValueError(f"invalid case: stacks[{si}].floor = {floor} (1 … {n})")
            if not alpha or len(mu) != len(alpha):
                raise ValueError(f"invalid case: stacks[{si}] has {len(alpha)} alpha and "
                                 f"{len(mu)} mu values")
            if any(not (math.isfinite(a) and a > 0) for a in alpha) or any(
                    not (math.isfinite(m) and m >= 0) for m in mu):
                raise ValueError(f"invalid case: stacks[{si}] alpha {alpha}, mu {mu}")
            if s.get("mu_static") is not None and [float(x) for x in s["mu_static"]] != mu:
                raise ValueError(f"stacks[{si}].mu_static differs from mu: static friction "
                                 f"above kinetic cannot be modelled by an elastic-plastic "
                                 f"spring")
            masses = [a * fm[floor - 1] for a in alpha]
            load[floor - 1] += sum(alpha)
            idx = []
            for bi, m in enumerate(masses):
                k = len(self.block_m)
                idx.append(k)
                self.block_m.append(m)
                self.block_below.append(floor if bi == 0 else n + k)  # node tags
                self.block_mu.append(mu[bi])
                self.block_limit.append(mu[bi] * G * sum(masses[bi:]))
                self.block_floor.append(floor)
            self.stacks.append({"floor": floor, "blocks": idx})
        # Stiffness scaled to the first period; damping from the named basis.
        w2rel, _ = modes(fm, ks)
        omega1 = 2 * math.pi / self.period
        sc = omega1 ** 2 / w2rel[0]
        self.k = [x * sc for x in ks]
        self.omega1 = omega1
        self.periods = [2 * math.pi / math.sqrt(w * sc) for w in w2rel]
        self.basis_m = (fm if self.basis == "structure"
                        else [m * (1 + a) for m, a in zip(fm, load, strict=True)])
        self.C = modal_damping(self.basis_m, self.k, self.zeta)
        self.fy = None
        self.r = 0.0
        if self.structure != "elastic":
            cy = b.get("yield_strength_ratios")
            if cy is None or len(cy) != n:
                raise ValueError(f"invalid case: building.yield_strength_ratios must list {n} "
                                 f"values for a {self.structure} building")
            self.r = float(b.get("post_yield_ratio", 0.0)) if self.structure == "bilinear" else 0.0
            if not (math.isfinite(self.r) and 0 <= self.r < 1):
                raise ValueError(f"invalid case: building.post_yield_ratio = {self.r!r}")
            above = sum(fm)
            self.fy = []
            for i in range(n):
                c = float(cy[i])
                if not (math.isfinite(c) and c > 0):
                    raise ValueError(f"invalid case: building.yield_strength_ratios[{i}] = {c!r}")
                self.fy.append(c * G * above)
                above -= fm[i]

    def block_node(self, k: int) -> int:
        return self.n + 1 + k

    def mass_matrix(self, with_blocks: bool):
        """Diagonal masses of the floors, with every block's mass added to its floor or not."""
        m = list(self.floor_m)
        if with_blocks:
            for bm, f in zip(self.block_m, self.block_floor, strict=True):
                m[f - 1] += bm
        return np.diag(m)


# --------------------------------------------------------------------------- the model

def build(ops, bld: Building, dt: float, accel_g, stick_stiffness: float, friction: str,
          dashpots: bool = True) -> list:
    """Defines the model, ground motion and analysis in a wiped OpenSees domain. Returns the
    element tag of each block's interface below it (None where μ = 0: no element)."""
    if friction not in FRICTIONS:
        raise ValueError(f"friction must be one of {FRICTIONS}, got {friction!r}")
    if not (math.isfinite(stick_stiffness) and stick_stiffness > 0):
        raise ValueError(f"stick_stiffness must be > 0, got {stick_stiffness!r}")
    if not (math.isfinite(dt) and dt > 0) or len(accel_g) < 2:
        raise ValueError("invalid record: dt must be > 0 and there must be 2 samples or more")
    two_d = friction == "flatslider"
    ops.wipe()
    if two_d:
        ops.model("basic", "-ndm", 2, "-ndf", 3)
    else:
        ops.model("basic", "-ndm", 1, "-ndf", 1)

    def node(tag, mass=None, fixed_vertical=True):
        coords = (0.0, 0.0) if two_d else (0.0,)
        if mass is None:
            ops.node(tag, *coords)
        elif two_d:
            ops.node(tag, *coords, "-mass", float(mass), 0.0, 0.0)
        else:
            ops.node(tag, *coords, "-mass", float(mass))
        if two_d:
            ops.fix(tag, 1 if mass is None else 0, 1 if fixed_vertical else 0, 1)
        elif mass is None:
            ops.fix(tag, 1)

    n = bld.n
    node(0)
    for j in range(1, n + 1):
        node(j, bld.floor_m[j - 1])
    for k, m in enumerate(bld.block_m):
        node(bld.block_node(k), m, fixed_vertical=not two_d)
    tag = 0

    def zero_length(i, j, mat):
        nonlocal tag
        tag += 1
        ops.element("zeroLength", tag, i, j, "-mat", mat, "-dir", 1)

    for i in range(n):
        tag_m = tag + 1
        if bld.fy is None:
            ops.uniaxialMaterial("Elastic", tag_m, bld.k[i])
        else:
            ops.uniaxialMaterial("Steel01", tag_m, bld.fy[i], bld.k[i], bld.r)
        zero_length(i, i + 1, tag_m)
    if dashpots:
        C = bld.C
        scale_c = float(np.abs(C).max()) or 1.0
        for i in range(n):
            for j in range(-1, i):  # j = −1: to the ground (node 0)
                c = float(C[i].sum()) if j < 0 else -float(C[i, j])
                if abs(c) <= 1e-15 * scale_c:
                    continue
                ops.uniaxialMaterial("Elastic", tag + 1, 0.0, c)
                zero_length(0 if j < 0 else j + 1, i + 1, tag + 1)
    gravity = []
    friction_tags: list = [None] * len(bld.block_m)
    for k, (m, below, mu, lim) in enumerate(zip(bld.block_m, bld.block_below, bld.block_mu,
                                                 bld.block_limit, strict=True)):
        ks = stick_stiffness * bld.omega1 ** 2 * bld.floor_m[bld.block_floor[k] - 1]
        if two_d:
            if mu == 0.0:
                raise ValueError("flatslider with mu = 0: the bearing would carry no shear and "
                                 "the gravity step would be singular (use elasticpp)")
            tag += 1
            ops.frictionModel("Coulomb", tag, mu)
            ops.uniaxialMaterial("Elastic", tag + 1, 1e3 * ks)
            ops.uniaxialMaterial("Elastic", tag + 2, 1e3 * ks)
            ops.element("flatSliderBearing", tag + 3, below, bld.block_node(k), tag, ks,
                        "-P", tag + 1, "-Mz", tag + 2, "-orient", 0, 1, 0, -1, 0, 0)
            tag += 3
            friction_tags[k] = tag
            gravity.append((bld.block_node(k), m * G))
        elif lim > 0.0:
            tag += 1
            ops.uniaxialMaterial("ElasticPP", tag, ks, lim / ks)
            zero_length(below, bld.block_node(k), tag)
            friction_tags[k] = tag
    ops.constraints("Plain")
    ops.numberer("Plain")
    ops.system("FullGeneral")
    ops.test("NormDispIncr", 1e-12, 20)
    ops.algorithm("Newton")
    if gravity:
        ops.timeSeries("Constant", 2)
        ops.pattern("Plain", 2, 2)
        for nd, w in gravity:
            ops.load(nd, 0.0, -w, 0.0)
        ops.integrator("LoadControl", 1.0)
        ops.analysis("Static")
        if ops.analyze(1) != 0:
            raise RuntimeError("the gravity step failed")
        ops.loadConst("-time", 0.0)
        ops.wipeAnalysis()
        ops.constraints("Plain")
        ops.numberer("Plain")
        ops.system("FullGeneral")
        ops.test("NormDispIncr", 1e-12, 20)
        ops.algorithm("Newton")
    ops.timeSeries("Path", 1, "-dt", dt, "-values", *map(float, accel_g),
                   "-factor", G * bld.scale, "-useLast")
    ops.pattern("UniformExcitation", 1, 1, "-accel", 1)
    ops.integrator("Newmark", 0.5, 0.25)
    ops.analysis("Transient")
    # At t = 0 every spring and damper force is zero: every mass accelerates at −a_g(0).
    a0 = -G * bld.scale * float(accel_g[0])
    for nd in list(range(1, n + 1)) + [bld.block_node(k) for k in range(len(bld.block_m))]:
        ops.setNodeAccel(nd, 1, a0, "-commit")
    return friction_tags


def stuck_test(ops, bld: Building, friction_tags, friction: str):
    """stuck(k): whether block k's interface below it carries less than its friction limit
    after the step (sticks), from its element's force. No element (μ = 0): never stuck."""
    if friction == "flatslider":
        def stuck(k: int) -> bool:
            tag = friction_tags[k]
            if tag is None:
                return False
            q = ops.eleResponse(tag, "basicForce")  # [axial, shear, moment]; axial < 0
            return abs(q[1]) < (1.0 - 1e-9) * bld.block_mu[k] * -q[0]
    else:
        def stuck(k: int) -> bool:
            tag = friction_tags[k]
            return tag is not None and abs(ops.eleForce(tag)[1]) < (1.0 - 1e-9) * bld.block_limit[k]
    return stuck


def analyse(ops, bld: Building, dt: float, accel_g, steps_per_sample: int,
            history: bool = False, friction_tags=None, friction: str = "elasticpp",
            step_history: bool = False) -> dict:
    """Runs the built model over the record, reading the state after every converged step.

    A floor's absolute acceleration is that of the floor and the blocks stuck to it (their
    mass-weighted mean, ``friction_tags`` from ``build`` telling which interfaces stick): the
    penalty spring of a sticking interface rings at its stick frequency after every jump of
    the friction force on the blocks above, undamped by Newmark's average acceleration rule and
    with an amplitude that does not shrink as s grows; the floor node's own acceleration
    carries that ringing, the stuck cluster's does not (docs/opensees-building.md, "The roof's
    acceleration and the stick springs' ringing"). The node's own is reported too."""
    if steps_per_sample < 1:
        raise ValueError(f"steps_per_sample must be >= 1, got {steps_per_sample}")
    n = bld.n
    nb = len(bld.block_m)
    floors = range(1, n + 1)
    blocks = [(bld.block_node(k), bld.block_below[k]) for k in range(nb)]
    if friction_tags is None:
        friction_tags = [None] * nb
    stuck = stuck_test(ops, bld, friction_tags, friction)
    on_floor = [[st["blocks"] for st in bld.stacks if st["floor"] == j] for j in floors]
    ag = [G * bld.scale * float(a) for a in accel_g]
    last = len(ag) - 1
    peak_u = [0.0] * n
    peak_a = [0.0] * n
    peak_an = [0.0] * n
    peak_d = [0.0] * n
    peak_s = [0.0] * nb
    u = [0.0] * n
    hist = [[0.0] * n] if history else None
    h = dt / steps_per_sample
    count = {"steps": 0, "split": 0}
    node_disp, node_accel, get_time = ops.nodeDisp, ops.nodeAccel, ops.getTime
    steps_rows = [] if step_history else None

    def read() -> None:
        count["steps"] += 1
        t = get_time()
        x = t / dt
        i = min(int(x), last - 1)
        a_g = ag[i] + (ag[i + 1] - ag[i]) * (x - i)
        below = 0.0
        row = [t, a_g] if step_history else None
        for j in floors:
            uj = node_disp(j, 1)
            u[j - 1] = uj
            if abs(uj) > peak_u[j - 1]:
                peak_u[j - 1] = abs(uj)
            a_node = node_accel(j, 1) + a_g
            mass, mom = bld.floor_m[j - 1], bld.floor_m[j - 1] * a_node
            for chain in on_floor[j - 1]:
                for k in chain:  # bottom-up: stuck to the floor while every interface below is
                    if not stuck(k):
                        break
                    mass += bld.block_m[k]
                    mom += bld.block_m[k] * (node_accel(blocks[k][0], 1) + a_g)
            a = abs(mom / mass)
            if a > peak_a[j - 1]:
                peak_a[j - 1] = a
            if abs(a_node) > peak_an[j - 1]:
                peak_an[j - 1] = abs(a_node)
            if step_history:
                row += [uj, a_node, mom / mass]
            d = abs(uj - below)
            if d > peak_d[j - 1]:
                peak_d[j - 1] = d
            below = uj
        for k, (nd, bl) in enumerate(blocks):
            s = abs(node_disp(nd, 1) - node_disp(bl, 1))
            if s > peak_s[k]:
                peak_s[k] = s
        if step_history:
            for k, (nd, bl) in enumerate(blocks):
                tag = friction_tags[k]
                force = 0.0 if tag is None else (
                    ops.eleResponse(tag, "basicForce")[1] if friction == "flatslider"
                    else ops.eleForce(tag)[1])
                row += [node_disp(nd, 1) - node_disp(bl, 1), node_accel(nd, 1) + a_g, force,
                        1.0 if stuck(k) else 0.0]
            steps_rows.append(row)

    def step(size: float, depth: int) -> None:
        if ops.analyze(1, size) == 0:
            read()
            return
        if depth == MAX_HALVINGS:
            raise RuntimeError(f"Newton does not converge at t = {get_time() + size:.6g} s "
                               f"even with the step halved {MAX_HALVINGS} times ({size:.3g} s)")
        if depth == 0:
            count["split"] += 1
        step(size / 2, depth + 1)
        step(size / 2, depth + 1)

    for _ in range(last):
        for _ in range(steps_per_sample):
            step(h, 0)
        if history:
            hist.append(list(u))
    drift = [u[0]] + [u[j] - u[j - 1] for j in range(1, n)]
    slip = [node_disp(nd, 1) - node_disp(bl, 1) for nd, bl in blocks]
    return {"floor_peak_displacement_m": peak_u,
            "floor_peak_abs_accel_g": [a / G for a in peak_a],
            "floor_peak_node_abs_accel_g": [a / G for a in peak_an],
            "storey_peak_drift_m": peak_d,
            "storey_residual_drift_m": drift,
            "stacks": [{"floor": s["floor"],
                        "peak_slip_m": [peak_s[k] for k in s["blocks"]],
                        "residual_slip_m": [slip[k] for k in s["blocks"]]}
                       for s in bld.stacks],
            "steps": count["steps"], "split_steps": count["split"],
            **({"floor_u_m": hist} if history else {}),
            **({"step_history": {"columns": step_columns(bld), "rows": steps_rows}}
               if step_history else {})}


def step_columns(bld: Building) -> list[str]:
    """The columns of ``step_history``: time, ground acceleration, per floor its displacement,
    its node's absolute acceleration and the absolute acceleration of it with its stuck blocks
    (the one reported), per block (stacks in order, each bottom-up) its slip on the body below,
    its absolute acceleration, its interface's force and whether that interface sticks."""
    cols = ["time_s", "ground_accel_mps2"]
    for j in range(1, bld.n + 1):
        cols += [f"floor{j}_disp_m", f"floor{j}_node_abs_accel_mps2", f"floor{j}_abs_accel_mps2"]
    names = [""] * len(bld.block_m)
    for si, st in enumerate(bld.stacks):
        for b, k in enumerate(st["blocks"]):
            names[k] = f"stack{si + 1}_block{b + 1}"
    for name in names:
        cols += [f"{name}_slip_m", f"{name}_abs_accel_mps2", f"{name}_interface_force_n",
                 f"{name}_interface_stuck"]
    return cols


NULLS = ("wall_s", "cpu_s", "floor_peak_displacement_m", "floor_peak_abs_accel_g",
         "floor_peak_node_abs_accel_g",
         "storey_peak_drift_m", "storey_residual_drift_m", "stacks", "steps", "split_steps")


def simulate(ops, bld: Building, dt: float, accel_g, steps_per_sample: int,
             stick_stiffness: float, friction: str = "elasticpp", history: bool = False,
             step_history: bool = False) -> dict:
    """One analysis: {"ok", "message", "wall_s", "cpu_s", outputs…}."""
    logged = oss.log_size()
    w0, c0 = time.perf_counter(), time.thread_time()
    try:
        tags = build(ops, bld, dt, accel_g, stick_stiffness, friction)
        out = analyse(ops, bld, dt, accel_g, steps_per_sample, history, tags, friction,
                      step_history)
    except Exception as e:  # noqa: BLE001 - OpenSeesError, bad input: reported, not raised
        ops.wipe()
        tail = oss.log_tail(logged)
        return {"ok": False, "message": f"{type(e).__name__}: {e}"
                + (f" (OpenSees log: {tail})" if tail else ""), **dict.fromkeys(NULLS)}
    cpu, wall = time.thread_time() - c0, time.perf_counter() - w0
    ops.wipe()
    flat = (out["floor_peak_displacement_m"] + out["storey_residual_drift_m"]
            + [x for s in out["stacks"] for x in s["residual_slip_m"]])
    if not all(math.isfinite(x) for x in flat):
        return {"ok": False, "message": "non-finite response", **dict.fromkeys(NULLS)}
    msg = "converged" + (f"; {out['split_steps']} of {(len(accel_g) - 1) * steps_per_sample} "
                         f"steps split" if out["split_steps"] else "")
    return {"ok": True, "message": msg, "wall_s": wall, "cpu_s": cpu, **out}


def run_case(ops, case: dict) -> dict:
    """All runs of one protocol case; times are medians over ``repeats`` analyses."""
    bld = Building(case)
    dt, accel = float(case["dt_s"]), case["accel_g"]
    repeats = max(1, int(case.get("repeats", 1)))
    history = bool(case.get("history", False))
    step_history = bool(case.get("step_history", False))
    runs = []
    for r in case["runs"]:
        sps, s = int(r["steps_per_sample"]), float(r["stick_stiffness"])
        fr = r.get("friction", "elasticpp")
        walls, cpus, res = [], [], None
        for _ in range(repeats):
            res = simulate(ops, bld, dt, accel, sps, s, fr, history, step_history)
            if not res["ok"]:
                break
            walls.append(res["wall_s"])
            cpus.append(res["cpu_s"])
        if res["ok"]:
            res["wall_s"], res["cpu_s"] = statistics.median(walls), statistics.median(cpus)
        runs.append({"steps_per_sample": sps, "stick_stiffness": s, "friction": fr,
                     "modes_s": bld.periods, **res})
    return {"id": case.get("id", ""), "modes_s": bld.periods,
            "storey_stiffness_n_per_m": bld.k, "damping_matrix": bld.C.tolist(), "runs": runs}


# --------------------------------------------------------------------------- exact references

def phi12(z: complex) -> tuple[complex, complex]:
    """φ₁(z) = (e^z − 1)/z and φ₂(z) = (e^z − 1 − z)/z²; by their series near 0."""
    if abs(z) < 0.25:
        p1 = sum(z ** k / math.factorial(k + 1) for k in range(18))
        p2 = sum(z ** k / math.factorial(k + 2) for k in range(18))
        return p1, p2
    e = cmath.exp(z)
    return (e - 1) / z, (e - 1 - z) / (z * z)


def exact_linear(M, C, K, load, ag, dt):
    """The exact response of M·ü + C·u̇ + K·u = −M·load·a_g(t), a_g linear between samples,
    from rest: (u at every sample, −M⁻¹(C·u̇ + K·u) at every sample: the absolute
    acceleration when load is all ones), arrays (samples × dofs). In the eigenvectors of the
    state matrix each mode is the scalar equation ẏ = λy + b·a_g(t), solved exactly per
    interval: y ← e^{λh}y + h·φ₁(λh)·b·a₀ + h·φ₂(λh)·b·(a₁ − a₀)."""
    n = M.shape[0]
    minv = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-minv @ K, -minv @ C]])
    lam, V = np.linalg.eig(A)
    b = np.linalg.solve(V, np.concatenate([np.zeros(n), -np.asarray(load, dtype=float)]))
    z = lam * dt
    e = np.exp(z)
    p = np.array([phi12(complex(x)) for x in z])
    c0, c1 = dt * p[:, 0] * b, dt * p[:, 1] * b
    y = np.zeros(2 * n, dtype=complex)
    zs = [np.zeros(2 * n)]
    for k in range(1, len(ag)):
        y = e * y + c0 * ag[k - 1] + c1 * (ag[k] - ag[k - 1])
        zs.append((V @ y).real)
    zs = np.array(zs)
    u, v = zs[:, :n], zs[:, n:]
    return u, -(minv @ (C @ v.T + K @ u.T)).T


def modal_reference(bld: Building, ag, dt):
    """The bare building (C classical in its own modes): each mode an exact SDOF."""
    M = bld.mass_matrix(False)
    w2, phi = modes(bld.floor_m, bld.k)
    modal_c = phi.T @ bld.C @ phi
    off = np.abs(modal_c - np.diag(np.diag(modal_c))).max() / np.abs(np.diag(modal_c)).max()
    u = np.zeros((len(ag), bld.n))
    acc = np.zeros((len(ag), bld.n))
    gamma = phi.T @ M @ np.ones(bld.n)
    for r in range(bld.n):
        q, qa = exact_linear(np.eye(1), np.array([[modal_c[r, r]]]), np.array([[w2[r]]]),
                             [gamma[r]], ag, dt)
        u += q[:, :1] * phi[:, r][None, :]
        # qa = −(c_r·q̇_r + ω_r²·q_r) = q̈_r + Γ_r·a_g, and Σ_r φ_r·Γ_r = 1 (the ones vector),
        # so Σ_r φ_r·qa_r = ü + a_g, the floors' absolute acceleration.
        acc += qa[:, :1] * phi[:, r][None, :]
    return u, acc, off


# --------------------------------------------------------------------------- --check

def check_damping_assembly(ops, bld: Building) -> float:
    """max |C_OpenSees − C| / max |C|, C_OpenSees from the assembled Newmark matrix
    A = K + γ/(βh)·C + M/(βh²) at two step sizes (elimination of K and M)."""
    n = bld.n
    accel = [0.0, 0.0, 0.0]
    mats = []
    for h in (1e-2, 2e-2):
        ops.wipe()
        ops.model("basic", "-ndm", 1, "-ndf", 1)
        ops.node(0, 0.0)
        ops.fix(0, 1)
        # blocks rigidly on their floors for the assembly: their masses on the floors
        m = np.diag(bld.mass_matrix(True))
        for j in range(1, n + 1):
            ops.node(j, 0.0, "-mass", float(m[j - 1]))
        tag = 0
        for i in range(n):
            tag += 1
            ops.uniaxialMaterial("Elastic", tag, bld.k[i])
            ops.element("zeroLength", tag, i, i + 1, "-mat", tag, "-dir", 1)
        C = bld.C
        for i in range(n):
            for j in range(-1, i):
                c = float(C[i].sum()) if j < 0 else -float(C[i, j])
                tag += 1
                ops.uniaxialMaterial("Elastic", tag, 0.0, c)
                ops.element("zeroLength", tag, 0 if j < 0 else j + 1, i + 1, "-mat", tag,
                            "-dir", 1)
        ops.timeSeries("Path", 1, "-dt", 0.01, "-values", *accel, "-factor", G)
        ops.pattern("UniformExcitation", 1, 1, "-accel", 1)
        ops.constraints("Plain")
        ops.numberer("Plain")
        ops.system("FullGeneral")
        ops.test("NormDispIncr", 1e-12, 5)
        ops.algorithm("Linear")
        ops.integrator("Newmark", 0.5, 0.25)
        ops.analysis("Transient")
        if ops.analyze(1, h) != 0:
            raise RuntimeError("assembly step failed")
        mats.append((h, np.array(ops.printA("-ret")).reshape(n, n), np.diag(m)))
        ops.wipe()
    (h1, a1, mm), (h2, a2, _) = mats
    # A(h) = K + 2/h·C + 4/h²·M  (γ = 1/2, β = 1/4); K eliminated by the difference.
    # a1 − a2 = 2C(1/h1 − 1/h2) + 4M(1/h1² − 1/h2²)
    c_os = ((a1 - a2) - 4 * mm * (1 / h1 ** 2 - 1 / h2 ** 2)) / (2 * (1 / h1 - 1 / h2))
    return float(np.abs(c_os - bld.C).max() / np.abs(bld.C).max())


def check_eigen(ops, bld: Building) -> float:
    ops.wipe()
    ops.model("basic", "-ndm", 1, "-ndf", 1)
    ops.node(0, 0.0)
    ops.fix(0, 1)
    for j in range(1, bld.n + 1):
        ops.node(j, 0.0, "-mass", float(bld.floor_m[j - 1]))
        ops.uniaxialMaterial("Elastic", j, bld.k[j - 1])
        ops.element("zeroLength", j, j - 1, j, "-mat", j, "-dir", 1)
    ops.constraints("Plain")
    ops.numberer("Plain")
    ops.system("FullGeneral")
    ops.algorithm("Linear")
    ops.integrator("LoadControl", 1.0)
    ops.analysis("Static")
    w2 = ops.eigen("-fullGenLapack", bld.n)
    ops.wipe()
    per = [2 * math.pi / math.sqrt(x) for x in w2]
    return max(abs(a / b - 1) for a, b in zip(per, bld.periods, strict=True))


def rel_peaks(run: dict, ref: dict) -> dict:
    """Differences of run from ref, each the largest over floors / storeys / interfaces:
    peaks relative to ref's peak, residuals relative to ref's peak of the same quantity."""
    def worst(key_a, key_b=None, scale_key=None):
        a, b = run[key_a], ref[key_a]
        sc = ref[scale_key] if scale_key else b
        return max(abs(x - y) / s for x, y, s in zip(a, b, sc, strict=True) if s > 0) \
            if any(s > 0 for s in sc) else 0.0

    out = {"disp": worst("floor_peak_displacement_m"),
           "accel": worst("floor_peak_abs_accel_g"),
           "drift": worst("storey_peak_drift_m"),
           "res_drift": worst("storey_residual_drift_m", scale_key="storey_peak_drift_m")}
    ps = [x for s in run["stacks"] for x in s["peak_slip_m"]]
    pr = [x for s in ref["stacks"] for x in s["peak_slip_m"]]
    rs = [x for s in run["stacks"] for x in s["residual_slip_m"]]
    rr = [x for s in ref["stacks"] for x in s["residual_slip_m"]]
    if pr:
        out["slip"] = max((abs(a - b) / b for a, b in zip(ps, pr, strict=True) if b > 0),
                          default=0.0)
        out["res_slip"] = max((abs(a - b) / p for a, b, p in zip(rs, rr, pr, strict=True)
                               if p > 0), default=0.0)
    return out


def reference_outputs(u, acc):
    """Peaks over the time points of an exact history (samples × floors), in a run's terms."""
    n = u.shape[1]
    drift = np.diff(np.concatenate([np.zeros((u.shape[0], 1)), u], axis=1), axis=1)
    return {"floor_peak_displacement_m": list(np.abs(u).max(axis=0)),
            "floor_peak_abs_accel_g": list(np.abs(acc).max(axis=0) / G),
            "storey_peak_drift_m": list(np.abs(drift).max(axis=0)),
            "storey_residual_drift_m": list(drift[-1]), "stacks": [], "n": n}


def phantom_slips(ops, bld: Building, dt: float, accel, steps_per_sample: int,
                  stick_stiffness: float):
    """flatslider model: (number of steps after which a bearing's committed plastic slip
    changed while its force was below μN, the time of the first)."""
    build(ops, bld, dt, accel, stick_stiffness, "flatslider")
    bearings = [t for t in ops.getEleTags() if ops.eleType(t) == "FlatSliderSimple2d"]
    mus = [m for m in bld.block_mu]
    ks = [stick_stiffness * bld.omega1 ** 2 * bld.floor_m[f - 1] for f in bld.block_floor]
    plastic = [0.0] * len(bearings)
    count, first = 0, None
    h = dt / steps_per_sample
    for _ in range((len(accel) - 1) * steps_per_sample):
        if ops.analyze(1, h) != 0:
            break
        bad = False
        for i, t in enumerate(bearings):
            q = ops.eleResponse(t, "basicForce")
            ub = ops.eleResponse(t, "basicDeformation")
            p = ub[1] - q[1] / ks[i]
            if abs(p - plastic[i]) > 1e-12 + 1e-9 * abs(p) and abs(q[1]) < (1 - 1e-9) * mus[i] * -q[0]:
                bad = True
            plastic[i] = p
        if bad:
            count += 1
            first = ops.getTime() if first is None else first
    ops.wipe()
    return count, first


def fmt(x: float) -> str:
    return f"{x:.1e}"


def check(args) -> None:
    ops = oss.import_opensees_or_exit()
    out: list[str] = []

    def say(text: str = "") -> None:
        print(text, flush=True)
        out.append(text)

    recs = REPO / "tests/fixtures/records"
    rec = "RSN960_NORTHR_LOS270.AT2"
    accel, dt = oss.read_at2(recs / rec)
    ag = [G * a for a in accel]
    doc_building = {"storeys": 3, "period": 0.6, "floor_masses": [1, 1, 1],
                    "storey_stiffnesses": [3, 2, 1], "structure": "elastic"}
    doc_stacks = [{"floor": 3, "alpha": [0.5, 0.5], "mu": [0.2, 0.1]},
                  {"floor": 1, "alpha": [1.0], "mu": [0.3]}]
    tall = {"storeys": 6, "period": 1.2, "floor_masses": [1.5, 1.2, 1.0, 1.0, 0.8, 0.6],
            "storey_stiffnesses": [6, 5, 4, 3, 2, 1], "structure": "elastic"}
    say(f"OpenSees {oss.opensees_version(ops)}, numpy {np.__version__}; record {rec} "
        f"({len(accel)} samples, dt {dt} s), scale 1.\n")

    # 1-2. assembly of C and the periods
    say("### 1-2. The damping matrix as assembled, and the periods\n")
    say("| building | basis | max abs(C_OpenSees − C) / max abs(C) | max abs(T_OpenSees/T − 1) |")
    say("|---|---|---|---|")
    for name, b, stacks in (("3 storeys [3,2,1], T 0.6 s, doc stacks", doc_building, doc_stacks),
                            ("6 storeys, T 1.2 s, bare", tall, [])):
        for basis in ("rigid", "structure"):
            bld = Building({"building": b, "stacks": stacks, "damping": 0.05,
                            "damping_basis": basis})
            say(f"| {name} | {basis} | {fmt(check_damping_assembly(ops, bld))} | "
                f"{fmt(check_eigen(ops, bld))} |")
    say()

    # 3. bare buildings against the modal solution
    sps_list = [1, 2, 5, 10, 20] if args.quick else [1, 2, 5, 10, 20, 50, 100]
    say("### 3. Bare elastic buildings against the exact modal solution\n")
    say("Cells: floor history, max over floors and samples of abs(u − u_exact) / max peak; "
        "the peak floor displacement, storey drift and floor absolute acceleration, and the "
        "residual drift, each the largest relative difference over floors / storeys (peaks "
        "over OpenSees's steps for both: the exact solution is evaluated on the same time "
        "grid, a_g being linear between samples); CPU time of one analysis.\n")
    for name, b, zeta in (("3 storeys [3,2,1], T 0.6 s, ζ 0.05", doc_building, 0.05),
                          ("6 storeys, T 1.2 s, ζ 0.03", tall, 0.03)):
        bld = Building({"building": b, "damping": zeta, "damping_basis": "structure"})
        say(f"#### {name}; periods {', '.join(f'{p:.4f}' for p in bld.periods)} s\n")
        off = None
        say("| steps/sample | history | peak displacement | peak drift | peak abs. acceleration "
            "| residual drift | CPU s |")
        say("|---|---|---|---|---|---|---|")
        errs = []
        for sps in sps_list:
            fine = [a + (b2 - a) * q / sps for a, b2 in zip(ag, ag[1:]) for q in range(sps)]
            fine.append(ag[-1])
            u_ex, a_ex, off = modal_reference(bld, fine, dt / sps)
            ref = reference_outputs(u_ex, a_ex)
            u_ex = u_ex[::sps]
            peak = np.abs(u_ex).max()
            r = simulate(ops, bld, dt, accel, sps, 1.0, history=True)
            if not r["ok"]:
                say(f"| {sps} | failed: {r['message']} | | | | | |")
                continue
            u = np.array(r["floor_u_m"])
            e_hist = float(np.abs(u - u_ex).max() / peak)
            d = rel_peaks(r, ref)
            errs.append((sps, e_hist))
            say(f"| {sps} | {fmt(e_hist)} | {fmt(d['disp'])} | {fmt(d['drift'])} | "
                f"{fmt(d['accel'])} | {fmt(d['res_drift'])} | {r['cpu_s']:.3g} |")
        orders = [f"{a}→{b}: {math.log(ea / eb) / math.log(b / a):.2f}"
                  for (a, ea), (b, eb) in zip(errs, errs[1:])]
        say("\nobserved order of the history difference: " + ", ".join(orders)
            + f". The damping matrix in the modes, ΦᵀCΦ: largest off-diagonal / largest "
              f"diagonal {fmt(off)} (classical, so the modes decouple).\n")

    # 4. unslidable stacks, non-classical damping
    say("### 4. Stacks that cannot slide (μ = 5), `structure` basis, against the exact "
        "building with the blocks' masses added\n")
    stacks5 = [{**s, "mu": [5.0] * len(s["mu"])} for s in doc_stacks]
    bld = Building({"building": doc_building, "stacks": stacks5, "damping": 0.05,
                    "damping_basis": "structure"})
    M_t = bld.mass_matrix(True)
    w2, phi = modes(list(np.diag(M_t)), bld.k)
    modal_c = phi.T @ bld.C @ phi
    off = np.abs(modal_c - np.diag(np.diag(modal_c))).max() / np.abs(np.diag(modal_c)).max()
    u_ex, a_ex = exact_linear(M_t, bld.C, stiffness_matrix(bld.k), np.ones(bld.n), ag, dt)
    ref = reference_outputs(u_ex, a_ex)
    peak = np.abs(u_ex).max()
    say(f"C in the loaded building's modes: largest off-diagonal / largest diagonal "
        f"{fmt(off)} (not classical), so the reference is the state-space solution (2N "
        f"complex modes, each exact). Cell: floor history difference / peak; CPU s.\n")
    stiffs = [1e2, 1e3, 1e4, 1e5, 1e6]
    sps4 = [1, 5, 20] if args.quick else [1, 2, 5, 10, 20, 50]
    say("| steps/sample | " + " | ".join(f"s = {s:.0e}" for s in stiffs) + " |")
    say("|---" * (len(stiffs) + 1) + "|")
    for sps in sps4:
        cells = []
        for s in stiffs:
            r = simulate(ops, bld, dt, accel, sps, s, history=True)
            if not r["ok"]:
                cells.append("failed")
                continue
            e = float(np.abs(np.array(r["floor_u_m"]) - u_ex).max() / peak)
            cells.append(f"{fmt(e)}; {r['cpu_s']:.2g}")
        say(f"| {sps} | " + " | ".join(cells) + " |")
    say()

    # 5. the comparison case: self-convergence
    say("### 5. The comparison case (sliding stacks): convergence in s and h\n")
    case = {"building": doc_building, "stacks": doc_stacks, "damping": 0.05,
            "damping_basis": "rigid"}
    bld = Building(case)
    fine_sps = 50 if args.quick else 100
    s_list = [1e3, 1e4, 1e5, 1e6] if args.quick else [1e3, 1e4, 1e5, 1e6, 1e7]
    say(f"#### 5a. The stick stiffness s at {fine_sps} steps/sample\n")
    say("Floor 3's peak displacement and absolute acceleration, the peak and residual slip of "
        "floor 3's bottom interface; Δ the change from the row above; CPU time.\n")
    say("| s | floor 3 peak disp. (m) | Δ | floor 3 peak abs. accel. (g) | peak slip (m) | Δ | "
        "residual slip (m) | CPU s | split steps |")
    say("|---|---|---|---|---|---|---|---|---|")
    ref, prev = None, None
    for s in s_list:
        r = simulate(ops, bld, dt, accel, fine_sps, s)
        if not r["ok"]:
            say(f"| {s:.0e} | failed: {r['message']} | | | | | | | |")
            continue
        u3 = r["floor_peak_displacement_m"][2]
        sl = r["stacks"][0]["peak_slip_m"][0]
        d1 = f"{u3 - prev[0]:.2e}" if prev else ""
        d2 = f"{sl - prev[1]:.2e}" if prev else ""
        say(f"| {s:.0e} | {u3:.7f} | {d1} | {r['floor_peak_abs_accel_g'][2]:.5f} | {sl:.6f} | "
            f"{d2} | {r['stacks'][0]['residual_slip_m'][0]:.6f} | {r['cpu_s']:.3g} | "
            f"{r['split_steps']} |")
        prev = (u3, sl)
        ref = r
    if ref is None:
        say("every run failed")
        ref = {"ok": False}
    say()
    if ref["ok"]:
        say(f"#### 5b. Steps per sample and stick stiffness against the run at s = "
            f"{s_list[-1]:.0e}, {fine_sps} steps/sample\n")
        say("Cells: the largest relative difference over floors / storeys / interfaces "
            "(residuals over the peak of the same quantity).\n")
        say("| s | steps/sample | floor disp. | floor abs. accel. | drift | residual drift | "
            "peak slip | residual slip | CPU s | split steps |")
        say("|---|---|---|---|---|---|---|---|---|---|")
        settings = [(s, sps) for s in (1e2, 1e3, 1e4, 1e5, 1e6)
                    for sps in ((1, 10) if args.quick else (1, 5, 20, 50))]
        for s, sps in settings:
            r = simulate(ops, bld, dt, accel, sps, s)
            if not r["ok"]:
                say(f"| {s:.0e} | {sps} | failed: {r['message']} | | | | | | | |")
                continue
            d = rel_peaks(r, ref)
            say(f"| {s:.0e} | {sps} | {fmt(d['disp'])} | {fmt(d['accel'])} | "
                f"{fmt(d['drift'])} | {fmt(d['res_drift'])} | {fmt(d['slip'])} | "
                f"{fmt(d['res_slip'])} | {r['cpu_s']:.3g} | {r['split_steps']} |")
        say()

    # 6. one storey
    say("### 6. One storey, one stack: against scripts/opensees_stack.py and slidestack\n")
    alpha, mu = [0.5, 0.5], [0.2, 0.1]
    bld = Building({"building": {"storeys": 1, "period": 1.0}, "damping": 0.05,
                    "damping_basis": "rigid",
                    "stacks": [{"floor": 1, "alpha": alpha, "mu": mu}]})
    zeta_bare = 0.05 * math.sqrt(1 + sum(alpha))  # the rigid basis's damper as a bare ratio
    slidestack = (args.slidestack or os.environ.get("SLIDESTACK")
                  or str(REPO / "target/release/slidestack"))
    ss = None
    if Path(slidestack).exists():
        ss, js = oss.slidestack_history(slidestack, recs / rec, 1.0, 0.05, alpha, mu)
        ss_peak = js["peak_displacement_m"]
    say("| steps/sample | s | history vs opensees_stack.py | split steps (this / "
        "opensees_stack.py) | history vs slidestack | peak vs slidestack's exact peak |")
    say("|---|---|---|---|---|---|")
    for sps, s in ((1, 1e4), (10, 1e4), (10, 1e5), (50, 1e5)):
        r = simulate(ops, bld, dt, accel, sps, s, history=True)
        o = oss.simulate(ops, dt, accel, 1.0, zeta_bare, alpha, mu, sps, s)
        if not (r["ok"] and o["ok"]):
            say(f"| {sps} | {s:.0e} | failed | | | |")
            continue
        u = [row[0] for row in r["floor_u_m"]]
        h1 = max(abs(x - y) for x, y in zip(u, o["u_m"], strict=True)) / o["peak_m"]
        theirs = o["message"].split(";")[1].split(" of")[0].strip() if ";" in o["message"] \
            else "0"
        cells = [fmt(h1), f"{r['split_steps']} / {theirs}"]
        if ss is not None:
            _, h2 = oss.compare(u, ss)
            cells += [fmt(h2), fmt(abs(r["floor_peak_displacement_m"][0] / ss_peak - 1))]
        else:
            cells += ["no slidestack", ""]
        say(f"| {sps} | {s:.0e} | " + " | ".join(cells) + " |")
    say(f"\nslidestack: `{slidestack}`" + ("" if ss is not None else " (not found)") + "\n")
    # 7. flatSliderBearing
    say("### 7. flatSliderBearing (Coulomb) against ElasticPP\n")
    say("The same model with every interface a `flatSliderBearing` (2-D, normal force from "
        "the blocks' weight through the elements' axial force) at s = 1e4, 10 steps/sample. "
        "Phantom slip: after each converged step, the bearing's plastic slip "
        "ub − q/kInit from its basic deformation and force; a change while "
        "abs(q) < μN (the bearing did not slip) cannot come from a correct return map.\n")
    say("| building, stack(s) | peak slips ElasticPP (m) | peak slips flatSliderBearing (m) | "
        "largest relative difference, every output | steps with phantom slip (first at) |")
    say("|---|---|---|---|---|")
    for name, b, stacks in (
            ("1 storey T 1 s, α [0.5] μ [0.2]", {"storeys": 1, "period": 1.0},
             [{"floor": 1, "alpha": [0.5], "mu": [0.2]}]),
            ("1 storey T 1 s, α [0.5, 0.5] μ [0.2, 0.1]", {"storeys": 1, "period": 1.0},
             [{"floor": 1, "alpha": [0.5, 0.5], "mu": [0.2, 0.1]}]),
            ("the comparison case", doc_building, doc_stacks)):
        bld = Building({"building": b, "stacks": stacks, "damping": 0.05})
        a = simulate(ops, bld, dt, accel, 10, 1e4, "elasticpp")
        f = simulate(ops, bld, dt, accel, 10, 1e4, "flatslider")
        if not (a["ok"] and f["ok"]):
            say(f"| {name} | {a['message']} | {f['message']} | | |")
            continue
        d = max(rel_peaks(f, a).values())
        phantom, first = phantom_slips(ops, bld, dt, accel, 10, 1e4)
        say(f"| {name} | {[round(x, 6) for st in a['stacks'] for x in st['peak_slip_m']]} | "
            f"{[round(x, 6) for st in f['stacks'] for x in st['peak_slip_m']]} | {fmt(d)} | "
            f"{phantom}" + (f" (t = {first:.3f} s)" if first is not None else "") + " |")
    say()
    if args.markdown:
        Path(args.markdown).write_text("\n".join(out) + "\n")


# --------------------------------------------------------------------------- main

def main() -> None:
    p = argparse.ArgumentParser(description="slidestack's building in OpenSees (see the "
                                            "docstring).")
    p.add_argument("input", nargs="?", help="IN.json")
    p.add_argument("output", nargs="?", help="OUT.json")
    p.add_argument("--check", action="store_true", help="verify the model (see the docstring)")
    p.add_argument("--quick", action="store_true", help="--check with fewer settings")
    p.add_argument("--slidestack", help="slidestack binary for --check's one-storey part")
    p.add_argument("--markdown", help="--check: also write the tables to this file")
    args = p.parse_args()
    if args.check:
        check(args)
        return
    if not (args.input and args.output):
        p.error("IN.json and OUT.json are required (or --check)")
    spec = json.loads(Path(args.input).read_text())
    ops = oss.import_opensees_or_exit()
    cases = []
    for c in spec["cases"]:
        try:
            cases.append(run_case(ops, c))
        except ValueError as e:
            sys.exit(f"opensees_building: case {c.get('id', '?')!r}: {e}")
    Path(args.output).write_text(json.dumps({"opensees_version": oss.opensees_version(ops),
                                             "cases": cases}))


if __name__ == "__main__":
    main()
