#!/usr/bin/env bash
# Fuzz smoke test: each cargo-fuzz target runs for a short time from its committed seed corpus
# (fuzz/corpus/<target>/seed-*; see docs/FUZZING.md to run long). Every target of fuzz/Cargo.toml
# must run: a failing `cargo fuzz list` or a target missing from it fails the step.
# cargo-fuzz needs nightly-only sanitizer flags; RUSTC_BOOTSTRAP lets the stable toolchain accept
# them (this machine has no nightly).
set -euo pipefail
. ci/lib.sh
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked --quiet
cd fuzz
targets=$(cargo fuzz list)
declared=$(grep -c '^\[\[bin\]\]' Cargo.toml)
listed=$(echo "$targets" | grep -c .)
[ "$listed" -eq "$declared" ] || { echo "cargo fuzz list gave $listed targets, fuzz/Cargo.toml declares $declared" >&2; exit 1; }
ran=0
for target in $targets; do
  RUSTC_BOOTSTRAP=1 cargo fuzz run "$target" -- -max_total_time="${FUZZ_SECONDS:-20}" 2>&1 | tail -n 1
  ran=$((ran + 1))
done
echo "fuzz smoke: $ran of $declared targets ran"
