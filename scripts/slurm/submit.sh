#!/usr/bin/env bash
# Renders SCENE on a Slurm cluster as a job array of TILES tasks, each one tile of the
# frame, and merges the parts into OUT once every task has succeeded:
#
#   scripts/slurm/submit.sh SCENE TILES OUT [render flags]
#
# The parts go to OUT.parts/ (beside OUT). Run it again with the same arguments after
# tasks were cancelled, preempted or failed: it submits only the tiles that
# `p3trace merge --missing` lists, then the merge. Prints `array=JOBID` (absent when no
# tile is missing) and `merge=JOBID`.
#
# Environment: P3TRACE, the p3trace binary (default: the one on PATH; every node must
# reach it and the scene at the same path); P3TRACE_PARTITIONS, binaries for the tiles of
# some partitions, as "PARTITION=BINARY ..." (say a build for AVX-512 for a partition of
# such nodes: every build renders the same image; the merge runs $P3TRACE);
# P3TRACE_CPUS, CPUs (and threads) per task (default 1); P3TRACE_SBATCH, more sbatch
# options (partitions, a time limit, ...).
set -euo pipefail
if [ $# -lt 3 ]; then
  echo "usage: $0 SCENE TILES OUT [render flags]" >&2
  exit 2
fi
here=$(cd "$(dirname "$0")" && pwd)
scene=$1 tiles=$2 out=$3
shift 3
case $tiles in '' | *[!0-9]* | 0) echo "$0: TILES must be a positive integer" >&2; exit 2 ;; esac
# Absolute paths: the jobs may start in another folder.
abs() { case $1 in /*) echo "$1" ;; *) echo "$PWD/$1" ;; esac; }
[ "$scene" = random ] || scene=$(abs "$scene")
out=$(abs "$out")
parts=$out.parts
P3TRACE=$(command -v "${P3TRACE:-p3trace}") || { echo "$0: no p3trace binary (set P3TRACE)" >&2; exit 2; }
export P3TRACE
for entry in ${P3TRACE_PARTITIONS:-}; do
  case $entry in
    ?*=/*) [ -x "${entry#*=}" ] || { echo "$0: P3TRACE_PARTITIONS: ${entry#*=} is not an executable" >&2; exit 2; } ;;
    *) echo "$0: P3TRACE_PARTITIONS: '$entry' is not PARTITION=/absolute/path/to/p3trace" >&2; exit 2 ;;
  esac
done
mkdir -p "$parts"
# Only the tiles without a part: all of them on the first run.
shopt -s nullglob
missing=$("$P3TRACE" merge --missing --tiles "$tiles" "$parts"/tile-*-of-"$tiles".exr)
sbatch_options=(--parsable --cpus-per-task="${P3TRACE_CPUS:-1}" ${P3TRACE_SBATCH:-})
dependency=()
if [ -n "$missing" ]; then
  # 0/8 1/8 2/8 5/8 -> 0-2,5: sbatch's array syntax, short however many tiles.
  array=$(echo "$missing" | cut -d/ -f1 | awk '
    NR == 1 { first = last = $1; next }
    $1 == last + 1 { last = $1; next }
    { printf "%s%s,", first, (last > first ? "-" last : ""); first = last = $1 }
    END { printf "%s%s\n", first, (last > first ? "-" last : "") }')
  job=$(sbatch "${sbatch_options[@]}" --array="$array" \
    --export=ALL,P3TRACE_TILES="$tiles" --output="$parts/slurm-%A_%a.out" \
    "$here/render-array.sbatch" "$scene" "$parts" "$@")
  job=${job%%;*}
  echo "array=$job"
  echo "submit: tiles $array of $tiles as job array $job" >&2
  dependency=(--dependency=afterok:"$job" --kill-on-invalid-dep=yes)
fi
merge=$(sbatch "${sbatch_options[@]}" "${dependency[@]}" --output="$parts/slurm-merge-%j.out" \
  "$here/merge.sbatch" "$parts" "$tiles" "$out")
merge=${merge%%;*}
echo "merge=$merge"
echo "submit: merge job $merge writes $out" >&2
