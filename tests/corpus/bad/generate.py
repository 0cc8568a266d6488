#!/usr/bin/env python3
"""Regenerates the synthetic files of the bad-input corpus (maps/, plans/, recordings/).

Run from this directory with a good recording and a good Plan object at hand:
    station record --out /tmp/good.rec --seconds 2
    station plan --map builtin:micro-rato-99 --out-object /tmp/good.plan
    python3 generate.py /tmp/good.rec /tmp/good.plan
The good recording must be of format version 1 (the station writes version 2 since issue 17):
station/tests/data/recording-v1.rec is the one the committed files were made from.
Arena files (arenas/) are copies of emulator/tests/data/bad. MANIFEST.tsv says how each file
is used and what the error must say; keep the two in step.

`python3 generate.py small` writes the cases that need no good file (recordings/18-...).

The large hostile arenas (hundreds of KB each: deep nesting, tens of thousands of unknown keys,
huge values) are not committed: `python3 generate.py big DIR` writes them into DIR/generated/,
and tests/tests/bad_inputs.rs does that itself before running the cases that name them.
"""
import os
import json
import struct
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools"))
from wire import cobs, crc32c, varint  # noqa: E402  (one CRC and varint for every script: tests/tools/wire.py)


def write(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data)


def map_object(w=4, h=4, cell=300, flags=0, reserved=0, version=1, kind=0, cells=None,
               start=(0, 0), goal=(0, 0)):
    head = bytes([version, kind, flags, reserved]) + struct.pack("<HHIii", w, h, cell, 0, 0)
    head += struct.pack("<ii", *start) + struct.pack("<ii", *goal)
    if cells is None:
        cells = bytes([0x55]) * ((w * h + 3) // 4)
    return head + cells


def maps():
    write("maps/01-empty.obj", b"")
    write("maps/02-truncated-header.obj", map_object()[:20])
    write("maps/03-truncated-cells.obj", map_object(w=8, h=8)[:-3])
    write("maps/04-trailing-bytes.obj", map_object() + b"\0\0")
    write("maps/05-version-9.obj", map_object(version=9))
    write("maps/06-unknown-kind.obj", map_object(kind=7))
    write("maps/07-reserved-flag.obj", map_object(flags=0x80))
    write("maps/08-reserved-byte.obj", map_object(reserved=1))
    write("maps/09-zero-width.obj", map_object(w=0))
    write("maps/10-too-tall.obj", map_object(h=5000, cells=b""))
    write("maps/11-zero-cell.obj", map_object(cell=0))
    write("maps/12-absent-start-not-zero.obj", map_object(start=(5, 0)))
    write("maps/13-reserved-cell-code.obj", map_object(cells=bytes([0x55, 0x55, 0xFF, 0x55])))
    write("maps/14-padding-not-zero.obj", map_object(w=3, h=1, cells=bytes([0xD5])))


def plans(good):
    write("plans/01-truncated.obj", good[: len(good) // 2])
    write("plans/02-trailing-bytes.obj", good + b"\0")
    write("plans/03-version-2.obj", b"\x02" + good[1:])
    write("plans/04-a-map-object.obj", map_object())
    write("plans/05-reserved-flags.obj", good[:2] + b"\x80" + good[3:])
    write("plans/06-empty.obj", b"")
    write("plans/07-reserved-byte.obj", good[:3] + b"\x01" + good[4:])


def split_recording(rec):
    meta_len = struct.unpack_from("<I", rec, 12)[0]
    header_end = 16 + meta_len + 4
    return rec[:header_end], rec[header_end:], meta_len


def record(t_us, kind, data):
    body = varint(t_us) + bytes([kind]) + varint(len(data)) + data
    return body + struct.pack("<I", crc32c(body))


def record2(t_us, kind, link, data):
    """A record of format version 2: the link id follows the kind."""
    body = varint(t_us) + bytes([kind, link]) + varint(len(data)) + data
    return body + struct.pack("<I", crc32c(body))


def frame(kind, seq, payload):
    """A link frame (PROTOCOL.md §2-§4): version 1, kind, seq, the payload, CRC-32C; COBS with
    its delimiter."""
    raw = bytes([1, kind]) + struct.pack("<H", seq) + payload
    return cobs(raw + struct.pack("<I", crc32c(raw))) + b"\x00"


def zigzag(n):
    return varint((n << 1) ^ (n >> 63) if n < 0 else n << 1)


def header(meta, version=1):
    fixed = b"\x89STREC\r\n" + struct.pack("<HHI", version, 0, len(meta)) + meta
    return fixed + struct.pack("<I", crc32c(fixed))


def recordings(good):
    head, body, meta_len = split_recording(good)
    meta = head[16:16 + meta_len]
    first = record(0, 2, b"\x01sim")
    write("recordings/01-empty.rec", b"")
    write("recordings/02-text-file.rec", b"time,x,y\n0,1,2\n")
    write("recordings/03-bad-magic.rec", b"\x89STREX\r\n" + good[8:])
    write("recordings/04-version-3.rec", header(meta, version=3) + body)
    write("recordings/05-header-crc.rec", head[:-1] + bytes([head[-1] ^ 1]) + body)
    write("recordings/06-meta-too-long.rec",
          b"\x89STREC\r\n" + struct.pack("<HHI", 1, 0, 1 << 20) + b"{}")
    write("recordings/07-meta-not-json.rec", header(b"not json at all") + first)
    write("recordings/08-torn-tail.rec", good[:-5])
    flipped = bytearray(good)
    flipped[len(head) + 40] ^= 0x10
    write("recordings/09-flipped-bit.rec", bytes(flipped))
    write("recordings/10-time-goes-back.rec",
          header(meta) + record(5000, 0, b"\x00") + record(4000, 0, b"\x00"))
    write("recordings/11-after-end.rec",
          header(meta) + record(0, 3, b"stopped") + record(10, 0, b"\x00"))
    write("recordings/12-huge-record.rec", header(meta) + varint(0) + b"\x00" + varint(1 << 30))
    write("recordings/13-header-only-truncated.rec", good[:10])
    # A last record at 2^64 - 1 us: the summary once stepped through it a second at a time.
    write("recordings/14-time-beyond-a-year.rec",
          header(meta) + first + record(2**64 - 1, 0, b"\x00"))
    # Format version 2 (several links): the good recording's records as link 0 of two.
    two = json.loads(meta)
    two["links"] = ["/tmp/robot1", "/tmp/robot2"]
    meta2 = json.dumps(two).encode()
    body2 = b""
    at = 0
    while at < len(body):
        rec, at = next_record(body, at)
        t_us, kind, data = rec
        body2 += record2(t_us, kind, 0, data)
    # A record naming link 5 of a file of two, after a good one.
    write("recordings/15-v2-bad-link-id.rec",
          header(meta2, version=2) + record2(0, 2, 1, b"\x01sim") + record2(10, 0, 5, b"\x00"))
    # A version 2 file torn inside a record (its length says more than follows).
    write("recordings/16-v2-torn-tail.rec", header(meta2, version=2) + body2[:-7])
    # A version 2 header that names no links.
    write("recordings/17-v2-no-links.rec", header(meta, version=2) + body2)


def next_record(body, at):
    """A version 1 record at `at`: (t_us, kind, data) and the offset after it."""
    def uvar(at):
        v, shift = 0, 0
        while True:
            b = body[at]
            v |= (b & 0x7F) << shift
            at += 1
            shift += 7
            if not b & 0x80:
                return v, at
    t_us, at = uvar(at)
    kind = body[at]
    n, at = uvar(at + 1)
    data = body[at:at + n]
    return (t_us, kind, data), at + n + 4


def light_bin(outputs=None, neurons=60, inputs=6):
    """A `station calibrate` binary light map: "LSOM", version, shape, hundredths, CRC-32C."""
    body = b"LSOM" + struct.pack("<HHH", 1, neurons, inputs)
    for i in range(neurons):
        body += struct.pack("<6H", *[5000 + 700 * k + 50 * i for k in range(inputs)])
        body += struct.pack("<H", outputs[i] if outputs else 300 * i)
    return body + struct.pack("<I", crc32c(body))


def light_json(outputs=None, rows=60):
    weights = [[50 + 7 * k + 0.5 * i for k in range(6)] for i in range(rows)]
    outs = outputs if outputs else [3.0 * i for i in range(rows)]
    return json.dumps({"format": "robot-station light-som", "version": 1, "neurons": 60,
                       "inputs": 6, "weights": weights, "outputs": outs}).encode()


def calibrations():
    good = light_bin()
    flipped = bytearray(good)
    flipped[100] ^= 0x04
    write("calibrations/01-flipped-bit.bin", bytes(flipped))
    write("calibrations/02-truncated.bin", good[:400])
    write("calibrations/03-output-past-180.bin", light_bin(outputs=[300 * i for i in range(59)] + [18100]))
    write("calibrations/04-59-rows.json", light_json(rows=59))
    write("calibrations/05-output-past-180.json", light_json(outputs=[3.0 * i for i in range(59)] + [181.0]))
    write("calibrations/06-syntax.json", light_json()[:-7] + b",,]}")


ROS_KEYS = "resolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"


def big(out, scale=1):
    """Hostile arenas whose cost grows with size: a quadratic importer takes minutes on them.
    `scale` multiplies the element counts (benchmarks use 5: 300,000 keys)."""
    g = os.path.join(out, "generated")
    pgm = b"P5 4 4 255\n" + bytes([254]) * 16
    write(os.path.join(g, "small.pgm"), pgm)
    # 100,000 nested flow sequences (200 KB).
    write(os.path.join(g, "yaml_nested.yaml"),
          ("image: small.pgm\n" + ROS_KEYS + "extra: " + "[ " * (100000 * scale) + "\n").encode())
    # 60,000 unknown top-level keys (660 KB).
    keys = "".join("k%06d: 1\n" % i for i in range(60000 * scale))
    write(os.path.join(g, "yaml_keys.yaml"), ("image: small.pgm\n" + ROS_KEYS + keys).encode())
    # An origin of a million elements (3 MB): the error must quote an excerpt, not the list.
    origin = "origin: [" + ", ".join(["0"] * 1000000) + "]\n"
    write(os.path.join(g, "yaml_long_origin.yaml"),
          ("image: small.pgm\nresolution: 0.05\n" + origin +
           "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n").encode())
    # 60,000 unknown keys, then a misspelt one: the error must come in bounded time.
    write(os.path.join(g, "yaml_keys_misspelt.yaml"),
          ("image: small.pgm\n" + ROS_KEYS + keys + "resolutin: 1\n").encode())
    # A 100 KB image name (echoed whole before).
    write(os.path.join(g, "yaml_long_image.yaml"),
          ("image: " + "x" * 100000 + ".pgm\n" + ROS_KEYS).encode())
    # A 128 x 128 maze: at the station's smallest cell (5 mm) more than its 2048 cells a side.
    m = 128
    rows = ["o" + "---o" * m]
    for r in range(m):
        rows.append("|" + "   |" * m)
        rows.append("o" + "---o" * m)
    write(os.path.join(g, "maze_128.txt"), ("\n".join(rows) + "\n").encode())
    # A 65 x 65 maze: one cell a side past the 64 x 64 the emulator's world takes.
    m = 65
    rows = ["o" + "---o" * m]
    for r in range(m):
        rows.append("|" + "   |" * m)
        rows.append("o" + "---o" * m)
    write(os.path.join(g, "maze_65.txt"), ("\n".join(rows) + "\n").encode())
    # A 640 x 640 checkerboard map (400 KB): every obstacle pixel its own wall, 204,800 of
    # them, past the 200,000 walls the emulator's world takes.
    n = 640
    board = bytes(0 if (i // n + i % n) % 2 == 0 else 255 for i in range(n * n))
    write(os.path.join(g, "checker.pgm"), b"P5 640 640 255\n" + board)
    write(os.path.join(g, "checker.yaml"),
          ("image: checker.pgm\n" + ROS_KEYS).encode())
    # An 8192 x 8192 map at 0.5 m (4 km a side): past the station's 2048-cell grid at any
    # --cell it accepts, so it must be refused from the PGM's header, before its 64 MiB of
    # pixels are read (the pixels are left out: a refusal must not need them).
    write(os.path.join(g, "huge_map.pgm"), b"P5 8192 8192 255\n")
    write(os.path.join(g, "huge_map.yaml"),
          b"image: huge_map.pgm\nresolution: 0.5\norigin: [0, 0, 0]\nnegate: 0\n"
          b"occupied_thresh: 0.65\nfree_thresh: 0.196\n")
    write(os.path.join(g, "random_situations.rec"), random_situations(2000 * scale))


def random_situations(n):
    """A recording of `n` ALICE situations (kind 16) with random light, whiskers and odometry,
    each a robot second after the last: every one grows the station's QT network, to its
    2,000-cell cap, and each is due a `/qt_model` snapshot of the whole network (issue 31:
    116 KB of them made a 277 MB MCAP). Deterministic (an LCG)."""
    state = 31

    def rand(bits):
        nonlocal state
        state = (state * 6364136223846793005 + 1442695040888963407) % (1 << 64)
        return state >> (64 - bits)

    meta = json.dumps({"created_unix_ms": 0, "writer": "generate.py", "port": "corpus",
                       "baud": 115200}).encode()
    body = record(0, 2, b"\x02corpus")
    for i in range(n):
        payload = (varint(1000 * (i + 1)) + varint(i % 65536) + varint(rand(24))
                   + bytes(rand(8) for _ in range(24))
                   + zigzag(rand(14) - 8192) + zigzag(rand(14) - 8192) + zigzag(rand(12) - 2048))
        body += record(1000 * (i + 1), 0, frame(16, i % 65536, payload))
    return header(meta) + body + record(1000 * (n + 1), 3, b"end")


def small():
    """Cases built from nothing: a recording whose header text holds what a terminal acts on
    (CSI as U+009B, ESC ] ... BEL, DEL, a bidirectional override), written raw as a careless
    writer would, and a torn tail so that `replay --json` prints its summary and fails (issue
    31: the summary's JSON copied U+009B to the terminal raw)."""
    text = "robot\u009b31m\u001b]0;owned\u0007\u007f\u202egnp"
    meta = json.dumps({"created_unix_ms": 0, "writer": text, "port": text, "baud": 115200,
                       "arena": text}, ensure_ascii=False).encode()
    body = record(0, 2, b"\x02" + text.encode()) + record(1000, 0, b"\x00")
    write("recordings/18-control-text.rec", header(meta) + body + record(2000, 3, b"end")[:-3])


if __name__ == "__main__":
    if sys.argv[1:2] == ["small"]:
        small()
        sys.exit(0)
    if sys.argv[1:2] == ["big"]:
        big(sys.argv[2], int(sys.argv[3]) if len(sys.argv) > 3 else 1)
        sys.exit(0)
    good_rec = open(sys.argv[1], "rb").read()
    good_plan = open(sys.argv[2], "rb").read()
    maps()
    plans(good_plan)
    recordings(good_rec)
    calibrations()
