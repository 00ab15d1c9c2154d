#!/usr/bin/env bash
# README.md's "With hardware", word for word, against the simulated Telega: the commands of the
# section's ```sh blocks, in order, with PORT one end of a socat pty pair and `propid sim-drive` on
# the other (node 42, started misconfigured: feedback at 20 Hz without the drive's timestamps, so
# the first check must fail and the fix must make it pass). Every command must exit 0, except the
# first `propid telega`, which must exit 1 naming both registers. Then the files the section
# promises must exist and the simulated Telega must have seen STANDBY and a zero setpoint last.
# usage: tests/readme_hardware.sh [PROPID_BINARY]   (default: target/release/propid)
set -euo pipefail
shopt -s inherit_errexit
repo=$(cd "$(dirname "$0")/.." && pwd)
bin=$(realpath "${1:-$repo/target/release/propid}")
[ -x "$bin" ] || { echo "readme_hardware: no propid at $bin (cargo build --release -p propid)" >&2; exit 1; }
command -v socat >/dev/null || { echo "readme_hardware: needs socat" >&2; exit 1; }

. "$repo/ci/lib.sh"
work=$(mktemp -d)
clean_at_exit "$work"

# The commands: the ```sh blocks of the section, continuation lines joined.
awk '/^## With hardware/ { on = 1; next } /^## / { on = 0 }
     on && /^```sh$/ { block = 1; next } on && /^```/ { block = 0; next }
     on && block && NF { print }' "$repo/README.md" >"$work/commands"
n=$(grep -c . "$work/commands" || true)
[ "$n" -ge 10 ] || { echo "readme_hardware: only $n commands found in README.md's \"With hardware\"" >&2; exit 1; }

socat "pty,raw,echo=0,link=$work/babel" "pty,raw,echo=0,link=$work/telega" 2>/dev/null &
pids+=($!)
for _ in $(seq 100); do [ -e "$work/babel" ] && [ -e "$work/telega" ] && break; sleep 0.05; done
"$bin" sim-drive --iface "slcan:$work/telega@115200" --readiness-id 10 \
    --interval 0.05 --local-timestamp false 2>"$work/sim.err" &
sim=$!
pids+=("$sim")

# The README's words, in a shell of their own: `propid` is the binary under test, PORT the pty.
mkdir "$work/run"
mkdir "$work/bin"
ln -s "$bin" "$work/bin/propid"
checks=0
while IFS= read -r line; do
    echo "\$ $line"
    status=0
    (cd "$work/run" && PATH="$work/bin:$PATH" PORT="$work/babel" bash -c "
        set -euo pipefail
        $(cat "$work/exports" 2>/dev/null || true)
        $line") >"$work/out" 2>&1 || status=$?
    sed 's/^/    /' "$work/out"
    case $line in
        export\ *) echo "$line" >>"$work/exports" ;;
    esac
    want=0
    if [[ $line == "propid telega "* || $line == "propid telega" ]] && [ "$checks" -eq 0 ]; then
        # The simulated Telega starts misconfigured: the first check fails, naming both.
        checks=1
        want=1
        grep -q "mns.pub_interval_min is 0.05" "$work/out"
        grep -q "mns.local_timestamp is false" "$work/out"
    fi
    if [[ $line == "propid drive "*--fit* ]]; then
        # drive --fit ends with the recording's Result, after the stop.
        grep -q "the recording's Result" "$work/out" && grep -q "^   J    = " "$work/out" || {
            echo "readme_hardware: \`$line\` printed no Result" >&2
            exit 1
        }
    fi
    if [ "$status" -ne "$want" ]; then
        echo "readme_hardware: \`$line\` exited $status, expected $want" >&2
        exit 1
    fi
done <"$work/commands"

for f in first.tsv first.yaml plan.json run.tsv report.html; do
    [ -s "$work/run/$f" ] || { echo "readme_hardware: $f was not written" >&2; exit 1; }
done
kill -INT "$sim"
wait "$sim"
grep -q "last readiness STANDBY, last setpoint 0" "$work/sim.err" || {
    echo "readme_hardware: the simulated Telega did not see STANDBY and a zero setpoint last:" >&2
    cat "$work/sim.err" >&2
    exit 1
}
echo "readme_hardware: $n commands of README.md's \"With hardware\" ran against the simulated Telega"
