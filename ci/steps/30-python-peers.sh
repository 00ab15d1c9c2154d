#!/usr/bin/env bash
# The tests that compare propid with Python originals. They are #[ignore = "needs …"] so that a
# machine without the packages never reports them `ok`; here ci/setup.sh has installed numpy,
# scipy, pandas (the seed regressor), so they run (all of them, counted) and a missing package
# fails them.
set -euo pipefail
. ci/lib.sh
run_ignored propid host-cli/tests/fit_vs_seed.rs
