#!/usr/bin/env python3
"""A minimal client on the robot's serial port: the round trip of a Stop command.

Issue 15's row "a minimal client on the pty": the floor that the station's own code adds to.
It handshakes (the Hello of PROTOCOL.md §10's vector, read from protocol/PROTOCOL.md, so its
fingerprint is this build's), sets the telemetry rate, then sends Stop commands at
random moments (not synchronised with the robot's telemetry, as a teleop key is) and times each
from the write to the Ack's delimiter. Prints p50 / p99 / max in ms, and with --json one line.
It forgets the frames received during each pause before writing, and checks only the frames it
awaits: decoding telemetry in Python while the answer came made up to 0.5 ms of the 50 Hz p50.

    min_client_rtt.py PORT [--hz 50] [--n 200] [--gap-ms 20-60] [--json]

Standard library only. Exit 1 when the robot does not answer.
"""

import argparse
import json
import os
import random
import select
import sys
import termios
import time
import tty

from wire import cobs as cobs_raw, crc32c, uncobs, varint

def hello_wire():
    """The wire bytes of PROTOCOL.md §10's `hello` vector, read from the document beside this
    repository's protocol crate, so the fingerprint is always this build's (a fixed copy goes
    stale, and the robot refuses it, whenever the message set changes)."""
    doc = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "protocol", "PROTOCOL.md")
    with open(doc, encoding="utf-8") as f:
        lines = f.read().splitlines()
    start = next(i for i, l in enumerate(lines) if l.startswith("vector `hello`:"))
    wire = next(l for l in lines[start:] if l.strip().startswith("wire:"))
    return bytes.fromhex(wire.split(":", 1)[1])


HELLO_WIRE = hello_wire()
# Frame kinds the client reads: HelloReply (1), Ack (5), Nack (6).
WANTED = (1, 5, 6)


def cobs(data):
    """A COBS frame with its delimiter."""
    return cobs_raw(data) + b"\x00"




def frame(kind, seq, payload):
    raw = bytes([1, kind, seq & 0xFF, seq >> 8]) + payload
    return cobs(raw + crc32c(raw).to_bytes(4, "little"))


class Port:
    def __init__(self, path):
        self.fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        tty.setraw(self.fd)
        self.buf = bytearray()

    def raw_frames(self, timeout, wanted=lambda raw: True):
        """Decoded frames `raw` (COBS removed, CRC not checked) for which `wanted(raw)`, with
        the time each delimiter was read, within `timeout` s; returns as soon as at least one
        is whole."""
        end = time.monotonic() + timeout
        got = []
        while not got:
            left = end - time.monotonic()
            if left <= 0:
                return got
            r, _, _ = select.select([self.fd], [], [], left)
            if not r:
                continue
            now = time.monotonic()
            try:
                self.buf += os.read(self.fd, 65536)
            except BlockingIOError:
                continue
            while b"\x00" in self.buf:
                i = self.buf.index(0)
                enc = bytes(self.buf[:i])
                del self.buf[: i + 1]
                raw = uncobs(enc) if enc else None
                if raw and wanted(raw):
                    got.append((raw, now))
        return got

    def frames(self, timeout):
        """Decoded frames (kind, seq, payload) read within `timeout` s, with the time each
        delimiter was read; returns as soon as at least one is whole."""
        # Only the kinds awaited (HelloReply, Ack, Nack) are checked: the CRC in Python
        # costs about 0.2 ms a telemetry frame, time an answer arriving meanwhile waits.
        ok = lambda raw: (len(raw) >= 8 and raw[1] in WANTED
                          and crc32c(raw[:-4]) == int.from_bytes(raw[-4:], "little"))
        return [(raw[1], raw[2] | raw[3] << 8, raw[4:-4], now)
                for raw, now in self.raw_frames(timeout, ok)]

    def drain(self):
        """Forgets the whole frames already received (the telemetry of the pause before a
        command): left for after the write, their decoding in Python (a CRC-32C a byte at a
        time, about 0.2 ms a telemetry frame) ran while the answer came, and was timed with it.
        The bytes of a frame still arriving are kept."""
        while True:
            try:
                got = os.read(self.fd, 4096)
            except BlockingIOError:
                break
            if not got:
                break
            self.buf += got
        if 0 in self.buf:
            del self.buf[: len(self.buf) - self.buf[::-1].index(0)]

    def write(self, b):
        os.write(self.fd, b)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("port")
    ap.add_argument("--hz", type=int, default=50)
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--gap-ms", default="20-60")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    lo, hi = (float(x) for x in a.gap_ms.split("-"))
    p = Port(a.port)
    seq = 0
    p.write(b"\x00" + HELLO_WIRE)
    seq += 1
    deadline = time.monotonic() + 3
    while time.monotonic() < deadline:
        if any(k == 1 for k, *_ in p.frames(0.5)):
            break
    else:
        print("no HelloReply", file=sys.stderr)
        return 1
    # SetTelemetryRate(hz): Command index 10.
    p.write(frame(4, seq, bytes([10, a.hz])))
    seq += 1
    time.sleep(0.3)
    p.frames(0.05)
    rtts = []
    lost = 0
    for _ in range(a.n):
        time.sleep(random.uniform(lo, hi) / 1000)
        me = seq
        seq += 1
        f = frame(4, me, bytes([2]))
        p.drain()
        t0 = time.monotonic()
        p.write(f)
        done = None
        end = t0 + 0.5
        while done is None and time.monotonic() < end:
            for kind, s, payload, t in p.frames(end - time.monotonic()):
                # Ack (5) / Nack (6): cmd_seq is the payload's first varint.
                if kind in (5, 6) and payload[: len(varint(me))] == varint(me):
                    done = t
        if done is None:
            lost += 1
        else:
            rtts.append((done - t0) * 1000)
    if not rtts:
        print("no Ack", file=sys.stderr)
        return 1
    rtts.sort()
    q = lambda f: rtts[min(len(rtts) - 1, int(f * len(rtts)))]
    out = {"n": len(rtts), "lost": lost, "p50_ms": q(0.5), "p99_ms": q(0.99), "max_ms": rtts[-1],
           "min_ms": rtts[0], "hz": a.hz, "deciles_ms": [round(q(i / 10), 2) for i in range(1, 10)]}
    if a.json:
        print(json.dumps(out))
    else:
        print("n {n} lost {lost}: min {min_ms:.2f} p50 {p50_ms:.2f} p99 {p99_ms:.2f} max {max_ms:.2f} ms; deciles {deciles_ms}".format(**out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
