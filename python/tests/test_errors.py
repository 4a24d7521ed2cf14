"""Each kind of bad input raises the Python exception of its kind with the CLI's message, and
nothing brings the interpreter down."""

import json
import shutil

import numpy as np
import pytest

import slidestack
from conftest import ROOT, held_child, run_cli


def cli_error(cli, *args, code=2):
    p = run_cli(cli, *args, ok=False)
    assert p.returncode == code, p.stderr
    return p.stderr.strip().removeprefix("error: ")


def test_a_bad_value_is_a_value_error_with_the_cli_message(cli):
    want = cli_error(cli, "simulate", "--period", "-1")
    with pytest.raises(ValueError) as e:
        slidestack.simulate(period=-1)
    # The CLI names the flag, the module the keyword: the same message otherwise.
    assert str(e.value).replace("`period`", "--period") == want


def test_a_missing_record_is_file_not_found(cli):
    want = cli_error(cli, "simulate", "--record", "no/such.AT2")
    with pytest.raises(FileNotFoundError) as e:
        slidestack.simulate(record="no/such.AT2")
    assert str(e.value) == want
    with pytest.raises(FileNotFoundError):
        slidestack.read_record("no/such.AT2")


def test_a_directory_as_record_is_bad_input(cli):
    want = cli_error(cli, "simulate", "--record", str(ROOT / "configs"))
    with pytest.raises(ValueError) as e:
        slidestack.read_record(ROOT / "configs")
    assert str(e.value) == want
    assert e.value.kind == "bad_input"  # type: ignore[attr-defined]
    assert e.value.file == str(ROOT / "configs")  # type: ignore[attr-defined]


def test_a_bad_record_file_names_file_and_line(cli, tmp_path):
    bad = tmp_path / "bad.txt"
    bad.write_text("0 0.1\n0.01 x\n")
    want = cli_error(cli, "simulate", "--record", str(bad))
    with pytest.raises(ValueError) as e:
        slidestack.simulate(record=bad)
    assert str(e.value) == want
    assert f"{bad}:2" in str(e.value)


def test_bad_samples_name_the_sample():
    with pytest.raises(ValueError, match="sample 1 is not finite"):
        slidestack.simulate(record=(np.array([0.0, np.nan, 0.0]), 0.01))
    with pytest.raises(ValueError, match="time step"):
        slidestack.spectrum([0.0, 0.1, 0.0], -0.01)
    with pytest.raises(ValueError, match="path or an"):
        slidestack.simulate(record=(1, 2, 3))


def test_an_unknown_word_is_a_value_error():
    with pytest.raises(ValueError, match="unknown variant `plastic`"):
        slidestack.simulate(structure="plastic")
    with pytest.raises(TypeError):
        slidestack.simulate(perod=1.0)  # type: ignore[call-arg]


def test_settings_that_do_not_go_together(cli):
    want = cli_error(cli, "simulate", "--structure", "epp")
    with pytest.raises(ValueError) as e:
        slidestack.simulate(structure="epp")
    assert str(e.value).replace("`structure: epp`", "--structure epp").replace(
        "`yield_strength_ratio`", "--yield-strength-ratio"
    ) == want
    with pytest.raises(ValueError, match="does not apply to a case with `building`"):
        slidestack.simulate(period=1.0, building={"storeys": 1, "period": 1.0})


def test_spectrum_damping_and_periods(cli):
    rec = str(ROOT / "tests/fixtures/records/RSN68_SFERN_PEL090.AT2")
    want = cli_error(cli, "spectrum", "--record", rec, "--damping", "1.5")
    accel, dt = slidestack.read_record(rec)
    with pytest.raises(ValueError) as e:
        slidestack.spectrum(accel, dt, damping=1.5)
    assert str(e.value).replace("`damping`", "--damping") == want
    with pytest.raises(ValueError):
        slidestack.spectrum(accel, dt, periods="4:0.05:0.1")


def test_study_errors(cli, tmp_path):
    with pytest.raises(FileNotFoundError):
        slidestack.run(tmp_path / "none.yaml")
    with pytest.raises(FileNotFoundError):
        slidestack.design(tmp_path, "III", 1.0, [0.5, 0.5], [0.2, 0.1])
    bad = {"output_dir": str(tmp_path / "o"), "zones": []}
    with pytest.raises(ValueError, match="<config dict>"):
        slidestack.status(bad)
    with pytest.raises(ValueError, match="is a file"):
        slidestack.status(ROOT / "configs/quick.yaml", out=ROOT / "README.md")
    cfg = ROOT / "configs/quick.yaml"
    want = cli_error(cli, "tnew", str(cfg), "--out", str(tmp_path / "q"), code=2)
    with pytest.raises(FileNotFoundError) as e:
        slidestack.tnew(cfg, out=tmp_path / "q")
    assert str(e.value) == want


def test_a_bad_target_for_match():
    accel, dt = slidestack.read_record(ROOT / "tests/fixtures/records/RSN68_SFERN_PEL090.AT2")
    with pytest.raises(ValueError, match="invalid `target`"):
        slidestack.match((accel, dt), "is1893:zone=IX")
    with pytest.raises(ValueError, match="invalid `settings`"):
        slidestack.match((accel, dt), "is1893:zone=V,soil=I", settings={"bogus": 1})


def test_a_panic_is_an_exception_not_an_abort():
    from slidestack import _native

    with pytest.raises(BaseException) as e:
        _native._panic()  # type: ignore[attr-defined]
    assert type(e.value).__name__ == "PanicException"
    assert "deliberate panic" in str(e.value)
    assert slidestack.simulate()["switches"] > 0


def small_study(tmp_path, name: str) -> dict:
    """configs/quick.yaml's zone III, three motions, with one case (too few to fit)."""
    return {
        "output_dir": str(tmp_path / name),
        "zones": [{"name": "III", "target": "is1893:zone=III,soil=I"}],
        "motions": {"seeds": {"stochastic": {"count": 3, "seed": 2016}}},
        "grid": {"period_s": [1.0], "alpha": [[0.5], [0.5]], "mu": [[0.1], [0.05]]},
    }


def test_every_kind_of_fault_has_its_class_and_names_its_place(tmp_path):
    """The library's one classification (src/fault.rs) decides the class; `kind`, `file`,
    `key`, `line` say what and where."""
    # Bad input, with the key of the config.
    cfg = small_study(tmp_path, "bad")
    cfg["grid"]["damping"] = 2.0
    with pytest.raises(ValueError) as e:
        slidestack.status(cfg)
    assert (e.value.kind, e.value.key) == ("bad_input", "grid.damping")  # type: ignore[attr-defined]
    # Bad input, with the file and the line of a record.
    bad = tmp_path / "bad.txt"
    bad.write_text("0 0.1\n0.01 x\n")
    with pytest.raises(ValueError) as e:
        slidestack.read_record(bad)
    assert (e.value.file, e.value.line) == (str(bad), 2)  # type: ignore[attr-defined]
    # A missing file.
    with pytest.raises(FileNotFoundError) as e:
        slidestack.read_record(tmp_path / "none.AT2")
    assert e.value.kind == "missing_file"  # type: ignore[attr-defined]
    # I/O: an output directory that cannot be made.
    (tmp_path / "a-file").write_text("")
    with pytest.raises(OSError) as e:
        slidestack.motions(small_study(tmp_path, "a-file/o"))
    assert e.value.kind == "io"  # type: ignore[attr-defined]
    assert not isinstance(e.value, FileNotFoundError)
    # A grid too small to fit a design equation: bad input naming the key, before any work.
    cfg = small_study(tmp_path, "one")
    for stage in (slidestack.motions, slidestack.sweep, slidestack.tnew):
        stage(cfg)
    with pytest.raises(ValueError, match="the grid gives 1") as e:
        slidestack.fit(cfg)
    assert (e.value.kind, e.value.key) == ("bad_input", "grid")  # type: ignore[attr-defined]
    # A run that cannot produce its result: a record file changed while the stage ran (held by
    # the test hook after the config, and its records, were read).
    record = tmp_path / "RSN960_NORTHR_LOS270.AT2"
    shutil.copy(ROOT / "tests/fixtures/records/RSN960_NORTHR_LOS270.AT2", record)
    changing = small_study(tmp_path, "changing")
    changing["motions"] = {"seeds": {"records": {"files": [str(record)]}}}
    script = (
        "import json, sys, slidestack\n"
        "try:\n"
        "    slidestack.motions(json.loads(sys.argv[1]))\n"
        "except slidestack.Error as e:\n"
        "    print(e.kind, isinstance(e, RuntimeError), e)\n"
        "    sys.exit(4)\n"
    )
    held = tmp_path / "held"
    p = held_child(script, [json.dumps(changing)], "session.locked", held)
    record.write_bytes(record.read_bytes() + b"\n")
    held.unlink()
    out, err = p.communicate()
    assert p.returncode == 4, (p.returncode, out, err)
    assert out.startswith("failed True") and "changed after the study was loaded" in out, out
    # A damaged file: a flipped byte in sweep.h5.
    sweep = tmp_path / "one" / "sweep.h5"
    data = bytearray(sweep.read_bytes())
    data[len(data) // 2] ^= 0xFF
    sweep.write_bytes(bytes(data))
    with pytest.raises(slidestack.Error, match="does not match its checksum") as e:
        slidestack.tnew(cfg, force=True)
    assert e.value.kind == "damaged_file"  # type: ignore[attr-defined]
    # Interrupted: KeyboardInterrupt (test_study.py, the Ctrl-C tests).


def test_a_whole_number_keyword_is_a_value_error_naming_it(tmp_path):
    """Negative, fractional, boolean or huge integers raise ValueError naming the keyword (pyo3's
    own conversion raised OverflowError or TypeError), before any file is read."""
    question = (tmp_path, "III", 0.7, [1, 1], [0.3, 0.1])
    for storeys in (-3, 0, 1.5, True, 2**70, "3"):
        with pytest.raises(ValueError, match="^`storeys` must be a whole number ≥ 1, got "):
            slidestack.design(*question, storeys=storeys, floor="roof")
    for floor in (-1, 0, 1.5, "top"):
        with pytest.raises(ValueError, match="is not a floor, `roof`, `mid` or `all`"):
            slidestack.design(*question, storeys=3, floor=floor)
    for shard in ((-1, 2), (1, 2**70), (1.5, 2)):
        with pytest.raises(ValueError, match="^`shard` must be a whole number ≥ 1, got "):
            slidestack.sweep(tmp_path / "none.yaml", shard=shard)
    for shard in ((1,), "12", 3):
        with pytest.raises(ValueError, match=r"^`shard` must be a pair \(k, n\)"):
            slidestack.sweep(tmp_path / "none.yaml", shard=shard)
    for n in (-1, 0, 2.5):
        with pytest.raises(ValueError, match="^`rk4_substeps` must be a whole number ≥ 1, got "):
            slidestack.simulate(integrator="rk4", rk4_substeps=n)
    # numpy's integers are whole numbers too.
    with pytest.raises(FileNotFoundError):
        slidestack.design(*question, storeys=np.int64(3), floor="roof")
