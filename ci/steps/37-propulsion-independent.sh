#!/usr/bin/env bash
# propid propulsion against the independent Python stand's thrust cases (numpy and scipy from
# ci/setup.sh). The test is #[ignore]d so that a machine without them never reports it `ok`; here
# it runs, and the step fails unless exactly one test ran and passed.
set -euo pipefail
out=$(cargo test -p propid-tests --test propulsion_independent -- --ignored 2>&1) || { echo "$out"; exit 1; }
echo "$out" | tail -5
echo "$out" | grep -q "test result: ok. 1 passed" || { echo "propulsion_independent: expected 1 test to run and pass"; exit 1; }
