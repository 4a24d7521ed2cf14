"""simulate_many: many cases in one call equal one simulate call per case, bit for bit, whatever
the thread count; labelled dims; bad cases named before any run; Ctrl-C within one run."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from conftest import ROOT, interrupt_when_held

import slidestack
from slidestack._batch import LABELLING, _dims_of, _flatten

KOBE = ROOT / "tests/fixtures/records/RSN1111_KOBE_NIS000.AT2"

BUILDING = dict(
    building={"storeys": 3, "period": 0.6, "floor_masses": [1, 1, 1],
              "storey_stiffnesses": [3, 2, 1]},
    stacks=[{"floor": 3, "alpha": [0.5, 0.5], "mu": [0.2, 0.1], "mu_static": [0.25, 0.1]},
            {"floor": 1, "alpha": [1.0], "mu": [0.3]}],
)


def monte_carlo(n: int, seed: int = 7) -> list[dict]:
    """The Section 7.1 structure (T_p = 1 s) with a two-block stack, μ₁, μ₂ and α drawn."""
    rng = np.random.default_rng(seed)
    return [dict(period=1.0, alpha=[a, a], mu=[m1, m2])
            for a, m1, m2 in zip(rng.uniform(0.1, 1.0, n), rng.uniform(0.05, 0.4, n),
                                 rng.uniform(0.05, 0.4, n))]


def same(got, value) -> None:
    """A Dataset value equals simulate's: floats bit for bit, whole numbers as int64, None as NaN
    (numbers) or "" (strings), a list element by element with NaN beyond its length."""
    got = np.asarray(got)
    if value is None:
        assert got.item() == "" if got.dtype == object else np.isnan(got).all(), got
    elif isinstance(value, list):
        for k, v in enumerate(value):
            same(got[k], v)
        assert np.isnan(got[len(value):]).all(), got
    elif isinstance(value, float):
        assert got.dtype == np.float64 and got.tobytes() == np.float64(value).tobytes(), (
            got, value)
    else:
        assert got.item() == value, (got, value)


LABELS = dict(LABELLING)


def check_against_simulate(ds: xr.Dataset, cases: list[dict], records: list, one: bool,
                           done: list[dict] | None = None) -> None:
    """Every key of simulate's dict for each case under each record (`done`: the dicts of one
    record, already run) equals the Dataset's value."""
    for i, case in enumerate(cases):
        for j, record in enumerate(records):
            out = done[i] if done is not None else slidestack.simulate(**case, record=record)
            alone = _flatten(out)
            at = ds.isel(case=i) if one else ds.isel(case=i, record=j)
            for key, value in alone.items():
                if key == "record":
                    assert str(at["record"].values).startswith(value)
                    continue
                key = LABELS.get(key, key) if key not in ds else key
                assert key in ds, f"simulate's `{key}` is not in the Dataset"
                same(at[key].values, value)


def test_a_thousand_cases_are_a_thousand_simulate_calls_on_any_thread_count():
    cases = monte_carlo(1000)
    loop = [slidestack.simulate(**c) for c in cases]
    for threads in (1, 2):
        ds = slidestack.simulate_many(cases, threads=threads)
        assert ds.sizes["case"] == 1000 and "record" not in ds.dims
        check_against_simulate(ds, cases, [None], one=True, done=loop)


def test_every_key_of_a_building_case_under_two_records():
    cases = [BUILDING, dict(BUILDING, damping=0.02, scale=1.5)]
    accel, dt = slidestack.read_record(KOBE)
    records = [KOBE, (accel[:800] * 2.0, dt)]
    ds = slidestack.simulate_many(cases, records)
    assert ds.sizes == {"case": 2, "record": 2, "floor": 3, "storey": 3, "mode": 3, "stack": 2,
                        "block": 2, "interface": 2}
    assert list(ds["record"].values) == [KOBE.name, "array"]
    assert ds["stacks_peak_slip_m"].dims == ("case", "record", "stack", "interface")
    assert ds["floor_peak_abs_accel_g"].attrs["units"] == "g"
    check_against_simulate(ds, cases, records, one=False)
    # The friction energy per interface, split by stack, sums to the whole.
    total = ds["stacks_energy_friction_per_interface"].sum(["stack", "interface"])
    np.testing.assert_allclose(total, ds["energy_friction"], rtol=1e-12)


def test_every_list_of_simulate_has_a_dimension():
    """Every list simulate gives (one storey, yielding, building) has as many dimensions as
    nested levels: a new list key fails here until LIST_DIMS labels it."""
    outs = [slidestack.simulate(), slidestack.simulate(structure="bilinear",
                                                       yield_strength_ratio=0.1,
                                                       post_yield_ratio=0.05),
            slidestack.simulate(**BUILDING),
            slidestack.simulate(**dict(BUILDING, building=dict(
                BUILDING["building"], structure="epp", yield_strength_ratios=[0.3, 0.3, 0.3]))),
            slidestack.simulate(aspect=[0.5, 0.15]),
            slidestack.simulate(**ROCKING_BUILDING)]

    def depth(v) -> int:
        return 1 + max([depth(x) for x in v] + [0]) if isinstance(v, list) else 0

    for out in outs:
        for key, value in _flatten(out).items():
            if value is None:
                continue
            assert len(_dims_of(key, value)) == depth(value), key


ROCKING_BUILDING = dict(BUILDING, stacks=[dict(BUILDING["stacks"][0], aspect=[0.5, 0.05]),
                                          BUILDING["stacks"][1]])


def test_the_rocking_onset_is_a_variable_per_field_nan_where_a_stack_never_rocks():
    """`rocking_onset` (null, or {block, time_s}) as `rocking_onset_block` and
    `rocking_onset_time_s`: NaN for a stack that never rocks, or one not checked."""
    cases = [dict(alpha=[0.5, 0.5], mu=[0.3, 0.2], aspect=[0.5, 0.15]),
             dict(alpha=[0.5, 0.5], mu=[0.3, 0.2], aspect=[1.0, 1.0]),
             dict(alpha=[0.5, 0.5], mu=[0.3, 0.2])]
    ds = slidestack.simulate_many(cases)
    assert ds["aspect"].dims == ("case", "block")
    block = ds["rocking_onset_block"].values
    assert block[0] == 2 and np.isnan(block[1:]).all()
    assert ds["rocking_onset_time_s"].attrs["units"] == "s"
    check_against_simulate(ds, cases, [None], one=True)
    ds = slidestack.simulate_many([ROCKING_BUILDING, BUILDING])
    assert ds["stacks_rocking_onset_block"].dims == ("case", "stack")
    onset = ds["stacks_rocking_onset_block"].values
    assert onset[0, 0] == 2 and np.isnan(onset[0, 1]) and np.isnan(onset[1]).all()
    check_against_simulate(ds, [ROCKING_BUILDING, BUILDING], [None], one=True)


def test_stacks_of_different_sizes_are_padded_with_nan():
    cases = [dict(alpha=[1.0], mu=[0.3]), dict(alpha=[0.3, 0.3, 0.3], mu=[0.2, 0.1, 0.05])]
    ds = slidestack.simulate_many(cases)
    assert ds.sizes["interface"] == 3 and ds.sizes["body"] == 4
    assert np.isnan(ds["peak_slip_m"].values[0, 1:]).all()
    check_against_simulate(ds, cases, [None], one=True)


def test_a_dataframe_and_a_dataset_of_cases_are_the_list_of_dicts():
    cases = monte_carlo(12, seed=3)
    want = slidestack.simulate_many(cases)
    df = pd.DataFrame({"period": [c["period"] for c in cases],
                       "alpha": [c["alpha"] for c in cases],
                       "mu": [c["mu"] for c in cases]})
    xr.testing.assert_identical(slidestack.simulate_many(df), want)
    cases_ds = xr.Dataset({"alpha": (("case", "block"), np.array([c["alpha"] for c in cases])),
                           "mu": (("case", "interface"), np.array([c["mu"] for c in cases])),
                           "period": 1.0})
    xr.testing.assert_identical(slidestack.simulate_many(cases_ds), want)


@pytest.mark.parametrize("cases, message, key", [
    ([{}, {}, {"mu": "x"}], "case 2: invalid case: `mu`: invalid type", "cases[2].mu"),
    ([{"mux": [0.1]}], "case 0: unknown key `mux`", None),
    ([{}, {"period": -1.0}], "case 1: invalid case: period_s must be", "cases[1]"),
    ([{}, BUILDING], "case 1 is a building case and case 0 a one-storey one", "cases[1]"),
    ([{"record": str(KOBE)}], "case 0: `record` is given once for all the cases", None),
    ([], "no case to run", "cases"),
])
def test_a_bad_case_is_named_before_any_run(cases, message, key):
    with pytest.raises(ValueError) as e:
        slidestack.simulate_many(cases)
    assert str(e.value).startswith(message), e.value
    assert getattr(e.value, "key", None) == key


def test_threads_must_be_a_whole_number():
    with pytest.raises(ValueError, match="`threads` must be a whole number ≥ 1"):
        slidestack.simulate_many([{}], threads=0)


def test_a_list_of_records_and_one_record():
    ds = slidestack.simulate_many([{}], [KOBE])
    assert ds.sizes["record"] == 1
    one = slidestack.simulate_many([{}], KOBE)
    assert "record" not in one.dims and str(one["record"].values) == KOBE.name
    assert math.isclose(float(one["peak_displacement_m"][0]),
                        float(ds["peak_displacement_m"][0, 0]), rel_tol=0, abs_tol=0)


BATCH_SCRIPT = """
import signal, sys, slidestack
signal.signal(signal.SIGINT, signal.default_int_handler)
try:
    slidestack.simulate_many([{}] * 50, threads=1)
except KeyboardInterrupt as e:
    print("KeyboardInterrupt:", e, file=sys.stderr)
    # The interpreter goes on: the next call runs to its end.
    print(slidestack.simulate_many([{}] * 3, threads=1).sizes["case"])
    sys.exit(3)
print("returned")
"""


def test_ctrl_c_stops_simulate_many_within_one_run(tmp_path):
    """On one thread, the built-in record's 1,999 samples pass the watch 32 times a run: held
    at the 40th pass (the second run's 8th), SIGINT stops the batch with one run done."""
    out, err = interrupt_when_held(BATCH_SCRIPT, [], "simulate.samples:40", tmp_path / "held")
    assert "stopped (interrupted) with 1 of 50 runs done" in err, err
    assert out.strip() == "3", out


def test_spectra_of_many_records_are_each_records_spectrum():
    kobe = slidestack.read_record(KOBE)
    short = (kobe[0][:900] * -0.5, kobe[1])
    ds = slidestack.spectra([KOBE, short], periods="0.1:2:0.1", damping=[0.02, 0.05])
    assert dict(ds.sizes) == {"record": 2, "damping": 2, "period": 20}
    assert list(ds["record"].values) == [KOBE.name, "array"]
    assert ds["psa_g"].attrs["units"] == "g"
    for r, (accel, dt) in enumerate([kobe, short]):
        for z, alone in enumerate(slidestack.spectrum(accel, dt, "0.1:2:0.1", [0.02, 0.05])):
            assert float(ds["damping"][z]) == alone["damping"]
            for key in ("sd_m", "psv_mps", "psa_g", "peak_time_s"):
                assert ds[key].values[r, z].tobytes() == alone[key].tobytes(), key
            assert ds["period"].values.tobytes() == alone["periods_s"].tobytes()


@pytest.mark.parametrize("records, message", [
    ([], "`records` is empty"),
    (KOBE, "`records` is a list of records"),
])
def test_spectra_refuse_no_records(records, message):
    with pytest.raises(ValueError, match=message):
        slidestack.spectra(records)


def test_floor_spectra_of_many_cases_are_each_cases():
    """A building case and its variants with floor_spectra: psa_g over (case,
    oscillator_damping, floor, period), the periods and damping ratios as coordinates, every
    value simulate's."""
    fs = {"periods": [0.1, 0.3, 1.0], "damping": [0.02, 0.05]}
    cases = [dict(BUILDING, floor_spectra=fs), dict(BUILDING, damping=0.03, floor_spectra=fs)]
    ds = slidestack.simulate_many(cases)
    assert ds["floor_spectra_psa_g"].dims == ("case", "oscillator_damping", "floor", "period")
    assert list(ds["period"].values) == [0.1, 0.3, 1.0]
    assert list(ds["oscillator_damping"].values) == [0.02, 0.05]
    check_against_simulate(ds, cases, [None], one=True)
