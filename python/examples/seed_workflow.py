#!/usr/bin/env python3
"""The seed's workflow from Python, as in a notebook: load the recording, fit, diagnose, plot.

    python examples/seed_workflow.py [RUN.tsv] [--plot OUT.png]

Without a file it records one first with the wheel's own command (`propid sim`, a simulated
stand with a hidden 12 ms torque lag, as `propid demo` hides). The plot needs matplotlib
(`pip install matplotlib`); without it the plot is skipped with a message. Runs in CI
(ci/steps/36-python.sh); docs/PYTHON.md walks through it.
"""

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import propid

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("tsv", nargs="?", help="a recording (propid's TSV); default: simulate one")
parser.add_argument("--plot", default="seed_workflow.png", help="where to save the figure")
args = parser.parse_args()

# %% 1. The recording: the seed driver's TSV (t, force, velocity, acceleration).
if args.tsv is None:
    args.tsv = str(Path(tempfile.mkdtemp(prefix="propid-")) / "run.tsv")
    # The same command `pip install` put on the PATH, here as `python -m propid`.
    subprocess.run(
        [sys.executable, "-m", "propid", "sim", "--pattern", "chirp", "--duration", "60",
         "--torque-lag", "0.012", "--output", args.tsv],
        check=True,
    )
run = propid.read_tsv(args.tsv)
print(f"{len(run)} rows, {run['t'].iloc[-1] - run['t'].iloc[0]:.1f} s from {args.tsv}")

# %% 2. The seed's regressor, exact: J (the seed's `mass`), c1, c2 with standard errors.
fit = propid.fit(run)
print(fit)

# %% 3. What that model gets wrong, the named cause, and the extended model.
diagnosis = propid.diagnose(run)
print(diagnosis)  # the command's text report
for effect in diagnosis.effects:
    print(f"named: {effect.name} = {effect.value:.4g} {effect.unit}")
print(f"J: seed's model {fit.mass:.4e}, extended model {diagnosis.extended.inertia:.4e} kg·m²")

# %% 4. Measured against predicted acceleration.
try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib is not installed: plot skipped (pip install matplotlib)")
else:
    window = run.iloc[len(run) // 2 : len(run) // 2 + 2000]
    fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(9, 6))
    ax1.plot(window["t"], window["acceleration"], ".", markersize=2, label="measured")
    ax1.plot(window["t"], fit.predict_acceleration(window["force"], window["velocity"]),
             label="the seed's model (propid.fit)")
    ax1.set_ylabel("acceleration [rad/s²]")
    ax1.legend()
    ax2.plot(window["t"], window["force"])
    ax2.set_ylabel("torque [N·m]")
    ax2.set_xlabel("t [s]")
    fig.tight_layout()
    fig.savefig(args.plot)
    print(f"plot written to {args.plot}")
