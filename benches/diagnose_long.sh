#!/usr/bin/env bash
# `propid diagnose` on an hour-long log: 2,000,000 rows (4000 s at 500 Hz, the seed's sine, an
# 8 ms torque lag hidden) written by the stand simulator, timed as a whole process; median wall
# and CPU time (user + sys) of several runs and the peak RSS, for this build and, with
# BEFORE=path, another build on the same file in the same run.
#
# usage: benches/diagnose_long.sh [RUNS]      (default 3)
#   BEFORE=path   also time another propid binary (e.g. an older build)
#   SMOKE=1       20,000 rows, one run: checks that the script works (CI)
# Needs GNU time (/usr/bin/time).
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-3}
cargo build --release -q -p propid
P=${CARGO_TARGET_DIR:-target}/release/propid
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
rows=2000000
if [ "${SMOKE:-0}" = 1 ]; then rows=20000; runs=1; fi
$P sim --rate 500 --duration $((rows / 500)) --torque-lag 0.008 --seed 7 -o "$dir/long.tsv" 2>/dev/null
. benches/common.sh
. ci/lib.sh
measure() {
  local bin=$1 walls=() cpus=() rss=0
  for _ in $(seq "$runs"); do
    /usr/bin/time -f '%e %U %S %M' -o "$dir/t" "$bin" diagnose "$dir/long.tsv" > "$dir/out" 2>/dev/null ||
      { echo "failed: $bin diagnose" >&2; exit 1; }
    read -r wall user sys kib < "$dir/t"
    walls+=("$wall"); cpus+=("$(echo "$user + $sys" | bc)")
    [ "$kib" -gt "$rss" ] && rss=$kib
  done
  printf '%s\t%s\t%s\t%s\n' "$(printf '%s\n' "${walls[@]}" | median)" \
    "$(printf '%s\n' "${cpus[@]}" | median)" "$((rss / 1024))" "$(grep -c . "$dir/out")"
}
echo "diagnose on $rows rows ($(stat -c %s "$dir/long.tsv") bytes), median of $runs runs"
printf 'program\twall s\tCPU s\tpeak RSS MiB\treport lines\n'
# Each measured into a variable first: a failure inside $(…) given to printf would not stop
# the script.
now=$(measure "$P")
cp "$dir/out" "$dir/out_now"
printf 'propid diagnose\t%s\n' "$now"
if [ -n "${BEFORE:-}" ]; then
  before=$(measure "$BEFORE")
  printf 'before\t%s\n' "$before"
fi
grep -q "torque_lag .*← named" "$dir/out_now" || { echo "the hidden torque lag was not named" >&2; exit 1; }
# This build's reading of the hidden 8 ms lag, and J and c2 (truth 2e-5 and 1.5e-8), as its Result
# prints them, and the held-out gain of the model named.
grep -m 3 -E '^   (J|c2|torque_lag) +=' "$dir/out_now"
grep -m 1 -E '^   Simulated-velocity RMS error on held-out data' "$dir/out_now"
