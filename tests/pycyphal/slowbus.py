#!/usr/bin/env python3
"""A slow CAN bus between two SLCAN pseudo-terminals, for the congestion test.

The relay opens two pty pairs. Side A is for `propid drive`, side B for PyCyphal. What A writes
reaches B at the pace of a CAN bus of BITRATE bit/s: each SLCAN frame line is released once the
frame it carries would have crossed the bus (44 + 8·DLC bits for an 11-bit ID, 64 + 8·DLC for a
29-bit ID, plus 3 bits of interframe space; no bit stuffing counted, so the real bus is slower
still). Other lines (set-up commands, status polls) cost nothing. The relay holds at most one
line read ahead, so the backlog sits in the kernel's pty buffer, as it would in a USB adapter's:
once that is full, A's writes fail with EAGAIN. What B writes reaches A at once.

`--stall-at S --stall-for D`: S seconds after the first frame from A, the relay stops reading A
for D seconds (the kernel buffer fills; nothing reaches B), then resumes.

stdout, one JSON object per line, flushed: first {"a": PATH, "b": PATH}; then {"event": "first"},
{"event": "stall"}, {"event": "resume"} with the wall time "t" (time.time()); on SIGTERM or SIGINT
the totals ({"event": "end", ...}) and exit.

usage: slowbus.py BITRATE [--stall-at S --stall-for D]
"""
import argparse
import errno
import fcntl
import json
import os
import select
import signal
import sys
import time
import tty


def say(obj) -> None:
    print(json.dumps(obj), flush=True)


def pty_pair():
    master, slave = os.openpty()
    tty.setraw(master)
    tty.setraw(slave)
    fcntl.fcntl(master, fcntl.F_SETFL, fcntl.fcntl(master, fcntl.F_GETFL) | os.O_NONBLOCK)
    return master, slave, os.ttyname(slave)


def frame_bits(line: bytes) -> int:
    """Bits a frame line occupies on the bus (0 for anything that is not a frame)."""
    if not line:
        return 0
    kind, id_len, base = line[:1], 0, 0
    if kind in (b"T", b"R"):
        id_len, base = 8, 64
    elif kind in (b"t", b"r"):
        id_len, base = 3, 44
    else:
        return 0
    try:
        dlc = int(line[1 + id_len : 2 + id_len])
    except ValueError:
        return 0
    data = 0 if kind in (b"R", b"r") else 8 * min(dlc, 8)
    return base + data + 3


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("bitrate", type=float)
    p.add_argument("--stall-at", type=float, default=None)
    p.add_argument("--stall-for", type=float, default=0.0)
    args = p.parse_args()

    ma, _sa, path_a = pty_pair()  # the slave ends stay open here: a peer's close is not a hang-up
    mb, _sb, path_b = pty_pair()
    say({"a": path_a, "b": path_b})

    running = True

    def on_term(_sig, _frame):
        nonlocal running
        running = False

    signal.signal(signal.SIGTERM, on_term)
    signal.signal(signal.SIGINT, on_term)

    from_a = bytearray()  # read from A, not yet a whole line (at most one line ahead)
    ready = None  # (release time, line) of the frame on the bus now
    to_b = bytearray()
    to_a = bytearray()
    bus_free = time.monotonic()
    first = None
    stall_from = stall_to = None
    stalled_said = resumed_said = False
    totals = {"frames": 0, "other_lines": 0, "bytes_a_to_b": 0, "bytes_b_to_a": 0}

    while running:
        now = time.monotonic()
        stalled = stall_from is not None and stall_from <= now < stall_to
        if stall_from is not None and now >= stall_from and not stalled_said:
            stalled_said = True
            say({"event": "stall", "t": time.time()})
        if stall_to is not None and now >= stall_to and not resumed_said:
            resumed_said = True
            bus_free = max(bus_free, now)
            say({"event": "resume", "t": time.time()})

        # Release the frame on the bus once its time has come.
        if ready is not None and ready[0] <= now and not to_b:
            to_b += ready[1]
            totals["bytes_a_to_b"] += len(ready[1])
            ready = None
        # Take the next whole line (no more than one ahead of the bus).
        if ready is None and not stalled:
            cut = from_a.find(b"\r")
            if cut >= 0:
                line = bytes(from_a[: cut + 1])
                del from_a[: cut + 1]
                bits = frame_bits(line[:-1])
                if bits:
                    totals["frames"] += 1
                    if first is None:
                        first = now
                        say({"event": "first", "t": time.time()})
                        if args.stall_at is not None:
                            stall_from = first + args.stall_at
                            stall_to = stall_from + args.stall_for
                else:
                    totals["other_lines"] += 1
                bus_free = max(bus_free, now) + bits / args.bitrate
                ready = (bus_free, line)
                continue

        readers = [mb]
        if not stalled and ready is None and len(from_a) < 64:
            readers.append(ma)
        writers = ([mb] if to_b else []) + ([ma] if to_a else [])
        timeout = 0.05
        if ready is not None:
            timeout = max(0.0, min(timeout, ready[0] - now))
        if stall_from is not None and now < stall_from:
            timeout = min(timeout, stall_from - now)
        if stalled:
            timeout = min(timeout, stall_to - now)
        try:
            r, w, _ = select.select(readers, writers, [], timeout)
        except InterruptedError:
            continue
        for fd in r:
            try:
                if fd == ma:
                    data = os.read(ma, 64 - len(from_a))
                    from_a += data
                else:
                    data = os.read(mb, 4096)
                    to_a += data
                    totals["bytes_b_to_a"] += len(data)
            except OSError as e:
                if e.errno not in (errno.EAGAIN, errno.EIO):
                    raise
        for fd in w:
            buf = to_b if fd == mb else to_a
            try:
                n = os.write(fd, buf)
                del buf[:n]
            except OSError as e:
                if e.errno not in (errno.EAGAIN, errno.EIO):
                    raise

    totals["event"] = "end"
    totals["backlog_a"] = len(from_a)
    say(totals)


if __name__ == "__main__":
    main()
