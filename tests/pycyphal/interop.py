#!/usr/bin/env python3
"""The PyCyphal side of the interop test: PyCyphal 1.27.1 over python-can's slcan interface on one end
of a pseudo-terminal pair; `propid drive` on the other.

PyCyphal (node 20) publishes DoF3rdTs on subject 110 at 100 Hz with known values (velocity = k,
force = k/1000, timestamp = k·10 ms) and a Heartbeat; it subscribes to Readiness (subject 10) and
Vector31 (subject 24) and prints what it received as JSON at the end (with the wall time, time.time(),
of each reception, and its transfer-ID), with the values it sent (and the wall time of each
publication), and the reassembly errors PyCyphal counted on the two subscriptions (a transfer
discarded as a repeat counts one UNEXPECTED_TRANSFER_ID per frame).

usage: interop.py COMPILED_DIR IFACE SECONDS
"""
import asyncio
import json
import sys
import time

sys.path.insert(0, sys.argv[1])
import pycyphal  # noqa: E402
import pycyphal.presentation  # noqa: E402
from pycyphal.transport.can import CANTransport  # noqa: E402
from pycyphal.transport.can.media.pythoncan import PythonCANMedia  # noqa: E402
import uavcan.node  # noqa: E402
import zubax.physics.dynamics  # noqa: E402
import zubax.primitive.real16  # noqa: E402
import zubax.service  # noqa: E402
import zubax  # noqa: E402


async def main() -> None:
    iface, seconds = sys.argv[2], float(sys.argv[3])
    media = PythonCANMedia(iface, 1_000_000, 8)
    pres = pycyphal.presentation.Presentation(CANTransport(media, 20))
    pub_fb = pres.make_publisher(zubax.physics.dynamics.DoF3rdTs_1, 110)
    pub_hb = pres.make_publisher(uavcan.node.Heartbeat_1, 7509)
    sub_ready = pres.make_subscriber(zubax.service.Readiness_1, 10)
    sub_sp = pres.make_subscriber(zubax.primitive.real16.Vector31_1, 24)
    readiness, setpoints, readiness_t, setpoints_t = [], [], [], []
    readiness_tid, setpoints_tid = [], []

    async def on_ready(msg, meta):
        readiness.append(int(msg.value))
        readiness_t.append(time.time())
        readiness_tid.append(meta.transfer_id)

    async def on_sp(msg, meta):
        setpoints.append([float(x) for x in msg.value])
        setpoints_t.append(time.time())
        setpoints_tid.append(meta.transfer_id)

    sub_ready.receive_in_background(on_ready)
    sub_sp.receive_in_background(on_sp)
    print("ready", file=sys.stderr, flush=True)
    sent = []
    loop = asyncio.get_event_loop()
    end = loop.time() + seconds
    k = 0
    while loop.time() < end:
        k += 1
        fb = zubax.physics.dynamics.DoF3rdTs_1(
            timestamp=zubax.Timestamp_1(microsecond=k * 10_000),
            value=zubax.physics.dynamics.DoF3rd_1(
                kinematics=zubax.physics.kinematics.DoF3rd_1(
                    base=zubax.physics.kinematics.DoF2nd_1(position=0.25, velocity=float(k)),
                    acceleration=float(-k),
                ),
                force=k / 1000.0,
            ),
        )
        await pub_fb.publish(fb)
        sent.append(
            {"t": k * 0.01, "velocity": float(k), "acceleration": float(-k), "force": k / 1000.0, "wall": time.time()}
        )
        if k % 100 == 1:
            await pub_hb.publish(uavcan.node.Heartbeat_1(uptime=k // 100))
        await asyncio.sleep(0.01)
    await asyncio.sleep(1.0)

    def reassembly_errors(sub):
        counters = sub.sample_statistics().transport_session.reception_error_counters
        return {k.name: v for k, v in counters.items()}

    errors = {"setpoints": reassembly_errors(sub_sp), "readiness": reassembly_errors(sub_ready)}
    pres.close()
    print(
        json.dumps(
            {
                "sent": sent,
                "readiness": readiness,
                "setpoints": setpoints,
                "readiness_t": readiness_t,
                "setpoints_t": setpoints_t,
                "readiness_tid": readiness_tid,
                "setpoints_tid": setpoints_tid,
                "reassembly_errors": errors,
            }
        )
    )


asyncio.run(main())
