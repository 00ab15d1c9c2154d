#!/usr/bin/env bash
# propid must build on macOS and Windows too (SLCAN works everywhere; SocketCAN is Linux only and
# sits behind cfg(target_os = "linux")). `cargo check` needs only each target's standard library,
# no linker or SDK, so both run on this Linux machine.
set -euo pipefail
rustup target add x86_64-apple-darwin x86_64-pc-windows-gnu
for target in x86_64-apple-darwin x86_64-pc-windows-gnu; do
  cargo check --workspace --target "$target"
  echo "propid checks for $target"
done
