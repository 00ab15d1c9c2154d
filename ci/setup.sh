#!/usr/bin/env bash
# Installs what the tests need on a fresh machine (called by .ci/run before the test command).
set -euo pipefail
# The seed regressor (tests compare propid fit with it) and the PyCyphal interop peer.
python3 -m pip install --quiet --disable-pip-version-check numpy scipy pandas
