"""The functions of the package: data in (a DataFrame, a dict of arrays or a path), typed results
out, every computation in the Rust crates the command uses (``propid._propid``)."""

from __future__ import annotations

import json
import os
import tempfile
from typing import Any, Dict, List, Mapping, Optional, Tuple, Union

import numpy as np
import pandas as pd

from . import _propid
from ._propid import InputError
from ._results import Diagnosis, FitResult, Plan

#: A recording: a pandas DataFrame or a mapping of column names to arrays (the TSV's column names
#: ``t``, ``force``, ``velocity``, ``acceleration``, optionally ``ts_local`` and ``position``), or
#: the path of a TSV.
Data = Union[pd.DataFrame, Mapping[str, Any], str, "os.PathLike[str]"]

_REQUIRED = ("t", "force", "velocity", "acceleration")
_OPTIONAL = ("ts_local", "position", "thrust")


def _is_path(data: Any) -> bool:
    return isinstance(data, (str, bytes, os.PathLike))


def _columns(data: Any, names: Tuple[str, ...]) -> Tuple[Dict[str, np.ndarray], str]:
    """The named columns of a DataFrame or mapping as contiguous float64 arrays (a view where
    the column already is one: no copy), and the name messages give the data."""
    if isinstance(data, pd.DataFrame):
        name = str(data.attrs.get("source", "<DataFrame>"))
        have = [str(c) for c in data.columns]
        get = lambda c: data[c].to_numpy(dtype=np.float64, copy=False)  # noqa: E731
    elif isinstance(data, Mapping):
        name = "<dict>"
        have = [str(c) for c in data.keys()]
        get = lambda c: np.asarray(data[c], dtype=np.float64)  # noqa: E731
    else:
        raise TypeError(
            f"data must be a pandas DataFrame, a dict of arrays or a path, not {type(data).__name__}"
        )
    out = {}
    for c in names:
        if c not in have:
            if c in _OPTIONAL:
                continue
            # The words of the TSV reader's message for the same file.
            raise InputError(f"{name}: missing column `{c}` (columns: {', '.join(have)})")
        a = np.ascontiguousarray(get(c))
        if a.ndim != 1:
            raise InputError(f"{name}: column `{c}` must be one-dimensional (shape {a.shape})")
        out[c] = a
    return out, name


def fit(
    data: Data,
    *,
    mass_min: Optional[float] = None,
    mass_max: Optional[float] = None,
    c1_max: Optional[float] = None,
    c2_max: Optional[float] = None,
    diameter: Optional[float] = None,
    density: Optional[float] = None,
    flip_torque: bool = False,
    velocity_unit: Optional[str] = None,
) -> FitResult:
    """Fits the seed's model ``J·a = F − c1·ω − c2·ω|ω|`` exactly, with the seed's trimming
    (the last run of complete rows, its first 10 % dropped) and bounds — ``propid fit``.

    ``data`` is a DataFrame or dict with the columns ``t``, ``force``, ``velocity``,
    ``acceleration``, or the path of a TSV (read as ``propid fit`` reads it: memory-mapped, on
    all cores). The bounds are the command's flags; ``None`` takes the command's default
    (``mass_min`` 1e-9, ``mass_max`` 1e3, ``c1_max`` 0 — no viscous term, as the seed —,
    ``c2_max`` 1e2). ``diameter`` [m] adds the torque coefficient C_Q at ``density``
    (default 1.225 kg/m³). ``flip_torque`` and ``velocity_unit`` (``"rpm"``, ``"rev/s"``,
    ``"deg/s"``) read the columns as the command's ``--flip-torque`` and ``--velocity-unit`` do
    (what its plausibility check asks for when the sign or the unit looks wrong).

    Raises :class:`propid.InputError` with the command's message when the data cannot give a
    fit. The work runs without the GIL.
    """
    bounds = dict(
        mass_min=mass_min,
        mass_max=mass_max,
        c1_max=c1_max,
        c2_max=c2_max,
        diameter=diameter,
        density=density,
        flip_torque=flip_torque,
        velocity_unit=velocity_unit,
    )
    if _is_path(data):
        return FitResult(json.loads(_propid.fit_path(os.fspath(data), bounds)))
    cols, name = _columns(data, _REQUIRED)
    return FitResult(json.loads(_propid.fit_columns(*cols.values(), name, bounds)))


def diagnose(data: Data, *, max_effects: int = 3, **options: Any) -> Diagnosis:
    """What the fitted model gets wrong, the named cause, the extended model and the measured
    gain — ``propid diagnose``.

    ``data`` as for :func:`fit`; ``ts_local`` (host receive times), ``position`` and ``thrust``
    are used when present. Rows with a missing value are skipped (and counted in the notes).
    Every option of ``propid diagnose`` is a keyword argument, ``-`` written ``_``, checked as the
    command checks it: ``diameter="7in"`` (C_Q, and C_T where there is thrust), ``density``,
    ``temperature`` with ``pressure``, ``flip_torque=True``, ``velocity_unit="rpm"``,
    ``despike=True``, ``compare="force_sensor_lag,drag_exponent"`` (a model to score beside the
    one named: ``result.compared``). ``str(result)`` is the command's text report.

    Raises :class:`propid.CannotJudge` when the data cannot support a verdict (the diagnosis,
    with its reasons, is the exception's ``diagnosis``), :class:`propid.InputError` for bad
    input or a bad option. The work runs without the GIL.
    """
    flags = _flags({"max_effects": max_effects, **options})
    if _is_path(data):
        report, text, cannot_judge = _propid.diagnose_path(os.fspath(data), flags)
    else:
        cols, name = _columns(data, _REQUIRED + _OPTIONAL)
        report, text, cannot_judge = _propid.diagnose_columns(
            cols["t"],
            cols["force"],
            cols["velocity"],
            cols["acceleration"],
            cols.get("ts_local"),
            cols.get("position"),
            cols.get("thrust"),
            name,
            flags,
        )
    result = Diagnosis(json.loads(report), text)
    if cannot_judge is not None:
        error = _propid.CannotJudge(cannot_judge)
        error.diagnosis = result
        raise error
    return result


def _frame(columns: Dict[str, np.ndarray], source: Optional[str]) -> pd.DataFrame:
    frame = pd.DataFrame(columns, copy=False)
    if source is not None:
        frame.attrs["source"] = source
    return frame


def read_tsv(path: Union[str, "os.PathLike[str]"]) -> pd.DataFrame:
    """Reads a recording (propid's TSV, the seed driver's output) with propid's reader: the
    columns ``t``, ``force``, ``velocity``, ``acceleration``, ``ts_local`` and ``position`` when
    the header has them, and the stand columns ``thrust`` [N], ``voltage`` [V], ``current`` [A]
    and ``command`` when it has them (other columns are ignored, as by ``propid fit``). Empty fields and
    ``nan`` are NaN. ``attrs["source"]`` holds the path, so :func:`fit` and :func:`diagnose` of
    the frame name the file in their messages, as they do given the path.

    Raises :class:`propid.InputError` naming the file, line and column of bad input.
    """
    path = os.fspath(path)
    return _frame(_propid.read_tsv(path), path)


def _imported(columns: Dict[str, np.ndarray], assumptions: List[str], path: str) -> pd.DataFrame:
    frame = _frame(columns, None)
    frame.attrs["assumptions"] = assumptions
    frame.attrs["imported_from"] = path
    return frame


def import_rcbench(
    path: Union[str, "os.PathLike[str]"], *, subtract_zero_offset: bool = False
) -> pd.DataFrame:
    """An RCbenchmark / Tyto Robotics CSV export as a recording — ``propid import rcbench``.

    Returns the TSV's columns plus ``command`` (the ESC signal) when the log has one;
    ``attrs["assumptions"]`` lists what the importer measured and assumed (the command prints
    them on stderr).
    """
    path = os.fspath(path)
    return _imported(*_propid.import_rcbench(path, subtract_zero_offset), path)


def import_autoquad(path: Union[str, "os.PathLike[str]"], *, kv: float) -> pd.DataFrame:
    """AutoQuad ESC32 telemetry as a recording — ``propid import autoquad --kv KV``: torque
    from the bus current and duty with Kt = 60/(2π·kv). As :func:`import_rcbench` returns."""
    path = os.fspath(path)
    return _imported(*_propid.import_autoquad(path, float(kv)), path)


def _flags(options: Mapping[str, Any]) -> List[str]:
    """Keyword arguments as the command's flags: ``torque_lag=0.012`` → ``--torque-lag=0.012``
    (joined, so that a negative value is a value), ``True`` → the bare flag, ``False`` and
    ``None`` → nothing."""
    out: List[str] = []
    for key, value in options.items():
        flag = "--" + key.replace("_", "-")
        if value is None or value is False:
            continue
        if value is True:
            out.append(flag)
        else:
            text = os.fspath(value) if isinstance(value, os.PathLike) else str(value)
            out.append(f"{flag}={text}")
    return out


def simulate(*, output: Optional[Union[str, "os.PathLike[str]"]] = None, **options: Any) -> pd.DataFrame:
    """A simulated stand's recording — ``propid sim``, run in-process.

    Every option of ``propid sim`` is a keyword argument, ``-`` written ``_``
    (``propid sim --help`` lists them): for example ``duration=60``, ``rate=500``,
    ``pattern="chirp"``, ``torque_lag=0.012``, ``seed=3``, ``stand="mechanism"``,
    ``pattern_file=plan_path``. ``output`` keeps the TSV at that path too. The command's
    summary line goes to stderr.

    Raises :class:`propid.InputError` with the command's message for a bad option.
    """
    if output is not None:
        _propid.call_cli(["propid", "sim", *_flags(options), "--output", os.fspath(output)])
        return read_tsv(output)
    with tempfile.TemporaryDirectory(prefix="propid-") as tmp:
        path = os.path.join(tmp, "sim.tsv")
        _propid.call_cli(["propid", "sim", *_flags(options), "--output", path])
        frame = read_tsv(path)
    del frame.attrs["source"]  # the file is gone
    return frame


def _write_tsv(data: Any, path: str) -> None:
    """The known columns of a DataFrame or dict of arrays as propid's TSV (floats by ``repr``,
    which reads back to the same float64; NaN as ``nan``)."""
    frame = pd.DataFrame(data) if not isinstance(data, pd.DataFrame) else data
    known = [c for c in ("ts_local", "t", "force", "velocity", "acceleration", "position",
                         "thrust", "voltage", "current", "command") if c in frame.columns]
    frame[known].to_csv(path, sep="\t", index=False, na_rep="nan")


def propulsion(data: Data, *, diameter: Union[str, float], **options: Any) -> Dict[str, Any]:
    """C_T and C_Q over speed, thrust per watt, the figure of merit and, where voltage and current
    are logged, the motor's constants — ``propid propulsion``, run in-process.

    ``data`` as for :func:`diagnose`, with the stand columns ``thrust``, ``voltage``, ``current``,
    ``command`` where the stand has them (:func:`import_rcbench` gives them); a frame is written
    to a temporary TSV for the command. ``diameter`` as the command takes it (``"7in"``,
    ``"178mm"``, or metres). Other options are its flags, ``-`` written ``_``: ``pole_pairs``,
    ``command_is_duty=True``, ``method="plateaus"``, ``reference_speed="12000rpm"``, ``motor=True``,
    ``density``. Returns the result file's dict (what ``propid size --propeller`` reads). The
    command's report goes to standard output.

    Raises :class:`propid.CannotJudge` when a coefficient asked for is not identified (the dict is
    then the exception's ``result``), :class:`propid.InputError` for bad input or a bad option.
    """
    with tempfile.TemporaryDirectory(prefix="propid-") as tmp:
        out = os.path.join(tmp, "propulsion.json")
        if _is_path(data):
            path = os.fspath(data)
        else:
            path = os.path.join(tmp, "data.tsv")
            _write_tsv(data, path)
        args = ["propid", "propulsion", path, "--diameter", str(diameter), *_flags(options)]
        try:
            _propid.call_cli([*args, "--output", out])
        except _propid.CannotJudge as e:
            if os.path.exists(out):
                with open(out) as f:
                    e.result = json.load(f)
            raise
        with open(out) as f:
            return json.load(f)


def size(*, propeller: Optional[Union[Dict[str, Any], str, "os.PathLike[str]"]] = None, **options: Any) -> Dict[str, Any]:
    """The drivetrain for a thrust, torque or speed — ``propid size``, run in-process.

    ``propeller`` is a :func:`propulsion` result (its dict) or the path of a result file; or give
    ``c_t``, ``c_q`` and ``diameter`` instead. Every other option is the command's flag, ``-``
    written ``_`` (``propid size --help``): ``thrust="6N"``, ``hover_mass="1.6kg"``, ``rotors=4``,
    ``kv=1750``, ``resistance="60mohm"``, ``no_load_current="0.8A"``, ``voltage="4S"``,
    ``battery="3000mAh"``. Returns the answer as the command's ``--format json`` gives it. The
    command's text goes to standard output.

    Raises :class:`propid.InputError` with the command's message for a bad option.
    """
    with tempfile.TemporaryDirectory(prefix="propid-") as tmp:
        out = os.path.join(tmp, "size.json")
        args = ["propid", "size"]
        if isinstance(propeller, Mapping):
            path = os.path.join(tmp, "propeller.json")
            with open(path, "w") as f:
                json.dump(propeller, f)
            args += ["--propeller", path]
        elif propeller is not None:
            args += ["--propeller", os.fspath(propeller)]
        _propid.call_cli([*args, *_flags(options), "--output", out])
        with open(out) as f:
            return json.load(f)


def plan(
    *,
    max_torque: float,
    inertia: Optional[float] = None,
    c2: Optional[float] = None,
    fit: Optional[Union[FitResult, str, "os.PathLike[str]"]] = None,
    **options: Any,
) -> Plan:
    """Designs the excitation from a prior — ``propid plan``, run in-process: the pattern with
    the most precise J and c2 within the setpoint range, its predicted standard errors, the time
    it needs to match the seed's sine, and which effects it can tell apart.

    The prior is ``inertia`` and ``c2``, or ``fit`` (a :class:`FitResult`, or the path of a
    ``propid fit`` YAML). Other options are the command's flags, ``-`` written ``_``:
    ``setpoint_rat_lo_hi="0.1 0.9"``, ``max_speed``, ``duration``, ``target_stderr`` [%],
    ``rate``. The command's summary goes to stderr. ``Plan.save(path)`` writes the pattern file.
    """
    if isinstance(fit, FitResult):
        inertia, c2, fit = fit.mass, fit.c2, None
    options = dict(max_torque=max_torque, inertia=inertia, c2=c2, fit=fit, **options)
    with tempfile.TemporaryDirectory(prefix="propid-") as tmp:
        path = os.path.join(tmp, "plan.json")
        _propid.call_cli(["propid", "plan", *_flags(options), "--output", path])
        with open(path, encoding="utf-8") as f:
            text = f.read()
    return Plan(json.loads(text), text)
