"""The study's stages from Python: the CLI's files, open_study, h5py beside the module, Ctrl-C."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import slidestack
from conftest import ROOT, interrupt_when_held, run_cli

QUICK = ROOT / "configs/quick.yaml"
STAGE_FILES = ("motions.h5", "sweep.h5", "tnew.h5", "fit.h5", "fit.yaml")


@pytest.fixture(scope="module")
def quick(tmp_path_factory, cli):
    """configs/quick.yaml run by the module and by the CLI into two directories."""
    base = tmp_path_factory.mktemp("quick")
    py_out, cli_out = base / "py", base / "cli"
    done = slidestack.run(QUICK, out=py_out)
    run_cli(cli, "run", str(QUICK), "--out", str(cli_out))
    return done, py_out, cli_out


def test_run_writes_the_clis_files(quick):
    done, py_out, cli_out = quick
    assert list(done) == ["motions", "sweep", "tnew", "fit", "report"]
    assert all(d["outcome"] == "wrote" for d in done.values())
    for name in STAGE_FILES:
        assert (py_out / name).read_bytes() == (cli_out / name).read_bytes(), name
    again = slidestack.run(QUICK, out=py_out)
    assert all(d["outcome"] == "up_to_date" for d in again.values())


def test_status_is_the_clis(quick, cli):
    _, py_out, _ = quick
    st = slidestack.status(QUICK, out=py_out)
    env = run_cli(cli, "status", str(QUICK), "--out", str(py_out), "--format", "env").stdout
    want = dict(line.split("=", 1) for line in env.split())
    for stage, word in st["stages"].items():
        assert want[stage.upper()] == word == "up_to_date"
    assert str(st["sweep_units"]) == want["SWEEP_UNITS"]
    assert str(st["sweep_samples_per_unit"]) == want["SWEEP_SAMPLES_PER_UNIT"]
    assert f"{st['sweep_ns_per_sample']:.0f}" == want["SWEEP_NS_PER_SAMPLE"] == "188"


def test_design_is_the_clis(quick, cli):
    _, py_out, _ = quick
    args = ["design", "--study", str(py_out), "--zone", "III", "--period", "1.0"]
    import json

    want = json.loads(
        run_cli(cli, *args, "--alpha", "0.5,0.5", "--mu", "0.2,0.1", "--json").stdout
    )
    assert slidestack.design(py_out, "III", 1.0, [0.5, 0.5], [0.2, 0.1]) == want


def test_a_config_dict_is_the_config_file(quick, tmp_path):
    _, py_out, _ = quick
    cfg = quick_dict(tmp_path / "d")
    done = slidestack.motions(cfg)
    assert done["outcome"] == "wrote"
    assert (tmp_path / "d/motions.h5").exists()
    st = slidestack.status(cfg)
    assert st["stages"]["motions"] == "up_to_date"
    assert st["output_dir"] == str(tmp_path / "d")


def test_open_study(quick):
    _, py_out, _ = quick
    study = slidestack.open_study(py_out)
    assert set(study) == {"motions", "sweep", "tnew", "fit"}
    sweep = study["sweep"]["III"]
    assert list(sweep["u_stack"].dims) == ["motion", "T_p", "alpha_1", "alpha_2", "mu_1", "mu_2"]
    assert sweep["T_p"].attrs["units"] == "s"
    assert sweep["T_p"].values.tolist() == [0.3, 0.6, 1.0, 1.5, 2.0]
    tnew = study["tnew"]["V"]
    assert list(tnew["T_new"].dims) == ["T_p", "alpha_1", "alpha_2", "mu_1", "mu_2"]
    flagged = [v for v in tnew.data_vars if v.endswith("_meaning")]
    assert flagged, list(tnew.data_vars)
    with pytest.raises(FileNotFoundError):
        slidestack.open_study(py_out / "report")


HDF5_SCRIPT = """
import sys
first, out, config = sys.argv[1], sys.argv[2], sys.argv[3]
if first == "h5py":
    import h5py, slidestack
else:
    import slidestack, h5py
import numpy as np
with h5py.File(out + "/tnew.h5", "r") as f:
    before = np.asarray(f["zone_III/T_new"])
    # The module reads and rewrites the study while h5py holds a file of it open.
    assert slidestack.status(config, out=out)["stages"]["tnew"] == "up_to_date"
    assert slidestack.tnew(config, out=out, force=True)["outcome"] == "wrote"
    a = slidestack.design(out, "III", 1.0, [0.5, 0.5], [0.2, 0.1])
with h5py.File(out + "/tnew.h5", "r") as f:
    after = np.asarray(f["zone_III/T_new"])
assert np.array_equal(before, after, equal_nan=True)
study = slidestack.open_study(out)
assert np.array_equal(study["tnew"]["III"]["T_new"].values, after, equal_nan=True)
print(h5py.version.hdf5_version, a["t_new_grid_s"])
"""


@pytest.mark.parametrize("first", ["h5py", "slidestack"])
def test_h5py_and_the_module_in_one_interpreter(quick, first, tmp_path):
    _, py_out, _ = quick
    out = tmp_path / "copy"
    out.mkdir()
    for name in STAGE_FILES:
        (out / name).write_bytes((py_out / name).read_bytes())
    for name in os.listdir(py_out):
        if name.endswith(".sha256"):
            (out / name).write_bytes((py_out / name).read_bytes())
    p = subprocess.run(
        [sys.executable, "-c", HDF5_SCRIPT, first, str(out), str(QUICK)],
        capture_output=True,
        text=True,
    )
    assert p.returncode == 0, p.stderr
    assert len(p.stdout.split()) == 2


def quick_dict(out: Path, periods=None) -> dict:
    """configs/quick.yaml as a dict (with other periods when given)."""
    return {
        "output_dir": str(out),
        "zones": [
            {"name": "III", "target": "is1893:zone=III,soil=I"},
            {"name": "V", "target": "is1893:zone=V,soil=I"},
        ],
        "motions": {"seeds": {"stochastic": {"count": 3, "seed": 2016}}},
        "grid": {
            "period_s": periods or [0.3, 0.6, 1.0, 1.5, 2.0],
            "alpha": [[0.1, 0.5, 1.0], [0.5, 1.0]],
            "mu": [[0.1, 0.3], [0.05, 0.2]],
            "damping": 0.05,
            "damping_basis": "rigid",
        },
    }


INTERRUPT_SCRIPT = """
import signal, sys, slidestack
# A child started from a non-interactive shell's background job inherits SIGINT ignored, and
# Python then keeps it so: install the interpreter's own handler, as an interactive one has.
signal.signal(signal.SIGINT, signal.default_int_handler)
stage = getattr(slidestack, sys.argv[2])
try:
    stage(eval(sys.argv[1]))
except KeyboardInterrupt as e:
    print("KeyboardInterrupt:", e, file=sys.stderr)
    sys.exit(3)
print("returned")
"""


def interrupted(cfg, stage: str, point: str, tmp_path: Path) -> str:
    """Runs `stage` of `cfg` in a child interpreter held at `point` of the test hook
    (slidestack.pipeline.pause), sends SIGINT while it holds there, and returns its stderr; the
    stage must end in KeyboardInterrupt (exit 3), however late the signal came."""
    out, err = interrupt_when_held(INTERRUPT_SCRIPT, [repr(cfg), stage], point,
                                   tmp_path / f"held-{stage}", {"RAYON_NUM_THREADS": "1"})
    assert "returned" not in out
    return err


def test_ctrl_c_during_units_stops_a_sweep_and_leaves_it_resumable(tmp_path):
    out = tmp_path / "big"
    periods = [round(0.1 + 0.02 * i, 2) for i in range(96)]
    cfg = quick_dict(out, periods)
    slidestack.motions(cfg)
    # Held after its second unit is stored, on one thread: exactly two units are kept.
    err = interrupted(cfg, "sweep", "sweep.unit:2", tmp_path)
    assert "sweep: interrupted" in err, err
    st = slidestack.status(cfg)
    assert st["stages"]["sweep"] == "missing"
    assert st["sweep_units_done"] == 2, st
    leftovers = [n for n in os.listdir(out) if ".tmp" in n]
    assert not leftovers, leftovers
    # The next run resumes: it computes only the units not stored.
    assert slidestack.sweep(cfg)["outcome"] == "wrote"
    assert slidestack.status(cfg)["stages"]["sweep"] == "up_to_date"


def test_ctrl_c_before_the_assembly_keeps_every_unit(tmp_path):
    out = tmp_path / "late"
    cfg = quick_dict(out, [0.5, 1.0])
    slidestack.motions(cfg)
    interrupted(cfg, "sweep", "sweep.assemble", tmp_path)
    st = slidestack.status(cfg)
    assert st["stages"]["sweep"] == "missing"
    assert st["sweep_units_done"] == st["sweep_units"], st
    assert slidestack.sweep(cfg)["outcome"] == "wrote"


def test_ctrl_c_after_the_work_is_done_is_still_reported(tmp_path):
    out = tmp_path / "done"
    cfg = quick_dict(out, [0.5, 1.0])
    slidestack.motions(cfg)
    # The signal comes once sweep.h5 is written and verified: the file is complete and
    # correct, and the interrupt still raises KeyboardInterrupt.
    interrupted(cfg, "sweep", "stage.done", tmp_path)
    assert slidestack.status(cfg)["stages"]["sweep"] == "up_to_date"
    assert slidestack.sweep(cfg)["outcome"] == "up_to_date"


def test_ctrl_c_stops_the_motions_stage_within_one_record(tmp_path):
    out = tmp_path / "motions"
    cfg = quick_dict(out, [0.5, 1.0])
    # Held before its second record is matched (of three per zone, two zones).
    err = interrupted(cfg, "motions", "motions.record:2", tmp_path)
    assert "motions: interrupted" in err, err
    assert slidestack.status(cfg)["stages"]["motions"] == "missing"
    assert slidestack.motions(cfg)["outcome"] == "wrote"


SWEEP_SCRIPT = """
import sys, slidestack
slidestack.sweep(sys.argv[1], out=sys.argv[2])
"""


def copy_motions(src: Path, dst: Path) -> None:
    dst.mkdir()
    for name in ("motions.h5", "motions.h5.sha256"):
        (dst / name).write_bytes((src / name).read_bytes())


def test_progress_shows_only_on_a_terminal(quick, tmp_path):
    import pty

    _, py_out, _ = quick
    quiet = tmp_path / "quiet"
    copy_motions(py_out, quiet)
    p = subprocess.run(
        [sys.executable, "-c", SWEEP_SCRIPT, str(QUICK), str(quiet)],
        capture_output=True,
        text=True,
    )
    assert p.returncode == 0, p.stderr
    assert "units to compute" not in p.stderr and p.stdout == ""

    shown = tmp_path / "shown"
    copy_motions(py_out, shown)
    master, slave = pty.openpty()
    child = subprocess.Popen(
        [sys.executable, "-c", SWEEP_SCRIPT, str(QUICK), str(shown)],
        stdout=subprocess.DEVNULL,
        stderr=slave,
    )
    os.close(slave)
    chunks = []
    while True:
        try:
            data = os.read(master, 65536)
        except OSError:  # EIO: the child closed the terminal
            break
        if not data:
            break
        chunks.append(data)
    os.close(master)
    assert child.wait() == 0
    text = b"".join(chunks).decode(errors="replace")
    # The CLI's lines (`sweep: …`) and its bar's counter (`N/30 units`).
    assert "sweep: 30 of 30 units to compute" in text, text
    assert "/30 units" in text, text


def test_shards_and_merge_make_the_same_sweep(quick, tmp_path):
    _, py_out, _ = quick
    out = tmp_path / "sharded"
    copy_motions(py_out, out)
    assert slidestack.sweep(QUICK, out=out, shard=(1, 2))["outcome"] == "shard_done"
    with pytest.raises(FileNotFoundError, match="15 of 30 units are missing") as e:
        slidestack.merge(QUICK, out=out)  # shard 2 is missing
    assert e.value.kind == "missing_file"  # type: ignore[attr-defined]
    assert slidestack.sweep(QUICK, out=out, shard=(2, 2))["shard"] == (2, 2)
    assert slidestack.merge(QUICK, out=out)["outcome"] == "wrote"
    assert (out / "sweep.h5").read_bytes() == (py_out / "sweep.h5").read_bytes()
    with pytest.raises(ValueError, match="needs 1 ≤ k ≤ n"):
        slidestack.sweep(QUICK, out=out, shard=(3, 2))


def test_ida_shards_make_the_unsharded_ida(tmp_path):
    """slidestack.ida(shard=(k, n)) traces its share; a call without it assembles the bytes of an
    unsharded run; a shard beyond the units is a ValueError naming `shard`."""
    cfg = ROOT / "configs/ida-quick.yaml"
    whole, split = tmp_path / "whole", tmp_path / "split"
    slidestack.motions(cfg, out=whole)
    copy_motions(whole, split)
    assert slidestack.ida(cfg, out=whole)["outcome"] == "wrote"
    for k in (2, 1):
        assert slidestack.ida(cfg, out=split, shard=(k, 2))["shard"] == (k, 2)
    assert slidestack.ida(cfg, out=split)["outcome"] == "wrote"
    assert (split / "ida.h5").read_bytes() == (whole / "ida.h5").read_bytes()
    with pytest.raises(ValueError, match="shard 1/99: needs 1 ≤ K ≤ N ≤ 6"):
        slidestack.ida(cfg, out=split, shard=(1, 99), force=True)


def test_tnew_shards_make_the_unsharded_tnew(tmp_path):
    """slidestack.tnew(shard=(k, n)) computes its share of a building study's attached fractions;
    a call without it assembles the bytes of an unsharded run."""
    cfg = ROOT / "configs/mdof-quick.yaml"
    whole, split = tmp_path / "whole", tmp_path / "split"
    slidestack.motions(cfg, out=whole)
    slidestack.sweep(cfg, out=whole)
    split.mkdir()
    for f in ("motions.h5", "motions.h5.sha256", "sweep.h5", "sweep.h5.sha256"):
        shutil.copy(whole / f, split / f)
    assert slidestack.tnew(cfg, out=whole)["outcome"] == "wrote"
    status = slidestack.status(cfg, out=split)
    assert (status["tnew_units"], status["tnew_units_done"]) == (48, 0)
    for k in (2, 1):
        assert slidestack.tnew(cfg, out=split, shard=(k, 2))["shard"] == (k, 2)
    assert slidestack.tnew(cfg, out=split)["outcome"] == "wrote"
    assert (split / "tnew.h5").read_bytes() == (whole / "tnew.h5").read_bytes()
    assert not (split / "tnew.units").exists()


def test_design_in_a_building_study_is_the_clis(tmp_path, cli):
    """configs/mdof-quick.yaml through its fit by the CLI; the module's design of one frame is
    the CLI's, and asking a building study without a frame raises ValueError naming the keys."""
    cfg, out = ROOT / "configs/mdof-quick.yaml", tmp_path / "mdof"
    for stage in ("motions", "sweep", "tnew", "fit"):
        run_cli(cli, stage, str(cfg), "--out", str(out))
    import json

    args = ["design", "--study", str(out), "--zone", "V", "--period", "0.6"]
    args += ["--alpha", "0.25,0.5", "--mu", "0.1,0.05", "--storeys", "3", "--floor", "roof"]
    want = json.loads(run_cli(cli, *args, "--json").stdout)
    got = slidestack.design(out, "V", 0.6, [0.25, 0.5], [0.1, 0.05], storeys=3, floor="roof")
    assert got == want and want["building"] == "3 storeys, stack on the roof"
    assert slidestack.design(out, "V", 0.6, [0.25, 0.5], [0.1, 0.05], storeys=3, floor=3) == want
    with pytest.raises(ValueError, match="say which building, its storey count and the floor"):
        slidestack.design(out, "V", 0.6, [0.25, 0.5], [0.1, 0.05])
    with pytest.raises(ValueError, match="needs both `storeys` and `floor`"):
        slidestack.design(out, "V", 0.6, [0.25, 0.5], [0.1, 0.05], storeys=3)
    # The same finished study's case as FEMA P-58 demands: the CLI's bytes.
    for attached in (False, True):
        flag = ["--attached"] if attached else []
        want_csv, got_csv = tmp_path / f"cli-{attached}.csv", tmp_path / f"py-{attached}.csv"
        run_cli(cli, "export", "edp", "--study", str(out), "--zone", "V", "--storeys", "3",
                "--stack-floor", "roof", "--period", "0.6", "--alpha", "0.25,0.5",
                "--mu", "0.1,0.05", "--out", str(want_csv), *flag)
        assert slidestack.export_frame_edp(out, "V", 3, "roof", 0.6, [0.25, 0.5], [0.1, 0.05],
                                           got_csv, attached=attached) == got_csv
        assert got_csv.read_bytes() == want_csv.read_bytes()
    with pytest.raises(ValueError, match="`mu\\[1\\]` 0.07 is not in the study"):
        slidestack.export_frame_edp(out, "V", 3, "roof", 0.6, [0.25, 0.5], [0.1, 0.07],
                                    tmp_path / "no.csv")


def test_floors_is_the_clis_and_open_study_labels_it(tmp_path, cli):
    """configs/mdof-floors-quick.yaml's floors stage from the module and from the CLI: the same
    floors.h5; open_study gives its spectra with their labelled dimensions."""
    cfg = ROOT / "configs/mdof-floors-quick.yaml"
    py_out, cli_out = tmp_path / "py", tmp_path / "cli"
    run_cli(cli, "motions", str(cfg), "--out", str(cli_out))
    copy_motions(cli_out, py_out)
    run_cli(cli, "floors", str(cfg), "--out", str(cli_out))
    assert slidestack.floors(cfg, out=py_out)["outcome"] == "wrote"
    assert (py_out / "floors.h5").read_bytes() == (cli_out / "floors.h5").read_bytes()
    psa = slidestack.open_study(py_out)["floors"]["V"]["psa_stack"]
    assert psa.dims == ("motion", "case", "storeys", "stack_floor", "damping", "floor", "period")
    roof = psa.sel(storeys=3, stack_floor="roof", damping=0.05, floor=3).mean("motion")
    assert float(roof.max()) > 0 and psa.attrs["units"] == "g"
