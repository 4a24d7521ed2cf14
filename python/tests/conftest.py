"""Shared fixtures: the repository, the command-line binary the module is compared with."""

import json
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


@pytest.fixture(scope="session")
def cli() -> Path:
    """The `slidestack` binary: $SLIDESTACK_BIN (tests/python.rs sets it to the one cargo just
    built), else target/release/slidestack."""
    path = Path(os.environ.get("SLIDESTACK_BIN", ROOT / "target/release/slidestack"))
    assert path.exists(), f"{path} is missing: run `cargo build --release` or set SLIDESTACK_BIN"
    return path


def run_cli(cli: Path, *args: str, ok: bool = True) -> subprocess.CompletedProcess:
    p = subprocess.run([str(cli), *args], capture_output=True, text=True, cwd=ROOT)
    if ok:
        assert p.returncode == 0, p.stderr
    return p


def cli_json(cli: Path, *args: str):
    return json.loads(run_cli(cli, *args, "--json").stdout)
