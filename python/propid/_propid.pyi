"""Type stubs of the extension module (python/src/lib.rs): the Python layer's only way in."""

from typing import Dict, List, Optional, Sequence, Tuple, TypedDict

import numpy as np
import numpy.typing as npt

class PropidError(Exception):
    """Any error propid reports (the command's exit status 1)."""

class InputError(PropidError):
    """Bad input: a file, a column or a value (exit status 2); the message says where."""

class CannotJudge(PropidError):
    """The data cannot support a verdict (exit status 3)."""

    diagnosis: object

Column = npt.NDArray[np.float64]

class _Bounds(TypedDict):
    """Every key present; None: the command's default."""

    mass_min: Optional[float]
    mass_max: Optional[float]
    c1_max: Optional[float]
    c2_max: Optional[float]
    diameter: Optional[float]
    density: Optional[float]
    flip_torque: Optional[bool]
    velocity_unit: Optional[str]

def fit_path(path: str, bounds: _Bounds) -> str: ...
def fit_columns(
    t: Column, force: Column, velocity: Column, acceleration: Column, name: str, bounds: _Bounds
) -> str: ...
def diagnose_path(path: str, flags: Sequence[str]) -> Tuple[str, str, Optional[str]]: ...
def diagnose_columns(
    t: Column,
    force: Column,
    velocity: Column,
    acceleration: Column,
    ts_local: Optional[Column],
    position: Optional[Column],
    thrust: Optional[Column],
    name: str,
    flags: Sequence[str],
) -> Tuple[str, str, Optional[str]]: ...
def read_tsv(path: str) -> Dict[str, Column]: ...
def import_rcbench(path: str, subtract_zero_offset: bool = ...) -> Tuple[Dict[str, Column], List[str]]: ...
def import_autoquad(path: str, kv: float) -> Tuple[Dict[str, Column], List[str]]: ...
def run_cli(args: Sequence[str]) -> int: ...
def call_cli(args: Sequence[str]) -> None: ...
