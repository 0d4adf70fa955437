#!/usr/bin/env bash
# Measures `p3trace view` as a user drives it: on an X server of its own (Xvfb), a left
# drag of 40 steps 20 ms apart, then the wait for the image to converge; prints the
# viewer's log line (frames per second while moving, input to screen, time to converge)
# and the CPU the idle window takes over 5 s. Needs Xvfb and xdotool (as .ci/run installs).
#   scripts/view-latency.sh [P3TRACE] SCENE... (default P3TRACE: target/release/p3trace)
set -euo pipefail
bin=target/release/p3trace
if [ $# -gt 0 ] && [ -x "$1" ] && [ ! -d "$1" ]; then bin=$1; shift; fi
exec 3< <(exec Xvfb -displayfd 1 -screen 0 1920x1080x24 -nolisten tcp -noreset 2>/dev/null)
xvfb=$!
read -r -u 3 number
export DISPLAY=":$number"
trap 'kill -TERM "$xvfb" 2>/dev/null || true' EXIT
for scene in "$@"; do
  log=$(mktemp)
  "$bin" view "$scene" 2>"$log" >/dev/null &
  viewer=$!
  name=$(basename "$scene")
  until window=$(xdotool search --name "^$name" 2>/dev/null | head -1) && [ -n "$window" ]; do
    sleep 0.05
  done
  until grep -q converged "$log"; do sleep 0.05; done
  xdotool mousemove --window "$window" 40 40 mousedown 1
  for _ in $(seq 40); do xdotool mousemove_relative 3 1; sleep 0.02; done
  xdotool mouseup 1
  until [ "$(grep -c converged "$log")" -ge 2 ]; do sleep 0.05; done
  ticks() { awk '{print $14 + $15}' "/proc/$viewer/stat"; }
  before=$(ticks); sleep 5; after=$(ticks)
  idle=$(awk -v t=$((after - before)) -v hz="$(getconf CLK_TCK)" 'BEGIN {printf "%.1f", 100 * t / hz / 5}')
  echo "$name: $(grep converged "$log" | tail -1 | sed 's/^p3trace: view: //'); idle ${idle}% of a core"
  xdotool key --window "$window" Escape 2>/dev/null || true
  kill "$viewer" 2>/dev/null || true
  wait "$viewer" 2>/dev/null || true
  rm -f "$log"
done
