"""simulate against `slidestack simulate --json`: the same dict, bit for bit."""

import json
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import slidestack
from conftest import ROOT, cli_json, interrupt_when_held, run_cli

KOBE = ROOT / "tests/fixtures/records/RSN1111_KOBE_NIS000.AT2"

BUILDING = {
    "storeys": 3,
    "period": 0.6,
    "floor_masses": [1, 1, 1],
    "storey_stiffnesses": [3, 2, 1],
    "structure": "elastic",
}
STACKS = [
    {"floor": 3, "alpha": [0.5, 0.5], "mu": [0.2, 0.1], "mu_static": [0.25, 0.1]},
    {"floor": 1, "alpha": [1.0], "mu": [0.3]},
]


def test_version_is_the_crates(cli):
    assert run_cli(cli, "--version").stdout.split()[-1] == slidestack.__version__


def test_section_7_1_case_equals_the_cli(cli):
    want = cli_json(cli, "simulate", "--config", "configs/section71-case.yaml")
    got = slidestack.simulate(period=1.0, alpha=[0.5, 0.5], mu=[0.2, 0.1], damping=0.05)
    assert list(got) == list(want)
    assert got == want
    # The case file given as such, and the defaults, are the same case.
    assert slidestack.simulate(config=ROOT / "configs/section71-case.yaml") == want
    assert slidestack.simulate() == want


def test_yielding_case_equals_the_cli(cli):
    flags = ["--structure", "bilinear", "--yield-strength-ratio", "0.08"]
    flags += ["--post-yield-ratio", "0.05", "--record", str(KOBE), "--scale", "1.5"]
    want = cli_json(cli, "simulate", *flags)
    got = slidestack.simulate(
        structure="bilinear",
        yield_strength_ratio=0.08,
        post_yield_ratio=0.05,
        record=KOBE,
        scale=1.5,
    )
    assert got == want
    assert got["ductility"] > 1  # the case does yield


def test_building_case_equals_the_cli(cli):
    want = cli_json(cli, "simulate", "--config", "configs/building.yaml")
    got = slidestack.simulate(
        scale=1.5,
        building=BUILDING,
        stacks=STACKS,
        damping=0.05,
        damping_basis="rigid",
        integrator="exact",
    )
    assert got == want
    assert len(got["stacks"]) == 2
    assert slidestack.simulate(config=ROOT / "configs/building.yaml") == want


def test_floor_spectra_equal_the_cli(cli, tmp_path):
    """`floor_spectra` as a keyword and as a case file's key: the CLI's numbers."""
    case = tmp_path / "case.yaml"
    case.write_text((ROOT / "configs/building.yaml").read_text()
                    + "\nfloor_spectra: {periods: \"0.1:1:0.3\", damping: [0.05]}\n")
    want = cli_json(cli, "simulate", "--config", str(case))
    got = slidestack.simulate(scale=1.5, building=BUILDING, stacks=STACKS,
                              floor_spectra={"periods": "0.1:1:0.3", "damping": [0.05]})
    assert got == want
    assert len(got["floor_spectra"]["psa_g"][0]) == 3  # floors


def test_rk4_equals_the_cli(cli):
    want = cli_json(cli, "simulate", "--integrator", "rk4", "--rk4-substeps", "4")
    assert slidestack.simulate(integrator="rk4", rk4_substeps=4) == want


def test_record_as_samples_is_the_record_file():
    accel, dt = slidestack.read_record(KOBE)
    from_file = slidestack.simulate(record=str(KOBE))
    from_arrays = slidestack.simulate(record=(accel, dt))
    assert from_arrays["record"] == "array"
    from_file.pop("record")
    from_arrays.pop("record")
    assert from_arrays == from_file


def test_history_equals_the_cli_file(cli, tmp_path):
    import h5py

    path = tmp_path / "h.h5"
    run_cli(cli, "simulate", "--history", str(path))
    got = slidestack.simulate(history=True)
    h = got.pop("history")
    assert got == slidestack.simulate()
    rows = len(h["time_s"])
    assert h["displacement_m"].shape == (rows, 3)
    assert h["contact"].shape == (rows, 2)
    assert h["bodies"] == ["ps", "block1", "block2"]
    with h5py.File(path, "r") as f:
        pairs = [
            ("time", "time_s"),
            ("ground_accel", "ground_accel_mps2"),
            ("displacement", "displacement_m"),
            ("velocity", "velocity_mps"),
            ("abs_accel", "abs_accel_mps2"),
            ("contact", "contact"),
        ]
        for file_key, key in pairs:
            assert np.array_equal(np.asarray(f[file_key]), h[key]), key
    # The history is sampled at the record's samples; the summary's peak may fall between them.
    peak = np.max(np.abs(h["displacement_m"][:, 0]))
    assert 0.98 * got["peak_displacement_m"] <= peak <= got["peak_displacement_m"]


def test_building_history_names_floors_and_stacks():
    h = slidestack.simulate(building=BUILDING, stacks=STACKS, history=True)["history"]
    assert h["bodies"][:3] == ["floor1", "floor2", "floor3"]
    assert h["displacement_m"].shape[1] == len(h["bodies"]) == 6
    assert h["contact"].shape[1] == len(h["interfaces"]) == 3


def test_two_threads_simulate_at_once_with_the_gil_released():
    cases = [dict(period=0.5 + 0.25 * i, integrator="rk4", rk4_substeps=50) for i in range(4)]
    alone = [slidestack.simulate(**c) for c in cases]
    with ThreadPoolExecutor(max_workers=2) as pool:
        together = list(pool.map(lambda c: slidestack.simulate(**c), cases))
    assert together == alone

    # While one thread simulates, another runs Python code: the GIL is released.
    ticks = 0
    stop = threading.Event()

    def count():
        nonlocal ticks
        while not stop.is_set():
            ticks += 1

    t = threading.Thread(target=count)
    t.start()
    try:
        before = ticks
        slidestack.simulate(integrator="rk4", rk4_substeps=400)
        during = ticks - before
    finally:
        stop.set()
        t.join()
    assert during > 1000, during


def test_warnings_become_python_warnings(cli):
    # A structure whose period is far beyond the record's length: the CLI warns on stderr.
    p = run_cli(cli, "simulate", "--period", "1000", "--json")
    want = p.stderr.strip().removeprefix("simulate: warning: ")
    assert want.startswith("T_rigid = ")
    with pytest.warns(RuntimeWarning) as w:
        got = slidestack.simulate(period=1000)
    assert [str(x.message) for x in w] == [want]
    assert got == json.loads(p.stdout)


SIMULATE_SCRIPT = """
import signal, sys, slidestack
signal.signal(signal.SIGINT, signal.default_int_handler)
case = dict(building={"storeys": 6, "period": 1.0},
            stacks=[{"floor": j, "alpha": [0.5, 0.5], "mu": [0.2, 0.1]} for j in range(1, 7)])
try:
    slidestack.simulate(**case)
except KeyboardInterrupt as e:
    print("KeyboardInterrupt:", e, file=sys.stderr)
    # The interpreter goes on: the next call runs to its end.
    print(slidestack.simulate()["switches"] > 0)
    sys.exit(3)
print("returned")
"""


def test_ctrl_c_stops_a_simulation_within_a_few_samples(tmp_path):
    """Held by the test hook after 128 samples of a six-storey building (the watch is asked
    every 64 samples), SIGINT: KeyboardInterrupt names the sample, and the interpreter goes on."""
    out, err = interrupt_when_held(SIMULATE_SCRIPT, [], "simulate.samples:3", tmp_path / "held")
    assert "stopped at sample 128 of" in err, err
    assert out.strip() == "True", out


def test_export_edp_writes_the_clis_file(cli, tmp_path):
    records = [ROOT / "tests/fixtures/records" / n for n in
               ("RSN1111_KOBE_NIS000.AT2", "RSN960_NORTHR_LOS270.AT2")]
    for attached in (False, True):
        flag = ["--attached"] if attached else []
        want = tmp_path / f"cli-{attached}.csv"
        run_cli(cli, "export", "edp", "--config", "configs/building.yaml",
                "--record", *map(str, records), "--out", str(want), *flag)
        got = tmp_path / f"py-{attached}.csv"
        assert slidestack.export_edp(ROOT / "configs/building.yaml", records, got,
                                     attached=attached) == got
        assert got.read_bytes() == want.read_bytes()
    with pytest.raises(ValueError, match="section71-case.yaml.*`building`"):
        slidestack.export_edp(ROOT / "configs/section71-case.yaml", records,
                              tmp_path / "no.csv")
    with pytest.raises(ValueError, match="`records`: .*at least one record"):
        slidestack.export_edp(ROOT / "configs/building.yaml", [], tmp_path / "no.csv")
    assert not (tmp_path / "no.csv").exists()
