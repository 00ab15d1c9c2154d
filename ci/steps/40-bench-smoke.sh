#!/usr/bin/env bash
# Benchmarks must build and run; CI runs each once (no numbers are taken from CI). Every bench
# target declared must run (counted), and the scripts fail when a program they time fails.
set -euo pipefail
. ci/lib.sh
for crate in benches mechsim; do
  log=$(mktemp)
  cargo bench -p "propid-${crate/benches/benches}" -- --test 2>&1 | tee "$log"
  declared=$(grep -c '^\[\[bench\]\]' "$crate/Cargo.toml")
  ran=$(grep -cE '^\s+Running benches/' "$log")
  rm -f "$log"
  [ "$ran" -eq "$declared" ] || { echo "$crate: $ran of $declared bench targets ran" >&2; exit 1; }
done
SMOKE=1 bash benches/compare_fit.sh
SMOKE=1 bash benches/diagnose_long.sh
