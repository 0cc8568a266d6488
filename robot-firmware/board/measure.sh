#!/usr/bin/env bash
# Issue 35's measures, on the robot's own image (QEMU mps2-an386, Cortex-M4):
# - flash and static RAM, from the ELF's sections;
# - the stack's high-water mark: painted at reset (cortex-m-rt paint-stack), read back by the
#   image and sent to the world in its Report (docs/hil.md §4), the deepest of four runs that
#   take the deep paths: a flood of commands, a map and plan upload, the plan executed, a
#   search, a signed session;
# - state + worst stack against the Dom Dinis board's 32 KB;
# - instructions per control cycle and per link frame: a second run under QEMU's
#   `-icount shift=0` (1 instruction = 1 ns, one 25 MHz timer tick = 40 instructions, as
#   robot-firmware/plan-cost.sh), the robot searching the arena while a station probes it;
# - the station link under a 115200-baud flood (tests/tools/board_flood.py): every command
#   answered, no byte dropped by the 256-byte FIFO, and a Stop's Ack and the moment the wheels
#   stopped (the world's motor_stops_monotonic_s), to be within 300 ms; once on QEMU's own
#   UART (bytes as fast as written) and once on a line paced at 115200 baud both ways.
#
# Needs qemu-system-arm. Usage: measure.sh [--json]
set -euo pipefail
cd "$(dirname "$0")/../.."
json=0
[[ "${1:-}" == "--json" ]] && json=1
source robot-firmware/board/common.sh
work="$(mktemp -d)"
world=""
trap '[ -n "$world" ] && kill "$world" 2>/dev/null; rm -rf "$work"' EXIT

start_world() { # OUT LINK ARGS...: robot-emulator hil in the background, once its port is up
  local out="$1" link="$2"
  shift 2
  "$emu" hil --image "$image" --json --link "$link" "$@" >"$out" 2>"$out.err" &
  world=$!
  for _ in $(seq 200); do [ -e "$link" ] && return 0; sleep 0.05; done
  echo "error: the image's port did not come up" >&2
  cat "$out.err" >&2
  exit 1
}

stop_world() {
  kill -INT "$world"
  wait "$world" || true
  world=""
}

# 1. Real time: the flood and its Stop, uploads, a plan executed, a search.
link="$work/robot"
start_world "$work/rt.json" "$link" --seed 1
python3 tests/tools/board_flood.py "$link" --json >"$work/flood.json"
"$station" plan --map builtin:micro-rato-99 --out-object "$work/plan.obj" >/dev/null
"$station" upload-map --port "$link" --map builtin:micro-rato-99 --json >"$work/upload-map.json"
"$station" upload-plan --port "$link" --plan "$work/plan.obj" --json >"$work/upload-plan.json"
plan_id="$(python3 -c 'import json,sys; print(hex(json.load(open(sys.argv[1]))["id"]))' "$work/upload-plan.json")"
"$station" send --port "$link" execute "$plan_id" >/dev/null
sleep 15
"$station" send --port "$link" explore >/dev/null
sleep 15
stop_world

# 3. The flood again with the station link paced at 115200 baud both ways through the world
#    (hil::relay), as a real UART: the robot's answers then exceed the line.
link="$work/robot-line"
start_world "$work/line.json" "$link" --seed 1 --line-baud 115200
python3 tests/tools/board_flood.py "$link" --json >"$work/flood-line.json"
sleep 1
stop_world

# 4. A signed session (PROTOCOL.md §13: HMAC-SHA256 on every frame, the deepest stack the
#    link has): telemetry, a teleop and a Stop, a map upload.
link="$work/robot-signed"
printf '%s\n' 6b1f0a2c9d8e7f60514233241506f7e8d9cabbac9d8e7f60514233241506f7e8 >"$work/link.key"
chmod 600 "$work/link.key"
start_world "$work/signed.json" "$link" --seed 1 --key-file "$work/link.key"
"$station" stats --port "$link" --key-file "$work/link.key" -s 2 >/dev/null
"$station" send --port "$link" --key-file "$work/link.key" teleop 150 0 >/dev/null
"$station" send --port "$link" --key-file "$work/link.key" stop >/dev/null
"$station" upload-map --port "$link" --key-file "$work/link.key" --map builtin:micro-rato-99 >/dev/null
sleep 1
stop_world

# 2. -icount shift=0: instructions, 60 s of world time of the robot searching from power-on,
#    a station probing it for the first 10 s of wall time.
link="$work/robot-icount"
start_world "$work/icount.json" "$link" --seed 1 --icount 0 --power-on-mode explore --seconds 60
"$station" stats --port "$link" -s 10 --json >"$work/stats.json" || true
wait "$world" || true
world=""

python3 - "$image" "$work" "$json" <<'PY'
import json, struct, sys
image, work, as_json = sys.argv[1], sys.argv[2], sys.argv[3] == "1"

def sections(path):
    """(name, type, flags, addr, size) of an ELF32 little-endian file's sections."""
    b = open(path, "rb").read()
    shoff, = struct.unpack_from("<I", b, 0x20)
    shentsize, shnum, shstrndx = struct.unpack_from("<HHH", b, 0x2E)
    hdrs = [struct.unpack_from("<IIIIIIIIII", b, shoff + i * shentsize) for i in range(shnum)]
    strtab = hdrs[shstrndx]
    name = lambda off: b[strtab[4] + off: b.index(b"\0", strtab[4] + off)].decode()
    return [(name(h[0]), h[1], h[2], h[3], h[5]) for h in hdrs]

SHF_ALLOC, SHT_NOBITS, RAM = 0x2, 8, 0x2000_0000
secs = [s for s in sections(image) if s[2] & SHF_ALLOC and s[4]]
flash = sum(s[4] for s in secs if s[1] != SHT_NOBITS)  # code, constants, .data's image
ram_static = sum(s[4] for s in secs if s[3] >= RAM)

def last_json(path):
    return json.loads(open(path).read().strip().splitlines()[-1])

rt, ic = last_json(f"{work}/rt.json"), last_json(f"{work}/icount.json")
b, bi = rt["board"], ic["board"]
runs = [rt, ic, last_json(f"{work}/line.json"), last_json(f"{work}/signed.json")]

def flood_figures(flood, run):
    """The flood's figures, the wheels' stop timed by the world's clock."""
    board = run["board"]
    stop_at = flood["stop_written_monotonic_s"]
    stops = [t for t in run["motor_stops_monotonic_s"] if stop_at is not None and t >= stop_at]
    wheels_ms = round((stops[0] - stop_at) * 1000, 1) if stops else None
    return {
        "baud": flood["baud"], "bytes_sent": flood["bytes_sent"],
        "bytes_per_s": flood["bytes_per_s"], "frames_sent": flood["frames_sent"],
        "frames_answered": flood["answered"], "frames_unanswered": flood["unanswered"],
        "fifo_bytes_received": board["rx_bytes"], "fifo_dropped": board["rx_dropped"],
        "fifo_max_fill": board["rx_fifo_max"], "fifo_size": 256,
        "stop_ack_ms": flood["stop_ack_ms"], "stop_at_wheels_ms": wheels_ms,
        "stop_within_300_ms": wheels_ms is not None and wheels_ms <= 300,
    }

TICK = 40  # instructions per 25 MHz tick under -icount shift=0
budget = 32 * 1024
stack = max(r["board"]["stack_used"] for r in runs)
out = {
    "image": "robot-board (Dom Dinis, micro-rato), thumbv7em-none-eabihf, QEMU mps2-an386",
    "flash_bytes": flash,
    "ram_static_bytes": ram_static,
    "ram_static_reported_by_image": b["static_ram"],
    "stack_reserved_bytes": b["stack_size"],
    "stack_high_water_bytes": stack,
    "state_plus_stack_bytes": b["static_ram"] + stack,
    "budget_bytes": budget,
    "fits": b["static_ram"] + stack <= budget,
    "instructions": {
        "per_cycle_mean": round(bi["cycle_ticks_sum"] * TICK / max(bi["cycles"], 1)),
        "per_cycle_max": bi["cycle_ticks_max"] * TICK,
        "cycles": bi["cycles"],
        "per_link_frame_mean": round(bi["rx_pass_ticks_sum"] * TICK / max(bi["rx_frames"], 1)),
        "link_pass_max": bi["rx_pass_ticks_max"] * TICK,
        "link_frames": bi["rx_frames"],
        "note": "QEMU -icount shift=0: 1 insn = 1 ns; timer resolution 40 insns; a Cortex-M4 "
                "takes about 1.2-1.5 cycles an instruction, so cycles are a little more",
    },
    "flood": flood_figures(last_json(f"{work}/flood.json"), rt),
    "flood_on_a_115200_line": flood_figures(last_json(f"{work}/flood-line.json"),
                                            last_json(f"{work}/line.json")),
    "session": {"world_time_s": rt["world_time_s"], "distance_m": round(rt["distance_m"], 2),
                "fault": rt["fault"], "hil_errors": b["hil_errors"]},
}
if as_json:
    print(json.dumps(out, indent=1))
else:
    print(f"flash {flash} B, static RAM {ram_static} B, stack high-water {stack} B of "
          f"{out['stack_reserved_bytes']} B reserved: state + stack "
          f"{out['state_plus_stack_bytes']} B of {budget} B")
    i = out["instructions"]
    print(f"instructions per control cycle: mean {i['per_cycle_mean']:,}, max {i['per_cycle_max']:,} "
          f"({i['cycles']} cycles, searching); per link frame: mean {i['per_link_frame_mean']:,} "
          f"({i['link_frames']} frames)")
    for name, f in (("QEMU's UART", out["flood"]), ("a 115200-baud line", out["flood_on_a_115200_line"])):
        print(f"flood at {f['baud']} baud on {name}: {f['frames_sent']} frames, "
              f"{f['frames_answered']} answered, FIFO {f['fifo_bytes_received']} B in, "
              f"{f['fifo_dropped']} dropped, fullest {f['fifo_max_fill']} of 256; Stop acked in "
              f"{f['stop_ack_ms']} ms, wheels stopped {f['stop_at_wheels_ms']} ms after it was written")
floods = (out["flood"], out["flood_on_a_115200_line"])
ok = out["fits"] and all(f["fifo_dropped"] == 0 and f["stop_within_300_ms"] for f in floods)
sys.exit(0 if ok else 1)
PY
