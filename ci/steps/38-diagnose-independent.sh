#!/usr/bin/env bash
# propid diagnose against the independent Python stand (tests/independent_stand; numpy and scipy
# from ci/setup.sh): every diagnosis case, six noise seeds (two tuning, four held out), judged against the stand's truth. The
# test is #[ignore]d so that a machine without python never reports it `ok`; here it runs, and
# the step fails unless it ran and passed. Its table is docs/SCIENCE.md's "The independent stand".
set -euo pipefail
cd "$(dirname "$0")/../.."
. ci/lib.sh
run_ignored propid-tests tests/tests/diagnose_independent.rs --nocapture
