#!/usr/bin/env python3
"""Worst-case stack of the firmware's entry points, from the compiler's own numbers.

Reads a thumbv7em image built with -Zemit-stack-sizes: each function's frame from its
.stack_sizes section (llvm-readobj --stack-sizes) and the direct calls between functions from
its disassembly (bl/blx/b.w to a symbol, llvm-objdump -d). The worst case of a function is its
frame plus the worst of its callees. Limits, stated in the output: indirect calls (function
pointers, dyn) are not followed, and a cycle (recursion) is reported, not summed.
Usage: stack_report.py BIN_DIR IMAGE
"""
import re, subprocess, sys
from functools import lru_cache

bindir, image = sys.argv[1], sys.argv[2]
rs = subprocess.run([f"{bindir}/llvm-readobj", "--stack-sizes", image], capture_output=True, text=True).stdout
frames = {}
for fn, size in re.findall(r"Functions: \[([^\]]+)\]\s*Size: (0x[0-9a-f]+)", rs):
    for f in fn.split(", "):
        frames[f] = int(size, 16)
dis = subprocess.run([f"{bindir}/llvm-objdump", "-d", "--no-show-raw-insn", image], capture_output=True, text=True).stdout
calls, cur, indirect = {}, None, set()
for line in dis.splitlines():
    m = re.match(r"^[0-9a-f]+ <(.+)>:$", line)
    if m:
        cur = m.group(1); calls.setdefault(cur, set()); continue
    if cur is None:
        continue
    m = re.search(r"\s(bl|blx|b\.w|b)\s+0x[0-9a-f]+ <([^>+]+)(\+0x[0-9a-f]+)?>", line)
    if m and m.group(2) != cur:
        calls[cur].add(m.group(2))
    elif re.search(r"\sblx\s+r\d+", line):
        indirect.add(cur)
cycles = set()

memo, visiting = {}, set()

def worst(f):
    """(bytes, path) of the deepest chain from f; a call back into the chain is a cycle."""
    if f in memo:
        return memo[f]
    if f in visiting:
        cycles.add(f)
        return (0, ())
    visiting.add(f)
    best = (0, ())
    for c in calls.get(f, ()):
        w = worst(c)
        if w[0] > best[0]:
            best = w
    visiting.discard(f)
    memo[f] = (frames.get(f, 0) + best[0], (f,) + best[1])
    return memo[f]

def demangle(names):
    out = subprocess.run(["rustfilt"], input="\n".join(names), capture_output=True, text=True) if False else None
    return names

sys.setrecursionlimit(10000)
for label, pat in [("Robot::step", r"^size_probe_robot_step$"), ("link handler (Link::receive, handle inlined)", r"robot_firmware4linkNtB4_4Link7receive")]:
    roots = [f for f in calls if re.search(pat, f)]
    if not roots:
        print(f"{label}: not found in the image"); continue
    w = max((worst(r) for r in roots), key=lambda t: t[0])
    ind = sorted({f for f in w[1] if f in indirect})
    print(f"{label}: worst-case stack {w[0]} B over {len(w[1])} frames (deepest path below)")
    for f in w[1][:12]:
        print(f"    {frames.get(f, 0):6d} B  {f[:110]}")
    if ind:
        print(f"    note: {len(ind)} function(s) on that path make indirect calls, not followed")
if cycles:
    print(f"note: recursion through {len(cycles)} function(s) was cut, not summed")
