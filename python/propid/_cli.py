"""The ``propid`` command of the wheel: the Rust command line, run in this process."""

import sys
from typing import List, Optional

from . import _propid


def main(argv: Optional[List[str]] = None) -> None:
    """Runs ``propid`` with ``argv`` (default: the process's arguments) and exits with its
    status (0 done, 1 failed, 2 bad input, 3 cannot judge)."""
    args = sys.argv[1:] if argv is None else argv
    sys.stdout.flush()
    try:
        status = _propid.run_cli(["propid", *args])
    except KeyboardInterrupt:
        # The command handles SIGINT itself (a drive commands STANDBY first) and has returned;
        # Python saw the same signal afterwards.
        status = 130
    sys.exit(status)
