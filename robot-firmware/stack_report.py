#!/usr/bin/env python3
"""State and worst-case stack of each robot composition, from the compiler's own numbers.

Reads a thumbv7em image built with -Zemit-stack-sizes: each function's frame from its
.stack_sizes section (llvm-readobj --stack-sizes) and the direct calls between functions from
its disassembly (bl/blx/b.w to a symbol, llvm-objdump -d). The worst case of a function is its
frame plus the worst of its callees. The link handler is called through a function pointer
(`Link::receive` takes `&mut dyn FnMut(Inbound)`), which a disassembly does not show: the
report adds that one edge, from `Link::receive` to the composition's own handler closure
(`Robot<K>::receive::{closure}`, where `Core::handle` is inlined). Other indirect calls are not
followed, and a cycle (recursion) is reported, not summed; both are stated in the output.
With the type sizes (-Zprint-type-sizes output) it adds each composition's state
(`Robot<K>`) and prints state + worst stack against the 32 KB of the Dom Dinis board.
Usage: stack_report.py BIN_DIR IMAGE [TYPE_SIZES [--json] [--check]]
(--check: exit 1 when the Dom Dinis robot's state + worst stack is over 32 KB or unknown)
"""
import json, re, subprocess, sys

RAM = 32 * 1024
# (name in reports, mangled name of the kit type, the size probe's symbol suffix)
KITS = [
    ("dom-dinis", "8DomDinis", "dom_dinis"),
    ("khepera", "7Khepera", "khepera"),
    ("alice", "5Alice", "alice"),
]

bindir, image = sys.argv[1], sys.argv[2]
type_sizes = sys.argv[3] if len(sys.argv) > 3 else None
as_json = "--json" in sys.argv[4:]
check = "--check" in sys.argv[4:]

rs = subprocess.run([f"{bindir}/llvm-readobj", "--stack-sizes", image], capture_output=True, text=True).stdout
frames = {}
for fn, size in re.findall(r"Functions: \[([^\]]+)\]\s*Size: (0x[0-9a-fA-F]+)", rs):
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

LINK_RECEIVE = re.compile(r"robot_firmware4linkNtB\w+_4Link7receive$")
sys.setrecursionlimit(10000)


def walk(root, extra):
    """(bytes, path) of the deepest chain from root; `extra` adds callees to functions whose
    name matches a pattern (the dyn callback). A call back into the chain is a cycle."""
    memo, visiting, cycles = {}, set(), set()

    def worst(f):
        if f in memo:
            return memo[f]
        if f in visiting:
            cycles.add(f)
            return (0, ())
        visiting.add(f)
        best = (0, ())
        callees = set(calls.get(f, ()))
        for pat, targets in extra:
            if pat.search(f):
                callees |= set(targets)
        for c in callees:
            w = worst(c)
            if w[0] > best[0]:
                best = w
        visiting.discard(f)
        memo[f] = (frames.get(f, 0) + best[0], (f,) + best[1])
        return memo[f]

    return worst(root), cycles


def state_sizes():
    sizes = {}
    if not type_sizes:
        return sizes
    text = open(type_sizes).read()
    for name, kit, _ in KITS:
        m = re.search(r"type: `robot::Robot<robot::kit::" + kit[1:] + r">`: (\d+) bytes", text)
        if m:
            sizes[name] = int(m.group(1))
    return sizes


report, out = {}, []
states = state_sizes()
for name, kit, sym in KITS:
    handler = [f for f in calls if re.search(r"kit" + kit + r"E7receive.*E0Cs", f)]
    links = [f for f in calls if LINK_RECEIVE.search(f)]
    extra = [(LINK_RECEIVE, handler)]
    entry = {}
    for label, root, ex in [
        ("init", f"size_probe_init_{sym}", []),
        ("step", f"size_probe_step_{sym}", extra),
        ("link_handler", links[0] if links else None, extra),
    ]:
        if root not in calls:
            out.append(f"{name}: {label}: not found in the image")
            continue
        (total, path), cycles = walk(root, ex)
        ind = sorted({f for f in path if f in indirect and not LINK_RECEIVE.search(f)})
        entry[label] = total
        out.append(f"{name}: {label}: worst-case stack {total} B over {len(path)} frames (deepest path below)")
        for f in path[:12]:
            out.append(f"    {frames.get(f, 0):6d} B  {f[:110]}")
        if ind:
            out.append(f"    note: {len(ind)} function(s) on that path make other indirect calls, not followed")
        if cycles:
            out.append(f"    note: recursion through {len(cycles)} function(s) was cut, not summed")
    if name in states:
        stack = max(entry.get("step", 0), entry.get("link_handler", 0), entry.get("init", 0))
        entry["state"] = states[name]
        entry["total"] = states[name] + stack
        fits = "fits" if entry["total"] <= RAM else "does NOT fit"
        out.append(f"{name}: state {states[name]} B + worst stack {stack} B = {entry['total']} B "
                   f"({fits} {RAM} B)")
    report[name] = entry

if as_json:
    print(json.dumps(report, indent=1, sort_keys=True))
else:
    print("\n".join(out))
if check:
    total = report.get("dom-dinis", {}).get("total")
    if total is None or total > RAM:
        sys.exit(f"error: Dom Dinis state + worst stack is {total} B, over {RAM} B (or not measured)")
