#!/usr/bin/env bash
# Renders the cost images of docs/cost/: the primitives each pixel's rays test, with the
# 8-wide BVH and with the course's uniform grid, the two structures of a scene on one
# logarithmic scale: the sphereflake (scenes/balls_high.p3f) and the course's dragon.
#
#   scripts/cost-gallery.sh                          # builds the release binary, writes docs/cost/
#   P3TRACE=path/to/p3trace OUT=dir scripts/cost-gallery.sh   # that binary, into dir
#
# The dragon is the course's own scene, read from the course material beside the project
# (../shared, or $P3TRACE_SHARED); without it, its images are left out and the script
# says so. Counts are deterministic, so the images equal the committed ones on any
# machine (tests/integration/gallery.rs holds docs/cost/ to this script).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
if [[ -z "${P3TRACE:-}" ]]; then
    # From the project's folder, which holds the build's settings (.cargo/config.toml).
    (cd "$root" && cargo build --release --quiet)
    P3TRACE="$root/target/release/p3trace"
fi
out="${OUT:-$root/docs/cost}"
shared="${P3TRACE_SHARED:-$root/../shared}"
mkdir -p "$out"

# cost SCENE NAME MAX FLAGS...: the BVH's and the grid's images of SCENE on one scale.
cost() {
    local scene=$1 name=$2 max=$3
    shift 3
    for accel in bvh grid; do
        "$P3TRACE" render "$scene" --accel "$accel" --cost prims --cost-max "$max" \
            --cost-scale log --no-skybox -q "$@" -o "$out/${name}_${accel}_prims.png"
    done
}

cost "$root/scenes/balls_high.p3f" balls_high 2000 --resolution 320x320
if [[ -f "$shared/scenes/dragon.p3f" ]]; then
    cost "$shared/scenes/dragon.p3f" dragon 2000 --resolution 400x300
else
    echo "cost-gallery: no course dragon at $shared/scenes/dragon.p3f: its images left out" >&2
fi
