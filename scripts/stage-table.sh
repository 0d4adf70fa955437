#!/usr/bin/env bash
# The stream renderer's tile loop by stage (BENCHMARKS.md, issue 33): one render of SCENE
# (1 thread, SAH BVH, no skybox), its instructions counted by callgrind and its time
# sampled by perf, each instruction or sample put at the line of render/stream/ whose
# statement it serves through every inlined call (scripts/inline-lines.py), and the lines
# summed into the stages of scripts/stream-stages.txt. Prints a Markdown table; with
# --time, the time alone (no callgrind, which takes fifty times the render).
# Usage: scripts/stage-table.sh [--time] [SHARED_DIR] [SCENE] [SPP] [RESOLUTION]
#        (default ../shared mount_very_high 16, and the scene's own resolution)
set -euo pipefail
cd "$(dirname "$0")/.."
time_only=false
if [ "${1:-}" = --time ]; then time_only=true; shift; fi
shared=${1:-../shared}
scene=${2:-mount_very_high}
spp=${3:-16}
resolution=${4:+--resolution $4}
for tool in perf valgrind addr2line; do
  command -v "$tool" >/dev/null || { echo "stage-table: $tool is missing" >&2; exit 2; }
done
# The portable build (x86-64-v3): valgrind cannot run AVX-512, which the default build
# uses where the CPU has it.
RUSTFLAGS='-C target-cpu=x86-64-v3' cargo build --release --quiet --target-dir target/portable
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
binary=$out/p3trace   # a copy, so that a rebuild meanwhile cannot part the profiles
cp target/portable/release/p3trace "$binary"
render=("$binary" render "$shared/scenes/$scene.p3f" --threads 1 --accel bvh --no-skybox -q
        --spp "$spp" $resolution -o "$out/image.png")
perf record -q -e cpu-clock -F 20000 -o "$out/perf.data" -- "${render[@]}" 2>/dev/null
stages() {
  scripts/inline-lines.py "$@" "$binary" src/render/stream/ --expand shade_depth \
    --expand trace_hits --expand shade_lit --expand spawn \
    --stages scripts/stream-stages.txt --top 0
}
stages --perf "$out/perf.data" >"$out/time"
if ! $time_only; then
  valgrind --tool=callgrind --dump-instr=yes --callgrind-out-file="$out/cg.out" "${render[@]}" \
    2>/dev/null
  stages "$out/cg.out" >"$out/instructions"
fi
python3 - "$out/time" "$out/instructions" "$scene, ${4:-its resolution}, $spp spp" <<'PY'
import os, re, sys
def shares(path):
    """The loop's size and each stage's share, in the file's order."""
    lines = open(path).read().splitlines()
    size = lines[1].split()[0]
    rows = {}
    for line in lines[2:]:
        match = re.match(r"\s*[\d.,]+(?: M)?\s+([\d.]+)%\s+(.*?):?$", line)
        if match:
            rows[match.group(2)] = match.group(1) + "%"
    return size, rows
samples, by_time = shares(sys.argv[1])
columns = [by_time]
heading = f"{samples} samples (20 kHz)"
if os.path.exists(sys.argv[2]):
    instructions, by_count = shares(sys.argv[2])
    columns.insert(0, by_count)
    heading = f"{instructions} instructions and {heading}"
print(f"{sys.argv[3]}: {heading} in the tile loop\n")
print("| stage | " + ("instructions | " if len(columns) == 2 else "") + "time |")
print("|---" * (len(columns) + 1) + "|")
for stage in columns[0]:
    print(f"| {stage} | " + " | ".join(column.get(stage, "-") for column in columns) + " |")
PY
