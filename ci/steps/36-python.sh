#!/usr/bin/env bash
# The Python package as a user gets it (issue 28): a fresh venv, `pip install ./python` (maturin
# builds the wheel through cargo), then its pytest suite, the docs' example and a smoke run of its
# benchmark, all against the wheel's own `propid` command.
# Cheap by reuse: CARGO_TARGET_DIR is the workspace's target/, so the release-profile
# dependencies the demo step compiled (`cargo run --release`) are not compiled again, and the venv
# sees the numpy, scipy and pandas ci/setup.sh installed (--system-site-packages).
set -euo pipefail
cd "$(dirname "$0")/../.."
start=$(date +%s)
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$PWD/target}
venv=$(mktemp -d)/venv
python3 -m venv --system-site-packages "$venv"
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check pytest
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check ./python
echo "python: wheel built and installed in $(( $(date +%s) - start )) s"
# From the repository root, so that `import propid` is the installed package, not python/propid.
"$venv/bin/python" -m pytest python/tests -q -p no:cacheprovider
"$venv/bin/python" python/examples/seed_workflow.py --plot "$(dirname "$venv")/seed_workflow.png"
SMOKE=1 "$venv/bin/python" benches/python_fit.py
echo "python: step done in $(( $(date +%s) - start )) s"
