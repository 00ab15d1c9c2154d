#!/usr/bin/env bash
# Benchmarks must build and run; CI runs each once (no numbers are taken from CI).
set -euo pipefail
cargo bench -q -p propid-benches -- --test
cargo bench -q -p propid-mechsim -- --test
SMOKE=1 bash benches/compare_fit.sh
SMOKE=1 bash benches/diagnose_long.sh
