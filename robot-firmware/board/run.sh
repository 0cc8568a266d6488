#!/usr/bin/env bash
# The robot's own firmware image on QEMU's mps2-an386 (Cortex-M4), its sensors and motors
# served by the emulator's world in lockstep (docs/hil.md): builds the image and
# robot-emulator, starts both, and prints the station's port on the first line of standard
# output. Then, in another terminal:   station --port <that port> [--key-file K]
#
# Usage: run.sh [robot-emulator hil options...]   e.g. run.sh --seed 3 --key-file link.key
#   --icount N: QEMU's -icount shift=N (0: the board's timer counts instructions)
#   Ctrl-C stops it and prints the world's summary with --json.
# Another profile's image: ROBOT_BOARD_FEATURES=khepera run.sh --profile khepera
set -euo pipefail
cd "$(dirname "$0")/../.."
target=thumbv7em-none-eabihf
dir="${CARGO_TARGET_DIR:-$PWD/target}"
features=()
if [ -n "${ROBOT_BOARD_FEATURES:-}" ]; then
  features=(--no-default-features --features "$ROBOT_BOARD_FEATURES")
fi
if ! command -v qemu-system-arm >/dev/null; then
  echo "error: qemu-system-arm not found (Debian/Ubuntu: apt-get install qemu-system-arm)" >&2
  exit 1
fi
rustup target add "$target" >/dev/null 2>&1 || true
cargo build -q -p robot-board --release --target "$target" "${features[@]}"
cargo build -q -p emulator --release --bin robot-emulator
exec "$dir/release/robot-emulator" hil --image "$dir/$target/release/robot-board" "$@"
