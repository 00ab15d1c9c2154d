#!/usr/bin/env bash
# The README's main job, exactly as a user runs it: the whole pipeline on the simulated stand.
# Its closing line and the report's headline are the Result: the extended model's J within 2 % of
# the simulated truth, and C_Q with the diameter it was computed with (issue 26).
set -euo pipefail
out=$(mktemp -d)
cargo run --release -q -- demo --out "$out/demo" | tee "$out/stdout"
for f in run.tsv fit.yaml fit.svg diagnose.txt diagnose.json diagnose.svg report.md report.html result.yaml; do
  test -s "$out/demo/$f" || { echo "demo did not write $f" >&2; exit 1; }
done
grep -q '"name": "torque_lag"' "$out/demo/diagnose.json" || { echo "demo: diagnose did not find the hidden torque lag" >&2; exit 1; }
closing=$(tail -n 1 "$out/stdout")
# "demo: J = … (with torque_lag = …), C_Q = … at D = 0.1778 m (7.00 in), … (truth J = …, +0.19 %; …)"
off=$(sed -n 's/.*truth J = [^,]*, \([-+][0-9.]*\) %.*/\1/p' <<<"$closing")
[[ -n "$off" ]] || { echo "demo: the closing line does not compare J with the truth: $closing" >&2; exit 1; }
awk -v o="$off" 'BEGIN { exit !(o < 2 && o > -2) }' || { echo "demo: the Result's J is $off % off the truth (limit 2 %): $closing" >&2; exit 1; }
grep -q 'with torque_lag' <<<"$closing" || { echo "demo: the closing line is not the extended model's: $closing" >&2; exit 1; }
grep -q 'C_Q = [0-9.e-]* at D = 0.1778 m' <<<"$closing" || { echo "demo: the closing line has no C_Q with its diameter: $closing" >&2; exit 1; }
# The report's first section is the Result, with the same J.
j=$(sed -n 's/^demo: J = \([0-9.e-]*\) .*/\1/p' <<<"$closing")
first=$(grep -o '<section><h2>[^<]*</h2>' "$out/demo/report.html" | head -n 1)
[[ "$first" == '<section><h2>Result</h2>' ]] || { echo "demo: the report's headline is $first, not the Result" >&2; exit 1; }
grep -q "J    = $j kg·m²" "$out/demo/report.html" || { echo "demo: the report's Result does not quote J = $j" >&2; exit 1; }
echo "demo: report and plots written, hidden torque lag found, Result J $off % off the truth"
