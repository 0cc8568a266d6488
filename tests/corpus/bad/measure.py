#!/usr/bin/env python3
"""Time and peak memory of every bad-input case (docs/reliability.md).

    cargo build --release -p station -p emulator
    python3 tests/corpus/bad/measure.py [--bin-dir target/release] [--scale N] [--json]

Runs each MANIFEST.tsv case as tests/tests/bad_inputs.rs does (a fresh copy of this folder,
the large cases from `generate.py big DIR SCALE`), but only measures: wall time, the child's
peak resident set (ru_maxrss from wait4) and the bytes of the files it added (an `out:N`
case's bounded output; 0 for a refusal). The test checks the messages; this reports how long
a refusal takes and how much memory it holds, which a test must not assert.
"""
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", "..", ".."))
TIMEOUT_S = 30.0


def cases():
    out = []
    with open(os.path.join(HERE, "MANIFEST.tsv"), encoding="utf-8") as f:
        for n, line in enumerate(f, 1):
            line = line.rstrip("\n")
            if not line.strip() or line.startswith("#"):
                continue
            binary, args = line.split("\t")[:2]
            out.append((n, binary, args.split(" ")))
    return out


def files(top):
    """Every file under `top` and its length."""
    out = {}
    for d, _, names in os.walk(top):
        for n in names:
            p = os.path.join(d, n)
            out[p] = os.path.getsize(p)
    return out


def run(binary, args, cwd):
    """(wall seconds, peak RSS bytes, exit status or None when killed at the timeout)."""
    start = time.monotonic()
    child = subprocess.Popen(
        [binary, *args],
        cwd=cwd,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    killed = False
    while True:
        pid, status, usage = os.wait4(child.pid, os.WNOHANG)
        if pid:
            break
        if time.monotonic() - start > TIMEOUT_S:
            os.kill(child.pid, signal.SIGKILL)
            killed = True
            pid, status, usage = os.wait4(child.pid, 0)
            break
        time.sleep(0.002)
    wall = time.monotonic() - start
    code = None if killed else os.waitstatus_to_exitcode(status)
    return wall, usage.ru_maxrss * 1024, code


def main():
    argv = sys.argv[1:]
    as_json = "--json" in argv
    bin_dir = os.path.join(ROOT, "target", "release")
    scale = "1"
    if "--bin-dir" in argv:
        bin_dir = os.path.abspath(argv[argv.index("--bin-dir") + 1])
    if "--scale" in argv:
        scale = argv[argv.index("--scale") + 1]
    with tempfile.TemporaryDirectory(prefix="bad-measure-") as tmp:
        big = os.path.join(tmp, "big")
        subprocess.run(
            [sys.executable, os.path.join(HERE, "generate.py"), "big", big, scale], check=True
        )
        rows = []
        for line, binary, args in cases():
            work = os.path.join(tmp, "work")
            shutil.rmtree(work, ignore_errors=True)
            shutil.copytree(HERE, work)
            if any(a.startswith("generated/") for a in args):
                shutil.copytree(os.path.join(big, "generated"), os.path.join(work, "generated"))
            before = files(work)
            wall, rss, code = run(os.path.join(bin_dir, binary), args, work)
            added = sum(n for p, n in files(work).items() if before.get(p) != n)
            rows.append(
                {"line": line, "binary": binary, "args": " ".join(args), "wall_s": round(wall, 4),
                 "max_rss_bytes": rss, "exit": code, "output_bytes": added}
            )
    walls = sorted(r["wall_s"] for r in rows)
    slowest = max(rows, key=lambda r: r["wall_s"])
    biggest = max(rows, key=lambda r: r["max_rss_bytes"])
    summary = {
        "cases": len(rows),
        "timed_out": sum(1 for r in rows if r["exit"] is None),
        "median_wall_s": walls[len(walls) // 2],
        "max_wall_s": slowest["wall_s"],
        "slowest": f"MANIFEST.tsv:{slowest['line']}: {slowest['binary']} {slowest['args']}",
        "max_rss_mb": round(biggest["max_rss_bytes"] / 1e6, 1),
        "biggest": f"MANIFEST.tsv:{biggest['line']}: {biggest['binary']} {biggest['args']}",
        "max_output_bytes": max(r["output_bytes"] for r in rows),
    }
    if as_json:
        print(json.dumps({"summary": summary, "cases": rows}, indent=1))
    else:
        for k, v in summary.items():
            print(f"{k}: {v}")


if __name__ == "__main__":
    main()
