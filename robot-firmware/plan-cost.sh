#!/usr/bin/env bash
# Seed 004 §6's planning cost (the paper: under 5 s on a 68HC11) on a Cortex-M4 beside the
# host: the firmware's planner (robot-firmware/plan-cost, the robot's own Nav64 instance) built
# for thumbv7em-none-eabihf and run on QEMU's mps2-an386 board (Cortex-M4F) with
# `-icount shift=0`, which makes every instruction 1 ns of virtual time; the board's timer
# turns that into instruction counts (+-40). QEMU does not model cycles: a Cortex-M4 needs
# about 1.2-1.5 cycles an instruction on such code, so the counts are a lower bound on cycles.
# The host column is the same code's fastest of 31 runs on this machine. The checksum column
# says whether both targets made the same plan, the method column which planner made it.
#
# Needs qemu-system-arm (Debian: apt-get install qemu-system-arm). Usage: plan-cost.sh [--json]
set -euo pipefail
cd "$(dirname "$0")/.."
json=0
[[ "${1:-}" == "--json" ]] && json=1
target=thumbv7em-none-eabihf
if ! command -v qemu-system-arm >/dev/null; then
  echo "error: qemu-system-arm not found (Debian/Ubuntu: apt-get install qemu-system-arm)" >&2
  exit 1
fi
rustup target add "$target" >/dev/null 2>&1 || true
cargo build -q -p plan-cost --release --target "$target"
cargo build -q -p plan-cost --release
dir="${CARGO_TARGET_DIR:-$PWD/target}"
m4="$(mktemp)"
host="$(mktemp)"
trap 'rm -f "$m4" "$host"' EXIT
timeout 600 qemu-system-arm -M mps2-an386 -nographic -monitor none -serial none \
  -icount shift=0 -chardev file,id=results,path="$m4" \
  -semihosting-config enable=on,target=native,chardev=results \
  -kernel "$dir/$target/release/plan-cost"
"$dir/release/plan-cost" >"$host"
python3 - "$m4" "$host" "$json" <<'PY'
import json, sys
def rows(path):
    out = {}
    for line in open(path):
        parts = line.rstrip("\n").split("\t")
        if len(parts) == 4:
            out[parts[0]] = (int(parts[1]), parts[2], parts[3])
    return out
m4, host, as_json = rows(sys.argv[1]), rows(sys.argv[2]), sys.argv[3] == "1"
m4_check = next((v[0] for k, v in m4.items() if k.startswith("check:")), None)
if not m4:
    sys.exit("error: the Cortex-M4 image printed no results")
table = []
for name, (insns, sum_m4, method) in m4.items():
    if name.startswith("check:"):
        # The counter against a loop of known length (the timer's resolution is 40).
        if abs(insns - 1_000_001) > 200:
            sys.exit(f"error: instruction counter off: {insns:,} for a 1,000,001-instruction loop")
        continue
    ns, sum_host, _ = host.get(name, (None, None, None))
    table.append({"case": name, "method": method, "m4_instructions": insns,
                  "m4_ms_at_168mhz_1_cycle_per_insn": round(insns / 168e3, 3),
                  "host_us": None if ns is None else round(ns / 1e3, 1),
                  "same_plan": sum_m4 == sum_host})
if as_json:
    print(json.dumps({"target": "thumbv7em-none-eabihf on qemu mps2-an386, -icount shift=0",
                      "cases": table}, indent=1))
else:
    print(f"{'case':<78} {'method':<10} {'Cortex-M4 insns':>15} {'ms @168MHz':>10} {'host us':>8}  same")
    for r in table:
        print(f"{r['case']:<78} {r['method']:<10} {r['m4_instructions']:>15,} "
              f"{r['m4_ms_at_168mhz_1_cycle_per_insn']:>10.2f} {r['host_us']:>8}  "
              f"{'yes' if r['same_plan'] else 'NO'}")
    print("counter check: a 1,000,001-instruction loop read " + f"{m4_check:,}")
    print("insns: QEMU icount (1 insn = 1 ns), timer resolution 40; ms @168MHz assumes 1 cycle per"
          " instruction (an STM32F4/e-puck2 clock): a lower bound, real code takes ~1.2-1.5x.")
if not all(r["same_plan"] for r in table):
    sys.exit("error: the Cortex-M4 and the host made different plans")
PY
