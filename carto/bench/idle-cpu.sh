#!/usr/bin/env bash
# Idle CPU of the carto binary (issue 45): serves the twin (scenarios/empty.ron, real time, TCP
# board ports), starts carto against it, lets it settle, then reads utime + stime from
# /proc/PID/stat over SECONDS and prints the share of one core. With --client, an idle client
# (a position sent, then nothing) stays connected during the measurement.
#
#   carto/bench/idle-cpu.sh [--client] [CARTO_BINARY] [SECONDS]
#
# Run from the workspace root after `cargo build --release -p explobot -p carto`.
set -euo pipefail
client=0
if [[ "${1:-}" == "--client" ]]; then client=1; shift; fi
target="${CARGO_TARGET_DIR:-target}/release"
carto="${1:-$target/carto}"
seconds="${2:-60}"
base=$((20000 + RANDOM % 20000))
listen=$((base + 2))
dir="$(mktemp -d)"
cleanup() { kill "${pids[@]}" 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$dir"; }
pids=()
trap cleanup EXIT
"${EXPLOBOT:-$target/explobot}" sim scenarios/empty.ron --serve --tcp "$base" --run-dir "$dir/run" >"$dir/twin.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do grep -q "start Carto with" "$dir/twin.log" 2>/dev/null && break; sleep 0.2; done
RUST_LOG=info "$carto" --transport tcp --motor-port "127.0.0.1:$base" --sensor-port "127.0.0.1:$((base + 1))" \
  --listen "127.0.0.1:$listen" --profile scenarios/robots/mecanum-4wd.ron --cell 0.30 2>"$dir/carto.log" &
pid=$!
pids+=($pid)
sleep 5
if [[ $client == 1 ]]; then
  # SEND_ROBOT_POSITION (0, 0) east, then stay connected and silent.
  exec 3<>"/dev/tcp/127.0.0.1/$listen"
  printf '\x00\x05\x07\x00\x00\x00\x03' >&3
  sleep 2
fi
ticks() { awk '{print $14 + $15}' "/proc/$pid/stat"; }
hz=$(getconf CLK_TCK)
t0=$(ticks)
sleep "$seconds"
t1=$(ticks)
awk -v d=$((t1 - t0)) -v hz="$hz" -v s="$seconds" -v c="$client" 'BEGIN {
  printf "carto idle%s: %d ticks of CPU in %d s = %.2f %% of one core\n", (c ? " (client connected)" : ""), d, s, 100 * d / hz / s }'
