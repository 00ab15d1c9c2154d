#!/usr/bin/env bash
# Interop with the reference stack, PyCyphal 1.27.1 over an SLCAN socat pty (ci/setup.sh installs
# pycyphal[transport-can-pythoncan] and socat): values both ways at a 50 ms setpoint period, and the
# seed's 5 ms period, which python-can's slcan reader may not drain: the run completes, drops are
# reported, and PyCyphal's last readiness is STANDBY and its last setpoint zero.
# Then congestion for real (tests/pycyphal/slowbus.py, a 125 kbit/s bus between propid and
# PyCyphal that also stops for a second): the run completes, a SIGINT mid-stall and the end of the
# pattern both leave STANDBY and zero last at PyCyphal, a killed relay stops propid with whole rows.
# Every #[ignore]d test of both files must run and pass.
set -euo pipefail
. ci/lib.sh
run_ignored propid host-cli/tests/pycyphal_interop.rs
run_ignored propid host-cli/tests/pycyphal_congestion.rs --test-threads=1
