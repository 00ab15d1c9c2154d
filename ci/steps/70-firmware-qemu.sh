#!/usr/bin/env bash
# The firmware demo: build for the Cortex-M4F, prove no allocator is linked, run it under QEMU
# twice (the instruction counts must repeat exactly), print the flash and RAM footprint.
set -euo pipefail
command -v qemu-system-arm >/dev/null || DEBIAN_FRONTEND=noninteractive apt-get install -y -qq qemu-system-arm >/dev/null
rustup target add thumbv7em-none-eabihf >/dev/null
cd firmware-demo
# Panic locations embed source paths, so the flash size would depend on where the clone and
# CARGO_HOME live (8 bytes apart between two machines). Mapped to fixed prefixes, the build is
# the same wherever it runs, and the figures the docs quote can be compared byte for byte.
# (CARGO_ENCODED_RUSTFLAGS replaces .cargo/config.toml's rustflags, so the linker script is repeated.)
root=$(cd .. && pwd -P)
CARGO_ENCODED_RUSTFLAGS=$(printf '%s\x1f' -C link-arg=-Tlink.x "--remap-path-prefix=$root=/propid" \
  "--remap-path-prefix=${CARGO_HOME:-$HOME/.cargo}=/cargo" | sed 's/\x1f$//')
export CARGO_ENCODED_RUSTFLAGS
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
footprint=$(size "$elf" | awk 'NR==2 {printf "firmware footprint: flash %d bytes (text+rodata+vectors), static RAM %d bytes (data+bss)\n", $1+$2, $2+$3}')
echo "$footprint"
# docs/FIRMWARE.md and README.md quote these figures; on the toolchain they were measured with, they
# must be this build's (another rustc may lay the code out differently: its figures are printed only).
doc=../docs/FIRMWARE.md
measured_with=$(grep -o -m1 'rustc [0-9][0-9.]*' "$doc")
if [ "rustc $(rustc --version | awk '{print $2}')" = "$measured_with" ]; then
  flash=$(sed -n 's/.*flash \([0-9]*\) bytes.*/\1/p' <<<"$footprint")
  ram=$(sed -n 's/.*static RAM \([0-9]*\) bytes.*/\1/p' <<<"$footprint")
  commas() { sed ':a;s/\B[0-9]\{3\}\>/,&/;ta' <<<"$1"; }
  grep -q "^flash $(commas "$flash") bytes (text, rodata and vector table), static RAM $(commas "$ram") bytes" "$doc" \
    || { echo "docs/FIRMWARE.md's footprint is not this build's ($footprint): update it" >&2; exit 1; }
  kb() { awk -v b="$1" 'BEGIN { printf "%.1f", b / 1000 }'; }
  grep -q "| firmware footprint | flash $(kb "$flash") kB, static RAM $(kb "$ram") kB |" ../README.md \
    || { echo "README.md's footprint is not this build's ($footprint): update it" >&2; exit 1; }
  grep -qF "$(echo "$first" | grep -m1 cost)" "$doc" \
    || { echo "docs/FIRMWARE.md does not quote this build's cost line: $(echo "$first" | grep -m1 cost)" >&2; exit 1; }
  echo "firmware: the footprint and costs docs/FIRMWARE.md and README.md quote are this build's ($measured_with)"
else
  echo "firmware: docs quote figures measured with $measured_with; this is $(rustc --version): printed, not compared"
fi
