#!/usr/bin/env python3
"""propid.fit on a DataFrame against `propid fit` on the same data, in one run.

The data: `propid sim --rate 500 --duration 6000` (3,002,500 rows, the 3 M-row file of
benches/compare_fit.sh). Timed side by side, each the median of RUNS runs:

- `propid fit FILE`: the release binary (`cargo build --release -p propid`), a whole process,
  wall time from fork to exit (what a user waits for);
- `propid.fit(df)`: the Python package on a DataFrame already in memory (read once by
  propid.read_tsv), in this process: the columns handed to Rust in place, the seed's window
  and the sums, the result as a FitResult;
- `propid.fit(FILE)` in this process (the command's memory-mapped scan, without the process);
- for scale: reading the file into a DataFrame once, with propid.read_tsv and with pandas.

The ratio asked of the package: propid.fit(df) / `propid fit` (≤ 2). The results must agree
(the script fails otherwise). Needs the package installed (pip install ./python) and cargo.

usage: python3 benches/python_fit.py [RUNS]     (default 5)
       SMOKE=1 python3 benches/python_fit.py    (8,000 rows, one run: checks that it works; CI)
"""

import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd

import propid

REPO = Path(__file__).resolve().parents[1]
smoke = os.environ.get("SMOKE") == "1"
runs = 1 if smoke else int(sys.argv[1]) if len(sys.argv) > 1 else 5
rows = 8000 if smoke else 3_000_000

subprocess.run(["cargo", "build", "--release", "-q", "-p", "propid"], cwd=REPO, check=True)
target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
binary = str(target / "release" / "propid")


def median_time(call, n=runs):
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        value = call()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), value


def cli_fit(path):
    out = subprocess.run([binary, "fit", str(path), "--format", "json"], capture_output=True)
    if out.returncode != 0:
        sys.exit(f"propid fit failed: {out.stderr.decode()}")
    return out.stdout


with tempfile.TemporaryDirectory(prefix="propid-bench-") as tmp:
    path = Path(tmp) / "large.tsv"
    subprocess.run(
        [binary, "sim", "--rate", "500", "--duration", str(rows // 500), "--seed", "2", "-o", str(path)],
        check=True, stderr=subprocess.DEVNULL,
    )
    size = path.stat().st_size
    load = os.getloadavg()
    print(f"machine: {os.cpu_count()} cores, load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    read_propid, frame = median_time(lambda: propid.read_tsv(path), 1)
    read_pandas, _ = median_time(lambda: pd.read_table(path), 1)
    cli_wall, cli_json = median_time(lambda: cli_fit(path))
    df_wall, by_frame = median_time(lambda: propid.fit(frame))
    path_wall, by_path = median_time(lambda: propid.fit(path))
    by_cli = propid.FitResult(__import__("json").loads(cli_json))
    if by_cli != by_path:
        sys.exit(f"propid.fit(path) {by_path!r} differs from propid fit {by_cli!r}")
    # One piece (the columns) against the file's pieces among threads: rounding only.
    for key in ("mass", "c2"):
        a, b = getattr(by_frame, key), getattr(by_cli, key)
        if abs(a - b) > 1e-12 * abs(a):
            sys.exit(f"{key}: propid.fit(df) {a} differs from propid fit {b}")
    print(f"data: {len(frame):,} rows, {size / 1e6:.0f} MB; median of {runs} runs each")
    print(f"| what | wall | vs `propid fit` |")
    print(f"|---|---|---|")
    print(f"| `propid fit FILE` (release binary, whole process) | {cli_wall:.4f} s | 1 |")
    print(f"| `propid.fit(df)` (DataFrame in memory) | {df_wall:.4f} s | {df_wall / cli_wall:.3f} |")
    print(f"| `propid.fit(FILE)` (in this process) | {path_wall:.4f} s | {path_wall / cli_wall:.3f} |")
    print(f"| `propid.read_tsv(FILE)` (once) | {read_propid:.3f} s | |")
    print(f"| `pandas.read_table(FILE)` (once) | {read_pandas:.3f} s | |")
    print(f"ratio propid.fit(df) / propid fit: {df_wall / cli_wall:.3f} (asked: at most 2)")
    if df_wall > 2 * cli_wall and not smoke:
        sys.exit("propid.fit(df) is more than 2x the command's time")
