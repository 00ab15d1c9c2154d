#!/usr/bin/env python3
"""Checks the independent stand against closed-form results, so that its truth files can be trusted.

Each check prints one line: PASS/FAIL, what was compared, the measured error and the bound.
Exit status 0 only when every check passes. Runs in seconds:

    python3 tests/independent_stand/selfcheck.py
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import sys
import tempfile
import time
from dataclasses import replace

import numpy as np
from scipy import signal

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import stand  # noqa: E402

RESULTS: list[tuple[bool, str]] = []


def check(name: str, error: float, bound: float, unit: str = "") -> None:
    ok = bool(np.isfinite(error) and error <= bound)
    line = f"{'PASS' if ok else 'FAIL'}  {name}: {error:.3g}{unit} (bound {bound:.3g}{unit})"
    RESULTS.append((ok, line))
    print(line, flush=True)


def rel(a, b) -> float:
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300)))


J, C2 = stand.SEVEN_INCH.J, stand.SEVEN_INCH.c2


def run_constant(q, *, seconds, w0=0.0, c1=0.0, p=2.0, kp=C2, coulomb=0.0, braking=0.0, rate=4000.0):
    """Integrates the rotor under a constant torque q; returns times and speeds on the state grid."""
    n = int(round(seconds * rate))
    U = [q] * (n + 1)
    D = [c1] * (n + 1)
    W, TH = stand.integrate_rotor(U, D, J, kp, p, coulomb, braking, 1.0 / rate, w0)
    return np.arange(n + 1) / rate, W, TH


# ----------------------------------------------------------------------------------------------
# 1. The rotor against closed-form solutions
# ----------------------------------------------------------------------------------------------


def rotor_closed_forms() -> None:
    q = 0.09
    w_ss = math.sqrt(q / C2)
    t, W, TH = run_constant(q, seconds=10.0)
    # J w' = q - c2 w^2 from rest: w = w_ss tanh(t sqrt(q c2)/J); angle = J/c2 ln cosh(...)
    k = math.sqrt(q * C2) / J
    exact = w_ss * np.tanh(k * t)
    check("spin-up from rest, w = sqrt(Q/c2) tanh(t sqrt(Q c2)/J)", float(np.max(np.abs(W - exact)) / w_ss), 1e-9)
    th_exact = J / C2 * np.log(np.cosh(k * t))
    check("angle during spin-up, J/c2 ln cosh(...)", float(np.max(np.abs(TH - th_exact)) / th_exact[-1]), 1e-9)
    check("steady speed under constant torque = sqrt(Q/c2)", abs(W[-1] / w_ss - 1.0), 1e-9)

    # Spin-down with no torque: w = w0 / (1 + c2 w0 t / J).
    w0 = 2000.0
    t, W, _ = run_constant(0.0, seconds=3.0, w0=w0)
    check("spin-down, w = w0/(1 + c2 w0 t/J)", rel(W, w0 / (1.0 + C2 * w0 * t / J)), 1e-9)

    # Viscous + quadratic: steady w solves c2 w^2 + c1 w = Q.
    c1 = 3e-6
    _, W, _ = run_constant(q, seconds=10.0, c1=c1)
    w_exact = (-c1 + math.sqrt(c1 * c1 + 4 * C2 * q)) / (2 * C2)
    check("steady speed with viscous friction, c2 w^2 + c1 w = Q", abs(W[-1] / w_exact - 1.0), 1e-9)

    # Drag |w|^p: steady w = (Q/k)^(1/p).
    for p in (1.8, 2.2):
        kp = C2 * 1500.0 ** (2.0 - p)
        _, W, _ = run_constant(q, seconds=10.0, p=p, kp=kp)
        check(f"steady speed with drag k|w|^{p}, (Q/k)^(1/p)", abs(W[-1] / (q / kp) ** (1.0 / p) - 1.0), 1e-9)

    # Coulomb friction: steady w solves c2 w^2 + Fc = Q; spin-down with friction reaches zero and
    # sticks; a torque below Fc never starts the rotor.
    fc = 0.005
    _, W, _ = run_constant(q, seconds=10.0, coulomb=fc)
    check("steady speed with Coulomb friction, c2 w^2 + Fc = Q", abs(W[-1] / math.sqrt((q - fc) / C2) - 1.0), 1e-9)
    t, W, _ = run_constant(0.0, seconds=3.0, w0=300.0, coulomb=fc)
    # J w' = -c2 w^2 - Fc: w = sqrt(Fc/c2) tan(atan(w0/sqrt(Fc/c2)) - t sqrt(Fc c2)/J) until w = 0.
    s = math.sqrt(fc / C2)
    t_stop = J / math.sqrt(fc * C2) * math.atan(300.0 / s)
    exact = np.where(t < t_stop, s * np.tan(np.arctan(300.0 / s) - t * math.sqrt(fc * C2) / J), 0.0)
    check("coast-down with Coulomb friction (tan law), then stuck at 0", float(np.max(np.abs(W - exact))), 0.01, " rad/s")
    stuck_after = float(np.max(np.abs(W[t > t_stop + 1e-3])))
    check("rotor stays at rest after stopping (|w| max)", stuck_after, 0.0, " rad/s")
    _, W, _ = run_constant(0.8 * fc, seconds=1.0, coulomb=fc)
    check("a torque below Coulomb friction never starts the rotor (|w| max)", float(np.max(np.abs(W))), 0.0, " rad/s")

    # Braking: with constant q the rotor never slows from rest, so B has no effect; coasting
    # down from above the steady speed, it brakes with B while w' < 0: J w' = q - c2 w^2 - B.
    B = 0.008
    _, W, _ = run_constant(q, seconds=10.0, braking=B)
    check("braking does not act while the rotor speeds up (steady = sqrt(Q/c2))", abs(W[-1] / w_ss - 1.0), 1e-9)
    t, W, _ = run_constant(q, seconds=1.0, w0=3000.0, braking=B)
    # Slowing all the way (the braked steady speed sqrt((q-B)/c2) is never reached; it ends at
    # sqrt(q/c2) once the unbraked net torque stops being negative). Closed form while braking:
    # w' = -(c2/J)(w^2 - a^2), a^2 = (q - B)/c2: w = a coth(a c2 t/J + acoth(w0/a)).
    a = math.sqrt((q - B) / C2)
    exact = a / np.tanh(a * C2 * t / J + np.arctanh(a / 3000.0))
    braking_phase = exact > w_ss
    check(
        "coast-down under braking: w = a coth(a c2 t/J + acoth(w0/a)), a^2 = (Q-B)/c2",
        rel(W[braking_phase], exact[braking_phase]),
        1e-9,
    )
    check("braking releases at w = sqrt(Q/c2) and the speed stays there", abs(W[-1] / w_ss - 1.0), 1e-6)


# ----------------------------------------------------------------------------------------------
# 2. Convergence: the same run at twice the integration rate
# ----------------------------------------------------------------------------------------------


def convergence() -> None:
    """The integrator's own error: the same input function (linear between the 4 kHz points) at a
    step of 1/4000 s and of 1/8000 s (the finer grid's extra points interpolated, so the input is
    identical)."""

    def run(rate, U, D, coulomb=0.0, braking=0.0, w0=1000.0):
        return stand.integrate_rotor(U.tolist(), D.tolist(), J, C2, 2.0, coulomb, braking, 1.0 / rate, w0)[0]

    def halved(x):
        y = np.empty(2 * len(x) - 1)
        y[::2] = x
        y[1::2] = 0.5 * (x[1:] + x[:-1])
        return y

    t = np.arange(int(20.0 * 4000) + 1) / 4000.0
    sine = 0.05 + 0.04 * np.sin(2 * math.pi * 0.5 * t) + 0.002 * np.sin(2 * math.pi * 7.3 * t)
    # A staircase as a drive latches it: jumps (a ramp over one step) every 0.3 s.
    steps = np.round(sine * 50.0 * (1 + (np.floor(t / 0.3) % 3))) / 150.0
    reversing = 0.06 * np.sin(2 * math.pi * 0.5 * t)
    # Bounds: 1e-7 rad/s where nothing switches; where a torque dQ switches (B = 8 mN*m when braking
    # starts or stops; 2 Fc = 10 mN*m when the speed crosses zero), freezing the mode over one of
    # the 64 sub-steps of 1/4000 s costs up to dQ/J * H/64 (1.6e-3 and 2.0e-3 rad/s).
    sub = 1.0 / 4000.0 / stand.REFINE_SUBSTEPS
    for label, U, kw, w0, bound in (
        ("smooth sine, drag + viscous", sine, dict(), 1000.0, 1e-7),
        ("torque jumps every 0.3 s", steps, dict(), 1000.0, 1e-7),
        ("braking 8 mN*m switching", sine, dict(braking=0.008), 1000.0, 0.008 / J * sub),
        ("Coulomb 5 mN*m on a reversing sine", reversing, dict(coulomb=0.005), 0.0, 0.010 / J * sub),
    ):
        D = np.full_like(U, 3e-6 if label.startswith("smooth") else 0.0)
        W1 = run(4000.0, U, D, w0=w0, **kw)
        W2 = run(8000.0, halved(U), halved(D), w0=w0, **kw)
        check(f"step halving, same input: {label}, max |dw|", float(np.max(np.abs(W2[::2] - W1))), bound, " rad/s")

    # A whole case with the drive's latch and integration both at 8 kHz instead of 4 kHz: how much
    # the data depend on that choice.
    case = replace(stand.CASES_BY_NAME["braking_lag"], duration=20.0)
    a = stand.simulate(case, 3, noise_scale=0.0)
    b = stand.simulate(case, 3, noise_scale=0.0, state_rate_min=8000.0)
    check("whole case (braking_lag), latch and integration at 8 kHz vs 4 kHz: velocity, max |dw|",
          float(np.max(np.abs(a["velocity_true"] - b["velocity_true"]))), 0.01, " rad/s")
    check("whole case (braking_lag), latch and integration at 8 kHz vs 4 kHz: force, max |dQ| / noise",
          float(np.max(np.abs(a["force_true"] - b["force_true"]))) / stand.SEVEN_INCH.torque_noise, 0.01)


def independent_integrator() -> None:
    """RK4 against scipy's adaptive DOP853 (rtol 1e-11) on the same inputs (linear between grid
    points), over windows that hold the hard parts: the setpoint's jump from the
    init to the pattern, braking switching on and off, the speed crossing zero against Coulomb
    friction, the motor's electrical damping, a load transient's edges."""
    from scipy.integrate import solve_ivp

    for name, t0, t1 in (
        ("clean", -0.1, 0.3),
        ("braking", 1.0, 1.6),
        ("coulomb_reversing", 2.0, 2.6),
        ("thrust_sine", -0.1, 0.3),
        ("transient_early", 9.9, 10.3),
    ):
        case = replace(stand.CASES_BY_NAME[name], duration=12.0)
        out = stand.simulate(case, 13, noise_scale=0.0)
        f, g = out["inputs"], out["grid"]
        tf, U, D = f["t"], f["U"], f["D"]
        kp, p, fc, B, J_ = f["kp"], f["p"], f["coulomb"], f["braking"], case.rotor.J

        keep = (tf >= t0 - 0.01) & (tf <= t1 + 0.01)
        tf, U, D = tf[keep], U[keep], D[keep]

        def rhs(t, y):
            w = y[0]
            u = np.interp(t, tf, U)
            d = np.interp(t, tf, D)
            sc = math.copysign(1.0, w) if w != 0.0 else math.copysign(1.0, u)
            net = u - d * w - sc * kp * abs(w) ** p - fc * sc
            if B > 0.0 and net * sc < 0.0:
                net -= B * sc
            return [net / J_]

        sel = (g["t"] >= t0 - 1e-12) & (g["t"] <= t1 + 1e-12)
        ts = g["t"][sel]
        H = 1.0 / out["state_rate"]
        # max_step H/2: an adaptive step must not stride over the inputs' corners unseen.
        sol = solve_ivp(rhs, (ts[0], ts[-1]), [g["omega"][sel][0]], method="DOP853", t_eval=ts,
                        rtol=1e-11, atol=1e-9, max_step=H / 2)
        err = float(np.max(np.abs(sol.y[0] - g["omega"][sel])))
        # Bound: 1e-6 rad/s, plus, where a torque switches (2 Fc at a zero crossing, B when braking
        # starts or stops), the error of freezing the mode for one sub-step: dQ/J * H/64 per switch.
        switched = max(2.0 * fc, B)
        bound = 1e-6 + switched / J_ * H / stand.REFINE_SUBSTEPS
        check(f"{name}: RK4 vs DOP853 (rtol 1e-11) over {t0:g}..{t1:g} s, max |dw|", err, bound, " rad/s")


# ----------------------------------------------------------------------------------------------
# 3. Linear stages
# ----------------------------------------------------------------------------------------------


def stages() -> None:
    dt = 1.0 / 4000.0
    tau = 0.015
    x = np.ones(4000)
    x[0] = 0.0
    y = stand.apply_stage(stand.first_order(tau), x, dt)
    # FOH input: a ramp 0 -> 1 over the first interval, then 1. Exact response:
    t = np.arange(4000) * dt
    y_h = 1.0 - tau / dt * (1.0 - math.exp(-dt / tau))
    exact = np.where(t < dt, 0.0, 1.0 - (1.0 - y_h) * np.exp(-(t - dt) / tau))
    check("first-order stage: step (ramp over one sample) response, exact", float(np.max(np.abs(y - exact))), 1e-12)

    ramp = t * 3.0
    y = stand.apply_stage(stand.first_order(tau), ramp, dt)
    check("first-order stage: a ramp lags by tau (steady lag / tau - 1)", abs((ramp[-1] - y[-1]) / 3.0 / tau - 1.0), 1e-9)

    # Second-order stage: the discrete filter's group delay at 0.5 Hz and its DC gain.
    st = stand.second_order(15.0, 0.7)
    num, den = st.transfer_function()
    bd, ad, _ = signal.cont2discrete((num, den), dt, method="foh")
    b = np.squeeze(bd)
    w = 2 * math.pi * np.array([0.49, 0.51]) * dt
    _, hresp = signal.freqz(b, ad, worN=w)
    ph = np.unwrap(np.angle(hresp))
    gd = -(ph[1] - ph[0]) / (w[1] - w[0]) * dt
    check("second-order stage: discrete group delay at 0.5 Hz vs 2 zeta wn (wn^2+w^2)/(...)", abs(gd / st.group_delay(0.5) - 1.0), 1e-3)
    check("second-order stage: group delay at 0.5 Hz vs its equivalent lag 2 zeta/wn", abs(st.group_delay(0.5) / st.equivalent_lag() - 1.0), 2e-3)
    x = np.ones(40000)
    check("second-order stage: unit DC gain", abs(stand.apply_stage(st, x, dt)[-1] - 1.0), 1e-12)

    # End to end: in torque_lag_15ms the felt torque is the reported one through the stage, so a
    # sinusoid fit of both at the sine's frequency shows the stage's phase delay atan(w tau)/w.
    case = replace(stand.CASES_BY_NAME["torque_lag_15ms"], duration=20.0)
    out = stand.simulate(case, 5, noise_scale=0.0)
    g = out["grid"]
    sel = g["t"] >= 2.0
    tt = g["t"][sel]
    w0 = 2 * math.pi / case.period

    def phase(x):
        X = np.column_stack([np.sin(w0 * tt), np.cos(w0 * tt), np.ones_like(tt)])
        c, *_ = np.linalg.lstsq(X, x, rcond=None)
        return math.atan2(c[1], c[0])

    delay = (phase(g["torque_reported_source"][sel]) - phase(g["felt"][sel])) / w0
    check("torque_lag_15ms: felt lags reported by atan(w tau)/w at the sine's frequency",
          abs(delay / stand.first_order(0.015).phase_delay(0.5) - 1.0), 1e-3)


# ----------------------------------------------------------------------------------------------
# 4. Every case: integration consistency, energy, and the truth file against the data
# ----------------------------------------------------------------------------------------------


def every_case() -> None:
    for base in stand.CASES:
        # 16 s keeps the check fast and still holds transient_early's window (10-13 s).
        case = replace(base, duration=16.0)
        out = stand.simulate(case, 11, noise_scale=0.0)
        doc = stand.truth(case, 11, out, 0.0)
        g = out["grid"]
        H = 1.0 / out["state_rate"]
        switching = base.coulomb or base.braking or base.electric or base.transient
        w = g["omega"]
        # Energy: drive work = kinetic energy change + dissipated work (trapezoid).
        def integral(x):
            return float(np.sum(0.5 * H * (x[1:] + x[:-1])))

        ke = 0.5 * doc["J"] * (w[-1] ** 2 - w[0] ** 2)
        work_in = integral(g["felt"] * w)
        lost = integral((g["drag"] + g["viscous"] + g["friction"] + g["brake"] + g["load"]) * w)
        check(f"{base.name}: energy balance |W_drive - dKE - W_lost| / W_drive",
              abs(work_in - ke - lost) / abs(work_in), 1e-5 if not switching else 1e-4)

        # The truth file against the data: the torque balance written from the JSON alone, on the
        # grid where the stages were applied (so exact), relative to the torque noise.
        resid = stand.truth_torque_residual(doc, g["t"], g["force_reported"], w, g["accel_reported"])
        check(f"{base.name}: torque balance of the JSON's truth on the noise-free grid, max / torque noise",
              float(np.max(np.abs(resid))) / case.rotor.torque_noise, 1e-9)
        floor = doc["truth_model_on_noise_free_samples"]["relative_to_torque_noise"]
        check(f"{base.name}: the same on the feedback samples (stages at {case.rate:g} Hz), rms / torque noise",
              floor, 0.05)
        if base.name == "clean":
            seed_fit = doc["seed_model_on_noise_free_data"]
            check("clean: the seed's model fitted to the noise-free data gives J and c2 exactly (max |error| %)",
                  max(abs(seed_fit["J_error_pct"]), abs(seed_fit["c2_error_pct"])), 1e-6, " %")


# ----------------------------------------------------------------------------------------------
# 5. The electrical and thrust model
# ----------------------------------------------------------------------------------------------


def electrical() -> None:
    el = stand.ELECTRIC
    case = replace(stand.CASES_BY_NAME["thrust_steps"], duration=12.0)
    out = stand.simulate(case, 2, noise_scale=0.0)
    g = out["grid"]
    H = 1.0 / out["state_rate"]
    # Steady state at the end of the init (duty 0.9 for 5 s): Kt (d Vs - Ke w)/R' = Kt I0 + c2 w^2.
    d = float(np.float16(0.9))  # the duty as the float16 setpoint carries it
    r_eff = el.R + el.R_supply * d * d
    kt = el.kt
    qa, qb, qc = el.c2, kt * kt / r_eff, kt * el.I0 - kt * d * el.V_supply / r_eff
    w_exact = (-qb + math.sqrt(qb * qb - 4 * qa * qc)) / (2 * qa)
    i0 = int(np.searchsorted(g["t"], -1e-9))
    check("electrical: steady speed at duty 0.9 solves Kt(d Vs - Ke w)/R' = Kt I0 + c2 w^2",
          abs(g["omega"][i0] / w_exact - 1.0), 1e-9)
    # Back-EMF law at every instant: d V_bus = Ke w + R I (the relation Kv and R come from).
    resid = g["duty"] * g["voltage_bus"] - (kt * g["omega"] + el.R * g["current_motor"])
    check("electrical: d*V_bus = Ke*w + R*I at every instant, max |residual|", float(np.max(np.abs(resid))), 1e-9, " V")
    # Thrust and torque laws: T/(rho n^2 D^4) = C_T; the drag equals C_Q rho n^2 D^5.
    n = g["omega"] / (2 * math.pi)
    sel = n > 10.0
    check("thrust: T/(rho n^2 D^4) = C_T", rel(g["thrust"][sel] / (el.rho * n[sel] ** 2 * el.D**4), el.C_T), 1e-12)
    check("torque: drag/(rho n^2 D^5) = C_Q", rel(g["drag"][sel] / (el.rho * n[sel] ** 2 * el.D**5), el.C_Q), 1e-12)
    # The load cell reads J a + drag.
    check("load cell: force = J a + Q_aero", float(np.max(np.abs(g["force_reported"] - (case.rotor.J * g["a"] + g["drag"])))), 1e-12, " N*m")

    # Power: the supply's work = supply-lead loss + winding loss + no-load loss + aero work + dKE.
    def integral(x):
        return float(np.sum(0.5 * H * (x[1:] + x[:-1])))

    i_bus, i_m, w = g["current_bus"], g["current_motor"], g["omega"]
    p_supply = integral(el.V_supply * i_bus)
    parts = (integral(el.R_supply * i_bus**2) + integral(el.R * i_m**2) + integral(kt * el.I0 * np.abs(w))
             + integral(g["drag"] * w) + 0.5 * case.rotor.J * (w[-1] ** 2 - w[0] ** 2))
    check("electrical: supply energy = R_s I_bus^2 + R I^2 + Kt I0 |w| + Q_aero w + dKE", abs(p_supply - parts) / p_supply, 1e-4)
    # The ESC's current filter is the first-order stage on the bus current.
    rebuilt = stand.apply_stage(stand.first_order(el.current_filter), i_bus, H)
    check("current column = bus current through the 1 ms filter", float(np.max(np.abs(rebuilt - g["current_reported"]))), 1e-12, " A")


# ----------------------------------------------------------------------------------------------
# 6. Noise, format, determinism
# ----------------------------------------------------------------------------------------------


def noise_and_format() -> None:
    case = replace(stand.CASES_BY_NAME["clean"], duration=60.0)
    out = stand.simulate(case, 7, noise_scale=1.0)
    r = stand.SEVEN_INCH
    nf = out["force"] - out["force_true"]
    nv = out["velocity"] - out["velocity_true"]
    na = out["acceleration"] - out["acceleration_true"]
    check("torque noise std / stated", abs(np.std(nf) / r.torque_noise - 1.0), 0.03)
    check("velocity noise std / stated", abs(np.std(nv) / r.velocity_noise - 1.0), 0.03)
    check("acceleration noise std / stated", abs(np.std(na) / r.accel_noise - 1.0), 0.03)
    lag1 = float(np.corrcoef(na[1:], na[:-1])[0, 1])
    check("acceleration noise is a first difference (lag-1 correlation -0.5)", abs(lag1 + 0.5), 0.03)

    with tempfile.TemporaryDirectory() as d1, tempfile.TemporaryDirectory() as d2:
        short = replace(stand.CASES_BY_NAME["thrust_sine"], duration=6.0)
        paths = [stand.run_case(short, 4, d)[0] for d in (d1, d2)]
        other = stand.run_case(short, 5, d1)[0]
        digests = [hashlib.sha256(open(p, "rb").read()).hexdigest() for p in paths + [other]]
        check("same seed, same bytes (0 = identical)", float(digests[0] != digests[1]), 0.0)
        check("another seed, other bytes (0 = different)", float(digests[0] == digests[2]), 0.0)
        with open(paths[0], encoding="ascii") as fh:
            header = fh.readline().rstrip("\n").split("\t")
            rows = [line.rstrip("\n").split("\t") for line in fh]
        check("header is ts_local t force velocity acceleration position thrust voltage current command (0 = yes)",
              float(header != stand.BASE_COLUMNS + stand.ELECTRIC_COLUMNS), 0.0)
        m = np.array(rows, dtype=float)
        check("one row per sample (rows - duration*rate)", float(abs(len(rows) - 6.0 * short.rate)), 0.0)
        dtv = np.diff(m[:, 1])
        check("t steps by exactly 1/rate (max |dt - 1/rate|)", float(np.max(np.abs(dtv - 1.0 / short.rate))), 1e-9, " s")
        check("ts_local never decreases (count of decreases)", float(np.sum(np.diff(m[:, 0]) < 0)), 0.0)
        # Each printed value is a float32 (DoF3rdTs carries float32): read as float32 and printed
        # again with 9 significant digits, it gives back the same text.
        texts = [v for row in rows for v in row[2:]]
        changed = sum(1 for v in texts if "%.9g" % float(np.float32(float(v))) != v)
        check("printed values are float32 (count of values that do not round-trip)", float(changed), 0.0)
        with open(os.path.splitext(paths[0])[0] + ".json", encoding="utf-8") as fh:
            doc = json.load(fh)
        check("truth JSON names every column of the TSV (0 = yes)", float(doc["columns"] != header), 0.0)


def readme_table() -> None:
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "README.md")
    with open(path, encoding="utf-8") as fh:
        text = fh.read()
    check("README.md's case table is stand.py --markdown-table (0 = yes)", float(stand.markdown_table() not in text), 0.0)


def main(argv=None) -> int:
    start = time.monotonic()
    for part in (rotor_closed_forms, convergence, independent_integrator, stages, electrical, noise_and_format, readme_table, every_case):
        part()
    failed = [line for ok, line in RESULTS if not ok]
    print(f"{len(RESULTS) - len(failed)} of {len(RESULTS)} checks passed in {time.monotonic() - start:.1f} s")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
