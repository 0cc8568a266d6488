#!/usr/bin/env bash
# Size report of the firmware on a Cortex-M4F (thumbv7em-none-eabihf): the robot's state as the
# compiler lays it out for that target (-Zprint-type-sizes) and the worst-case stack of
# Robot::step and the link handler (stack_report.py over -Zemit-stack-sizes). The flags are
# nightly-only; RUSTC_BOOTSTRAP lets the stable toolchain take them, as for the fuzzers.
set -euo pipefail
cd "$(dirname "$0")/.."
target=thumbv7em-none-eabihf
rustup target add "$target" >/dev/null 2>&1
rustup component add llvm-tools >/dev/null 2>&1
bindir="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin"
dir="${CARGO_TARGET_DIR:-$PWD/target}/size-report"
mkdir -p "$dir"
RUSTC_BOOTSTRAP=1 RUSTFLAGS="-Zemit-stack-sizes" cargo rustc -q -p size-probe --release --target "$target" --target-dir "$dir" \
  -- -Zprint-type-sizes >"$dir/type-sizes.txt"
# A rebuild prints no type sizes; force one when the file came out empty.
if ! grep -q 'robot::Robot`' "$dir/type-sizes.txt"; then
  touch robot-firmware/size-probe/src/main.rs robot-firmware/src/lib.rs
  RUSTC_BOOTSTRAP=1 RUSTFLAGS="-Zemit-stack-sizes" cargo rustc -q -p robot-firmware --release --target "$target" \
    --target-dir "$dir" -- -Zprint-type-sizes >"$dir/type-sizes.txt"
fi
echo "== state on $target (bytes)"
for t in 'robot::Robot' 'robot::Core' 'link::Link' 'transfer::Objects' 'nav::fixed::FixedNav<' \
         'robot::linecorr::LineCorr' 'robot::calibrate::LightCalibration' 'robot::forage::Forage'; do
  grep -m1 -F "type: \`$t" "$dir/type-sizes.txt" | sed 's/print-type-size type: /  /'
done
echo "== stack on $target"
python3 robot-firmware/stack_report.py "$bindir" "$dir/$target/release/size-probe"
