#!/usr/bin/env bash
# Times every acceleration structure on every course scene (build and render, 2 threads,
# one sample per pixel at the file's resolution, no skybox) and checks that each image
# equals the brute-force one byte for byte. Prints a Markdown table for BENCHMARKS.md.
#
#   scripts/accel-table.sh [SHARED_DIR] [SCENE...]
#
# Brute force is skipped for the dragon (hours); the other structures are then compared
# with the grid's image. Takes about 20 minutes, mostly brute force on mount_very_high.
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
shared="${1:-$repo/../shared}"
shift || true
scenes=("$@")
if [ ${#scenes[@]} -eq 0 ]; then
    scenes=(balls_low balls_medium balls_high balls_box dof motion mount_low mount_high
            mount_very_high dragon)
fi
cargo build --release --quiet --manifest-path "$repo/Cargo.toml"
bin="$repo/target/release/p3trace"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

structures=("none" "grid" "grid --mailbox" "bvh --bvh midpoint" "bvh --bvh sah")
echo "| scene | objects | none | grid | grid + mailbox | bvh midpoint | bvh sah |"
echo "|---|---|---|---|---|---|---|"
for scene in "${scenes[@]}"; do
    file="$shared/scenes/$scene.p3f"
    objects="$("$bin" info "$file" --accel none | awk '/^objects:/ {print $2}')"
    row="| \`$scene\` | $objects |"
    reference=""
    for s in "${structures[@]}"; do
        if [ "$s" = none ] && [ "$scene" = dragon ]; then
            row="$row (skipped) |"
            continue
        fi
        image="$work/${s// /_}.png"
        out="$("$bin" render "$file" --no-skybox --threads 2 --accel $s --stats -o "$image")"
        build="$(echo "$out" | awk '/built in/ {print $(NF-1)}')"
        render="$(echo "$out" | awk -F', ' '/Mrays\/s/ {print $3}')"
        same=""
        if [ -z "$reference" ]; then
            reference="$image"
        elif ! "$bin" compare "$reference" "$image" >/dev/null; then
            same=" **differs**"
        fi
        row="$row $render (build $build s)$same |"
    done
    echo "$row"
done
