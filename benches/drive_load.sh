#!/usr/bin/env bash
# The share of a 500 Hz feedback stream that `propid drive` keeps over an SLCAN pseudo-terminal
# while every core is busy: `propid sim-drive` (a separate process, as a real drive is) on one end
# of a socat pty pair, `propid drive` on the other, and busy loops (LOAD_PER_CORE per core) beside
# them. Builds are compared in one time window by alternating them, run for run.
#
# usage: benches/drive_load.sh [LABEL=DRIVE_BINARY[,SIM_DRIVE_BINARY]] ...
#   default: current=target/release/propid (both sides); a LABEL ending in `-unprivileged` runs
#   both propid processes without CAP_SYS_NICE (setpriv), as a user who may not take a
#   real-time priority
# env: RUNS (3 per build), PATTERN_S (20), LOAD_PER_CORE (2), LOAD_SESSION (same: the busy loops
#   share propid's session, so Linux's autogroup scheduling gives them and propid one share of the
#   CPUs — the worst case; own: they run in a session of their own, like a build in another
#   terminal or a browser, and propid's session gets its own share)
#
# Per run it prints the rows recorded, the feedback missing by the drive's own timestamps (the
# `t` column: lost anywhere, in the simulated drive, the pty or propid) plus, when the run stopped
# early (the dead-man), the rest of the pattern, and the share kept; the drive's and the simulated
# drive's own accounts when the build prints them, and how long each process's control loop waited
# for a CPU (its run-queue delay from /proc/PID/schedstat: over the run, and the worst second). Then the median share per build. Needs socat.
# Exits non-zero when a completed run recorded nothing or a process fails otherwise.
set -euo pipefail
shopt -s inherit_errexit
cd "$(dirname "$0")/.."
. benches/common.sh
. ci/lib.sh
RUNS=${RUNS:-3}
PATTERN_S=${PATTERN_S:-20}
LOAD_PER_CORE=${LOAD_PER_CORE:-2}
LOAD_SESSION=${LOAD_SESSION:-same}
case $LOAD_SESSION in same | own) ;; *) echo "drive_load: LOAD_SESSION is same or own" >&2; exit 1 ;; esac
INTERVAL=0.002
[ $# -gt 0 ] || set -- "current=target/release/propid"
command -v socat >/dev/null || { echo "drive_load: needs socat (apt-get install socat)" >&2; exit 1; }

# socat stands in for the USB link: it runs at a real-time priority where permitted (the same for
# every build), so that what is measured is propid, not the relay.
relay=""
if chrt -r 10 true 2>/dev/null; then relay="chrt -r 10"; fi

work=$(mktemp -d)
clean_at_exit "$work"

busy() {
    local n=$(( $(nproc) * LOAD_PER_CORE ))
    for _ in $(seq "$n"); do
        if [ "$LOAD_SESSION" = own ]; then
            setsid bash -c 'while :; do :; done' &
        else
            ( while :; do :; done ) &
        fi
        pids+=($!)
    done
}

unbusy() {
    for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
    for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done
    pids=()
}

# The time a process's main thread (propid's control loop) spent waiting for a CPU so far [ns]
# (its run-queue delay, /proc/PID/schedstat), or nothing once it has gone.
waited() { cut -d' ' -f2 "/proc/$1/schedstat" 2>/dev/null || true; }

# Samples `waited` of PIDS every 0.2 s into FILE ("seconds pid ns") until they have all gone.
sample_waits() {
    local file=$1; shift
    local t0; t0=$(date +%s.%N)
    while :; do
        local alive=0
        for p in "$@"; do
            local w; w=$(waited "$p")
            [ -n "$w" ] || continue
            alive=1
            echo "$(date +%s.%N) $t0 $p $w" >>"$file"
        done
        [ "$alive" -eq 1 ] || break
        sleep 0.2
    done
}

# "NAME waited for a CPU X % of the run (at most Y ms in one second)", from `sample_waits` lines.
wait_summary() {
    awk -v pid="$2" -v name="$3" '$3 == pid {
            t = $1 - $2; w = $4 / 1e9
            if (n == 0) { t0 = t; w0 = w }
            ts[n] = t; ws[n] = w; n++
        }
        END {
            if (n < 2) exit
            worst = 0
            for (i = 0; i < n; i++)
                for (j = i + 1; j < n && ts[j] - ts[i] <= 1.0001; j++)
                    if (ts[j] - ts[i] >= 0.95 && ws[j] - ws[i] > worst) worst = ws[j] - ws[i]
            printf "%s waited for a CPU %.0f %% of the run (at most %.0f ms in one second)\n",
                name, 100 * (ws[n - 1] - w0) / (ts[n - 1] - t0), 1000 * worst
        }' "$1"
}

# One run: prints "rows missing share" on stdout; the processes' summaries on stderr.
run_once() {
    local drive_bin=$1 sim_bin=$2 tag=$3 as=""
    case $tag in *-unprivileged.*) as="setpriv --bounding-set -sys_nice --inh-caps -sys_nice" ;; esac
    local a="$work/ttyA" b="$work/ttyB"
    $relay socat "pty,raw,echo=0,link=$a" "pty,raw,echo=0,link=$b" 2>/dev/null &
    local socat_pid=$!
    for _ in $(seq 100); do [ -e "$a" ] && [ -e "$b" ] && break; sleep 0.02; done
    $as "$sim_bin" sim-drive --iface "slcan:$a" --interval "$INTERVAL" --readiness-id 10 \
        2>"$work/sim.$tag.err" &
    local sim_pid=$!
    busy
    local status=0
    UAVCAN__NODE__ID=10 UAVCAN__PUB__READINESS__ID=10 UAVCAN__PUB__SP_RAT__ID=24 \
        UAVCAN__SUB__FB_DYN__ID=110 \
        $as "$drive_bin" drive --iface "slcan:$b" --pattern-duration "$PATTERN_S" --init-duration 1 \
        --progress=false -o "$work/run.$tag.tsv" 2>"$work/drive.$tag.err" &
    local drive_pid=$!
    sample_waits "$work/waits.$tag" "$drive_pid" "$sim_pid" &
    local sampler=$!
    wait "$drive_pid" || status=$?
    unbusy
    wait_summary "$work/waits.$tag" "$drive_pid" "propid drive" | sed "s/^/  [$tag] /" >&2
    wait_summary "$work/waits.$tag" "$sim_pid" "propid sim-drive" | sed "s/^/  [$tag] /" >&2
    kill -INT "$sim_pid" 2>/dev/null || true
    wait "$sim_pid" 2>/dev/null || true
    wait "$sampler" 2>/dev/null || true
    kill "$socat_pid" 2>/dev/null || true
    wait "$socat_pid" 2>/dev/null || true
    grep -h -E '^(drive: (stopped|feedback|the control loop)|sim-drive: [0-9])' "$work/drive.$tag.err" "$work/sim.$tag.err" |
        sed "s/^/  [$tag] /" >&2 || true
    if [ "$status" -ne 0 ] && ! grep -q '^drive: stopped' "$work/drive.$tag.err"; then
        echo "drive_load: propid drive failed ($status):" >&2
        cat "$work/drive.$tag.err" >&2
        return 1
    fi
    [ "$status" -eq 0 ] || echo "  [$tag] stopped early: $(grep '^error:' "$work/drive.$tag.err")" >&2
    awk -v iv="$INTERVAL" -v expected=$((PATTERN_S * 500)) -v early=$((status != 0)) 'NR > 1 {
            rows++
            if (NR > 2) { k = int(($2 - last) / iv + 0.5); if (k > 1) missing += k - 1 }
            last = $2
        }
        END {
            if (rows == 0 && !early) { print "drive_load: a completed run recorded no rows" > "/dev/stderr"; exit 1 }
            if (early && rows + missing < expected) missing = expected - rows
            share = (rows + missing > 0) ? 100 * rows / (rows + missing) : 0
            printf "%d %d %.3f\n", rows, missing, share
        }' "$work/run.$tag.tsv"
}

echo "drive_load: relay ${relay:-at normal priority}; $(nproc) cores, $((LOAD_PER_CORE * $(nproc))) busy loops (session: $LOAD_SESSION), ${PATTERN_S} s at 500 Hz per run, $RUNS runs per build, alternating; load before: $(cut -d' ' -f1-3 /proc/loadavg)"
declare -A shares
for r in $(seq "$RUNS"); do
    for spec in "$@"; do
        label=${spec%%=*}
        bins=${spec#*=}
        drive_bin=${bins%%,*}
        sim_bin=${bins#*,}
        out=$(run_once "$drive_bin" "$sim_bin" "$label.$r") || exit 1
        read -r rows missing share <<<"$out"
        echo "run $r $label: $rows rows, $missing missing by the drive's timestamps, $share % kept"
        shares[$label]+="$share "
    done
done
for spec in "$@"; do
    label=${spec%%=*}
    # shellcheck disable=SC2086
    echo "median $label: $(printf '%s\n' ${shares[$label]} | median) % of feedback kept (runs: ${shares[$label]})"
done
