#!/usr/bin/env bash
# How the independent stand's diagnosis depends on the noise (docs/SCIENCE.md, "Against the
# noise"): diagnose_independent's judge on the held-out seeds with every noise of the stand scaled
# (0: none; 1: the stand's own). The test's ledger is written for scale 1 and is not asserted
# here; each line is the test's own tally, and each run it finds silently wrong.
#
# usage: tests/independent_stand/noise_sweep.sh [SCALES…]   (default 0.25 0.5 1; seeds 3,4,5,6)
#   SEEDS=1,2   other seeds
# Needs python3 with numpy and scipy; about 2.5 min per scale on two cores.
set -euo pipefail
cd "$(dirname "$0")/../.."
scales=("$@")
[ ${#scales[@]} -gt 0 ] || scales=(0.25 0.5 1)
for scale in "${scales[@]}"; do
  PROPID_NOISE_SCALE=$scale PROPID_SEED=${SEEDS:-3,4,5,6} \
    cargo test -q --release -p propid-tests --test diagnose_independent \
    the_independent_stand_is_diagnosed_right -- --ignored --nocapture 2>&1 |
    grep -E '^noise scale|SILENTLY WRONG' || { echo "noise scale $scale: the test did not run" >&2; exit 1; }
done
