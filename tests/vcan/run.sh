#!/usr/bin/env bash
# SocketCAN against a real kernel: boots the Debian kernel under QEMU (software emulation) with an
# initramfs holding busybox, the CAN modules, can-utils and the `propid` binary, creates vcan0,
# and checks with candump/cansend as the independent peer that
#  - frames `propid drive` sends appear in candump with the right IDs and data, Classic (MTU 8)
#    and CAN FD (MTU 64);
#  - a DoF3rdTs frame cansend injects reaches `propid drive` and becomes a TSV row.
#  The limits that need a drive answering (the soft start, the speed watchdog) are off: nothing
#  drives a rotor here; one injected frame stands for the feedback (the limits are tested against the
#  simulated Telega in drive_e2e and tests/readme_hardware.sh).
# usage: tests/vcan/run.sh [path/to/propid]   (needs qemu-system-x86, linux-image-amd64,
#                                              busybox-static, can-utils, cpio)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
propid=${1:-$here/../../target/release/propid}
# The newest installed kernel image and its modules (not the running kernel: this machine's has no CAN).
kernel=$(ls /boot/vmlinuz-* | sort -V | tail -n 1)
kver=${kernel#/boot/vmlinuz-}
[ -d "/lib/modules/$kver/kernel/net/can" ] || { echo "no CAN modules for $kver" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
root=$work/root
mkdir -p "$root"/{bin,sbin,proc,sys,dev,tmp,lib/modules,usr/bin}
cp /bin/busybox "$root/bin/busybox"
for m in net/can/can.ko net/can/can-raw.ko drivers/net/can/dev/can-dev.ko drivers/net/can/vcan.ko; do
  src=/lib/modules/$kver/kernel/$m
  [ -f "$src" ] || src=$(ls "$src".* 2>/dev/null | head -n 1)
  cp "$src" "$root/lib/modules/"
done
copy_with_libs() {
  cp "$1" "$root/usr/bin/"
  ldd "$1" | grep -o '/[^ ]*' | while read -r lib; do
    mkdir -p "$root$(dirname "$lib")"
    cp -n "$lib" "$root$lib"
  done
}
copy_with_libs "$propid"
copy_with_libs "$(command -v candump)"
copy_with_libs "$(command -v cansend)"
inject=$(python3 "$here/dof3rdts_frame.py")
cat > "$root/init" <<INIT
#!/bin/busybox sh
/bin/busybox --install -s /bin
mount -t proc proc /proc; mount -t sysfs sys /sys; mount -t devtmpfs dev /dev
for m in can can-raw can-dev vcan; do insmod /lib/modules/\$m.ko* || echo "VCAN-FAIL insmod \$m"; done
ip link add dev vcan0 type vcan && ip link set vcan0 mtu 72 && ip link set up vcan0
export UAVCAN__NODE__ID=10 UAVCAN__PUB__READINESS__ID=10 UAVCAN__PUB__SP_RAT__ID=24 UAVCAN__SUB__FB_DYN__ID=110
for mtu in 8 64; do
  candump -L vcan0 > /tmp/dump\$mtu.log & dump=\$!
  ( sleep 1; cansend vcan0 $inject ) &
  UAVCAN__CAN__MTU=\$mtu propid drive --iface socketcan:vcan0 --init-duration 0.5 --pattern-duration 1.5 --deadman 5 --soft-start-duration 0 --speed-watchdog 0 --progress false -o /tmp/run\$mtu.tsv 2>/tmp/drive\$mtu.err
  echo "VCAN-DRIVE-EXIT mtu=\$mtu status=\$?"
  sleep 0.2; kill \$dump
  echo "VCAN-CANDUMP mtu=\$mtu frames=\$(wc -l < /tmp/dump\$mtu.log)"
  grep -m 3 ' 0C600A0A#' /tmp/dump\$mtu.log | sed 's/^/VCAN-READINESS mtu='\$mtu' /'
  grep -m 2 ' 0C60180A#\| 0C60180A##' /tmp/dump\$mtu.log | sed 's/^/VCAN-SETPOINT mtu='\$mtu' /'
  grep -m 1 ' 107D550A#' /tmp/dump\$mtu.log | sed 's/^/VCAN-HEARTBEAT mtu='\$mtu' /'
  grep '12345' /tmp/run\$mtu.tsv | sed 's/^/VCAN-ROW mtu='\$mtu' /'
  tail -n 2 /tmp/drive\$mtu.err | sed 's/^/VCAN-LOG /'
done
echo VCAN-DONE
poweroff -f
INIT
chmod +x "$root/init"
(cd "$root" && find . | cpio -o -H newc --quiet | gzip -1) > "$work/initrd.gz"
timeout 300 qemu-system-x86_64 -accel tcg -m 512 -kernel "$kernel" -initrd "$work/initrd.gz" \
  -append "console=ttyS0 panic=-1 quiet" -nographic -no-reboot > "$work/console.log" 2>&1 || true
# -o: a marker line can follow console noise on the same line (kernel messages, the shell's echo).
tr -d '\r' < "$work/console.log" | grep -o 'VCAN-.*' | tee "$work/result.txt"
r=$work/result.txt
fail() { echo "vcan test FAILED: $*" >&2; exit 1; }
grep -q VCAN-DONE "$r" || fail "the VM did not finish (console: $(tail -n 20 "$work/console.log"))"
! grep -q VCAN-FAIL "$r" || fail "module loading"
# propid ran both times and completed its pattern (exit 0: STANDBY and zero confirmed sent).
for mtu in 8 64; do
  grep -q "VCAN-DRIVE-EXIT mtu=$mtu status=0$" "$r" ||
    fail "propid drive (MTU $mtu) did not complete: $(grep "VCAN-DRIVE-EXIT mtu=$mtu\|VCAN-LOG" "$r")"
done
# propid's readiness: priority 3, subject 10, node 10, payload ENGAGED (03), single frame (tail E0|tid).
grep -Eq 'VCAN-READINESS mtu=8 .* 0C600A0A#03E[0-9A-F]$' "$r" || fail "no Classic readiness frame from propid"
grep -Eq 'VCAN-READINESS mtu=64 .* 0C600A0A#03E[0-9A-F]$' "$r" || fail "no readiness frame from propid (FD run)"
# The 62-byte setpoint: Classic = multi-frame (8 bytes, first frame's tail A0|tid); FD = one 64-byte frame.
grep -Eq 'VCAN-SETPOINT mtu=8 .* 0C60180A#[0-9A-F]{14}A[0-9A-F]$' "$r" || fail "no Classic multi-frame setpoint"
grep -Eq 'VCAN-SETPOINT mtu=64 .* 0C60180A##[0-9][0-9A-F]{128}$' "$r" || fail "no 64-byte FD setpoint"
grep -q 'VCAN-HEARTBEAT mtu=8' "$r" || fail "no heartbeat from propid"
# cansend's DoF3rdTs reached propid: t = 1 s, force 0.5, velocity 12345, acceleration 1, position 2.
grep -Eq 'VCAN-ROW mtu=64 .*	1	0.5	12345	1	2$' "$r" || fail "the injected DoF3rdTs did not reach propid (FD)"
echo "vcan test passed: propid's frames seen by candump (Classic and FD), cansend's frame decoded by propid"
