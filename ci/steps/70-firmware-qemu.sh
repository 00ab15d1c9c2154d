#!/usr/bin/env bash
# The firmware demo: build for the Cortex-M4F, prove no allocator is linked, run it under QEMU
# twice (the instruction counts must repeat exactly), print the flash and RAM footprint.
set -euo pipefail
command -v qemu-system-arm >/dev/null || DEBIAN_FRONTEND=noninteractive apt-get install -y -qq qemu-system-arm >/dev/null
rustup target add thumbv7em-none-eabihf >/dev/null
cd firmware-demo
cargo build --release -q
elf=target/thumbv7em-none-eabihf/release/propid-firmware-demo
if nm "$elf" | grep -Eq '__rust_alloc|__rg_alloc|__rdl_alloc'; then
  echo "an allocator is linked into the firmware" >&2
  exit 1
fi
echo "firmware: no allocator symbols linked"
first=$(cargo run --release -q 2>&1)
echo "$first"
second=$(cargo run --release -q 2>&1)
costs=$(echo "$first" | grep -c cost) || true
[ "$costs" -gt 0 ] || { echo "the firmware printed no instruction counts" >&2; exit 1; }
[ "$(echo "$first" | grep cost)" = "$(echo "$second" | grep cost)" ] || { echo "instruction counts differ between runs" >&2; exit 1; }
echo "firmware: instruction counts repeat exactly"
size "$elf" | awk 'NR==2 {printf "firmware footprint: flash %d bytes (text+rodata+vectors), static RAM %d bytes (data+bss)\n", $1+$2, $2+$3}'
