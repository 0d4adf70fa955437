#!/usr/bin/env bash
# The shading shares of BENCHMARKS.md (issue 33) by render-profile's rule: dragon, balls_high
# and mount_very_high at their own resolution, 1 thread, SAH BVH, no skybox, at 1 and 16
# samples per pixel, each render's call stacks sampled as ../shared/bench/render-profile
# samples them (perf, 1999 Hz, 16 KiB of stack). For each render it prints the tile loop's
# samples and the share of them outside traversal. That rule counts every sample under a
# `for_lanes` frame as traversal, as the walks use it for their lanes; the shader uses it too
# (spawning, shadow rays, powf): scripts/stage-table.sh --time gives the share by the lines
# each sample serves instead.
# Usage: scripts/profile-table.sh [SHARED_DIR] [RUNS]   (default ../shared, 1 run)
set -euo pipefail
cd "$(dirname "$0")/.."
shared=${1:-../shared}
runs=${2:-1}
command -v perf >/dev/null || { echo "profile-table: perf is missing (apt-get install linux-perf)" >&2; exit 2; }
cargo build --release --quiet
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

shares() { # perf script text -> "samples share"
  python3 - "$1" <<'PY'
import re, sys
WALK = re.compile("|".join([
    r"^p3trace::accel::Tracer::(closest|occluded)", r"^p3trace::accel::(bvh8::(packet|traverse)|bvh2::Bvh2::(closest|occluded)|grid|none)",
    r"^(closest|occluded)(_packet|_planes|_in_leaf|_from)?$", r"^(triangle|sphere|box)_(leaf|packet)", r"^(test_packet|offer)$"]))
def frames(stack):
    for line in stack:
        m = re.match(r"\s*[0-9a-f]+ (.+?)\+0x[0-9a-f]+ ", line + " ") or re.match(r"\s*[0-9a-f]+ (\S+)", line)
        if m:
            full = m.group(1)
            yield full if full.startswith(("<", "p3trace::")) else re.sub(r"<.*", "", full)
samples = given = 0
def count(stack):
    global samples, given
    named = list(frames(stack))
    if not any(re.search(r"\brender_tile\b", n) for n in named):
        return
    samples += 1
    given += any(WALK.search(n) for n in named) or "for_lanes" in named
stack = []
for line in open(sys.argv[1], errors="replace"):
    if line.startswith(("\t", " ")):
        stack.append(line.rstrip())
    elif not line.strip():
        count(stack)
        stack = []
count(stack)
n = max(samples, 1)
print(samples, f"{100 * (n - given) / n:.1f}%")
PY
}

echo "| scene, spp | run | tile-loop samples | outside traversal, render-profile's rule |"
echo "|---|---|---|---|"
for scene in dragon balls_high mount_very_high; do
  for spp in 1 16; do
    for run in $(seq "$runs"); do
      perf record -q -F 1999 --call-graph dwarf,16384 -o "$out/perf.data" -- \
        target/release/p3trace render "$shared/scenes/$scene.p3f" --threads 1 --accel bvh \
        --no-skybox -q --spp "$spp" -o "$out/image.png" >/dev/null 2>"$out/err" ||
        { cat "$out/err" >&2; exit 1; }
      perf script -i "$out/perf.data" --inline 2>/dev/null >"$out/stacks.txt"
      read -r samples given < <(shares "$out/stacks.txt")
      echo "| $scene, $spp | $run | $samples | $given |"
    done
  done
done
