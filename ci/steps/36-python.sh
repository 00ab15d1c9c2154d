#!/usr/bin/env bash
# The Python package as a user gets it (issue 28): a fresh venv, `pip install ./python` (maturin
# builds the wheel through cargo), then its pytest suite, the docs' example and a smoke run of its
# benchmark, all against the wheel's own `propid` command.
# Cheap by reuse: CARGO_TARGET_DIR is the workspace's target/ and the wheel is built in the `test`
# profile (opt-level 2), so the dependencies `cargo test --workspace` compiled are not compiled
# again: only PyO3, numpy and the extension are. (The release build of the demo step cannot be
# reused: PyO3's proc-macros enable more features of syn than the command's do, which changes every
# proc-macro and so nearly every crate; `cargo test --workspace` resolves features over all members,
# python/ included, and so has them.) The venv sees the numpy, scipy and pandas ci/setup.sh
# installed (--system-site-packages).
set -euo pipefail
cd "$(dirname "$0")/../.."
start=$(date +%s)
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$PWD/target}
venv=$(mktemp -d)/venv
python3 -m venv --system-site-packages "$venv"
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check pytest
MATURIN_PEP517_ARGS="--profile test" \
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check ./python
echo "python: wheel built and installed in $(( $(date +%s) - start )) s"
# From the repository root, so that `import propid` is the installed package, not python/propid.
"$venv/bin/python" -m pytest python/tests -q -p no:cacheprovider
"$venv/bin/python" python/examples/seed_workflow.py --plot "$(dirname "$venv")/seed_workflow.png"
SMOKE=1 "$venv/bin/python" benches/python_fit.py
echo "python: step done in $(( $(date +%s) - start )) s"
