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
source robot-firmware/board/common.sh
exec "$emu" hil --image "$image" "$@"
