#!/usr/bin/env bash
# The register API against the reference tools over a socat pty pair: Yakut 0.14.2 lists, reads and
# writes the registers of `propid drive` and `propid sim-drive` (and the feedback rate follows a
# written interval); `propid telega` checks and fixes a register server written with PyCyphal.
# Needs yakut, pycyphal and socat (ci/setup.sh installs them); CYPHAL_PATH is the repo's dsdl/.
# Every #[ignore]d test of the file must run and pass.
set -euo pipefail
. ci/lib.sh
run_ignored propid host-cli/tests/yakut.rs --test-threads=1
