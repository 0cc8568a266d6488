# Sourced by run.sh, measure.sh and beacon.sh (from the workspace root): checks for QEMU,
# builds the board image (cargo features from ROBOT_BOARD_FEATURES, default dom-dinis),
# robot-emulator and the station in release, and sets $image, $emu and $station.
target=thumbv7em-none-eabihf
dir="${CARGO_TARGET_DIR:-$PWD/target}"
if ! command -v qemu-system-arm >/dev/null; then
  echo "error: qemu-system-arm not found (Debian/Ubuntu: apt-get install qemu-system-arm)" >&2
  exit 1
fi
features=()
if [ -n "${ROBOT_BOARD_FEATURES:-}" ]; then
  features=(--no-default-features --features "$ROBOT_BOARD_FEATURES")
fi
rustup target add "$target" >/dev/null 2>&1 || true
cargo build -q -p robot-board --release --target "$target" "${features[@]}"
cargo build -q -p emulator -p station --release
image="$dir/$target/release/robot-board"
emu="$dir/release/robot-emulator"
station="$dir/release/station"
