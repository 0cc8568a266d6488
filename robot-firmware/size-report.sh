#!/usr/bin/env bash
# Size report of the firmware on a Cortex-M4F (thumbv7em-none-eabihf), per profile's
# composition (robot::kit: Dom Dinis, Khepera, ALICE): the robot's state as the compiler lays it out
# for that target (-Zprint-type-sizes) and the worst-case stack of its construction in place
# (Robot::init), of Robot::step and of the link handler (stack_report.py over
# -Zemit-stack-sizes), then state + worst stack against the Dom Dinis board's 32 KB.
# The flags are nightly-only; RUSTC_BOOTSTRAP lets the stable toolchain take them, as for the
# fuzzers.
# Usage: size-report.sh [--json] [--check]   (--check: exit 1 when Dom Dinis does not fit)
set -euo pipefail
cd "$(dirname "$0")/.."
json=""
check=""
for a in "$@"; do
  case "$a" in
    --json) json="--json" ;;
    --check) check=1 ;;
    *) echo "usage: $0 [--json] [--check]" >&2; exit 2 ;;
  esac
done
target=thumbv7em-none-eabihf
rustup target add "$target" >/dev/null 2>&1
rustup component add llvm-tools >/dev/null 2>&1
bindir="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin"
dir="${CARGO_TARGET_DIR:-$PWD/target}/size-report"
mkdir -p "$dir"
# Type sizes are printed only by a build that compiles the crates: touch them so it does.
touch robot-firmware/size-probe/src/main.rs robot-firmware/src/lib.rs
RUSTC_BOOTSTRAP=1 RUSTFLAGS="-Zemit-stack-sizes" cargo rustc -q -p size-probe --release --target "$target" --target-dir "$dir" \
  -- -Zprint-type-sizes >"$dir/type-sizes.txt"
if ! grep -q 'robot::Robot<' "$dir/type-sizes.txt"; then
  RUSTC_BOOTSTRAP=1 RUSTFLAGS="-Zemit-stack-sizes" cargo rustc -q -p robot-firmware --release --target "$target" \
    --target-dir "$dir" -- -Zprint-type-sizes >>"$dir/type-sizes.txt"
fi
report() {
  python3 robot-firmware/stack_report.py "$bindir" "$dir/$target/release/size-probe" "$dir/type-sizes.txt" "$@"
}
if [ -n "$json" ]; then
  report --json
else
  echo "== state on $target (bytes)"
  for t in 'robot::Robot<robot::kit::DomDinis>' 'robot::Robot<robot::kit::Khepera>' \
           'robot::Robot<robot::kit::Alice>' 'robot::alice::AliceState' 'link::Link' \
           'transfer::Objects' 'nav::fixed::FixedNav<' 'robot::linecorr::LineCorr' \
           'light_calibration::LightCalibration' 'robot::forage::Forage' 'explore::Explorer'; do
    # A type that moved or went is named, not skipped: this list follows the firmware's modules.
    line="$(grep -m1 -F "type: \`$t" "$dir/type-sizes.txt" || true)"
    if [ -n "$line" ]; then
      echo "$line" | sed 's/print-type-size type: /  /'
    else
      echo "  \`$t\`: not in the build's type sizes (renamed or moved? update size-report.sh)"
    fi
  done
  echo "== stack on $target"
  report
fi
if [ -n "$check" ]; then
  report --check >/dev/null
fi
