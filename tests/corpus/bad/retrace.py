"""Writes retrace/: recordings whose hardware trace (PROTOCOL.md §6 kind 15, §17) is
malformed, for `station retrace` (MANIFEST.tsv rows). Needs nothing else:
    python3 retrace.py
"""
import json
import struct

from generate import frame, header, record, varint, write


def hal_trace(offset, data, dropped=0):
    return frame(15, 1, varint(offset) + varint(dropped) + varint(len(data)) + data)


# START: format 1, Khepera, seed 42, start (0.5, 0.5, 0), from power-up, emulated, beacon and
# bounds.
START = (bytes([1, 1, 0]) + struct.pack("<I", 42) + struct.pack("<3f", 0.5, 0.5, 0.0)
         + varint(0) + b"\x01" + struct.pack("<6f", 2.5, 2.5, 0.0, 0.0, 5.0, 5.0))
META = json.dumps({"created_unix_ms": 0, "writer": "retrace.py", "port": "corpus",
                   "baud": 115200}).encode()


def rec(*traces):
    body = record(0, 2, b"\x02corpus")
    for i, data in enumerate(traces):
        body += record(1000 * (i + 1), 0, data)
    return header(META) + body + record(10_000, 3, b"stopped")


if __name__ == "__main__":
    write("retrace/01-no-trace.rec", rec())
    write("retrace/02-no-start.rec", rec(hal_trace(0, b"\x03\x00\x07" + bytes(8))))
    # A pass whose entry has a tag the format lacks, after a good START and STEP.
    write("retrace/03-unknown-tag.rec", rec(hal_trace(0, START + b"\x03\x00\x63\x03\x00")))
    # A serial read claiming a gigabyte.
    write("retrace/04-huge-rx.rec", rec(hal_trace(0, START + b"\x03\x00\x05" + varint(1 << 30)
                                                     + b"\x03\x00")))
    good = rec(hal_trace(0, START + b"\x03\x00\x16\x00\x00\x03\x00"))
    write("retrace/05-torn-tail.rec", good[:-3])
    # Issue 31 item 2: claims of work or robot time the recording does not bound. A control
    # cycle (a STEP with its IR reading) opens the trace, as the firmware's first pass does.
    cycle = b"\x03\x00\x07" + bytes(8)
    # One 8-byte IDLE entry claiming 2^32 - 1 passes 0 us apart (95 s of CPU before; `--until-ms`
    # did not stop it, the clock never moving).
    write("retrace/06-idle-passes.rec",
          rec(hal_trace(0, START + cycle + b"\x02" + varint(2**32 - 1) + varint(0) + b"\x03\x00")))
    # 1000 idle passes a second apart: 1000 s of robot time without a control cycle.
    write("retrace/07-idle-time.rec",
          rec(hal_trace(0, START + cycle + b"\x02" + varint(1000) + varint(10**6) + b"\x03\x00")))
    # Control cycles 10^12 us (11.6 days) apart in a recording spanning 10 ms.
    far = b"\x03" + varint(10**12) + b"\x07" + bytes(8)
    write("retrace/08-robot-time.rec",
          rec(hal_trace(0, START + cycle + far + far + b"\x03\x00")))
