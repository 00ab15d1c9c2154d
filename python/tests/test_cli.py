"""The wheel's `propid` command: the Rust command line, run in-process by the console script."""

from __future__ import annotations

import json

import propid
from conftest import cli


def test_the_installed_command_runs_the_demo(tmp_path):
    out = tmp_path / "demo"
    # A shorter pattern than the default 20 s (the demo runs in real time over a pty).
    result = cli(["demo", "--out", str(out), "--duration", "6", "--init-duration", "1"])
    assert result.returncode == 0
    for name in ("run.tsv", "fit.yaml", "diagnose.json", "report.md"):
        assert (out / name).stat().st_size > 0, name
    # What the demo recorded, fitted by the library, is what the demo's own fit says.
    report = json.loads((out / "diagnose.json").read_text())
    assert report["samples"] > 1000
    fit_yaml = (out / "fit.yaml").read_text()
    mass = float(fit_yaml.split("mass:")[1].split("#")[0])
    assert propid.fit(out / "run.tsv").mass == float(f"{mass:.9e}") or abs(
        propid.fit(out / "run.tsv").mass - mass
    ) <= 5e-10 * abs(mass)


def test_exit_statuses_are_the_commands(tmp_path):
    assert cli(["fit", str(tmp_path / "missing.tsv")], check=False).returncode == 2
    assert cli(["no-such-command"], check=False).returncode == 2
    assert "Usage: propid <COMMAND>" in cli(["--help"]).stdout
    assert cli(["--version"]).stdout.strip() == f"propid {propid.__version__}"
