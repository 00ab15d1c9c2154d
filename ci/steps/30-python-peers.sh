#!/usr/bin/env bash
# The tests that compare propid with Python originals. They are #[ignore = "needs …"] so that a
# machine without the packages never reports them `ok`; here ci/setup.sh has installed numpy,
# scipy, pandas (the seed regressor), so they run and a missing package fails them.
set -euo pipefail
cargo test -q -p propid --test fit_vs_seed -- --ignored
