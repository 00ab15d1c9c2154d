"""propid: identify the dynamics of a propeller or fan on an electric drive, from Python.

The same Rust crates as the ``propid`` command (installed with this package), no second
implementation::

    import propid
    run = propid.read_tsv("run.tsv")            # or a DataFrame / dict of arrays you have
    result = propid.fit(run)                     # the seed regressor, exact: mass (J), c1, c2
    diagnosis = propid.diagnose(run)             # what that model gets wrong, and why
    print(diagnosis)                             # the command's text report

Results are typed objects over the command's ``--format json`` (``.to_dict()`` gives it);
errors are :class:`PropidError`, :class:`InputError` (bad input, the command's exit status 2)
and :class:`CannotJudge` (the data cannot support a verdict, exit status 3), with the
command's messages.
"""

from importlib.metadata import PackageNotFoundError, version

from ._propid import CannotJudge, InputError, PropidError
from ._api import (
    Data,
    diagnose,
    fit,
    import_autoquad,
    import_rcbench,
    plan,
    propulsion,
    size,
    read_tsv,
    simulate,
)
from ._results import Diagnosis, Effect, FitResult, Model, Plan

try:
    __version__ = version("propid")
except PackageNotFoundError:  # pragma: no cover - an uninstalled source tree
    __version__ = "0+unknown"

__all__ = [
    "CannotJudge",
    "Data",
    "Diagnosis",
    "Effect",
    "FitResult",
    "InputError",
    "Model",
    "Plan",
    "PropidError",
    "diagnose",
    "fit",
    "import_autoquad",
    "import_rcbench",
    "plan",
    "propulsion",
    "size",
    "read_tsv",
    "simulate",
]
