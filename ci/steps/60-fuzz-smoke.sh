#!/usr/bin/env bash
# Fuzz smoke test: each cargo-fuzz target runs for a short time from its committed seed corpus
# (fuzz/corpus/<target>/seed-*; see docs/FUZZING.md to run long).
# cargo-fuzz needs nightly-only sanitizer flags; RUSTC_BOOTSTRAP lets the stable toolchain accept
# them (this machine has no nightly).
set -euo pipefail
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked --quiet
cd fuzz
for target in $(cargo fuzz list); do
  RUSTC_BOOTSTRAP=1 cargo fuzz run "$target" -- -max_total_time="${FUZZ_SECONDS:-20}" 2>&1 | tail -n 1
done
