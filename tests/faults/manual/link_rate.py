#!/usr/bin/env python3
"""Measures the throughput of a TCP stream over a shaped link (manual check
of deploy/netns-link; not part of ctest). Needs root for the namespace.

  link_rate.py receive BIND_ADDR PORT      count bytes of one connection, print JSON
  link_rate.py send ADDR PORT SECONDS      send as fast as possible for SECONDS

The receiver reports the rate from its first to its last byte, and the rate
over the stream minus its first `burst_window` second (tbf lets one bucket
of bytes through at once, so the steady rate is what the shaping enforces).
"""
import json
import socket
import sys
import time

CHUNK = 64 * 1024


def receive(bind_addr, port):
    server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    server.bind((bind_addr, port))
    server.listen(1)
    server.settimeout(30.0)
    conn, _ = server.accept()
    conn.settimeout(30.0)
    total = 0
    first = last = None
    after_first_second = 0
    while True:
        data = conn.recv(CHUNK)
        if not data:
            break
        now = time.monotonic()
        if first is None:
            first = now
        elif now - first >= 1.0:
            after_first_second += len(data)
        last = now
        total += len(data)
    seconds = (last - first) if first is not None else 0.0
    result = {
        "bytes": total,
        "seconds": round(seconds, 3),
        "rate_bit_s": round(8 * total / seconds) if seconds > 0 else None,
        "steady_rate_bit_s": round(8 * after_first_second / (seconds - 1.0)) if seconds > 1.5 else None,
    }
    print(json.dumps(result), flush=True)


def send(addr, port, seconds):
    payload = b"\x5a" * CHUNK
    deadline = time.monotonic() + seconds
    with socket.create_connection((addr, port), timeout=10.0) as conn:
        sent = 0
        while time.monotonic() < deadline:
            sent += conn.send(payload)
    print(json.dumps({"sent_bytes": sent, "seconds": seconds}), flush=True)


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "receive":
        receive(sys.argv[2], int(sys.argv[3]))
    elif len(sys.argv) == 5 and sys.argv[1] == "send":
        send(sys.argv[2], int(sys.argv[3]), float(sys.argv[4]))
    else:
        sys.exit(__doc__)
