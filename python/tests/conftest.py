"""Shared helpers: the installed ``propid`` command (the wheel's console script) as the peer every
test compares with, and simulated recordings made by it."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import List, Sequence

import pytest

REPO = Path(__file__).resolve().parents[2]


def propid_command() -> List[str]:
    """The ``propid`` console script installed beside this interpreter (the venv's bin)."""
    here = Path(sys.executable).parent / ("propid.exe" if os.name == "nt" else "propid")
    found = str(here) if here.exists() else shutil.which("propid")
    if found is None:
        pytest.fail("the wheel's `propid` command is not installed beside this Python")
    return [found]


def cli(args: Sequence[str], check: bool = True) -> subprocess.CompletedProcess:
    """Runs the installed command; stdout and stderr as text."""
    out = subprocess.run(propid_command() + list(args), capture_output=True, text=True)
    if check and out.returncode != 0:
        raise AssertionError(f"propid {' '.join(args)} exited {out.returncode}: {out.stderr}")
    return out


def cli_error(args: Sequence[str]) -> tuple[int, str]:
    """(exit status, the message after `error: `) of a command that fails."""
    out = cli(args, check=False)
    assert out.returncode != 0, f"propid {' '.join(args)} succeeded"
    lines = [l for l in out.stderr.splitlines() if l.startswith("error: ")]
    assert lines, out.stderr
    return out.returncode, out.stderr[out.stderr.index("error: ") + len("error: ") :].rstrip("\n")


@pytest.fixture(scope="session")
def small_run(tmp_path_factory) -> Path:
    """A simulated recording under 1 MiB (so `propid fit` scans it as one piece)."""
    path = tmp_path_factory.mktemp("runs") / "small.tsv"
    cli(["sim", "--duration", "20", "--rate", "250", "--seed", "7", "--output", str(path)])
    assert path.stat().st_size < 1 << 20, "the file must be scanned as one chunk"
    return path


@pytest.fixture(scope="session")
def lag_run(tmp_path_factory) -> Path:
    """A simulated recording with a hidden 12 ms torque lag (the demo's), on a chirp."""
    path = tmp_path_factory.mktemp("runs") / "lag.tsv"
    cli(
        [
            "sim", "--duration", "60", "--pattern", "chirp", "--torque-lag", "0.012",
            "--seed", "3", "--output", str(path),
        ]
    )
    return path
