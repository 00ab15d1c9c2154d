#!/usr/bin/env bash
# propid must build on macOS and Windows too (SLCAN works everywhere; SocketCAN is Linux only and
# sits behind cfg(target_os = "linux")). `cargo check` needs only each target's standard library,
# no linker or SDK, so both run on this Linux machine. The Python extension (python/) is left out:
# PyO3 needs the target's Python configuration to cross-compile; its wheel is built per platform by
# maturin, from the same crates checked here.
set -euo pipefail
rustup target add x86_64-apple-darwin x86_64-pc-windows-gnu
for target in x86_64-apple-darwin x86_64-pc-windows-gnu; do
  cargo check --workspace --exclude propid-python --target "$target"
  echo "propid checks for $target"
done
