#!/usr/bin/env bash
# Installs what the tests need on a fresh machine (called by .ci/run before the test command).
set -euo pipefail
# The seed regressor (tests compare propid fit with it).
python3 -m pip install --quiet --disable-pip-version-check numpy scipy pandas
# benches/compare_fit.sh: bc for arithmetic, GNU time for peak RSS.
if command -v apt-get >/dev/null; then
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq bc time >/dev/null
fi
