#!/usr/bin/env bash
# propid fit vs the seed regressor, side by side in one run: both as whole processes on the same
# files written by the stand simulator (`propid sim`, 500 Hz): 24,000 rows and 3,000,000 rows,
# median wall time of several runs each and the ratio; then propid's throughput on a 128 MiB file
# and its peak RSS. CPU time (user + sys) is printed beside the wall time: on a shared machine
# the wall time includes waiting for a core.
#
# Each run is timed alone with bash's $EPOCHREALTIME (microseconds; no process is started to read
# the clock, so only the fork, exec and wait of the program itself are added, as for the seed), and
# the median of the runs is reported; the CPU time is the children's user + sys time from bash's
# `times` over all the runs, divided by their number. propid on the 24,000-row file takes a few
# milliseconds, so it is run SMALL_RUNS times (default 50): the ratio there has the resolution of
# a microsecond, not of bash's `time` (1 ms).
#
# usage: benches/compare_fit.sh [RUNS] [SEED_RUNS_LARGE]
#   RUNS             runs of propid (and of the seed on the small file), default 5
#   SEED_RUNS_LARGE  runs of the seed on the 3 M-row file (minutes each), default 1; 0: not run
#   SMALL_RUNS=n     runs of propid on the 24,000-row file, default 50
#   BEFORE=path      also time another propid binary (e.g. an older build) on the same files
#   ONLY_SMALL=1     only the 24,000-row file (no 3 M-row file, no throughput run)
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
[ "${ONLY_SMALL:-0}" = 1 ] && large=$small
$P sim --rate 500 --duration $((large / 500)) --seed 2 -o "$dir/large.tsv" 2>/dev/null
# The throughput file: the large file's first $mib MiB, cut at a line end.
head -c $((mib << 20)) "$dir/large.tsv" | head -n -1 > "$dir/mib.tsv"
if [ "$(stat -c %s "$dir/mib.tsv")" -lt $(((mib << 20) * 9 / 10)) ]; then
  $P sim --rate 500 --duration $((mib * 20)) --seed 3 -o "$dir/big.tsv" 2>/dev/null
  head -c $((mib << 20)) "$dir/big.tsv" | head -n -1 > "$dir/mib.tsv"
fi

. benches/common.sh
. ci/lib.sh
export LC_ALL=C
# Children's user + sys CPU time [s] in the output of bash's `times` (which must run in the shell
# that waited for them, not in a command substitution).
children_cpu() { awk 'NR == 2 { split($0, f, /[ms]+ */); print f[1] * 60 + f[2] + f[3] * 60 + f[4] }' "$1"; }
# time_runs N command... → "median-wall mean-cpu peak-RSS-KiB": the wall time of each of N runs
# (µs resolution), their median, the CPU time per run over all N, and the RSS from one more run
# under GNU time (not for the seed, run through sh: its minutes on the large file are not
# repeated for that).
time_runs() {
  local n=$1; shift
  local log=$dir/time.log
  : > "$log"
  local cpu0 cpu1 t0 t1
  times > "$dir/times0"
  for _ in $(seq "$n"); do
    # The clock is read in this shell (a command substitution would fork a subshell inside
    # the timed interval): microseconds, with the decimal point taken out.
    t0=${EPOCHREALTIME/./}
    "$@" >/dev/null 2>&1 || { echo "failed: $*" >&2; exit 1; }
    t1=${EPOCHREALTIME/./}
    echo $((10#$t1 - 10#$t0)) >> "$log"
  done
  times > "$dir/times1"
  cpu0=$(children_cpu "$dir/times0")
  cpu1=$(children_cpu "$dir/times1")
  local wall cpu rss
  wall=$(median < "$log" | awk '{ printf "%.6f", $1 / 1e6 }')
  cpu=$(awk -v a="$cpu0" -v b="$cpu1" -v n="$n" 'BEGIN { printf "%.6f", (b - a) / n }')
  rss=0
  if [ "$1" != sh ]; then
    /usr/bin/time -o "$dir/rss" -f "%M" "$@" >/dev/null 2>&1 || { echo "failed: $*" >&2; exit 1; }
    rss=$(tail -1 "$dir/rss")
  fi
  [ "$(grep -c . "$log")" -eq "$n" ] || { echo "timed $(grep -c . "$log") of $n runs: $*" >&2; exit 1; }
  echo "$wall $cpu $rss"
}

# Before any timing: each program answers on the small file (a seed or a build that prints
# nothing, or fails, is not timed).
for prog in "$P" ${BEFORE:+"$BEFORE"}; do
  "$prog" fit "$dir/small.tsv" > "$dir/answer"
  grep -q '^mass: ' "$dir/answer" || { echo "$prog fit gave no fit" >&2; exit 1; }
done
python3 tests/seed/dynamics_id_regressor.py --no-plot < "$dir/small.tsv" > "$dir/answer" 2>/dev/null
grep -q '^mass:' "$dir/answer" || { echo "the seed regressor gave no fit" >&2; exit 1; }
echo "machine: $(nproc) cores, $(uname -sm), load average $(cut -d' ' -f1-3 /proc/loadavg)"
small_runs=${SMALL_RUNS:-50}
[ "${SMOKE:-0}" = 1 ] && small_runs=3
printf '%-6s %10s %-14s %5s %12s %12s %10s\n' file rows program runs "wall [s]" "cpu [s]" "RSS [KiB]"
declare -A wall cpu
files=(small large); [ "${ONLY_SMALL:-0}" = 1 ] && files=(small)
for f in "${files[@]}"; do
  rows=$(($(wc -l < "$dir/$f.tsv") - 1))
  n_seed=$runs n_propid=$runs
  [ $f = large ] && n_seed=$seed_runs_large
  [ $f = small ] && n_propid=$small_runs
  progs=(propid); [ -n "${BEFORE:-}" ] && progs+=(before)
  [ "$n_seed" -gt 0 ] && progs+=(seed)
  for prog in "${progs[@]}"; do
    case $prog in
      propid) n=$n_propid; r=$(time_runs "$n" "$P" fit "$dir/$f.tsv") ;;
      before) n=$n_propid; r=$(time_runs "$n" "$BEFORE" fit "$dir/$f.tsv") ;;
      seed) n=$n_seed; r=$(time_runs "$n" sh -c "exec python3 tests/seed/dynamics_id_regressor.py --no-plot < '$dir/$f.tsv'") ;;
    esac
    read -r w c m <<< "$r"
    [ -n "$w" ] || { echo "no timing for $prog on $f" >&2; exit 1; }
    wall[$f.$prog]=$w cpu[$f.$prog]=$c
    printf '%-6s %10d %-14s %5d %12.6f %12.6f %10d\n' "$f" "$rows" "$prog" "$n" "$w" "$c" "$m"
  done
  [ "$n_seed" -gt 0 ] && printf '%-6s seed / propid: %.1f× wall, %.1f× CPU' "$f" \
    "$(echo "${wall[$f.seed]} / ${wall[$f.propid]}" | bc -l)" \
    "$(echo "${cpu[$f.seed]} / ${cpu[$f.propid]}" | bc -l)"
  [ -n "${BEFORE:-}" ] && printf '   before / propid: %.2f× wall' "$(echo "${wall[$f.before]} / ${wall[$f.propid]}" | bc -l)"
  echo
done
[ "${ONLY_SMALL:-0}" = 1 ] && exit 0
bytes=$(stat -c %s "$dir/mib.tsv")
r=$(time_runs "$runs" "$P" fit "$dir/mib.tsv")
read -r w c m <<< "$r"
rate() { awk -v b="$1" -v t="$2" 'BEGIN { if (t > 0) printf "%.0f", b / t / 1e6; else printf "n/a" }'; }
printf 'throughput on %d MiB: %s MB/s wall (%.3f s), %s MB/s per CPU second (%.3f s), peak RSS %d KiB\n' \
  "$mib" "$(rate "$bytes" "$w")" "$w" "$(rate "$bytes" "$c")" "$c" "$m"
if [ -n "${BEFORE:-}" ]; then
  r=$(time_runs "$runs" "$BEFORE" fit "$dir/mib.tsv")
  read -r w c m <<< "$r"
  printf 'before, same file:  %s MB/s wall (%.3f s), %s MB/s per CPU second (%.3f s), peak RSS %d KiB\n' \
    "$(rate "$bytes" "$w")" "$w" "$(rate "$bytes" "$c")" "$c" "$m"
fi
# Same answers: propid's YAML on the large file printed for the record.
$P fit "$dir/large.tsv" | head -3
