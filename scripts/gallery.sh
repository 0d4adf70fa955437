#!/usr/bin/env bash
# Renders the README's gallery (docs/gallery/) from the project's own scenes.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
p3trace=target/release/p3trace
out=docs/gallery
mkdir -p "$out"
"$p3trace" render scenes/balls_low.p3f --soft-shadows --spp 16 --resolution 320x320 -o "$out/soft_shadows.png"
"$p3trace" render scenes/dof.p3f --spp 16 --resolution 320x320 -o "$out/depth_of_field.png"
"$p3trace" render scenes/showcase.p3f --roughness 0.2 --spp 16 --resolution 320x240 -o "$out/fuzzy_reflections.png"
"$p3trace" render scenes/motion.p3f --spp 16 --resolution 320x320 -o "$out/motion_blur.png"
"$p3trace" render random --spp 16 --resolution 400x300 -o "$out/random.png"
