#!/usr/bin/env python3
"""An independent reference stand for propid.

Simulates a propeller on a motor drive driven the way the seed's driver drives it (a ratiometric
torque setpoint: a few seconds at `hi`, then a pattern between `lo` and `hi`), and writes what the
drive reports as propid's TSV together with a JSON file holding the truth: the rotor's inertia J,
its drag c2, every effect hidden in the data with its value and unit in propid's vocabulary, how
each value was derived, and what an ideal report would say.

It is written from first principles, without reading propid's own simulators or its diagnosis, so
that a diagnosis that passes on these data has been tested against something its authors did not
write. Every model equation is stated in README.md beside this file; `selfcheck.py` checks the
simulator against closed-form results.

Usage:
    python3 stand.py --list
    python3 stand.py --case NAME --seed N --out DIR [--rate HZ] [--duration S]
                     [--pattern sine|chirp|steps] [--noise-scale X]
    python3 stand.py --all --seed N --out DIR
    python3 stand.py --selfcheck

Only numpy and scipy are needed.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import zlib
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import signal

GENERATOR = "tests/independent_stand/stand.py"
GENERATOR_VERSION = 1

TWO_PI = 2.0 * math.pi

# Integration: the rotor's state is advanced by classical RK4 with step H on a grid of at least
# STATE_RATE_MIN Hz (an integer multiple of the feedback rate). The drive latches its setpoint at
# the same rate (its current loop's), and every input is linear between grid points.
STATE_RATE_MIN = 4000.0
# A step in which a switching mode changes (the sign of the speed for Coulomb friction, "the rotor
# slows" for braking) is redone in this many sub-steps, the mode frozen at each sub-step's start.
REFINE_SUBSTEPS = 64


# ----------------------------------------------------------------------------------------------
# Building blocks: rotors, linear stages, the motor, the cases
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Rotor:
    """The mechanical load and the drive's full scale, with the drive's sensor noise."""

    label: str
    J: float  # inertia [kg*m^2]
    c2: float  # quadratic drag coefficient [N*m*s^2/rad^2]
    q_fs: float  # torque at setpoint 1.0 [N*m]
    omega_ref: float  # speed [rad/s] at which a |w|^p drag law equals the quadratic one
    torque_noise: float  # [N*m], standard deviation, white
    velocity_noise: float  # [rad/s], standard deviation, white
    accel_noise: float  # [rad/s^2], standard deviation of a first-difference (blue) sequence


def propeller(label: str, J: float, c2: float, q_fs: float, omega_ref: float) -> Rotor:
    """A rotor on a torque-mode drive with the drive's noise: torque 1.5 % of full scale, velocity
    0.5 rad/s, acceleration 3 % of full-scale torque / J."""
    return Rotor(label, J, c2, q_fs, omega_ref, 0.015 * q_fs, 0.5, 0.03 * q_fs / J)


# A 7-inch propeller (J and c2 as the brief gives them; C_Q = 4 pi^2 c2 / (rho D^5) = 2.7e-3).
SEVEN_INCH = propeller("7-inch propeller", J=2e-5, c2=1.5e-8, q_fs=0.1, omega_ref=1500.0)

# A large propeller (numbers of issue 24).
LARGE = propeller("large propeller", J=1e-2, c2=1e-5, q_fs=4.0, omega_ref=400.0)


@dataclass(frozen=True)
class Stage:
    """A linear single-input single-output stage: first order, second order or a pure delay."""

    kind: str  # "first_order" | "second_order" | "delay"
    tau: float = 0.0  # [s] first order and delay
    fn: float = 0.0  # [Hz] second order natural frequency
    zeta: float = 0.0  # [1] second order damping ratio

    def transfer_function(self):
        if self.kind == "first_order":
            return [1.0], [self.tau, 1.0]
        if self.kind == "second_order":
            wn = TWO_PI * self.fn
            return [wn * wn], [1.0, 2.0 * self.zeta * wn, wn * wn]
        raise ValueError(f"stage {self.kind} has no rational transfer function")

    def equivalent_lag(self) -> float:
        """The low-frequency group delay -d(phase)/d(omega) at omega = 0 [s]."""
        if self.kind in ("first_order", "delay"):
            return self.tau
        return 2.0 * self.zeta / (TWO_PI * self.fn)

    def group_delay(self, f_hz: float) -> float:
        """-d(phase)/d(omega) at f_hz [s]."""
        w = TWO_PI * f_hz
        if self.kind == "delay":
            return self.tau
        if self.kind == "first_order":
            return self.tau / (1.0 + (w * self.tau) ** 2)
        wn = TWO_PI * self.fn
        z = self.zeta
        return 2.0 * z * wn * (wn * wn + w * w) / ((wn * wn - w * w) ** 2 + (2.0 * z * wn * w) ** 2)

    def phase_delay(self, f_hz: float) -> float:
        """-phase(omega)/omega at f_hz [s]: the time shift of a sinusoid of that frequency."""
        w = TWO_PI * f_hz
        if self.kind == "delay":
            return self.tau
        if self.kind == "first_order":
            return math.atan(w * self.tau) / w
        wn = TWO_PI * self.fn
        return math.atan2(2.0 * self.zeta * wn * w, wn * wn - w * w) / w

    def describe(self) -> dict:
        if self.kind == "first_order":
            return {
                "kind": "first_order",
                "transfer_function": "1/(1 + s*tau)",
                "tau_s": self.tau,
            }
        if self.kind == "delay":
            return {"kind": "delay", "transfer_function": "exp(-s*tau)", "tau_s": self.tau}
        return {
            "kind": "second_order",
            "transfer_function": "wn^2/(s^2 + 2*zeta*wn*s + wn^2)",
            "natural_frequency_hz": self.fn,
            "damping_ratio": self.zeta,
        }

    def derivation(self) -> str:
        if self.kind == "first_order":
            return (
                "first-order stage 1/(1+s*tau): phase -atan(omega*tau), group delay "
                "tau/(1+(omega*tau)^2), which is tau at low frequency; value = tau"
            )
        if self.kind == "delay":
            return "pure delay exp(-s*tau): group delay tau at every frequency; value = tau"
        return (
            "second-order stage wn^2/(s^2+2*zeta*wn*s+wn^2): phase -atan2(2*zeta*wn*omega, "
            "wn^2-omega^2), group delay at omega -> 0 is 2*zeta/wn; value = 2*zeta/(2*pi*fn) = "
            f"2*{self.zeta}/(2*pi*{self.fn} Hz)"
        )


def first_order(tau: float) -> Stage:
    return Stage("first_order", tau=tau)


def second_order(fn: float, zeta: float) -> Stage:
    return Stage("second_order", fn=fn, zeta=zeta)


@dataclass(frozen=True)
class Electric:
    """A DC-equivalent brushless motor on an averaged PWM bridge fed from a bench supply, with a
    propeller whose thrust and torque follow the static coefficient laws, on a stand with load cells
    for torque and thrust. The command is the PWM duty."""

    kv_rpm_per_v: float = 1800.0  # motor speed constant [rpm/V]
    R: float = 0.075  # DC-equivalent (line-to-line) winding resistance [ohm]
    I0: float = 1.0  # no-load current [A]
    V_supply: float = 16.0  # open-circuit supply voltage [V]
    R_supply: float = 0.03  # supply + leads resistance [ohm]
    current_filter: float = 1e-3  # the ESC's first-order current-sense filter [s]
    C_T: float = 0.10  # static thrust coefficient, T = C_T rho n^2 D^4 (n in rev/s)
    C_Q: float = 0.0065  # static torque coefficient, Q = C_Q rho n^2 D^5
    D: float = 0.1778  # diameter [m] (7 inch)
    rho: float = 1.225  # air density [kg/m^3]
    thrust_noise: float = 0.02  # [N]
    voltage_noise: float = 0.01  # [V]
    current_noise: float = 0.05  # [A]

    @property
    def kt(self) -> float:
        """Torque constant = back-EMF constant in SI [N*m/A] = [V*s/rad]."""
        return 60.0 / (TWO_PI * self.kv_rpm_per_v)

    @property
    def c2(self) -> float:
        return self.C_Q * self.rho * self.D**5 / (4.0 * math.pi**2)

    @property
    def kthrust(self) -> float:
        """Thrust per omega^2 [N*s^2/rad^2]."""
        return self.C_T * self.rho * self.D**4 / (4.0 * math.pi**2)


ELECTRIC = Electric()

# The rotor of the thrust cases: the 7-inch inertia with the drag of the propeller law above.
SEVEN_INCH_THRUST = Rotor(
    label="7-inch propeller with thrust and an electrical motor model",
    J=2e-5,
    c2=ELECTRIC.c2,
    q_fs=float("nan"),  # duty mode: no torque full scale
    omega_ref=1500.0,
    torque_noise=1.5e-3,
    velocity_noise=0.5,
    accel_noise=0.03 * 0.16 / 2e-5,
)


@dataclass(frozen=True)
class Case:
    name: str
    description: str
    rotor: Rotor = SEVEN_INCH
    rate: float = 500.0  # feedback samples per second
    duration: float = 120.0  # recorded seconds (after the init)
    pattern: str = "sine"
    lo: float = 0.1
    hi: float = 0.9
    period: float = 2.0  # sine period [s] (the seed's default)
    chirp_f0: float = 0.2
    chirp_f1: float = 8.0
    step_levels: int = 5
    step_hold: float = 2.0
    init_duration: float = 5.0  # the seed's default: 5 s at hi before the pattern
    current_loop: float = 1e-4  # closed current loop time constant, setpoint -> torque [s]
    torque_lag: Stage | None = None
    force_sensor: Stage | None = None
    accel_lag: Stage | None = None
    force_offset: float = 0.0  # [N*m]
    viscous: float = 0.0  # c1 [N*m*s/rad]
    coulomb: float = 0.0  # [N*m]
    drag_exponent: float = 2.0  # p
    braking: float = 0.0  # [N*m]
    transient: tuple[float, float, float] | None = None  # (t_start, length, torque)
    electric: Electric | None = None
    thrust_sensor: Stage | None = None  # the thrust load cell's stage (electrical cases)
    hold_rate: float = 0.0  # load-cell conversions per second, held between (0: fresh every sample)
    tags: tuple[str, ...] = field(default_factory=tuple)


REVERSING = dict(lo=-0.6, hi=0.6)

CASES: list[Case] = [
    Case("clean", "7-inch propeller, seed's sine, nothing hidden"),
    Case(
        "clean_chirp",
        "7-inch propeller, chirp 0.2-8 Hz, nothing hidden",
        pattern="chirp",
    ),
    Case(
        "torque_lag_8ms",
        "first-order torque lag of 8 ms (felt torque lags the reported one), 500 Hz",
        torque_lag=first_order(0.008),
    ),
    Case(
        "torque_lag_15ms",
        "first-order torque lag of 15 ms",
        torque_lag=first_order(0.015),
    ),
    Case(
        "force_offset",
        "reported torque reads +0.02 N*m above the true one",
        force_offset=0.02,
    ),
    Case(
        "viscous",
        "viscous friction c1 = 3e-6 N*m*s/rad (about 7 mN*m at top speed)",
        viscous=3e-6,
    ),
    Case(
        "coulomb_reversing",
        "Coulomb friction 5 mN*m on a reversing sine (-0.6..0.6)",
        coulomb=0.005,
        **REVERSING,
    ),
    Case(
        "drag_exponent_1p8",
        "drag |w|^1.8 (equal to the quadratic law at 1500 rad/s)",
        drag_exponent=1.8,
    ),
    Case(
        "drag_exponent_2p2",
        "drag |w|^2.2 (equal to the quadratic law at 1500 rad/s)",
        drag_exponent=2.2,
    ),
    Case(
        "force_sensor_lag",
        "reported torque through a first-order 10 ms filter",
        force_sensor=first_order(0.010),
    ),
    Case(
        "force_sensor_2nd_order",
        "reported torque through a second-order load-cell stage, 15 Hz, zeta 0.7",
        force_sensor=second_order(15.0, 0.7),
    ),
    Case(
        "acceleration_lag",
        "reported acceleration through a first-order 10 ms filter",
        accel_lag=first_order(0.010),
    ),
    Case(
        "braking",
        "8 mN*m braking the reported torque does not show while the rotor slows",
        braking=0.008,
    ),
    Case(
        "lag_offset",
        "torque lag 15 ms + force offset +0.02 N*m",
        torque_lag=first_order(0.015),
        force_offset=0.02,
    ),
    Case(
        "lag_viscous",
        "torque lag 10 ms + viscous friction c1 = 3e-6 N*m*s/rad",
        torque_lag=first_order(0.010),
        viscous=3e-6,
    ),
    Case(
        "lag_coulomb_reversing",
        "torque lag 10 ms + Coulomb friction 5 mN*m on a reversing sine",
        torque_lag=first_order(0.010),
        coulomb=0.005,
        **REVERSING,
    ),
    Case(
        "drag_exponent_offset",
        "drag |w|^1.8 + force offset +0.02 N*m",
        drag_exponent=1.8,
        force_offset=0.02,
    ),
    Case(
        "braking_lag",
        "braking 8 mN*m + torque lag 10 ms",
        braking=0.008,
        torque_lag=first_order(0.010),
    ),
    Case(
        "sensor_filter_drag_exponent",
        "reported torque through a first-order 10 ms filter + drag |w|^2.2",
        force_sensor=first_order(0.010),
        drag_exponent=2.2,
    ),
    Case(
        "large_clean",
        "large propeller J=1e-2, c2=1e-5, 4 N*m full scale, 100 Hz, nothing hidden",
        rotor=LARGE,
        rate=100.0,
    ),
    Case(
        "large_torque_lag_25ms",
        "large propeller, torque lag 25 ms, 100 Hz",
        rotor=LARGE,
        rate=100.0,
        torque_lag=first_order(0.025),
    ),
    Case(
        "transient_late",
        "a load of +0.03 N*m for 3 s at t = 70 s of a 120 s run",
        transient=(70.0, 3.0, 0.03),
    ),
    Case(
        "transient_early",
        "a load of +0.03 N*m for 3 s at t = 10 s of a 120 s run",
        transient=(10.0, 3.0, 0.03),
    ),
    Case(
        "thrust_sine",
        "duty-commanded motor (Kv, R, I0, supply) + thrust; load-cell torque; duty sine 0.1-0.9",
        rotor=SEVEN_INCH_THRUST,
        electric=ELECTRIC,
        tags=("thrust", "electrical"),
    ),
    Case(
        "thrust_loadcell",
        "as thrust_sine, torque and thrust from load cells: 15 Hz zeta 0.7 stage, 80 Hz held conversions",
        rotor=SEVEN_INCH_THRUST,
        electric=ELECTRIC,
        force_sensor=second_order(15.0, 0.7),
        thrust_sensor=second_order(15.0, 0.7),
        hold_rate=80.0,
        tags=("thrust", "electrical"),
    ),
    Case(
        "thrust_steps",
        "as thrust_sine on duty steps 0.9 -> 0.1 -> 0.9 (9 levels, 3 s each)",
        rotor=SEVEN_INCH_THRUST,
        electric=ELECTRIC,
        pattern="steps",
        step_levels=9,
        step_hold=3.0,
        tags=("thrust", "electrical"),
    ),
]

CASES_BY_NAME = {c.name: c for c in CASES}


# ----------------------------------------------------------------------------------------------
# The excitation
# ----------------------------------------------------------------------------------------------


def setpoint(case: Case, t: np.ndarray, phase0: float) -> np.ndarray:
    """The ratiometric setpoint (torque, or duty in the electrical cases) at times t [s]; t < 0 is
    the seed's init at `hi`. The seed sends it as float16 (zubax.primitive.real16.Vector31)."""
    lo, hi = case.lo, case.hi
    mid, amp = 0.5 * (lo + hi), 0.5 * (hi - lo)
    tp = np.maximum(t, 0.0)
    if case.pattern == "sine":
        u = mid + amp * np.sin(phase0 + TWO_PI * tp / case.period)
    elif case.pattern == "chirp":
        f0, f1, T = case.chirp_f0, case.chirp_f1, case.duration
        k = math.log(f1 / f0)
        ph = TWO_PI * f0 * T / k * (np.exp(k * tp / T) - 1.0)
        u = mid + amp * np.sin(0.5 * math.pi + ph)
    elif case.pattern == "steps":
        n = case.step_levels
        levels = [lo + (hi - lo) * i / (n - 1) for i in range(n)]
        # Down from hi (where the init left the rotor) to lo and back up: every step is one level.
        seq = np.array(levels[::-1] + levels[1:-1])
        idx = np.floor(tp / case.step_hold).astype(np.int64) % len(seq)
        u = seq[idx]
    else:
        raise ValueError(f"unknown pattern {case.pattern!r}")
    u = np.where(t < 0.0, hi, u)
    return u.astype(np.float16).astype(np.float64)


def pattern_description(case: Case) -> dict:
    d = {"name": case.pattern, "lo": case.lo, "hi": case.hi, "init_at_hi_s": case.init_duration}
    if case.pattern == "sine":
        d.update(
            period_s=case.period,
            formula="u = (lo+hi)/2 + (hi-lo)/2 * sin(phase0 + 2*pi*t/period); phase0 random per seed "
            "(pi/2 in the duty-commanded cases: they start at hi, where the init left them)",
        )
    elif case.pattern == "chirp":
        d.update(
            f0_hz=case.chirp_f0,
            f1_hz=case.chirp_f1,
            formula="u = (lo+hi)/2 + (hi-lo)/2 * sin(pi/2 + 2*pi*f0*T/ln(f1/f0)*((f1/f0)^(t/T)-1)), "
            "T = duration (one exponential sweep)",
        )
    else:
        d.update(
            levels=case.step_levels,
            hold_s=case.step_hold,
            formula="staircase of equal steps from hi down to lo and back up, each level held hold_s, "
            "repeated",
        )
    d["quantisation"] = "float16, as the seed's Vector31 of real16 carries it"
    return d


# ----------------------------------------------------------------------------------------------
# Linear stages on a uniform grid
# ----------------------------------------------------------------------------------------------


def apply_stage(stage: Stage, x: np.ndarray, dt: float) -> np.ndarray:
    """The stage's response to x sampled every dt, x taken as piecewise linear between samples
    (first-order-hold discretisation: exact for such an input), starting in steady state."""
    if stage.kind == "delay":
        t = np.arange(len(x)) * dt
        return np.interp(t - stage.tau, t, x, left=x[0])
    num, den = stage.transfer_function()
    bd, ad, _ = signal.cont2discrete((num, den), dt, method="foh")
    b = np.atleast_1d(np.squeeze(bd)).astype(float)
    a = np.atleast_1d(np.squeeze(ad)).astype(float)
    zi = signal.lfilter_zi(b, a) * x[0]
    y, _ = signal.lfilter(b, a, x, zi=zi)
    return y


# ----------------------------------------------------------------------------------------------
# The rotor: J dw/dt = U(t) - D(t) w - k |w|^p sgn(w) - Fc sgn(w) - B [slowing] sgn(w)
# ----------------------------------------------------------------------------------------------


def _drag_fn(kp: float, p: float):
    if p == 2.0:
        return lambda w: kp * w * abs(w)
    return lambda w: math.copysign(kp * abs(w) ** p, w)


def integrate_rotor(
    U: list[float],
    Dm: list[float],
    J: float,
    kp: float,
    p: float,
    coulomb: float,
    braking: float,
    H: float,
    w0: float = 0.0,
):
    """Integrates the rotor over the n steps of H between the n+1 grid points where U (drive torque
    minus external load, N*m) and Dm (linear damping, N*m*s/rad) are given; both are linear between
    grid points (so the RK4 midpoint inputs are the averages of the ends). Returns the speed and the
    angle at the grid points.

    Smooth terms go through classical RK4. Coulomb friction and braking switch: within a step their
    mode (the speed's sign; whether the rotor slows) is frozen at the step's start; a step whose
    mode differs at its end is redone in REFINE_SUBSTEPS sub-steps, each with the mode frozen at its
    own start. A rotor at rest sticks while the drive torque is within the Coulomb friction."""
    n = len(U) - 1
    W = np.empty(n + 1)
    TH = np.empty(n + 1)
    w = float(w0)
    th = 0.0
    W[0] = w
    TH[0] = th
    inv_j = 1.0 / J
    half = 0.5 * H
    sixth = H / 6.0
    quad = p == 2.0

    if coulomb == 0.0 and braking == 0.0:
        # The fast path: no switching terms.
        u0 = U[0]
        d0 = Dm[0]
        for m in range(n):
            u1 = U[m + 1]
            d1 = Dm[m + 1]
            um = 0.5 * (u0 + u1)
            dm = 0.5 * (d0 + d1)
            if quad:
                k1 = (u0 - d0 * w - kp * w * abs(w)) * inv_j
                w2 = w + half * k1
                k2 = (um - dm * w2 - kp * w2 * abs(w2)) * inv_j
                w3 = w + half * k2
                k3 = (um - dm * w3 - kp * w3 * abs(w3)) * inv_j
                w4 = w + H * k3
                k4 = (u1 - d1 * w4 - kp * w4 * abs(w4)) * inv_j
            else:
                k1 = (u0 - d0 * w - math.copysign(kp * abs(w) ** p, w)) * inv_j
                w2 = w + half * k1
                k2 = (um - dm * w2 - math.copysign(kp * abs(w2) ** p, w2)) * inv_j
                w3 = w + half * k2
                k3 = (um - dm * w3 - math.copysign(kp * abs(w3) ** p, w3)) * inv_j
                w4 = w + H * k3
                k4 = (u1 - d1 * w4 - math.copysign(kp * abs(w4) ** p, w4)) * inv_j
            th += sixth * (w + 2.0 * w2 + 2.0 * w3 + w4)
            w += sixth * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
            W[m + 1] = w
            TH[m + 1] = th
            u0 = u1
            d0 = d1
        return W, TH

    drag = _drag_fn(kp, p)

    def mode(w, u, d):
        if w > 0.0:
            sc = 1.0
        elif w < 0.0:
            sc = -1.0
        else:
            sc = 1.0 if u > 0.0 else (-1.0 if u < 0.0 else 0.0)
        br = 0.0
        if braking > 0.0:
            unbraked = u - d * w - drag(w) - coulomb * sc
            if unbraked * sc < 0.0:
                br = 1.0
        return sc, br

    def rk4(w, u0, u1, d0, d1, dt):
        hh = 0.5 * dt
        um = 0.5 * (u0 + u1)
        dm = 0.5 * (d0 + d1)
        k1 = (u0 - d0 * w - drag(w)) * inv_j
        w2 = w + hh * k1
        k2 = (um - dm * w2 - drag(w2)) * inv_j
        w3 = w + hh * k2
        k3 = (um - dm * w3 - drag(w3)) * inv_j
        w4 = w + dt * k3
        k4 = (u1 - d1 * w4 - drag(w4)) * inv_j
        return w + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4), dt / 6.0 * (w + 2.0 * w2 + 2.0 * w3 + w4)

    K = REFINE_SUBSTEPS
    hs = H / K
    stuck = w == 0.0 and coulomb > 0.0
    sc, br = mode(w, U[0], Dm[0])
    for m in range(n):
        u0, u1 = U[m], U[m + 1]
        d0, d1 = Dm[m], Dm[m + 1]
        if stuck:
            if abs(u0) <= coulomb:
                W[m + 1] = 0.0
                TH[m + 1] = th
                continue
            stuck = False
            sc, br = mode(0.0, u0, d0)
        ex = (coulomb + braking * br) * sc
        w1, dth = rk4(w, u0 - ex, u1 - ex, d0, d1, H)
        sc1, br1 = mode(w1, u1, d1)
        if sc1 != sc or br1 != br:
            # Redo the step in sub-steps with the mode re-evaluated at each sub-step's start.
            ww = w
            dth = 0.0
            du = (u1 - u0) / K
            dd = (d1 - d0) / K
            for k in range(K):
                ua = u0 + du * k
                ub = ua + du
                da = d0 + dd * k
                db = da + dd
                if stuck:
                    if abs(ua) <= coulomb:
                        continue
                    stuck = False
                sck, brk = mode(ww, ua, da)
                exk = (coulomb + braking * brk) * sck
                wn, dthk = rk4(ww, ua - exk, ub - exk, da, db, hs)
                if coulomb > 0.0 and wn * sck < 0.0 and abs(ub) <= coulomb:
                    wn = 0.0  # crossed zero where friction can hold it: it sticks
                    stuck = True
                ww = wn
                dth += dthk
            w1 = ww
            sc1, br1 = mode(w1, u1, d1)
        w = w1
        th += dth
        sc, br = sc1, br1
        W[m + 1] = w
        TH[m + 1] = th
    return W, TH


# ----------------------------------------------------------------------------------------------
# The simulation
# ----------------------------------------------------------------------------------------------


def _rng(seed: int, name: str) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence([int(seed), zlib.crc32(name.encode())]))


def drag_coefficient(case: Case) -> float:
    """k in k |w|^p sgn(w): equal to the quadratic law c2 w^2 at omega_ref."""
    p = case.drag_exponent
    return case.rotor.c2 * case.rotor.omega_ref ** (2.0 - p)


def grids(case: Case, state_rate_min: float = STATE_RATE_MIN):
    """(state rate, state steps per sample, init steps, rows, total steps)."""
    per_sample = int(math.ceil(state_rate_min / case.rate))
    f_state = case.rate * per_sample
    n_init = int(round(case.init_duration * f_state))
    n_rows = int(round(case.duration * case.rate))
    n_total = n_init + n_rows * per_sample
    return f_state, per_sample, n_init, n_rows, n_total


def simulate(case: Case, seed: int, noise_scale: float = 1.0, state_rate_min: float | None = None):
    """Runs the case. Returns a dict with the sampled columns ('t', 'force', ...), the noise-free
    signals on the output samples (keys ending in '_true') and on the state grid ('grid')."""
    f_state, per_sample, n_init, n_rows, n_total = grids(case, state_rate_min or STATE_RATE_MIN)
    H = 1.0 / f_state
    rng = _rng(seed, case.name)
    phase0 = float(rng.uniform(0.0, TWO_PI))
    if case.electric is not None:
        # A duty step from hi to lo at full speed would drive ~ -130 A of regenerative current
        # (no current limit is modelled): the duty sine starts where the init left it.
        phase0 = 0.5 * math.pi
    rotor = case.rotor
    J = rotor.J

    # The grid (the drive's latch rate and the integration's) from -init to the end. Every input is
    # linear between grid points.
    t_grid = (np.arange(n_total + 1) - n_init) * H
    u = setpoint(case, t_grid, phase0)

    load = np.zeros_like(t_grid)
    if case.transient is not None:
        t0, length, q = case.transient
        # On from t0 to t0+length (both on the grid); the edges are linear over one step.
        load = q * np.clip(np.minimum((t_grid - t0) / H + 1.0, (t0 + length - t_grid) / H), 0.0, 1.0)

    el = case.electric
    if el is None:
        tau_ref = u * rotor.q_fs
        tau_drive = apply_stage(first_order(case.current_loop), tau_ref, H)
        if case.torque_lag is not None:
            # The drive reports its torque; the rotor feels it through the lag.
            reported_source = tau_drive
            tau_felt = apply_stage(case.torque_lag, tau_drive, H)
        else:
            reported_source = None
            tau_felt = tau_drive
        A = tau_felt
        Bc = np.zeros_like(t_grid)
        coulomb = case.coulomb
    else:
        # Duty d: I = (d Vs - Ke w)/(R + Rs d^2), torque Kt I = A - Bc w.
        d = u
        r_eff = el.R + el.R_supply * d * d
        A = el.kt * d * el.V_supply / r_eff
        Bc = el.kt * el.kt / r_eff
        reported_source = None
        coulomb = el.kt * el.I0  # the no-load loss torque acts on the rotor like Coulomb friction
    kp = drag_coefficient(case)
    p = case.drag_exponent
    U = A - load
    Dm = Bc + case.viscous
    W, TH = integrate_rotor(U.tolist(), Dm.tolist(), J, kp, p, coulomb, case.braking, H)

    # Noise-free signals on the grid.
    Ug, Dg, Ag, Bg, Lg = U, Dm, A, Bc, load
    drag = np.sign(W) * kp * np.abs(W) ** p
    sc = np.sign(W)
    sc = np.where(sc == 0.0, np.sign(Ug), sc)
    friction = coulomb * sc
    unbraked = Ug - Dg * W - drag - friction
    slowing = (unbraked * sc < 0.0) if case.braking > 0.0 else np.zeros_like(W, dtype=bool)
    brake = case.braking * slowing * sc
    stuck = (W == 0.0) & (np.abs(Ug) <= coulomb) if coulomb > 0.0 else np.zeros_like(W, dtype=bool)
    a_true = np.where(stuck, 0.0, (unbraked - brake) / J)
    drive_torque = Ag - Bg * W  # the torque the motor puts on the rotor (felt)

    grid = {
        "t": t_grid,
        "omega": W,
        "theta": TH,
        "a": a_true,
        "felt": drive_torque,
        "load": Lg,
        "drag": drag,
        "viscous": case.viscous * W,
        "friction": np.where(stuck, 0.0, friction),
        "brake": brake,
        "slowing": slowing,
        "setpoint": u,
    }

    # What the sensors report, noise-free, on the state grid.
    if el is None:
        source = reported_source if reported_source is not None else drive_torque
        force = apply_stage(case.force_sensor, source, H) if case.force_sensor is not None else source
        force = force + case.force_offset
    else:
        # A stator load cell reads the reaction of everything acting between rotor and stator:
        # the electromagnetic torque minus the rotor's losses = J a + aerodynamic drag.
        force = J * a_true + drag
        if case.force_sensor is not None:
            force = apply_stage(case.force_sensor, force, H)
        force = force + case.force_offset
    accel = apply_stage(case.accel_lag, a_true, H) if case.accel_lag is not None else a_true
    grid["force_reported"] = force
    grid["accel_reported"] = accel
    if reported_source is not None:
        grid["torque_reported_source"] = reported_source

    if el is not None:
        dg = u
        r_eff = el.R + el.R_supply * dg * dg
        current_motor = (dg * el.V_supply - el.kt * W) / r_eff
        i_bus = dg * current_motor
        v_bus = el.V_supply - el.R_supply * i_bus
        grid.update(
            current_motor=current_motor,
            current_bus=i_bus,
            voltage_bus=v_bus,
            current_reported=apply_stage(first_order(el.current_filter), i_bus, H),
            thrust=el.kthrust * W * np.abs(W),
            duty=dg,
        )

    # Sample at the feedback instants t_k = k / rate, k = 0 .. n_rows-1.
    idx = n_init + per_sample * np.arange(n_rows)
    t = (idx - n_init) * H
    out = {
        "t": np.round(t * 1e6) / 1e6,
        "force_true": force[idx],
        "velocity_true": W[idx],
        "acceleration_true": accel[idx],
        "position_true": TH[idx],
    }
    s = noise_scale
    n = n_rows
    hold = None
    if case.hold_rate > 0.0:
        # Load-cell conversions at hold_phase + m/hold_rate; each row holds the last one.
        hold_phase = float(rng.uniform(0.0, 1.0 / case.hold_rate))
        m = np.floor((t - hold_phase) * case.hold_rate).astype(np.int64)
        t_conv = hold_phase + m / case.hold_rate
        hold = {"phase": hold_phase, "m": m - m.min(), "n": int(m.max() - m.min() + 1)}
        out["force_true_continuous"] = out["force_true"]
        out["force_true"] = np.interp(t_conv, grid["t"], force)
    if hold is None:
        noise_force = s * rotor.torque_noise * rng.standard_normal(n)
    else:
        # A held value carries the noise of its conversion.
        noise_force = s * rotor.torque_noise * rng.standard_normal(hold["n"])[hold["m"]]
    noise_vel = s * rotor.velocity_noise * rng.standard_normal(n)
    wa = rng.standard_normal(n + 1)
    noise_acc = s * rotor.accel_noise * (wa[1:] - wa[:-1]) / math.sqrt(2.0)
    latency = 4e-4 + rng.exponential(3e-4, n)
    host_offset = 1000.0 + float(rng.uniform(0.0, 1000.0))
    out["force"] = out["force_true"] + noise_force
    out["velocity"] = out["velocity_true"] + noise_vel
    out["acceleration"] = out["acceleration_true"] + noise_acc
    out["position"] = out["position_true"]
    out["ts_local"] = np.maximum.accumulate(t + host_offset + latency)
    if el is not None:
        thrust = grid["thrust"]
        if case.thrust_sensor is not None:
            thrust = apply_stage(case.thrust_sensor, thrust, H)
        grid["thrust_reported"] = thrust
        out["thrust_true"] = thrust[idx] if hold is None else np.interp(t_conv, grid["t"], thrust)
        out["voltage_true"] = grid["voltage_bus"][idx]
        out["current_true"] = grid["current_reported"][idx]
        out["command"] = grid["duty"][idx]
        thrust_noise = s * el.thrust_noise * rng.standard_normal(n if hold is None else hold["n"])
        out["thrust"] = out["thrust_true"] + (thrust_noise if hold is None else thrust_noise[hold["m"]])
        out["voltage"] = out["voltage_true"] + s * el.voltage_noise * rng.standard_normal(n)
        out["current"] = out["current_true"] + s * el.current_noise * rng.standard_normal(n)
    out["grid"] = grid
    # The rotor's inputs on the grid, for selfcheck's independent integration.
    out["inputs"] = {"t": t_grid, "U": U, "D": Dm, "kp": kp, "p": p, "coulomb": coulomb, "braking": case.braking}
    out["sample_index"] = idx
    out["phase0"] = phase0
    out["hold"] = hold
    out["state_rate"] = f_state
    return out


# ----------------------------------------------------------------------------------------------
# Output: TSV and truth
# ----------------------------------------------------------------------------------------------

BASE_COLUMNS = ["ts_local", "t", "force", "velocity", "acceleration", "position"]
ELECTRIC_COLUMNS = ["thrust", "voltage", "current", "command"]


def columns(case: Case) -> list[str]:
    return BASE_COLUMNS + (ELECTRIC_COLUMNS if case.electric is not None else [])


def write_tsv(path: str, case: Case, out: dict) -> None:
    cols = columns(case)
    f32 = lambda x: np.asarray(x, dtype=np.float32).astype(np.float64)  # noqa: E731
    data = []
    fmts = []
    for c in cols:
        if c in ("ts_local", "t"):
            data.append(out[c])
            fmts.append("%.6f")
        else:
            data.append(f32(out[c]))  # DoF3rdTs carries float32
            fmts.append("%.9g")
    matrix = np.column_stack(data)
    with open(path, "w", encoding="ascii", newline="\n") as fh:
        np.savetxt(fh, matrix, fmt=fmts, delimiter="\t", header="\t".join(cols), comments="")


def _rms(x) -> float:
    x = np.asarray(x, dtype=float)
    return float(np.sqrt(np.mean(x * x))) if x.size else 0.0


def _effect(name, value, unit, **extra):
    d = {"name": name, "value": value, "unit": unit}
    d.update(extra)
    return d


def seed_model_fit(force, accel, omega, trim=0.1):
    """The seed's model (c1 = 0) fitted to noise-free reported signals by least squares on the
    acceleration error, after the seed's trimming of the first 10 %: a = x1 * force - x2 * w|w|,
    J = 1/x1, c2 = x2/x1. Shows what the seed's regressor would conclude without noise."""
    k0 = int(trim * (len(force) - 1))
    X = np.column_stack([force[k0:], -omega[k0:] * np.abs(omega[k0:])])
    x, *_ = np.linalg.lstsq(X, accel[k0:], rcond=None)
    return 1.0 / x[0], x[1] / x[0]


def stage_from_model(model: dict) -> Stage:
    """The Stage a truth file's `model` describes."""
    if model["kind"] == "first_order":
        return first_order(model["tau_s"])
    if model["kind"] == "delay":
        return Stage("delay", tau=model["tau_s"])
    return second_order(model["natural_frequency_hz"], model["damping_ratio"])


def truth_torque_residual(doc: dict, t, force, omega, accel) -> np.ndarray:
    """The torque balance of the truth model, written with only what the truth file `doc` says,
    on reported columns sampled uniformly at times t: zero (to the discretisation of the stages on
    that grid) on noise-free data, [N*m].

    Without a force-sensor stage, the rotor's acceleration is rebuilt from the reported force
    (offset removed, torque lag applied, drag, frictions, braking, load transients subtracted,
    acceleration lag applied) and the residual is J*(rebuilt - reported acceleration). With one,
    the felt torque is rebuilt from the reported acceleration and the losses, passed through the
    sensor stage, offset added, and the residual is that minus the reported force."""
    dt = float(t[1] - t[0])
    eff = {e["name"]: e for e in doc["effects"]}
    J = doc["J"]
    w = np.asarray(omega, dtype=float)
    sgn = np.sign(w)
    if "drag_exponent" in eff:
        e = eff["drag_exponent"]
        drag = sgn * e["drag_coefficient"] * np.abs(w) ** e["value"]
    else:
        drag = doc["c2"] * w * np.abs(w)
    losses = drag.copy()
    if "viscous_friction" in eff:
        losses += eff["viscous_friction"]["value"] * w
    load = np.zeros_like(w)
    for u in doc["unexplained"]:
        load += np.where((t >= u["t_start_s"]) & (t < u["t_end_s"]), u["torque_Nm"], 0.0)
    offset = eff["force_offset"]["value"] if "force_offset" in eff else 0.0
    fc = eff["coulomb_friction"]["value"] if "coulomb_friction" in eff else 0.0
    brake = eff["braking_torque"]["value"] if "braking_torque" in eff else 0.0

    if "force_sensor_lag" in eff:
        # Braking acts exactly while the rotor slows: a*sgn(w) < 0.
        a = np.asarray(accel, dtype=float)
        felt = J * a + losses + fc * sgn + load + brake * np.where(a * sgn < 0.0, sgn, 0.0)
        rebuilt = apply_stage(stage_from_model(eff["force_sensor_lag"]["model"]), felt, dt) + offset
        return rebuilt - force

    felt = np.asarray(force, dtype=float) - offset
    if "torque_lag" in eff:
        felt = apply_stage(stage_from_model(eff["torque_lag"]["model"]), felt, dt)
    torque = felt - losses - load
    if fc:
        # Against the motion; at rest, against the drive torque that starts it; and at rest it
        # sticks while the drive torque is within the friction.
        torque -= fc * np.where(w != 0.0, sgn, np.sign(felt - load))
        torque = np.where((w == 0.0) & (np.abs(felt - load) <= fc), 0.0, torque)
    if brake:
        torque -= np.where(torque * sgn < 0.0, brake * sgn, 0.0)
    a = torque / J
    if "acceleration_lag" in eff:
        a = apply_stage(stage_from_model(eff["acceleration_lag"]["model"]), a, dt)
    return J * (a - accel)


def hold_description(case: Case, out: dict) -> dict:
    return {
        "conversions_per_s": case.hold_rate,
        "first_conversion_s": out["hold"]["phase"] - 1.0 / case.hold_rate,
        "rule": "conversions at first_conversion_s + m/conversions_per_s; a row holds the stage's "
        "output at the last conversion at or before its t (with that conversion's noise), so the "
        "value updates on about one row in rate/conversions_per_s; read at its updates, the stage's "
        "lag is the value above, and the hold adds nothing",
    }


def truth(case: Case, seed: int, out: dict, noise_scale: float) -> dict:
    rotor = case.rotor
    grid = out["grid"]
    idx = out["sample_index"]
    omega = grid["omega"][idx]
    a_true = grid["a"][idx]
    fundamental = 1.0 / case.period if case.pattern == "sine" else None
    p = case.drag_exponent
    kp = drag_coefficient(case)
    sigma_tau = rotor.torque_noise * noise_scale

    effects = []
    alternatives = []
    notes = []

    def visibility(rms):
        return {
            "torque_rms_if_ignored_Nm": rms,
            "relative_to_torque_noise": (rms / sigma_tau) if sigma_tau > 0 else None,
        }

    def lag_entry(name, stage, rms, what):
        e = _effect(
            name,
            stage.equivalent_lag(),
            "s",
            model=stage.describe(),
            mechanism=what,
            derivation=stage.derivation(),
        )
        if fundamental:
            e["group_delay_at_fundamental_s"] = stage.group_delay(fundamental)
            e["phase_delay_at_fundamental_s"] = stage.phase_delay(fundamental)
        elif case.pattern == "chirp":
            e["group_delay_at_chirp_ends_s"] = [
                stage.group_delay(case.chirp_f0),
                stage.group_delay(case.chirp_f1),
            ]
        e.update(visibility(rms))
        return e

    if case.torque_lag is not None:
        src = grid["torque_reported_source"][idx]
        effects.append(
            lag_entry(
                "torque_lag",
                case.torque_lag,
                _rms(grid["felt"][idx] - src),
                "the drive reports the torque it commands; the rotor feels it through this stage "
                "(a slow current loop)",
            )
        )
    if case.force_sensor is not None:
        if case.electric is None:
            src = grid.get("torque_reported_source", grid["felt"])[idx]
        else:
            src = rotor.J * a_true + grid["drag"][idx]
        entry = lag_entry(
            "force_sensor_lag",
            case.force_sensor,
            _rms(out.get("force_true_continuous", out["force_true"]) - case.force_offset - src),
            "the reported torque is the felt torque through this stage (a telemetry filter or "
            "a load cell)",
        )
        if out["hold"] is not None:
            entry["held"] = hold_description(case, out)
        effects.append(entry)
    if case.accel_lag is not None:
        effects.append(
            lag_entry(
                "acceleration_lag",
                case.accel_lag,
                rotor.J * _rms(out["acceleration_true"] - a_true),
                "the reported acceleration is the true one through this stage (the drive's "
                "differentiating estimator)",
            )
        )
    if case.force_offset != 0.0:
        effects.append(
            _effect(
                "force_offset",
                case.force_offset,
                "N*m",
                mechanism="reported torque = felt torque + offset (a current-sense or load-cell zero error)",
                derivation="direct parameter: reported minus true torque at zero torque",
                **visibility(abs(case.force_offset)),
            )
        )
        if omega.min() > 0.0:
            alternatives.append(
                {
                    "instead_of": "force_offset",
                    "name": "coulomb_friction",
                    "value": case.force_offset,
                    "unit": "N*m",
                    "why": "the speed never changes sign in this run, so a constant torque the "
                    "rotor does not feel (offset) and a friction Fc*sgn(w) are the same signal: "
                    "an ideal report names the offset or says 'ambiguous between force_offset and "
                    "coulomb_friction' with this value, and advises a reversing run",
                }
            )
    if case.coulomb != 0.0:
        reversals = int(np.count_nonzero(np.diff(np.sign(omega[omega != 0.0])) != 0))
        effects.append(
            _effect(
                "coulomb_friction",
                case.coulomb,
                "N*m",
                mechanism="friction torque -Fc*sgn(w) on the rotor (bearings), not in the reported torque",
                derivation="direct parameter; stick at rest while |drive torque| <= Fc",
                speed_sign_changes=reversals,
                **visibility(case.coulomb),
            )
        )
    if case.viscous != 0.0:
        effects.append(
            _effect(
                "viscous_friction",
                case.viscous,
                "N*m*s/rad",
                mechanism="friction torque -c1*w on the rotor, not in the reported torque",
                derivation="direct parameter c1",
                **visibility(_rms(case.viscous * omega)),
            )
        )
    if p != 2.0:
        w2 = omega * np.abs(omega)
        lawp = np.sign(omega) * kp * np.abs(omega) ** p
        c2_eq = float(np.dot(lawp, w2) / np.dot(w2, w2))
        effects.append(
            _effect(
                "drag_exponent",
                p,
                "1",
                mechanism="aerodynamic drag k*|w|^p*sgn(w) instead of c2*w*|w|",
                derivation=f"direct parameter p; k = c2_ref * w_ref^(2-p) with c2_ref = {rotor.c2}, "
                f"w_ref = {rotor.omega_ref} rad/s, so that the law equals the quadratic one at w_ref",
                drag_coefficient=kp,
                drag_coefficient_unit=f"N*m*(s/rad)^{p}",
                c2_quadratic_equivalent=c2_eq,
                c2_quadratic_equivalent_derivation="least squares of c2*w|w| on k|w|^p over this "
                "run's true speeds (uniform in time)",
                **visibility(_rms(lawp - c2_eq * w2)),
            )
        )
    if case.braking != 0.0:
        frac = float(np.mean(grid["slowing"][idx]))
        effects.append(
            _effect(
                "braking_torque",
                case.braking,
                "N*m",
                mechanism="while the rotor slows (net torque without braking < 0), an extra torque "
                "-B*sgn(w) acts on it that the reported torque does not show (regenerative or "
                "active braking the current sense misses)",
                derivation="direct parameter B; applied exactly when the rotor decelerates, so the "
                "model is consistent (a < 0 whenever it acts)",
                fraction_of_time_slowing=frac,
                **visibility(case.braking * math.sqrt(frac)),
            )
        )

    unexplained = []
    if case.transient is not None:
        t0, length, q = case.transient
        unexplained.append(
            {
                "name": "unexplained",
                "kind": "load_transient",
                "t_start_s": t0,
                "t_end_s": t0 + length,
                "torque_Nm": q,
                "mechanism": "an extra load torque q against the rotation, rectangular in time, that "
                "the reported torque does not show (a rub, a gust)",
                "relative_to_torque_noise": q / sigma_tau if sigma_tau > 0 else None,
            }
        )

    ideal = {
        "J": rotor.J,
        "J_unit": "kg*m^2",
        "c2": kp if p != 2.0 else rotor.c2,
        "c2_unit": "N*m*s^2/rad^2" if p == 2.0 else f"N*m*(s/rad)^{p} (coefficient of |w|^p)",
        "effects": {e["name"]: {"value": e["value"], "unit": e["unit"]} for e in effects},
        "unexplained": [{"t_start_s": u["t_start_s"], "t_end_s": u["t_end_s"]} for u in unexplained],
        "equivalent_alternatives": alternatives,
    }
    if not effects and not unexplained:
        notes.append("nothing is hidden: an ideal report names no effect and says the seed's model explains the data")

    J_seed, c2_seed = seed_model_fit(out["force_true"], out["acceleration_true"], omega)

    doc = {
        "case": case.name,
        "description": case.description,
        "seed": seed,
        "generator": {
            "path": GENERATOR,
            "version": GENERATOR_VERSION,
            "integration": {
                "method": "classical RK4 on the rotor speed and angle; switching terms (Coulomb, "
                "braking) refined in sub-steps; linear stages by exact first-order-hold discretisation",
                "state_rate_hz": out["state_rate"],
                "input_latch_rate_hz": out["state_rate"],
                "refine_substeps": REFINE_SUBSTEPS,
            },
        },
        "rows": int(len(out["t"])),
        "rate_hz": case.rate,
        "duration_s": case.duration,
        "columns": columns(case),
        "units": {
            "ts_local": "s (host receive time)",
            "t": "s (device time, microsecond resolution; 0 at the start of the pattern)",
            "force": "N*m",
            "velocity": "rad/s",
            "acceleration": "rad/s^2",
            "position": "rad",
            "thrust": "N",
            "voltage": "V",
            "current": "A",
            "command": "ratio (PWM duty)",
        },
        "pattern": pattern_description(case),
        "sine_phase0_rad": out["phase0"],
        "rotor": {
            "label": rotor.label,
            "J": rotor.J,
            "J_unit": "kg*m^2",
            "c2": rotor.c2,
            "c2_unit": "N*m*s^2/rad^2",
            "full_scale_torque_Nm": None if case.electric is not None else rotor.q_fs,
            "drag_law": "c2*w*|w|" if p == 2.0 else f"k*|w|^{p}*sgn(w), k = {kp}",
        },
        "J": rotor.J,
        "c2": kp if p != 2.0 else rotor.c2,
        "effects": effects,
        "unexplained": unexplained,
        "ideal_report": ideal,
        "notes": notes,
        "noise": {
            "scale": noise_scale,
            "force_Nm": rotor.torque_noise * noise_scale,
            "velocity_rad_s": rotor.velocity_noise * noise_scale,
            "acceleration_rad_s2": rotor.accel_noise * noise_scale,
            "acceleration_spectrum": "first difference of white noise (blue), as a differentiating "
            "estimator gives; its standard deviation is the value above",
            "float32": "force, velocity, acceleration, position (and the electrical columns) are "
            "rounded to float32 as DoF3rdTs carries them",
        },
        "run_statistics": {
            "omega_min_rad_s": float(omega.min()),
            "omega_max_rad_s": float(omega.max()),
            "omega_mean_rad_s": float(omega.mean()),
            "acceleration_rms_rad_s2": _rms(a_true),
            "setpoint_min": float(grid["setpoint"][idx].min()),
            "setpoint_max": float(grid["setpoint"][idx].max()),
        },
        "seed_model_on_noise_free_data": {
            "J": J_seed,
            "c2": c2_seed,
            "J_error_pct": 100.0 * (J_seed / rotor.J - 1.0),
            "c2_error_pct": 100.0 * (c2_seed / rotor.c2 - 1.0),
            "method": "a = force/J - (c2/J)*w|w| by least squares on the noise-free reported "
            "force and acceleration and the true speed, first 10 % dropped (the seed's trimming), c1 = 0",
        },
    }
    # The floor: the truth model, written from this document alone, on the noise-free samples a
    # diagnosis sees (its stages discretised at the feedback rate), after the seed's 10 % trimming.
    resid = truth_torque_residual(
        doc,
        out["t"],
        out.get("force_true_continuous", out["force_true"]),
        out["velocity_true"],
        out["acceleration_true"],
    )[int(0.1 * (len(out["t"]) - 1)) :]
    doc["truth_model_on_noise_free_samples"] = {
        "torque_residual_rms_Nm": _rms(resid),
        "relative_to_torque_noise": _rms(resid) / rotor.torque_noise,
        "meaning": "the torque balance of the stated truth on the noise-free samples (stages "
        "discretised at the feedback rate, first 10 % dropped; a held force taken before its "
        "hold): how close a perfect diagnosis can come before any noise; compare with the torque "
        "noise of one sample",
    }
    el = case.electric
    if el is not None:
        doc["electrical"] = {
            "model": "DC-equivalent brushless motor on an averaged PWM bridge: "
            "I = (d*V_supply - Ke*w)/(R + R_supply*d^2), V_bus = V_supply - R_supply*I_bus, "
            "I_bus = d*I, shaft torque Kt*(I - I0*sgn(w)); the ESC's current sense is I_bus through "
            "a first-order filter",
            "Kv_rpm_per_V": el.kv_rpm_per_v,
            "Kt_Nm_per_A": el.kt,
            "Ke_V_s_per_rad": el.kt,
            "R_ohm": el.R,
            "I0_A": el.I0,
            "V_supply_V": el.V_supply,
            "R_supply_ohm": el.R_supply,
            "current_filter_s": el.current_filter,
            "voltage_column": "V_bus (after the supply's resistance), as the ESC measures it",
            "current_column": "I_bus, the supply (DC-link) current, after the current filter",
            "command_column": "PWM duty d as applied (float16)",
            "force_column": "stator load cell: Kt*I - Kt*I0*sgn(w) = J*a + Q_aero"
            + (" through the load cell's stage (force_sensor_lag)" if case.force_sensor else " (no effect hidden)"),
            "no_load_torque_Nm": el.kt * el.I0,
        }
        doc["thrust"] = {
            "C_T": el.C_T,
            "C_Q": el.C_Q,
            "C_P": TWO_PI * el.C_Q,
            "D_m": el.D,
            "rho_kg_m3": el.rho,
            "law": "T = C_T*rho*n^2*D^4, Q = C_Q*rho*n^2*D^5, n = w/(2*pi) rev/s",
            "c2_from_C_Q": el.c2,
            "thrust_per_omega2": el.kthrust,
            "thrust_sensor": "load cell, no lag, white noise"
            if case.thrust_sensor is None
            else {
                "model": case.thrust_sensor.describe(),
                "equivalent_lag_s": case.thrust_sensor.equivalent_lag(),
                "derivation": case.thrust_sensor.derivation(),
            },
        }
        if out["hold"] is not None:
            doc["thrust"]["held"] = hold_description(case, out)
        doc["ideal_report"]["motor"] = {
            "Kv_rpm_per_V": el.kv_rpm_per_v,
            "R_ohm": el.R,
            "I0_A": el.I0,
        }
        doc["ideal_report"]["propeller"] = {"C_T": el.C_T, "C_Q": el.C_Q, "D_m": el.D, "rho_kg_m3": el.rho}
    return doc


def run_case(case: Case, seed: int, out_dir: str, noise_scale: float = 1.0) -> tuple[str, str]:
    out = simulate(case, seed, noise_scale)
    os.makedirs(out_dir, exist_ok=True)
    stem = os.path.join(out_dir, f"{case.name}-seed{seed}")
    write_tsv(stem + ".tsv", case, out)
    doc = truth(case, seed, out, noise_scale)
    with open(stem + ".json", "w", encoding="utf-8") as fh:
        json.dump(doc, fh, indent=2)
        fh.write("\n")
    return stem + ".tsv", stem + ".json"


def with_overrides(case: Case, rate=None, duration=None, pattern=None) -> Case:
    changes = {}
    if rate is not None:
        changes["rate"] = rate
    if duration is not None:
        changes["duration"] = duration
    if pattern is not None:
        changes["pattern"] = pattern
    return replace(case, **changes) if changes else case


def markdown_table() -> str:
    """The case table README.md carries (selfcheck asserts README has exactly this)."""
    lines = [
        "| case | rotor | rate | pattern (lo..hi) | hidden (truth) |",
        "|---|---|---|---|---|",
    ]
    for c in CASES:
        lags = (("torque_lag", c.torque_lag), ("force_sensor_lag", c.force_sensor), ("acceleration_lag", c.accel_lag))
        hidden = [f"{name} {st.equivalent_lag() * 1e3:.4g} ms" for name, st in lags if st]
        scalars = (
            ("force_offset", c.force_offset, f"{c.force_offset:+g} N·m"),
            ("viscous_friction", c.viscous, f"{c.viscous:g} N·m·s/rad"),
            ("coulomb_friction", c.coulomb, f"{c.coulomb:g} N·m"),
            ("drag_exponent", c.drag_exponent != 2.0, f"{c.drag_exponent:g}"),
            ("braking_torque", c.braking, f"{c.braking:g} N·m"),
        )
        hidden += [f"{name} {text}" for name, present, text in scalars if present]
        if c.transient:
            t0, length, q = c.transient
            hidden.append(f"unexplained {t0:g}–{t0 + length:g} s (+{q:g} N·m load)")
        if c.hold_rate:
            hidden.append(f"held at {c.hold_rate:g} Hz")
        if c.electric:
            hidden.append(
                "C_T, C_Q, Kv, R, I0 to identify"
                + (f"; thrust through the same {c.thrust_sensor.equivalent_lag() * 1e3:.4g} ms stage" if c.thrust_sensor else "")
            )
        rotor = {"7-inch propeller": "7-inch", "large propeller": "large"}.get(c.rotor.label, "7-inch + motor")
        lohi = f"{c.pattern} ({c.lo:g}..{c.hi:g})"
        lines.append(
            f"| `{c.name}` | {rotor} | {c.rate:g} Hz | {lohi} | {', '.join(hidden) or 'none'} |"
        )
    return "\n".join(lines) + "\n"


# ----------------------------------------------------------------------------------------------
# Command line
# ----------------------------------------------------------------------------------------------


def _number(name: str, allow_zero: bool):
    """An argparse type: a finite number above zero (or at least zero), named in its error."""

    def parse(text):
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a number, got {text!r}") from None
        if not (math.isfinite(v) and (v >= 0.0 if allow_zero else v > 0.0)):
            what = "zero or positive" if allow_zero else "a positive number"
            raise argparse.ArgumentTypeError(f"{name} must be {what}, got {text!r}")
        return v

    return parse


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        prog="stand.py",
        description="Independent reference stand for propid: writes DIR/NAME-seedN.tsv and its truth DIR/NAME-seedN.json.",
    )
    ap.add_argument("--list", action="store_true", help="list the cases and exit")
    ap.add_argument("--markdown-table", action="store_true", help="print README's case table and exit")
    ap.add_argument("--selfcheck", action="store_true", help="run selfcheck.py and exit with its status")
    ap.add_argument("--case", help="case name (see --list)")
    ap.add_argument("--all", action="store_true", help="write every case")
    ap.add_argument("--seed", type=int, default=None, help="noise and phase seed (integer)")
    ap.add_argument("--out", help="output directory (created if missing)")
    ap.add_argument("--rate", type=_number("--rate", False), help="feedback rate [Hz] (default: the case's)")
    ap.add_argument("--duration", type=_number("--duration", False), help="recorded seconds (default: the case's)")
    ap.add_argument("--pattern", choices=["sine", "chirp", "steps"], help="excitation (default: the case's)")
    ap.add_argument(
        "--noise-scale",
        type=_number("--noise-scale", True),
        default=1.0,
        help="multiplies every noise level (0: noise-free); default 1",
    )
    args = ap.parse_args(argv)

    if args.list:
        width = max(len(c.name) for c in CASES)
        for c in CASES:
            print(f"{c.name:<{width}}  {c.description}")
        return 0
    if args.markdown_table:
        sys.stdout.write(markdown_table())
        return 0
    if args.selfcheck:
        here = os.path.dirname(os.path.abspath(__file__))
        sys.path.insert(0, here)
        import selfcheck  # noqa: PLC0415

        return selfcheck.main([])
    if not args.case and not args.all:
        ap.error("give --case NAME (see --list), --all, --list or --selfcheck")
    if args.case and args.all:
        ap.error("give either --case or --all, not both")
    if args.seed is None:
        ap.error("--seed N is required to write a case")
    if args.seed < 0:
        ap.error(f"--seed must be zero or positive, got {args.seed}")
    if not args.out:
        ap.error("--out DIR is required to write a case")
    if args.case and args.case not in CASES_BY_NAME:
        ap.error(f"--case {args.case!r} is not a case; --list shows the {len(CASES)} cases")
    chosen = CASES if args.all else [CASES_BY_NAME[args.case]]
    for case in chosen:
        case = with_overrides(case, args.rate, args.duration, args.pattern)
        if case.duration * case.rate < 10:
            ap.error(f"--duration {case.duration:g} s at {case.rate:g} Hz gives fewer than 10 rows")
        try:
            tsv, js = run_case(case, args.seed, args.out, args.noise_scale)
        except OSError as exc:
            print(f"stand.py: cannot write to {args.out}: {exc.strerror}", file=sys.stderr)
            return 1
        print(f"{tsv}\t{js}")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except BrokenPipeError:  # `stand.py --list | head`: the reader left; nothing to report
        sys.stderr.close()
        sys.exit(0)
