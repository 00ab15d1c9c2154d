#!/usr/bin/env bash
# The Python package as a user gets it (issue 28): a fresh venv, `pip install ./python` (maturin
# builds the wheel through cargo), then its pytest suite, the docs' example and a smoke run of its
# benchmark, all against the wheel's own `propid` command.
# Reuse: CARGO_TARGET_DIR is the workspace's target/ (release profile, as the demo step's
# `cargo run --release`), and the venv sees the numpy, scipy and pandas ci/setup.sh installed
# (--system-site-packages). Part of the demo's release artifacts is rebuilt all the same: PyO3's
# proc-macros enable more features of syn (extra-traits, visit-mut), which changes every
# proc-macro (serde_derive, thiserror-impl, clap_derive) and each crate that derives with one (serde,
# clap, propid's io, science, drive, the command); core, nalgebra and the rest are reused. The `test`
# profile of `cargo test --workspace` has those features (resolved over all members, python/
# included), but maturin builds through `cargo rustc`, which compiles a `test`-profile library as a
# test harness that Python cannot load.
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
