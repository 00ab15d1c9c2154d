#!/usr/bin/env bash
# propid fit vs the seed regressor, side by side in one run: both as whole processes on the same
# files written by the stand simulator (`propid sim`, 500 Hz): 24,000 rows and 3,000,000 rows,
# median wall time of several runs each and the ratio; then propid's throughput on a 128 MiB file
# and its peak RSS. CPU time (user + sys) is printed beside the wall time: on a shared machine
# the wall time includes waiting for a core.
#
# usage: benches/compare_fit.sh [RUNS] [SEED_RUNS_LARGE]
#   RUNS             runs of propid (and of the seed on the small file), default 5
#   SEED_RUNS_LARGE  runs of the seed on the 3 M-row file (minutes each), default 1
#   BEFORE=path      also time another propid binary (e.g. an older build) on the same files
#   SMOKE=1          tiny files, one run: checks that the script works (CI)
# Needs python3 with numpy, scipy, pandas, GNU time (/usr/bin/time) and bc.
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-5}
seed_runs_large=${2:-1}
cargo build --release -q -p propid
P=${CARGO_TARGET_DIR:-target}/release/propid
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
if [ "${SMOKE:-0}" = 1 ]; then
  small=2000; large=8000; mib=1; runs=1; seed_runs_large=1
else
  small=24000; large=3000000; mib=128
fi
$P sim --rate 500 --duration $((small / 500)) --seed 1 -o "$dir/small.tsv" 2>/dev/null
$P sim --rate 500 --duration $((large / 500)) --seed 2 -o "$dir/large.tsv" 2>/dev/null
# The throughput file: the large file's first $mib MiB, cut at a line end.
head -c $((mib << 20)) "$dir/large.tsv" | head -n -1 > "$dir/mib.tsv"
if [ "$(stat -c %s "$dir/mib.tsv")" -lt $(((mib << 20) * 9 / 10)) ]; then
  $P sim --rate 500 --duration $((mib * 20)) --seed 3 -o "$dir/big.tsv" 2>/dev/null
  head -c $((mib << 20)) "$dir/big.tsv" | head -n -1 > "$dir/mib.tsv"
fi

. benches/common.sh
# time_runs N command... → "median-wall median-cpu peak-RSS-KiB": wall and CPU (user + sys) from
# bash's `time` (ms resolution) over N runs, the RSS from one more run under GNU time (not for
# the seed, run through sh: its minutes on the large file are not repeated for that).
time_runs() {
  local n=$1; shift
  local log=$dir/time.log
  : > "$log"
  local TIMEFORMAT='%3R %3U %3S'
  for _ in $(seq "$n"); do
    { time "$@" >/dev/null 2>&1; } 2>> "$log"
  done
  local wall cpu rss
  wall=$(awk '{print $1}' "$log" | median)
  cpu=$(awk '{print $2 + $3}' "$log" | median)
  rss=0
  [ "$1" != sh ] && rss=$(/usr/bin/time -f "%M" "$@" 2>&1 >/dev/null | tail -1)
  echo "$wall $cpu $rss"
}

echo "machine: $(nproc) cores, $(uname -sm), load average $(cut -d' ' -f1-3 /proc/loadavg)"
printf '%-6s %10s %-14s %12s %12s %10s\n' file rows program "wall [s]" "cpu [s]" "RSS [KiB]"
declare -A wall
for f in small large; do
  rows=$(($(wc -l < "$dir/$f.tsv") - 1))
  n_seed=$runs; [ $f = large ] && n_seed=$seed_runs_large
  progs=(propid seed); [ -n "${BEFORE:-}" ] && progs=(propid before seed)
  for prog in "${progs[@]}"; do
    case $prog in
      propid) r=$(time_runs "$runs" "$P" fit "$dir/$f.tsv") ;;
      before) r=$(time_runs "$runs" "$BEFORE" fit "$dir/$f.tsv") ;;
      seed) r=$(time_runs "$n_seed" sh -c "exec python3 tests/seed/dynamics_id_regressor.py --no-plot < '$dir/$f.tsv'") ;;
    esac
    read -r w c m <<< "$r"
    wall[$f.$prog]=$w
    printf '%-6s %10d %-14s %12.3f %12.3f %10d\n' "$f" "$rows" "$prog" "$w" "$c" "$m"
  done
  printf '%-6s seed / propid (wall): %.0f×' "$f" "$(echo "${wall[$f.seed]} / ${wall[$f.propid]}" | bc -l)"
  [ -n "${BEFORE:-}" ] && printf '   before / propid: %.1f×' "$(echo "${wall[$f.before]} / ${wall[$f.propid]}" | bc -l)"
  echo
done
bytes=$(stat -c %s "$dir/mib.tsv")
read -r w c m <<< "$(time_runs "$runs" "$P" fit "$dir/mib.tsv")"
rate() { awk -v b="$1" -v t="$2" 'BEGIN { if (t > 0) printf "%.0f", b / t / 1e6; else printf "n/a" }'; }
printf 'throughput on %d MiB: %s MB/s wall (%.3f s), %s MB/s per CPU second (%.3f s), peak RSS %d KiB\n' \
  "$mib" "$(rate "$bytes" "$w")" "$w" "$(rate "$bytes" "$c")" "$c" "$m"
if [ -n "${BEFORE:-}" ]; then
  read -r w c m <<< "$(time_runs "$runs" "$BEFORE" fit "$dir/mib.tsv")"
  printf 'before, same file:  %s MB/s wall (%.3f s), %s MB/s per CPU second (%.3f s), peak RSS %d KiB\n' \
    "$(rate "$bytes" "$w")" "$w" "$(rate "$bytes" "$c")" "$c" "$m"
fi
# Same answers: propid's YAML on the large file printed for the record.
$P fit "$dir/large.tsv" | head -3
