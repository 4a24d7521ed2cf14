"""Shared fixtures: the repository, the command-line binary the module is compared with."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
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


def held_child(script: str, args: list[str], point: str, held: Path,
               env: dict[str, str] | None = None) -> subprocess.Popen:
    """Starts `python -c script *args` held by the test hook at `point` (`SLIDESTACK_PAUSE_AT`,
    src/pipeline/pause.rs) and returns it once it holds there (the hook has written `held`);
    removing `held` lets it go on."""
    env = dict(os.environ, **(env or {}), SLIDESTACK_PAUSE_AT=point,
               SLIDESTACK_PAUSE_FILE=str(held))
    p = subprocess.Popen([sys.executable, "-c", script, *args], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env=env)
    while not held.exists():
        assert p.poll() is None, p.communicate()
        time.sleep(0.002)
    return p


def interrupt_when_held(script: str, args: list[str], point: str, held: Path,
                        env: dict[str, str] | None = None) -> tuple[str, str]:
    """Runs `python -c script *args` held at `point` ([`held_child`]), sends SIGINT while it
    holds there, and returns its (stdout, stderr); the child must end by its KeyboardInterrupt
    handler (exit 3)."""
    p = held_child(script, args, point, held, env)
    p.send_signal(signal.SIGINT)
    out, err = p.communicate()
    assert p.returncode == 3, (p.returncode, out, err)
    return out, err
