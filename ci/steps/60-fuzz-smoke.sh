#!/usr/bin/env bash
# Fuzz smoke test: each cargo-fuzz target runs for a short time from its committed seed corpus
# (fuzz/corpus/<target>/; see docs/FUZZING.md to run long). libFuzzer adds what it finds to the
# first corpus directory, so that is a scratch one and the committed seeds stay as they are.
# cargo-fuzz needs nightly-only sanitizer flags; RUSTC_BOOTSTRAP lets the stable toolchain accept
# them (this machine has no nightly).
set -euo pipefail
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked --quiet
cd fuzz
scratch=$(mktemp -d)
for target in decode_payloads reassembler candump tsv_reader importers; do
  mkdir -p "$scratch/$target" "corpus/$target"
  RUSTC_BOOTSTRAP=1 cargo fuzz run "$target" "$scratch/$target" "corpus/$target" -- \
    -max_total_time="${FUZZ_SECONDS:-20}" 2>&1 | tail -n 1
done
