#!/usr/bin/env python3
"""Every command round trip of a recording made in the TUI (`R`), and what was on the robot's
line while the slowest waited.

Issue 15's TUI round trip: the link view shows only p50 and p99 of the last 256; this reads
the recording's own bytes (the station's writes, and the robot's bytes as the station read
them, with the station's times) and prints, for the commands answered by an Ack: the count,
p50 / p90 / p99 / max from the write to the read of the Ack, and the share of round trips
during which a telemetry or truth frame arrived (the Ack queued behind the robot's burst).
While a command is in flight the station reads the port as bytes come, so those reads are
timely; a frame read within 0.3 ms of the write was already there (a paced read's backlog).

    tui_rtt_trace.py FILE.rec [--slowest 5]

Standard library only; expects a recording of one link, unsigned frames.
"""

import argparse
import json
import struct
import sys

from wire import read_varint, uncobs

KIND_NAMES = {3: "telemetry", 4: "command", 5: "ack", 6: "nack", 10: "event", 11: "log",
              12: "truth", 13: "localization", 14: "progress"}




class Cut(Exception):
    """The recording ends or goes wrong inside a record."""


def records(path, data):
    """(time µs, direction code, bytes) per record; exits naming the file and the byte offset
    where the recording stops making sense (a cut file, another format)."""
    def fail(at, what):
        sys.exit(f"{path}: byte {at}: {what}")

    if data[:8] != b"\x89STREC\r\n":
        fail(0, "not a station recording (no STREC magic)")
    if len(data) < 16:
        fail(len(data), "header cut short")
    version, = struct.unpack_from("<H", data, 8)
    if version not in (1, 2):
        fail(8, f"recording format {version}, this tool reads 1 and 2")
    meta_len, = struct.unpack_from("<I", data, 12)
    at = 16 + meta_len + 4
    if at > len(data):
        fail(16, f"metadata of {meta_len} B runs past the end ({len(data)} B)")
    while at < len(data):
        try:
            t_us, p = read_varint(data, at)
            if p >= len(data):
                raise Cut
            code = data[p]
            p += 2 if version >= 2 else 1
            n, p = read_varint(data, p)
            if p + n + 4 > len(data):
                raise Cut
        except (Cut, IndexError):
            fail(at, "record cut short (the recording ends inside it)")
        yield t_us, code, data[p:p + n]
        at = p + n + 4


def frames(chunks):
    """(time the delimiter was read or written, kind, seq, payload) per frame of a stream."""
    buf = bytearray()
    for t, data in chunks:
        for b in data:
            if b:
                buf.append(b)
                continue
            raw = uncobs(bytes(buf)) if buf else None
            buf.clear()
            if raw and len(raw) >= 8:
                yield t, raw[1], struct.unpack_from("<H", raw, 2)[0], raw[4:-4]


def pct(v, q):
    return v[min(len(v), max(1, -(-int(q * len(v) * 1000) // 1000))) - 1]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("file")
    ap.add_argument("--slowest", type=int, default=5)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    try:
        with open(a.file, "rb") as f:
            data = f.read()
    except OSError as e:
        sys.exit(f"{a.file}: {e.strerror}")
    recs = list(records(a.file, data))
    to_robot = list(frames((t, d) for t, c, d in recs if c == 1))
    from_robot = list(frames((t, d) for t, c, d in recs if c == 0))
    sent = {}
    for t, kind, seq, _ in to_robot:
        if kind == 4:
            sent.setdefault(seq, t)
    trips = []
    for i, (t, kind, _, payload) in enumerate(from_robot):
        if kind != 5:
            continue
        cmd_seq, _ = read_varint(payload, 0)
        w = sent.pop(cmd_seq, None)
        if w is None or t < w:
            continue
        between = [KIND_NAMES.get(k, str(k)) for (tf, k, _, _) in from_robot[:i]
                   if w + 300 < tf <= t and k in (3, 12)]
        trips.append((t - w, w, between))
    if not trips:
        sys.exit("no acknowledged command in the recording")
    rtts = sorted(r for r, _, _ in trips)
    behind = sum(1 for _, _, b in trips if b)
    out = {
        "commands": len(trips),
        "p50_ms": pct(rtts, 0.5) / 1000, "p90_ms": pct(rtts, 0.9) / 1000,
        "p99_ms": pct(rtts, 0.99) / 1000, "max_ms": rtts[-1] / 1000,
        "behind_a_burst": behind,
    }
    if a.json:
        print(json.dumps(out))
        return
    print(f"{out['commands']} commands acked: p50 {out['p50_ms']:.2f} ms, p90 "
          f"{out['p90_ms']:.2f} ms, p99 {out['p99_ms']:.2f} ms, max {out['max_ms']:.2f} ms; "
          f"{behind} ({100 * behind / len(trips):.1f} %) with a telemetry or truth frame "
          f"arriving during the round trip")
    for r, w, b in sorted(trips, reverse=True)[:a.slowest]:
        print(f"  {r / 1000:6.2f} ms, written at {w / 1e6:.3f} s; during it: {', '.join(b) or '-'}")


if __name__ == "__main__":
    main()
