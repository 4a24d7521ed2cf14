"""The type stub (slidestack/_native.pyi) as mypy sees it: right calls pass, wrong ones fail."""

import subprocess
import sys
from pathlib import Path

GOOD = """
from typing import Any, Dict
import numpy as np
import slidestack

r: Dict[str, Any] = slidestack.simulate(period=1.0, alpha=[0.5, 0.5], mu=(0.2, 0.1))
accel, dt = slidestack.read_record("x.AT2")
x: np.ndarray = accel
h = slidestack.simulate(record=(accel, dt), history=True, building={"storeys": 2})
s = slidestack.spectrum(accel, dt, "0.1:2:0.1", damping=0.05)
st: Dict[str, Any] = slidestack.status({"output_dir": "o"}, out="p")
study = slidestack.open_study("out")
v: str = slidestack.__version__
"""

BAD = """
import slidestack
slidestack.simulate(period="1.0")
slidestack.simulate(perod=1.0)
n: int = slidestack.read_record("x.AT2")
"""


def mypy(tmp_path: Path, name: str, text: str) -> subprocess.CompletedProcess:
    f = tmp_path / name
    f.write_text(text)
    return subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", "--no-incremental", str(f)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )


def test_stub_accepts_the_documented_calls(tmp_path):
    p = mypy(tmp_path, "good.py", GOOD)
    assert p.returncode == 0, p.stdout + p.stderr


def test_stub_refuses_wrong_calls(tmp_path):
    p = mypy(tmp_path, "bad.py", BAD)
    assert p.returncode == 1, p.stdout + p.stderr
    assert "bad.py:3: error" in p.stdout  # a str period
    assert "bad.py:4: error" in p.stdout  # an unknown keyword
    assert "bad.py:5: error" in p.stdout  # a tuple is not an int


def test_the_package_itself_is_strictly_typed(tmp_path):
    package = Path(__file__).resolve().parents[1] / "slidestack"
    p = subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", "--no-incremental", str(package)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert p.returncode == 0, p.stdout + p.stderr
