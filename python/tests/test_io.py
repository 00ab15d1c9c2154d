"""Reading, importing, simulating and planning: the command's files, as DataFrames."""

from __future__ import annotations

import subprocess

import numpy as np
import pandas as pd

import propid
from conftest import REPO, cli

DATA = REPO / "tests/data/esc_test_alspitz"


def frames_equal(a: pd.DataFrame, b: pd.DataFrame) -> None:
    assert list(a.columns) == list(b.columns)
    for c in a.columns:
        assert np.array_equal(a[c].to_numpy(), b[c].to_numpy(), equal_nan=True), c


def test_read_tsv_reads_the_columns_the_header_has(small_run, tmp_path):
    frame = propid.read_tsv(small_run)
    assert list(frame.columns) == ["ts_local", "t", "force", "velocity", "acceleration", "position"]
    assert frame.attrs["source"] == str(small_run)
    frames_equal(frame[["t", "force"]], pd.read_table(small_run)[["t", "force"]])
    seed = tmp_path / "seed.tsv"
    seed.write_text("t\tforce\tvelocity\tacceleration\n0\t1\t2\t3\n0.1\t\tnan\t4\n")
    frame = propid.read_tsv(seed)
    assert list(frame.columns) == ["t", "force", "velocity", "acceleration"]
    assert np.isnan(frame["force"][1]) and np.isnan(frame["velocity"][1])


def test_importers_give_what_the_command_writes(tmp_path):
    cases = [
        (["rcbench", str(DATA / "rcbench/Log_2019-11-07_174807.csv")],
         lambda: propid.import_rcbench(DATA / "rcbench/Log_2019-11-07_174807.csv")),
        (["autoquad", str(DATA / "autoquad/f40_steps_5-2.csv"), "--kv", "1600"],
         lambda: propid.import_autoquad(DATA / "autoquad/f40_steps_5-2.csv", kv=1600)),
    ]
    for args, call in cases:
        out = tmp_path / "imported.tsv"
        stderr = cli(["import", *args, "--output", str(out)]).stderr
        frame = call()
        written = pd.read_table(out)
        # Written with shortest round-trip floats: the same values, bit for bit.
        frames_equal(frame, written)
        for line in frame.attrs["assumptions"]:
            assert f"import: {line}" in stderr


def test_read_tsv_keeps_the_stand_columns(tmp_path):
    # A stand's thrust cell beside the drive's feedback: thrust, voltage, current, command.
    path = tmp_path / "thrust.tsv"
    cli(["sim", "--duration", "5", "--thrust-k", "4.3e-6", "--output", str(path)])
    frame = propid.read_tsv(path)
    stand = ["thrust", "voltage", "current", "command"]
    assert list(frame.columns) == ["ts_local", "t", "force", "velocity", "acceleration", "position", *stand]
    frames_equal(frame, pd.read_table(path)[list(frame.columns)])
    assert np.isfinite(frame["thrust"]).sum() > 100
    # The Result's C_T from the frame is the command's from the file.
    by_frame = propid.diagnose(frame, diameter="7in").to_dict()["result"]["thrust"]
    by_path = propid.diagnose(path, diameter="7in").to_dict()["result"]["thrust"]
    assert by_frame == by_path and 0.13 < by_frame["c_t"]["value"] < 0.15


def test_simulate_is_propid_sim(tmp_path):
    path = tmp_path / "sim.tsv"
    cli(["sim", "--duration", "5", "--seed", "4", "--torque-lag", "0.01", "--output", str(path)])
    frames_equal(propid.simulate(duration=5, seed=4, torque_lag=0.01), propid.read_tsv(path))
    mech = propid.simulate(duration=5, stand="mechanism", current_loop_bandwidth=2000)
    assert len(mech) > 1000 and np.isfinite(mech["velocity"]).all()
    kept = tmp_path / "kept.tsv"
    frame = propid.simulate(duration=2, output=kept)
    assert kept.exists() and frame.attrs["source"] == str(kept)


def test_plan_is_propid_plan_and_its_file_plays(tmp_path):
    out = tmp_path / "cli.json"
    cli(["plan", "--inertia", "2e-5", "--c2", "1.5e-8", "--max-torque", "0.05", "--output", str(out)])
    p = propid.plan(inertia=2e-5, c2=1.5e-8, max_torque=0.05)
    assert p.to_dict() == __import__("json").loads(out.read_text())
    assert 0 < p.predicted["rel_stderr_j"] < 1 and p.excitation["pattern"]
    assert repr(p).startswith("Plan(")
    saved = tmp_path / "plan.json"
    p.save(saved)
    assert saved.read_text() == out.read_text()
    run = propid.simulate(pattern_file=saved, inertia=2e-5, c2=1.5e-8)
    assert len(run) > 1000
    # A fit as the prior.
    fitted = propid.fit(run)
    assert propid.plan(fit=fitted, max_torque=0.05).to_dict()["prior"]["inertia"] == fitted.mass


def test_python_dash_m_propid_is_the_command():
    import sys

    out = subprocess.run([sys.executable, "-m", "propid", "--version"], capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.startswith("propid ")
