#!/usr/bin/env bash
# The render-mode table of BENCHMARKS.md (issue 18): render time alone (the JSON's
# render_s) of dragon, balls_high and mount_very_high at their own resolution, 1 thread,
# SAH BVH, no skybox, at 1 and 16 samples per pixel, in each mode; the ratios are
# scalar time / mode time, from runs interleaved so that a busy moment hits all modes.
# Usage: scripts/mode-table.sh [SHARED_DIR] [RUNS]   (default ../shared, 2 runs)
set -euo pipefail
cd "$(dirname "$0")/.."
shared=${1:-../shared}
runs=${2:-2}
cargo build --release --quiet
p3trace=target/release/p3trace
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
modes=(scalar stream)

seconds() { # scene spp mode
  "$p3trace" render "$shared/scenes/$1.p3f" --accel bvh --no-skybox --threads 1 --spp "$2" \
    --mode "$3" -q -o "$out/image.png" --json "$out/run.json"
  python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["render_s"])' "$out/run.json"
}

echo "| scene | spp | run | scalar s | stream s | stream / scalar |"
echo "|---|---|---|---|---|---|"
for scene in dragon balls_high mount_very_high; do
  for spp in 1 16; do
    for run in $(seq "$runs"); do
      declare -A t=()
      for mode in "${modes[@]}"; do t[$mode]=$(seconds "$scene" "$spp" "$mode"); done
      python3 -c 'import sys
s, st = map(float, sys.argv[4:6])
print(f"| {sys.argv[1]} | {sys.argv[2]} | {sys.argv[3]} | {s:.3f} | {st:.3f} | {s / st:.2f} |")' \
        "$scene" "$spp" "$run" "${t[scalar]}" "${t[stream]}"
    done
  done
done
