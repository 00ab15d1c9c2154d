#!/usr/bin/env python3
"""The seed driver's publication loop (publish_until, verbatim logic) with a publisher that only
records when it is called. Prints one monotonic timestamp [s] per publication."""
import asyncio
import sys
import time

stamps = []


class RecordingPublisher:
    def publish_soon(self, msg):
        stamps.append(time.monotonic())


async def publish_until(publisher_message_pairs, deadline, publication_period):
    get_time = asyncio.get_event_loop().time
    next_pub_at = get_time()
    while (now := get_time()) < deadline:
        for pub, msg in publisher_message_pairs:
            if pub is not None:
                pub.publish_soon(msg(now) if callable(msg) else msg)
        next_pub_at += publication_period
        if (sleep_duration := next_pub_at - get_time()) > 0:
            await asyncio.sleep(sleep_duration)


async def main():
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 5.0
    get_time = asyncio.get_event_loop().time
    await publish_until([(RecordingPublisher(), "setpoint")], get_time() + seconds, 0.005)


asyncio.run(main())
print("\n".join(repr(s) for s in stamps))
