"""The force noise's errors-in-variables bias on a force-sensor lag (docs/SCIENCE.md, "The force's
noise, taken out of the parameters"). propid's own analysis, not part of the independent stand:
it runs stand.py's `force_sensor_lag` case (a 10 ms first-order filter on the reported torque) for
one seed without noise, adds only the stand's white torque noise (1.5 mN·m) to the force, and fits
the acceleration equation a = θ₀·F − θ₁·ω|ω| + θ₂·Ḟ (Ḟ the ±10 ms least-squares slope; L = θ₂/θ₀)
by instrumental variables as propid does (Ḟ instrumented by the difference quotient of the
samples just outside the slope's window, the force by itself), then with the force's diagonal of
ZᵀΦ corrected by n·σ_F² (σ_F from the sample-to-sample differences, as propid measures it), and
with the force instrumented by the mean of its samples just outside the window.

usage: python3 tests/independent_stand/force_noise_bias.py [SEED]   (default 3)"""
import os, subprocess, sys, tempfile

import numpy as np
import pandas as pd

seed = int(sys.argv[1]) if len(sys.argv) > 1 else 3
here = os.path.dirname(os.path.abspath(__file__))
with tempfile.TemporaryDirectory() as out:
    subprocess.run([sys.executable, os.path.join(here, "stand.py"), "--case", "force_sensor_lag",
                    "--seed", str(seed), "--noise-scale", "0", "--out", out], check=True)
    d = pd.read_csv(os.path.join(out, f"force_sensor_lag-seed{seed}.tsv"), sep="\t")

t = d.t.values
w = d.velocity.values
a = d.acceleration.values
dt = t[1] - t[0]
h = round(0.01 / dt)
g = h + 1
k = np.arange(-h, h + 1)
kernel = k / (np.sum(k * k) * dt)
rng = np.random.default_rng(seed)
inside = slice(300, -300)


def fit(F, how):
    slope = np.convolve(F, kernel[::-1], mode="same")
    z = np.zeros_like(F)
    z[g:-g] = (F[2 * g:] - F[:-2 * g]) / (2 * g * dt)
    zf = F.copy()
    if how == "neighbours":
        zf[g:-g] = 0.5 * (F[2 * g:] + F[:-2 * g])
    X = np.column_stack([F, -w * np.abs(w), slope])[inside]
    Z = np.column_stack([zf, -w * np.abs(w), z])[inside]
    A = Z.T @ X
    if how == "corrected":
        dd = F[1:-1] - 0.5 * (F[:-2] + F[2:])
        sigma = 1.4826 * np.median(np.abs(dd - np.median(dd))) / np.sqrt(1.5)
        A[0, 0] -= len(X) * sigma ** 2
    b = np.linalg.solve(A, Z.T @ a[inside])
    return b[2] / b[0], 1.0 / b[0]


clean = d.force.values
noisy = clean + 1.5e-3 * rng.standard_normal(len(clean))
for label, F, how in [("noise-free", clean, "iv"), ("force noise, instrumental variables", noisy, "iv"),
                      ("force noise, force diagonal corrected", noisy, "corrected"),
                      ("force noise, force instrumented by its neighbours", noisy, "neighbours")]:
    L, J = fit(F, how)
    print(f"{label:<50} L = {1e3 * L:6.2f} ms   J = {J:.4e} kg·m² (truth 10 ms, 2.0000e-5)")
