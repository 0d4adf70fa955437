#!/usr/bin/env bash
# The distribution effects' render times (docs/effects.md sums them up): the course scenes at
# 16 samples per pixel, at their own resolution with the SAH BVH (the files say accel 0),
# with each distribution effect on in turn, on 1 and 2 threads.
# Usage: scripts/effects-table.sh [SHARED_DIR]   (default ../shared)
set -euo pipefail
cd "$(dirname "$0")/.."
shared=${1:-../shared}
cargo build --release --quiet
p3trace=target/release/p3trace
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

# name|flags: the first is the antialiased Whitted image the others add an effect to.
configs=(
  "16 spp|--shutter 0,0"
  "+ soft shadows|--shutter 0,0 --soft-shadows"
  "+ fuzzy 0.2|--shutter 0,0 --roughness 0.2"
  "+ depth of field|--shutter 0,0 --aperture 8"
  "+ motion blur|--shutter 0,0.3"
  "all|--soft-shadows --roughness 0.2 --aperture 8 --shutter 0,0.3"
)

header="| scene | threads |"
rule="|---|---|"
for config in "${configs[@]}"; do
  header+=" ${config%%|*} |"
  rule+="---|"
done
echo "$header"
echo "$rule"
for scene in balls_low dof motion dragon; do
  for threads in 1 2; do
    row="| $scene | $threads |"
    for config in "${configs[@]}"; do
      flags=${config#*|}
      # dof keeps its own lens (aperture 12, focal 1.5) rather than --aperture 8.
      if [ "$scene" = dof ]; then flags=${flags/--aperture 8/}; fi
      # shellcheck disable=SC2086
      seconds=$("$p3trace" render "$shared/scenes/$scene.p3f" --accel bvh --spp 16 --threads "$threads" \
        $flags -o "$out/image.png" | sed -E 's/.* ([0-9.]+) s, .*/\1/')
      row+=" $seconds |"
    done
    echo "$row"
  done
done
