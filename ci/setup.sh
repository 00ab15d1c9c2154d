#!/usr/bin/env bash
# Installs what the tests need on a fresh machine (called by .ci/run before the test command).
set -euo pipefail
# The seed regressor (tests compare propid fit with it) and PyCyphal, the reference stack the
# interop test talks to over SLCAN; Yakut, the reference Cyphal CLI the register tests drive
# (ci/steps/80-yakut.sh). NumPy, SciPy and pandas are pinned: where the seed's L-BFGS-B stops on
# a propeller's magnitudes (README, host-cli/tests/fit_vs_seed.rs) depends on SciPy's version.
python3 -m pip install --quiet --disable-pip-version-check 'numpy==2.4.6' 'scipy==1.17.1' 'pandas==3.1.1' 'pycyphal[transport-can-pythoncan]==1.27.1' 'yakut==0.14.2'
# socat: the pseudo-terminal pair of the interop test; bc and GNU time: benches/compare_fit.sh.
if command -v apt-get >/dev/null; then
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq socat bc time >/dev/null
fi
