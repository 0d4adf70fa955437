#!/usr/bin/env bash
# The shading shares of BENCHMARKS.md (issue 33): dragon, balls_high and mount_very_high at
# their own resolution, 1 thread, SAH BVH, no skybox, at 1 and 16 samples per pixel, each
# render's call stacks sampled as ../shared/bench/render-profile samples them (perf, 1999 Hz,
# 16 KiB of stack). For each render it prints the tile loop's samples and the share of them
# outside traversal twice: by render-profile's rule, and by the same rule but for one frame.
# render-profile counts every sample under a `for_lanes` frame as traversal, as the walks
# use it for their lanes; the shader uses it too (spawning, shadow rays, powf), so the second
# share counts a `for_lanes` frame as traversal only where its closure is a walk's.
# Usage: scripts/profile-table.sh [SHARED_DIR] [RUNS]   (default ../shared, 1 run)
set -euo pipefail
cd "$(dirname "$0")/.."
shared=${1:-../shared}
runs=${2:-1}
command -v perf >/dev/null || { echo "profile-table: perf is missing (apt-get install linux-perf)" >&2; exit 2; }
cargo build --release --quiet
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

shares() { # perf script text -> "samples as-given corrected"
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
            yield (full if full.startswith(("<", "p3trace::")) else re.sub(r"<.*", "", full)), full
samples = given = corrected = 0
def count(stack):
    global samples, given, corrected
    named = list(frames(stack))
    if not any(re.search(r"\brender_tile\b", n) for n, _ in named):
        return
    samples += 1
    walk = any(WALK.search(n) for n, _ in named)
    lanes = [full for n, full in named if n == "for_lanes"]
    given += walk or bool(lanes)
    corrected += walk or any(re.match(r"for_lanes<\w+, p3trace::accel::(?!stream)", f) for f in lanes)
stack = []
for line in open(sys.argv[1], errors="replace"):
    if line.startswith(("\t", " ")):
        stack.append(line.rstrip())
    elif not line.strip():
        count(stack)
        stack = []
count(stack)
n = max(samples, 1)
print(samples, f"{100 * (n - given) / n:.1f}%", f"{100 * (n - corrected) / n:.1f}%")
PY
}

echo "| scene, spp | run | tile-loop samples | outside traversal, render-profile | the shader's lane loops as shading |"
echo "|---|---|---|---|---|"
for scene in dragon balls_high mount_very_high; do
  for spp in 1 16; do
    for run in $(seq "$runs"); do
      perf record -q -F 1999 --call-graph dwarf,16384 -o "$out/perf.data" -- \
        target/release/p3trace render "$shared/scenes/$scene.p3f" --threads 1 --accel bvh \
        --no-skybox -q --spp "$spp" -o "$out/image.png" >/dev/null 2>"$out/err" ||
        { cat "$out/err" >&2; exit 1; }
      perf script -i "$out/perf.data" --inline 2>/dev/null >"$out/stacks.txt"
      read -r samples given corrected < <(shares "$out/stacks.txt")
      echo "| $scene, $spp | $run | $samples | $given | $corrected |"
    done
  done
done
