#!/usr/bin/env python3
"""Prints a cansend argument carrying one DoF3rdTs (zubax.physics.dynamics.DoF3rdTs.1.0) as a single
CAN FD frame from node 77 on subject 110 at priority 3: timestamp 1 s, position 2, velocity 12345,
acceleration 1, force 0.5. Built by hand from the DSDL layout (uint53 + void3, four float32,
little-endian) so that it is independent of propid's own encoder."""
import struct

us = 1_000_000
payload = (us & ((1 << 53) - 1)).to_bytes(7, "little") + struct.pack("<4f", 2.0, 12345.0, 1.0, 0.5)
assert len(payload) == 23
tail = 0xE0  # start, end, toggle 1, transfer-ID 0
can_id = (3 << 26) | (3 << 21) | (110 << 8) | 77
print(f"{can_id:08X}##0{(payload + bytes([tail])).hex().upper()}")
