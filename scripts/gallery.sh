#!/usr/bin/env bash
# Renders the README's gallery from the project's own scenes: the showcase as the README's
# first command makes it, then one image per distribution effect.
#
#   scripts/gallery.sh                          # builds the release binary, writes docs/gallery/
#   P3TRACE=path/to/p3trace OUT=dir scripts/gallery.sh   # that binary, into dir
#
# Renders are deterministic, so the images equal the committed ones on any machine
# (tests/integration/gallery.rs holds docs/gallery/ to this script).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
if [[ -z "${P3TRACE:-}" ]]; then
    # From the project's folder, which holds the build's settings (.cargo/config.toml).
    (cd "$root" && cargo build --release --quiet)
    P3TRACE="$root/target/release/p3trace"
fi
out="${OUT:-$root/docs/gallery}"
scenes="$root/scenes"
mkdir -p "$out"
"$P3TRACE" render "$scenes/showcase.p3f" -o "$out/showcase.png"
"$P3TRACE" render "$scenes/balls_low.p3f" --soft-shadows --spp 16 --resolution 320x320 -o "$out/soft_shadows.png"
"$P3TRACE" render "$scenes/dof.p3f" --spp 16 --resolution 320x320 -o "$out/depth_of_field.png"
"$P3TRACE" render "$scenes/showcase.p3f" --roughness 0.2 --spp 16 --resolution 320x240 -o "$out/fuzzy_reflections.png"
"$P3TRACE" render "$scenes/motion.p3f" --spp 16 --resolution 320x320 -o "$out/motion_blur.png"
"$P3TRACE" render random --spp 16 --resolution 400x300 -o "$out/random.png"
