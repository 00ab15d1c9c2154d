#!/usr/bin/env bash
# The core must build for a Cortex-M4F with no allocator: it is no_std and never names `alloc`.
set -euo pipefail
cargo build -p propid-core --target thumbv7em-none-eabihf --release
if grep -rn "extern crate alloc\|alloc::" core/src; then
  echo "propid-core must not use alloc" >&2
  exit 1
fi
echo "propid-core builds for thumbv7em-none-eabihf without alloc"
