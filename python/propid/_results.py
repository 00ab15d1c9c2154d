"""Typed results over the command's JSON.

Each class wraps the dictionary ``propid … --format json`` prints for the same input (the Rust
side hands over exactly that JSON). Every attribute is declared once, as a :class:`_Field` naming
its JSON key: when a key is renamed in Rust, one line here changes, and the test that checks
every declared key against a fresh result says which.
"""

from __future__ import annotations

import copy
import math
from typing import Any, Callable, ClassVar, Dict, Generic, List, Optional, TypeVar, overload

T = TypeVar("T")


class _Field(Generic[T]):
    """A read-only attribute backed by one key of the result's dictionary.

    ``kind`` says how the JSON value is read: ``"number"`` (JSON null, which is how serde writes
    NaN, reads as ``nan``), ``"optional"`` (null stays ``None``: not computed), or ``"value"``
    (as it is). ``wrap`` turns the value into a typed object.
    """

    def __init__(
        self,
        key: str,
        doc: str,
        kind: str = "value",
        wrap: Optional[Callable[[Any], T]] = None,
    ) -> None:
        self.key = key
        self.kind = kind
        self.wrap = wrap
        self.__doc__ = doc

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    @overload
    def __get__(self, obj: None, owner: type) -> "_Field[T]": ...

    @overload
    def __get__(self, obj: object, owner: type) -> T: ...

    def __get__(self, obj: Any, owner: type) -> Any:
        if obj is None:
            return self
        data = obj._data
        if self.key not in data:
            raise AttributeError(
                f"{type(obj).__name__}.{self.name}: the result has no `{self.key}` "
                f"(keys: {', '.join(data)}); propid's JSON changed and propid/_results.py "
                "maps the old name"
            )
        value = data[self.key]
        if self.kind == "number" and value is None:
            return math.nan
        if self.wrap is not None and value is not None:
            return self.wrap(value)
        return value


def _fields(cls: type) -> Dict[str, _Field[Any]]:
    return {
        name: f
        for klass in reversed(cls.__mro__)
        for name, f in vars(klass).items()
        if isinstance(f, _Field)
    }


def _number(v: Any, unit: str = "") -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "nan"
    text = f"{v:.6g}"
    return f"{text} {unit}".rstrip()


class _Record:
    """A result: typed attributes over the command's JSON, :meth:`to_dict` for all of it."""

    _repr_fields: ClassVar[List[str]] = []

    def __init__(self, data: Dict[str, Any]) -> None:
        self._data = data

    def to_dict(self) -> Dict[str, Any]:
        """The result as the command's ``--format json`` prints it (a deep copy; NaN is None)."""
        return copy.deepcopy(self._data)

    def __eq__(self, other: object) -> bool:
        return type(other) is type(self) and other._data == self._data  # type: ignore[attr-defined]

    def __repr__(self) -> str:
        shown = ", ".join(f"{name}={getattr(self, name)!r}" for name in self._repr_fields)
        return f"{type(self).__name__}({shown})"

    @classmethod
    def json_keys(cls) -> Dict[str, str]:
        """Attribute name → the JSON key it reads (the one mapping to change on a rename)."""
        return {name: f.key for name, f in _fields(cls).items()}


class FitResult(_Record):
    """The seed regressor's fit (``propid fit``): the seed's YAML keys plus standard errors.

    Attributes use the seed's names: ``mass`` is the inertia J [kg·m²] (or the mass [kg] of a
    linear stand), ``c1`` the viscous coefficient, ``c2`` the quadratic drag coefficient
    (drag torque ``c1·ω + c2·ω|ω|``).
    """

    mass: _Field[float] = _Field("mass", "Inertia J [kg·m²] (the seed's `mass`).", "number")
    c1: _Field[float] = _Field("c1", "Viscous coefficient c1 [N·m·s/rad].", "number")
    c2: _Field[float] = _Field("c2", "Quadratic drag coefficient c2 [N·m·s²/rad²].", "number")
    mass_stderr: _Field[float] = _Field("mass_stderr", "Standard error of `mass`.", "number")
    c1_stderr: _Field[float] = _Field("c1_stderr", "Standard error of `c1`.", "number")
    c2_stderr: _Field[float] = _Field("c2_stderr", "Standard error of `c2`.", "number")
    rms: _Field[float] = _Field("rms", "RMS of the acceleration residual [rad/s²].", "number")
    samples: _Field[int] = _Field("samples", "Samples fitted (after the seed's trimming).")
    rows: _Field[int] = _Field("rows", "Rows read.")
    condition_number: _Field[float] = _Field(
        "condition_number", "Condition number of the scaled normal matrix.", "number"
    )
    at_bound: _Field[List[str]] = _Field("at_bound", "Parameters sitting on a bound.")
    not_identified: _Field[List[str]] = _Field(
        "not_identified",
        "Free parameters the data do not identify (on a bound, or a standard error above 30 %).",
    )
    c_q: _Field[Optional[float]] = _Field(
        "c_q", "Torque coefficient C_Q, when a diameter was given.", "optional"
    )
    warnings: _Field[List[str]] = _Field("warnings", "Warnings about the data.")

    def predict_acceleration(self, force: Any, velocity: Any) -> Any:
        """The seed's model: ``(force − c1·ω − c2·ω|ω|) / mass`` (numpy arrays or floats)."""
        import numpy as np

        w = np.asarray(velocity, dtype=float)
        return (np.asarray(force, dtype=float) - self.c1 * w - self.c2 * w * np.abs(w)) / self.mass

    def __repr__(self) -> str:
        return (
            f"FitResult(mass={_number(self.mass)} ± {_number(self.mass_stderr)}, "
            f"c1={_number(self.c1)} ± {_number(self.c1_stderr)}, "
            f"c2={_number(self.c2)} ± {_number(self.c2_stderr)}, rms={_number(self.rms)}, "
            f"samples={self.samples}"
            + (f", at_bound={self.at_bound}" if self.at_bound else "")
            + (f", c_q={_number(self.c_q)}" if self.c_q is not None else "")
            + (f", warnings={len(self.warnings)}" if self.warnings else "")
            + ")"
        )


class Model(_Record):
    """A model of the diagnosis (the seed's base model, or base plus the named effects)."""

    inertia: _Field[float] = _Field(
        "inertia", "Inertia J [kg·m²] (NaN if not identified).", "number"
    )
    c1: _Field[float] = _Field("c1", "Viscous coefficient c1 [N·m·s/rad].", "number")
    c2: _Field[float] = _Field("c2", "Quadratic drag coefficient c2 [N·m·s²/rad²].", "number")
    inertia_stderr: _Field[float] = _Field(
        "inertia_stderr", "Standard error of `inertia`.", "number"
    )
    c2_stderr: _Field[float] = _Field("c2_stderr", "Standard error of `c2`.", "number")

    def __repr__(self) -> str:
        return (
            f"Model(inertia={_number(self.inertia)} ± {_number(self.inertia_stderr)}, "
            f"c2={_number(self.c2)} ± {_number(self.c2_stderr)})"
        )


class Effect(_Record):
    """An effect the diagnosis named, with its estimated parameter."""

    name: _Field[str] = _Field("name", "Effect name (`torque_lag`, `coulomb_friction`, …).")
    value: _Field[float] = _Field("value", "Its parameter, in `unit`.", "number")
    unit: _Field[str] = _Field("unit", "Unit of the parameter.")
    stderr: _Field[float] = _Field("stderr", "Standard error of the parameter.", "number")
    explanation: _Field[str] = _Field("explanation", "What it means, in a sentence.")

    def __repr__(self) -> str:
        return f"Effect({self.name} = {_number(self.value, self.unit)} ± {_number(self.stderr)})"


class Diagnosis(_Record):
    """What the fitted model gets wrong, the named causes, the extended model (``propid diagnose``).

    ``str(diagnosis)`` is the command's text report; :meth:`to_dict` its ``--format json``.
    """

    verdict: _Field[str] = _Field(
        "verdict",
        "`nothing_wrong`, `explained`, `unexplained`, `ambiguous`, `not_identified` or `cannot_judge`.",
        wrap=lambda v: v["kind"],
    )
    samples: _Field[int] = _Field("samples", "Samples analysed.")
    duration_s: _Field[float] = _Field("duration_s", "Duration [s].", "number")
    rate_hz: _Field[float] = _Field("rate_hz", "Median sample rate [Hz].", "number")
    base: _Field[Model] = _Field("base", "The seed's model fitted to all the data.", wrap=Model)
    extended: _Field[Model] = _Field(
        "extended", "The base model plus the named effects, fitted to all the data.", wrap=Model
    )
    effects: _Field[List[Effect]] = _Field(
        "effects", "The named effects.", wrap=lambda v: [Effect(e) for e in v]
    )
    simulation_rms: _Field[Dict[str, Any]] = _Field(
        "simulation_rms", "Held-out simulated-velocity RMS [rad/s]: base, extended, gain_percent."
    )
    unexplained: _Field[Optional[Dict[str, Any]]] = _Field(
        "unexplained", "Structure no candidate explains, if any.", "optional"
    )
    ambiguities: _Field[List[Dict[str, Any]]] = _Field(
        "ambiguities",
        "Effects the data cannot tell from a named one (`alongside`: the lag the other model holds "
        "beside it, where a term stands against a lag and another term): both estimates, the other "
        "model's J and c2, the separating run.",
    )
    unidentified: _Field[List[Dict[str, Any]]] = _Field(
        "unidentified", "Parameters these data do not identify (J, c2), with their estimates."
    )
    near_misses: _Field[List[Dict[str, Any]]] = _Field(
        "near_misses", "Candidates that came close, with the run that would show them."
    )
    concentration: _Field[Optional[Dict[str, Any]]] = _Field(
        "concentration",
        "Where the remaining held-out error concentrates (a condition or a window of time), if it does.",
        "optional",
    )
    left_out: _Field[Optional[Dict[str, Any]]] = _Field(
        "left_out",
        "The span of an event in time the extended model was fitted without (from_s, to_s, samples), "
        "and J and c2 with it (inertia_with, c2_with).",
        "optional",
    )
    simulation_only: _Field[Optional[Dict[str, Any]]] = _Field(
        "simulation_only",
        "What the simulated velocity still shows and the acceleration equation does not confirm "
        "(effect, value, unit, simulation_gain_percent, equation_gain_percent), where J and c2 "
        "move with it (inertia_with, c2_with); the verdict is then unexplained.",
        "optional",
    )
    compared: _Field[Optional[Dict[str, Any]]] = _Field(
        "compared",
        "The model asked about with ``compare=\"force_sensor_lag,drag_exponent\"``, fitted as the "
        "search fits one and scored beside the model named: its effects and values, J and c2 under "
        "it (model), its held-out gain over the model named (gain, and its equation and simulation "
        "parts) and which the data prefer (preferred: `asked`, `named`, `neither` or `same`); "
        "None where none was asked about.",
        "optional",
    )
    notes: _Field[List[str]] = _Field("notes", "Notes about the data.")

    def __init__(self, data: Dict[str, Any], text: str = "") -> None:
        super().__init__(data)
        self._text = text

    @property
    def text(self) -> str:
        """The command's text report."""
        return self._text

    @property
    def reasons(self) -> List[Dict[str, Any]]:
        """Why the data cannot support a verdict (empty unless the verdict is `cannot_judge`)."""
        return list(self._data.get("verdict", {}).get("reasons", []))

    @property
    def named(self) -> List[str]:
        """The names of the named effects."""
        return [e.name for e in self.effects]

    def __str__(self) -> str:
        return self._text

    def __repr__(self) -> str:
        if self.verdict == "cannot_judge":
            return f"Diagnosis(verdict='cannot_judge', reasons={len(self.reasons)})"
        effects = ", ".join(f"{e.name}={_number(e.value, e.unit)}" for e in self.effects)
        return (
            f"Diagnosis(verdict={self.verdict!r}, effects=[{effects}], "
            f"inertia={_number(self.extended.inertia)}, c2={_number(self.extended.c2)}, "
            f"samples={self.samples})"
        )


class Plan(_Record):
    """A designed experiment (``propid plan``): the pattern to play and its predicted precision.

    :meth:`save` writes the pattern file that ``propid drive --pattern-file`` and
    ``propid.simulate(pattern_file=…)`` play.
    """

    excitation: _Field[Dict[str, Any]] = _Field(
        "excitation", "The pattern: pattern, period, lo, hi, duration, init_duration."
    )
    predicted: _Field[Dict[str, Any]] = _Field(
        "predicted", "Predicted relative standard errors of J and c2 (rel_stderr_j, rel_stderr_c2)."
    )
    seed_sine: _Field[Dict[str, Any]] = _Field(
        "seed_sine", "The same for the seed's 2 s sine over the same range and time."
    )
    seconds_to_match_seed: _Field[float] = _Field(
        "seconds_to_match_seed", "Seconds the plan needs to match the seed's run.", "number"
    )
    separations: _Field[List[Dict[str, Any]]] = _Field(
        "separations", "Effect pairs the plan can and cannot tell apart."
    )

    def __init__(self, data: Dict[str, Any], text: str) -> None:
        super().__init__(data)
        self._text = text

    def save(self, path: "str | Any") -> None:
        """Writes the pattern file, byte for byte as ``propid plan`` wrote it."""
        with open(path, "w", encoding="utf-8") as f:
            f.write(self._text)

    def __repr__(self) -> str:
        e = self.excitation
        p = self.predicted
        return (
            f"Plan({e.get('pattern')} period {e.get('period')} s, {e.get('lo')}–{e.get('hi')}, "
            f"{e.get('duration')} s; predicted J ± {100 * p.get('rel_stderr_j', math.nan):.3g} %, "
            f"c2 ± {100 * p.get('rel_stderr_c2', math.nan):.3g} %)"
        )
