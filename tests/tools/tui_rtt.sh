#!/usr/bin/env bash
# The TUI's command round trip (docs/performance.md, "command round trip in the TUI")
# and the TUI's CPU and wake-ups over the same window.
#
# Runs `robot-emulator --speed 1 --link P` and `station --port P` in a detached tmux session
# of 120 x 40, sends `+` `+` (50 Hz telemetry) and, unless --idle, `Up` (teleop, repeating at
# 10 Hz), waits SECONDS, shows the link view (F5) and reads its `RTT` line (the last 256
# first-send acks). Over the same window it reads the station's utime + stime from
# /proc/PID/stat and the voluntary + involuntary context switches of all its threads from
# /proc/PID/task/*/status. Prints one line per run, with the machine's load (`uptime`):
#
#   tests/tools/tui_rtt.sh [--bin DIR] [--seconds 30] [--runs 1] [--idle] [--json] [--record DIR]
#
# --record DIR also records the link from the TUI (`R`) over the window, keeps it as
# DIR/tui-rtt-N.rec and prints every round trip's summary from it (tui_rtt_trace.py).
#
# DIR holds the release binaries `station` and `robot-emulator` (default:
# $CARGO_TARGET_DIR/release, else target/release). Needs tmux. Measure without `nice`: this
# times latency. Exit 1 when the station never connects or shows no RTT line.
set -euo pipefail

bin="${CARGO_TARGET_DIR:-target}/release"
seconds=30
runs=1
idle=0
json=0
record=""
while [ $# -gt 0 ]; do
    case "$1" in
        --bin) bin="$2"; shift 2 ;;
        --seconds) seconds="$2"; shift 2 ;;
        --runs) runs="$2"; shift 2 ;;
        --idle) idle=1; shift ;;
        --json) json=1; shift ;;
        --record) record="$2"; shift 2 ;;
        -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
        *) echo "tui_rtt.sh: unknown argument $1 (see --help)" >&2; exit 2 ;;
    esac
done
for b in station robot-emulator; do
    [ -x "$bin/$b" ] || { echo "tui_rtt.sh: no $bin/$b (cargo build --release --bins)" >&2; exit 2; }
done
command -v tmux >/dev/null || { echo "tui_rtt.sh: tmux is not installed" >&2; exit 2; }

tick=$(getconf CLK_TCK)
work=$(mktemp -d /tmp/tui-rtt.XXXXXX)
sock="tui-rtt-$$"
emu=""
cleanup() {
    tmux -L "$sock" kill-server 2>/dev/null || true
    [ -n "$emu" ] && kill "$emu" 2>/dev/null && wait "$emu" 2>/dev/null
    rm -rf "$work"
}
trap cleanup EXIT

screen() { tmux -L "$sock" capture-pane -p -t main; }
keys() { tmux -L "$sock" send-keys -t main "$@"; }
wait_screen() { # TEXT SECONDS
    local end=$((SECONDS + $2))
    while [ $SECONDS -lt $end ]; do
        screen | grep -q -- "$1" && return 0
        sleep 0.2
    done
    return 1
}
cpu_ticks() { awk '{print $14 + $15}' "/proc/$1/stat"; }
switches() {
    cat /proc/"$1"/task/*/status 2>/dev/null \
        | awk '/^(voluntary|nonvoluntary)_ctxt_switches/ {n += $2} END {print n + 0}'
}

for run in $(seq 1 "$runs"); do
    port="$work/robot$run"
    "$bin/robot-emulator" --speed 1 --link "$port" >"$work/emulator.log" 2>&1 &
    emu=$!
    for _ in $(seq 1 100); do [ -e "$port" ] && break; sleep 0.1; done
    rm -f "$work"/*.rec
    tmux -L "$sock" -f /dev/null new-session -d -s main -x 120 -y 40 -c "$work" \
        "'$bin/station' --port '$port'; sleep 30"
    if ! wait_screen "● " 20; then
        echo "tui_rtt.sh: the station did not connect; its screen:" >&2
        screen >&2
        exit 1
    fi
    pid=$(pgrep -n -x station -P "$(tmux -L "$sock" display -p -t main '#{pane_pid}')")
    keys +
    sleep 0.3
    keys +
    sleep 1
    if [ -n "$record" ]; then keys R; sleep 0.3; fi
    [ "$idle" = 1 ] || keys Up
    load=$(uptime | sed 's/.*load average: //')
    t0=$(cpu_ticks "$pid")
    s0=$(switches "$pid")
    sleep "$seconds"
    t1=$(cpu_ticks "$pid")
    s1=$(switches "$pid")
    if [ -n "$record" ]; then keys R; sleep 0.5; fi
    keys F5
    sleep 0.5
    rtt=$(screen | grep -o 'RTT [^│]*' | head -n 1 | sed 's/ *$//')
    cpu=$(awk -v d=$((t1 - t0)) -v hz="$tick" -v s="$seconds" 'BEGIN {printf "%.2f", 100 * d / hz / s}')
    wake=$(awk -v d=$((s1 - s0)) -v s="$seconds" 'BEGIN {printf "%.1f", d / s}')
    keys ' '
    sleep 0.3
    keys q
    sleep 0.5
    tmux -L "$sock" kill-server 2>/dev/null || true
    kill "$emu" 2>/dev/null || true
    wait "$emu" 2>/dev/null || true
    emu=""
    if [ "$idle" = 0 ] && ! echo "$rtt" | grep -q 'p99'; then
        echo "tui_rtt.sh: no RTT figure on the link view (run $run): '$rtt'" >&2
        exit 1
    fi
    mode=$([ "$idle" = 1 ] && echo idle || echo teleop)
    if [ -n "$record" ]; then
        mkdir -p "$record"
        for f in "$work"/*.rec; do [ -e "$f" ] && mv "$f" "$record/tui-rtt-$run.rec"; done
        [ -e "$record/tui-rtt-$run.rec" ] && python3 "$(dirname "$0")/tui_rtt_trace.py" "$record/tui-rtt-$run.rec" >&2
    fi
    if [ "$json" = 1 ]; then
        p50=$(echo "$rtt" | sed -n 's/.*p50 \([0-9.]*\) ms.*/\1/p')
        p99=$(echo "$rtt" | sed -n 's/.*p99 \([0-9.]*\) ms.*/\1/p')
        n=$(echo "$rtt" | sed -n 's/.*(n=\([0-9]*\)).*/\1/p')
        printf '{"run":%d,"mode":"%s","seconds":%s,"rtt_p50_ms":%s,"rtt_p99_ms":%s,"rtt_n":%s,"cpu_percent":%s,"switches_per_s":%s,"load":"%s"}\n' \
            "$run" "$mode" "$seconds" "${p50:-null}" "${p99:-null}" "${n:-0}" "$cpu" "$wake" "$load"
    else
        echo "run $run ($mode, ${seconds} s): ${rtt:-no RTT}; station CPU ${cpu} % of a core, ${wake} switches/s; load ${load}"
    fi
done
