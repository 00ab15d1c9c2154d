#!/usr/bin/env python3
"""Writes a synthetic test-stand TSV (the seed driver's columns) for comparing propid fit with the
seed regressor: a load J*dw/dt = Q - c1*w - c2*w|w| driven by the seed's sinusoidal torque pattern,
integrated finely, sampled at `rate`, with optional Gaussian noise on acceleration.

usage: make_case.py OUT J C1 C2 [--rows N] [--rate HZ] [--noise SIGMA] [--seed S] [--nan-head K]
"""
import argparse
import numpy as np

ap = argparse.ArgumentParser()
ap.add_argument("out")
ap.add_argument("J", type=float)
ap.add_argument("c1", type=float)
ap.add_argument("c2", type=float)
ap.add_argument("--rows", type=int, default=24000)
ap.add_argument("--rate", type=float, default=200.0)
ap.add_argument("--noise", type=float, default=0.0)
ap.add_argument("--seed", type=int, default=1)
ap.add_argument("--torque", default="0.01,0.09", help="lo,hi of the sinusoidal torque [N*m]")
ap.add_argument("--w0", type=float, default=100.0, help="initial velocity [rad/s]")
ap.add_argument("--nan-head", type=int, default=0, help="rows with a missing acceleration at the start")
a = ap.parse_args()
rng = np.random.default_rng(a.seed)
dt = 1.0 / a.rate
sub = 20
t = np.arange(a.rows) * dt
lo, hi = (float(v) for v in a.torque.split(","))
q = lo + (hi - lo) * (0.5 + 0.5 * np.sin(2 * np.pi * t / 2.0))  # the seed's pattern between lo and hi
w = np.empty(a.rows)
acc = np.empty(a.rows)
x = a.w0
h = dt / sub
for i in range(a.rows):
    w[i] = x
    acc[i] = (q[i] - a.c1 * x - a.c2 * x * abs(x)) / a.J
    for _ in range(sub):
        x += h * (q[i] - a.c1 * x - a.c2 * x * abs(x)) / a.J
acc_meas = acc + rng.normal(0.0, a.noise, a.rows) if a.noise > 0 else acc
acc_meas[: a.nan_head] = np.nan
with open(a.out, "w") as f:
    f.write("ts_local\tt\tforce\tvelocity\tacceleration\n")
    for i in range(a.rows):
        f.write(f"{1000 + t[i]:.17g}\t{t[i]:.17g}\t{q[i]:.17g}\t{w[i]:.17g}\t{acc_meas[i]:.17g}\n")
