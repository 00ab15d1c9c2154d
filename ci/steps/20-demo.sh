#!/usr/bin/env bash
# The README's main job, exactly as a user runs it: the whole pipeline on the simulated stand.
set -euo pipefail
out=$(mktemp -d)
cargo run --release -q -- demo --out "$out/demo"
for f in run.tsv fit.yaml fit.svg diagnose.txt diagnose.json diagnose.svg report.md; do
  test -s "$out/demo/$f" || { echo "demo did not write $f" >&2; exit 1; }
done
grep -q '"name": "torque_lag"' "$out/demo/diagnose.json" || { echo "demo: diagnose did not find the hidden torque lag" >&2; exit 1; }
echo "demo: report and plots written, hidden torque lag found"
