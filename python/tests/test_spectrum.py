"""spectrum and match against the CLI's."""

import numpy as np
import pytest

import slidestack
from conftest import ROOT, cli_json

REC = ROOT / "tests/fixtures/records/RSN1111_KOBE_NIS000.AT2"
ARRAYS = ("periods_s", "sd_m", "psv_mps", "psa_g", "peak_time_s")


def test_spectrum_equals_the_cli(cli):
    periods = "0.05:4:0.05"
    want = cli_json(cli, "spectrum", "--record", str(REC), "--periods", periods, "--damping", "0.02,0.05")
    accel, dt = slidestack.read_record(REC)
    got = slidestack.spectrum(accel, dt, periods, damping=[0.02, 0.05])
    assert len(got) == len(want) == 2
    for g, w in zip(got, want):
        assert g["damping"] == w["damping"]
        for key in ARRAYS:
            assert isinstance(g[key], np.ndarray)
            assert g[key].tolist() == w[key], key
    one = slidestack.spectrum(accel, dt, periods)
    assert one["damping"] == 0.05
    assert one["psa_g"].tolist() == want[1]["psa_g"]
    # Periods as numbers are the same periods.
    by_value = slidestack.spectrum(accel, dt, np.asarray(want[1]["periods_s"]))
    assert by_value["sd_m"].tolist() == want[1]["sd_m"]


def test_ductility_spectrum_equals_the_cli(cli):
    want = cli_json(cli, "spectrum", "--record", str(REC), "--periods", "0.5,1", "--ductility", "2,4")
    accel, dt = slidestack.read_record(REC)
    got = slidestack.spectrum(accel, dt, [0.5, 1.0], ductility=[2, 4])
    assert len(got) == 2
    for g, w in zip(got, want):
        assert g["strength_ratio"].tolist() == w["strength_ratio"]
        assert g["reduction_factor"].tolist() == w["reduction_factor"]


def test_read_record_is_the_file(cli):
    accel, dt = slidestack.read_record(REC)
    assert dt == 0.01 and accel.dtype == np.float64
    # PGA against the file's own numbers (the AT2 values in g).
    lines = REC.read_text().splitlines()[4:]
    values = [float(x) for line in lines for x in line.split()]
    assert accel.tolist() == values


def test_match_meets_the_target_and_writes_the_cli_numbers(cli, tmp_path):
    target = "is1893:zone=V,soil=I"
    accel, dt = slidestack.read_record(REC)
    m = slidestack.match(REC, target)
    assert m["report"]["converged"]
    # The matched record's spectrum is within the acceptance band of the target on the check
    # range (the report's worst misfit is that band's measure).
    assert m["report"]["worst_misfit"] <= 0.3
    out = tmp_path / "m"
    import subprocess

    subprocess.run([str(cli), "match", "--record", str(REC), "--target", target, "--out", str(out)], check=True, capture_output=True)
    cli_accel, cli_dt = slidestack.read_record(out / "RSN1111_KOBE_NIS000.AT2")
    # The CLI's .AT2 holds the matched samples in shortest round-trip form: the same numbers.
    assert cli_dt == dt
    assert cli_accel.tolist() == m["accel_g"].tolist()
