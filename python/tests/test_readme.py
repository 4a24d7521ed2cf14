"""The Python chapter's notebook-style example (docs/python.md) and the README's Monte Carlo run
and draw their figures, and the three prompt lines of the chapter and of the README's tour print
what they show."""

import os
import re
import subprocess
import sys

import pytest

from conftest import ROOT

# The chapter that holds the module's documentation and its full example (moved out of the
# README's "## Python" section; the README keeps the three prompt lines in its tour).
CHAPTER = "docs/python.md"


def test_the_readme_example_runs(tmp_path):
    section = (ROOT / CHAPTER).read_text()
    blocks = re.findall(r"```python\n(.*?)```", section, re.S)
    example = next(b for b in blocks if "savefig" in b)
    out = tmp_path / "quick"
    code = example.replace('"out/quick"', repr(str(out))).replace(
        'fig.savefig("python-example.svg")', f"fig.savefig({str(tmp_path / 'fig.svg')!r})"
    )
    assert code != example
    env = dict(os.environ, MPLBACKEND="Agg")
    p = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "fig.svg").read_text().startswith("<?xml")
    assert (out / "tnew.h5").exists()


def test_the_readme_monte_carlo_runs(tmp_path):
    """The README's simulate_many example draws its figure (of 1,000 cases, each of which the
    README's claim says equals simulate's: python/tests/test_batch.py checks that)."""
    blocks = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S)
    example = next(b for b in blocks if "simulate_many" in b)
    figure = tmp_path / "monte-carlo.svg"
    code = example.replace('fig.savefig("monte-carlo.svg")', f"fig.savefig({str(figure)!r})")
    assert code != example
    env = dict(os.environ, MPLBACKEND="Agg")
    p = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True,
                       text=True)
    assert p.returncode == 0, p.stderr
    assert figure.read_text().startswith("<?xml")


@pytest.mark.parametrize("document", [CHAPTER, "README.md"])
def test_the_three_lines(document):
    section = (ROOT / document).read_text()
    prompt = re.search(r"```python\n(>>> .*?)```", section, re.S).group(1)
    lines = prompt.strip().splitlines()
    code = "\n".join(line[4:] for line in lines if line.startswith(">>> "))
    shown = "\n".join(line for line in lines if not line.startswith(">>> "))
    *body, last = code.splitlines()
    ns: dict = {}
    exec("\n".join(body), ns)
    assert repr(eval(last, ns)) == shown
