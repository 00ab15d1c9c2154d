#!/usr/bin/env bash
# SocketCAN on a real Linux kernel with vcan, under QEMU (this machine's own kernel has no CAN),
# with can-utils' candump and cansend as the independent peer. See tests/vcan/run.sh.
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive
# Separate installs: qemu-system-x86 and the kernel in one command with the rest was refused once
# ("held packages") on this kind of machine.
apt-get install -y -qq busybox-static can-utils cpio >/dev/null
apt-get install -y -qq qemu-system-x86 >/dev/null
ls /boot/vmlinuz-* >/dev/null 2>&1 || apt-get install -y -qq linux-image-amd64 >/dev/null
cargo build --release -q -p propid
bash tests/vcan/run.sh target/release/propid
