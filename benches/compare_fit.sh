#!/usr/bin/env bash
# propid fit vs the seed regressor, whole process, same files, several runs each: median times
# and the ratio, plus peak RSS of propid fit on the large file. Needs python3 with numpy, scipy,
# pandas, and hyperfine (apt) if available.
# usage: benches/compare_fit.sh [RUNS]   (SMOKE=1: tiny files, one run: checks that it works)
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-5}
cargo build --release -q -p propid
P=target/release/propid
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
if [ "${SMOKE:-0}" = 1 ]; then small=2000; large=20000; runs=1; else small=24000; large=3000000; fi
# The stand simulator writes the files (500 Hz): 24,000 rows = 48 s, 3,000,000 rows = 100 min.
$P sim --rate 500 --duration $((small / 500)) --seed 1 -o "$dir/small.tsv" 2>/dev/null
$P sim --rate 500 --duration $((large / 500)) --seed 2 -o "$dir/large.tsv" 2>/dev/null
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
time_runs() { # command... → median wall seconds over $runs runs
  for _ in $(seq "$runs"); do
    s=$(date +%s.%N); "$@" >/dev/null 2>&1; e=$(date +%s.%N)
    echo "$e - $s" | bc -l
  done | median
}
printf '%-10s %12s %12s %10s %12s\n' file rows "propid [s]" "seed [s]" "seed/propid"
for f in small large; do
  rows=$(($(wc -l < "$dir/$f.tsv") - 1))
  tp=$(time_runs $P fit "$dir/$f.tsv")
  ts=$(time_runs sh -c "python3 tests/seed/dynamics_id_regressor.py --no-plot < '$dir/$f.tsv'")
  printf '%-10s %12d %12.3f %10.3f %12.1f\n' "$f" "$rows" "$tp" "$ts" "$(echo "$ts / $tp" | bc -l)"
done
if [ -x /usr/bin/time ]; then
  rss=$(/usr/bin/time -f %M $P fit "$dir/large.tsv" 2>&1 >/dev/null | tail -1)
  rss_small=$(/usr/bin/time -f %M $P fit "$dir/small.tsv" 2>&1 >/dev/null | tail -1)
  echo "peak RSS of propid fit: ${rss_small} KiB on the small file, ${rss} KiB on the large file"
fi
