#!/usr/bin/env python3
"""The station link under a 115200-baud flood, and a Stop within it (issue 35's measure).

Handshakes on PORT (the robot's station port: the board image's UART0 pty, or the emulator's),
switches to Manual and drives (Teleop at 20 Hz), and fills the line at 115200 baud (11520
bytes a second, paced by the clock) with harmless commands (GetParam) in between. Every
command must be answered: a command without an Ack or Nack is a frame lost on the way in.
After --stop-after seconds it sends a Stop (no more Teleop, the GetParam flood goes on) and
times the Stop's Ack and notes how many bytes it was queued behind in the port; the world's summary (robot-emulator hil --json, motor_stops_monotonic_s)
gives the moment the wheels stopped, on the same CLOCK_MONOTONIC as `stop_written_monotonic_s`.

    board_flood.py PORT [--seconds 6] [--stop-after 4] [--baud 115200] [--json]

Standard library only (and min_client_rtt.py beside it). Exit 1 when the robot does not answer.
"""

import argparse
import fcntl
import json
import struct
import sys
import termios
import time

from min_client_rtt import HELLO_WIRE, Port, frame
from wire import crc32c, read_varint, varint


def zigzag(n):
    return varint((n << 1) ^ (n >> 15))


def command(seq, payload):
    return frame(4, seq, payload)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("port")
    ap.add_argument("--seconds", type=float, default=6.0)
    ap.add_argument("--stop-after", type=float, default=4.0)
    ap.add_argument("--baud", type=int, default=115200)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    p = Port(a.port)
    p.write(b"\x00" + HELLO_WIRE)
    end = time.monotonic() + 3
    while time.monotonic() < end:
        if any(k == 1 for k, *_ in p.frames(0.5)):
            break
    else:
        print("no HelloReply", file=sys.stderr)
        return 1
    seq = 1
    answered = {}
    pending = {}

    def send(payload, what):
        nonlocal seq
        f = command(seq, payload)
        p.write(f)
        pending[seq] = (what, time.monotonic())
        seq = (seq + 1) & 0xFFFF
        return f, seq - 1

    def take(timeout):
        """Answers read within `timeout`, timed at their delimiter. Only the kind and cmd_seq
        are read (a CRC-32C in Python per Ack would make this script the bottleneck); the
        Stop's Ack alone is CRC-checked."""
        answer = lambda raw: len(raw) >= 9 and raw[1] in (5, 6)
        for raw, now in p.raw_frames(timeout, answer):
            cmd_seq, _ = read_varint(raw, 4)
            if cmd_seq not in pending:
                continue
            what, t0 = pending[cmd_seq]
            if what == "stop" and crc32c(raw[:-4]) != int.from_bytes(raw[-4:], "little"):
                continue
            del pending[cmd_seq]
            answered[cmd_seq] = (what, raw[1] == 5, now - t0, now)

    def queued():
        """Bytes written and not yet read from the port by the other side (TIOCOUTQ): what a
        command written now waits behind on the way in."""
        try:
            return struct.unpack("i", fcntl.ioctl(p.fd, termios.TIOCOUTQ, b"\0\0\0\0"))[0]
        except OSError:
            return None

    # Manual mode (SetMode index 0, Mode::Manual 1), then the flood.
    send(bytes([0, 1]), "mode")
    take(0.3)
    bytes_per_s = a.baud / 10
    t0 = time.monotonic()
    sent_bytes = 0
    next_teleop = t0
    stop_seq = stop_written = queued_before_stop = None
    get_param = bytes([5]) + varint(0)
    frames_sent = {"teleop": 0, "get_param": 0, "stop": 0}
    while True:
        now = time.monotonic()
        if now - t0 >= a.seconds:
            break
        budget = (now - t0) * bytes_per_s - sent_bytes
        while budget > 0:
            if stop_seq is None and now - t0 >= a.stop_after:
                queued_before_stop = queued()
                f, stop_seq = send(bytes([2]), "stop")
                stop_written = time.monotonic()
                frames_sent["stop"] += 1
            elif stop_seq is None and now >= next_teleop:
                f, _ = send(bytes([1]) + zigzag(150) + zigzag(0), "teleop")
                next_teleop += 0.05
                frames_sent["teleop"] += 1
            else:
                f, _ = send(get_param, "get_param")
                frames_sent["get_param"] += 1
            sent_bytes += len(f)
            budget -= len(f)
        take(0.001)
    # The last answers.
    end = time.monotonic() + 1.0
    while pending and time.monotonic() < end:
        take(0.05)
    elapsed = time.monotonic() - t0
    stop = answered.get(stop_seq) if stop_seq is not None else None
    out = {
        "baud": a.baud,
        "seconds": round(elapsed, 3),
        "bytes_sent": sent_bytes,
        "bytes_per_s": round(sent_bytes / elapsed, 1),
        "frames_sent": sum(frames_sent.values()),
        "by_kind": frames_sent,
        "answered": len(answered),
        "acked": sum(1 for v in answered.values() if v[1]),
        "nacked": sum(1 for v in answered.values() if not v[1]),
        "unanswered": len(pending),
        "stop_acked": bool(stop and stop[1]),
        "stop_ack_ms": round(stop[2] * 1000, 2) if stop else None,
        "stop_written_monotonic_s": stop_written,
        "bytes_queued_before_stop": queued_before_stop,
    }
    if a.json:
        print(json.dumps(out))
    else:
        print(json.dumps(out, indent=1))
    return 0 if out["answered"] else 1


if __name__ == "__main__":
    sys.exit(main())
