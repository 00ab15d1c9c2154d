"""Why a 10 ms torque lag beside viscous friction cannot be told from a constant torque on the
seed's sine at the independent stand's noise (docs/SCIENCE.md, "What propid still cannot find").
propid's own analysis, not part of the independent stand: it runs stand.py's `lag_viscous` case
for one seed twice, without noise and with the stand's noise, and scores two models of the
acceleration equation by blocked 10-fold cross-validation, the acceleration predicted from the
columns as measured:

  constant torque:  a = θ₀·F − θ₁·ω|ω| − θ₂
  lag + viscous:    a = θ₀·L(F) − θ₁·ω|ω| − θ₂·ω,  L a first-order lag of 10 ms (first-order hold)

Without noise the equation separates them by orders of magnitude. With the noise, each model's
held-out error is mostly the noise: the noise-free difference is printed as a share of the
constant torque's held-out error on the noisy record (a lag also averages the force's noise away,
which propid puts back before it compares; that is not repeated here), and the floor of the held-out simulated
velocity that the force's white noise alone sets (σ_F integrated through the rotor, whose drag
time constant is J/(2·c2·ω̄)).

usage: python3 tests/independent_stand/lag_viscous_limit.py [SEED]   (default 3)"""
import json, os, subprocess, sys, tempfile

import numpy as np
import pandas as pd

seed = int(sys.argv[1]) if len(sys.argv) > 1 else 3
here = os.path.dirname(os.path.abspath(__file__))
runs = {}
with tempfile.TemporaryDirectory() as out:
    for scale in ("0", "1"):
        sub = os.path.join(out, scale)
        subprocess.run([sys.executable, os.path.join(here, "stand.py"), "--case", "lag_viscous",
                        "--seed", str(seed), "--noise-scale", scale, "--out", sub],
                       check=True, stdout=subprocess.DEVNULL)
        d = pd.read_csv(os.path.join(sub, f"lag_viscous-seed{seed}.tsv"), sep="\t")
        with open(os.path.join(sub, f"lag_viscous-seed{seed}.json")) as f:
            runs[scale] = (d, json.load(f))


def lagged(x, tau, dt):
    """x through 1/(1 + s·tau), first-order hold."""
    e = np.exp(-dt / tau)
    b = 1.0 - tau / dt * (1.0 - e)
    y = np.empty_like(x)
    y[0] = x[0]
    for i in range(1, len(x)):
        y[i] = e * y[i - 1] + (1.0 - e) * x[i - 1] + (x[i] - x[i - 1]) * b
    return y


def held_out(d, lag):
    t, F, w, a = d.t.values, d.force.values, d.velocity.values, d.acceleration.values
    dt = t[1] - t[0]
    q = w * np.abs(w)
    n = len(t)
    idx = np.arange(n // 10, n)
    folds = np.array_split(idx, 10)
    if lag:
        X = np.column_stack([lagged(F, 0.01, dt), -q, -w])
    else:
        X = np.column_stack([F, -q, -np.ones(n)])
    err = []
    for b in folds:
        train = np.setdiff1d(idx, b)
        theta, *_ = np.linalg.lstsq(X[train], a[train], rcond=None)
        err.append(np.mean((a[b] - X[b] @ theta) ** 2))
    return np.sum(err)


d0, _ = runs["0"]
constant, true_model = held_out(d0, False), held_out(d0, True)
print(f"without noise: held-out equation error, constant torque {constant:.4e}, lag + viscous "
      f"{true_model:.4e} (rad/s²)² summed over folds: the truth's is {constant / true_model:.0f}× "
      f"lower")

d1, truth = runs["1"]
shared = held_out(d0, False) - held_out(d0, True)
print(f"the constant torque's extra error, {100 * shared / held_out(d1, False):.4f} % of its "
      f"held-out error with the noise")
noise = truth["noise"]["force_Nm"]
J, c2 = truth["J"], truth["rotor"]["c2"]
omega = truth["run_statistics"]["omega_mean_rad_s"]
dt = 1.0 / truth["rate_hz"]
T = J / (2 * c2 * omega)
floor = noise / J * np.sqrt(dt * T / 2)
print(f"simulated velocity's floor from the force's noise alone: σ_F = {noise * 1e3:.2f} mN·m "
      f"through a drag time constant of {T:.2f} s: {floor:.2f} rad/s RMS")
