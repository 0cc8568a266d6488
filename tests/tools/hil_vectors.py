#!/usr/bin/env python3
"""docs/hil.md §5's test vectors from the document's layouts alone (an independent check of
protocol::hil): COBS over [kind][body][crc32c LE], then 0x00 (COBS and CRC-32C from
wire.py, the station link's own)."""
import struct

from wire import cobs, crc32c


def frame(raw: bytes) -> bytes:
    return cobs(raw + struct.pack("<I", crc32c(raw))) + b"\x00"


def show(name: str, raw: bytes) -> None:
    print(f"{name}: {' '.join(f'{b:02x}' for b in frame(raw))}")


assert crc32c(b"123456789") == 0xE3069283
# PowerOn: version 1, profile micro-rato (1).
show("power_on", bytes([1, 1, 1]))
# Motors: seq 7, left 60, right -60, arm 0, open.
show("motors", bytes([4]) + struct.pack("<IhhBB", 7, 60, -60, 0, 0))
# Sensors: seq 7 at 0.35 s; compass 1.5 rad and beacon (-0.25 rad, 200) present; IR 1..6;
# battery 9600 mV; no encoders.
flags = 0x01 | 0x08
show("sensors", bytes([3]) + struct.pack("<IQH", 7, 350_000, flags)
     + struct.pack("<8H", 1, 2, 3, 4, 5, 6, 0, 0) + struct.pack("<8H", *[0] * 8)
     + struct.pack("<ffBHii", 1.5, -0.25, 200, 9600, 0, 0))
