#!/usr/bin/env python3
"""Map upload goodput on the real path: the real binaries over a real pseudo-terminal.

For each seed: `robot-emulator --seed S --drop-rate P --link PTY` (the emulator's UART at
115200 baud, its fault injector dropping P of the bytes both ways), then `station upload-map
--port PTY --map M --cell 0.078 --json` of a 64 x 64 map (a 1,060-byte Map object, distinct per
seed), as a user runs it: the upload starts as soon as the handshake completes. Goodput is
the object's bytes over the upload's time (`elapsed_ms`, the station's own clock), as a share
of the line rate (11,520 B/s). Prints one line per upload and the median, p10 and slowest;
`--json` prints the report as JSON.

The simulated counterpart (same code, simulated clocks, no machine load) is
`cargo bench -p station --bench transfer_goodput -- --json`, condition `drop_1pct_at_connect`.
Wall-clock figures depend on the machine: run it on a quiet one.

Usage: upload_goodput_pty.py [--drop-rate P] [--seeds N] [--bin DIR] [--json]
"""

import argparse
import json
import os
import random
import statistics
import subprocess
import sys
import tempfile
import time

LINE_RATE = 115200 / 10  # bytes a second, 8N1


def map_file(path, seed):
    """A 64 x 64 ASCII grid of mixed cells (0.078 m cells: a 1,060-byte Map object)."""
    r = random.Random(seed)
    rows = ["# cell 0.078", f"# name upload-{seed}"]
    for y in range(64):
        row = [r.choice("#.?") for _ in range(64)]
        if y == 32:
            row[0] = "S"
        if y == 40:
            row[50] = "G"
        rows.append("".join(row))
    with open(path, "w") as f:
        f.write("\n".join(rows) + "\n")


def upload(bin_dir, work, seed, drop):
    link = os.path.join(work, f"robot{seed}")
    emu = subprocess.Popen(
        [os.path.join(bin_dir, "robot-emulator"), "--link", link, "--seed", str(seed),
         "--drop-rate", str(drop)],
        stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        for _ in range(200):
            if os.path.exists(link):
                break
            time.sleep(0.02)
        m = os.path.join(work, f"map{seed}.txt")
        map_file(m, seed)
        out = subprocess.run(
            [os.path.join(bin_dir, "station"), "upload-map", "--port", link, "--map", m,
             "--cell", "0.078", "--json", "--timeout", "20"],
            capture_output=True, text=True, timeout=120)
        try:
            report = json.loads(out.stdout)
        except json.JSONDecodeError:
            return {"seed": seed, "ok": False, "error": out.stderr.strip()}
    finally:
        emu.terminate()
        emu.wait()
    ms = report.get("elapsed_ms") or 0
    ok = bool(report.get("ok")) and ms > 0
    return {
        "seed": seed,
        "ok": ok,
        "bytes": report.get("bytes"),
        "elapsed_ms": ms,
        "goodput_pct": report["bytes"] / (ms / 1000) / LINE_RATE * 100 if ok else 0.0,
        "sender": report.get("sender"),
    }


def nearest_rank(sorted_values, q):
    i = max(0, min(len(sorted_values) - 1, round((len(sorted_values) - 1) * q)))
    return sorted_values[i]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--drop-rate", type=float, default=0.01)
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--bin", default=os.path.join(os.path.dirname(__file__), "../../target/release"))
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    for b in ("station", "robot-emulator"):
        if not os.path.exists(os.path.join(a.bin, b)):
            sys.exit(f"error: {a.bin}/{b} not found: cargo build --release -p station -p emulator")
    with tempfile.TemporaryDirectory(prefix="upload-goodput-") as work:
        runs = [upload(a.bin, work, s, a.drop_rate) for s in range(1, a.seeds + 1)]
    pct = sorted(r["goodput_pct"] for r in runs)
    report = {
        "drop_rate": a.drop_rate,
        "seeds": a.seeds,
        "completed": sum(r["ok"] for r in runs),
        "goodput_pct_of_line_rate": {
            "median": statistics.median(pct),
            "p10": nearest_rank(pct, 0.1),
            "min": pct[0],
        },
        "load_average": os.getloadavg()[0],
        "runs": runs,
    }
    if a.json:
        print(json.dumps(report, indent=2))
        return
    for r in runs:
        s = r.get("sender") or {}
        print(f"seed {r['seed']:3}: {r['elapsed_ms']:5} ms  {r['goodput_pct']:5.1f} %  "
              f"chunks {s.get('chunks')} resent {s.get('resent')} timeouts {s.get('timeouts')} "
              f"first chunk {s.get('first_chunk')}")
    g = report["goodput_pct_of_line_rate"]
    print(f"{report['completed']}/{a.seeds} complete; goodput % of the line rate: median "
          f"{g['median']:.1f}, p10 {g['p10']:.1f}, slowest {g['min']:.1f} "
          f"(load average {report['load_average']:.1f})")


if __name__ == "__main__":
    main()
