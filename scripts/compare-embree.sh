#!/usr/bin/env bash
# Runs the trace-throughput protocol (../shared/bench/PROTOCOL.md) on a scene with
# p3trace and with Intel Embree, checks that their answers agree, and prints per ray set
# and thread count both hit counts and tsums, whether they agree, and the throughput
# ratio p3trace-best / embree-best. Exits 1 when any set disagrees.
#
#   scripts/compare-embree.sh SCENE.p3f [p3trace bench options, e.g. --accel grid]
#
# The Embree side (../shared/bench/embree-compare) installs Debian's libembree-dev when it
# is missing and compiles a small harness outside the repository. Not part of CI.
set -euo pipefail

if [ $# -lt 1 ]; then
    sed -n '2,10p' "$0" >&2
    exit 2
fi
scene="$1"
shift
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
shared="${P3TRACE_SHARED:-$repo/../shared}"
cargo build --release --quiet --manifest-path "$repo/Cargo.toml"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

"$repo/target/release/p3trace" bench "$scene" "$@" >"$work/p3trace.txt"
"$shared/bench/embree-compare" "$scene" >"$work/embree.txt"
grep '^#' "$work/p3trace.txt" | grep -E 'structure|cpu' || true
grep '^#' "$work/embree.txt" | grep -E 'build_s|embree [0-9]' || true

# Fields: ray-set api threads rays hits tsum mrays_per_s. Tolerance: 0.05% of the rays
# for hits, 0.05% for tsum (PROTOCOL.md, "Agreement").
awk '
    FNR == 1 { file++ }
    /^#/ || NF < 7 { next }
    file == 1 && $2 == "p3trace-best" { key = $1 " " $3; ph[key] = $5; pt[key] = $6; pm[key] = $7; n[key] = $4; order[++count] = key }
    file == 2 && $2 == "embree-best" { key = $1 " " $3; eh[key] = $5; et[key] = $6; em[key] = $7 }
    END {
        printf "%-10s %7s %9s %9s %16s %16s %6s %9s %9s %7s\n", "ray-set", "threads", "hits", "embree", "tsum", "embree", "agree", "p3trace", "embree", "ratio"
        bad = 0; logsum = 0; ones = 0
        for (i = 1; i <= count; i++) {
            key = order[i]
            if (!(key in eh)) { print "no Embree line for " key; bad = 1; continue }
            dh = ph[key] - eh[key]; if (dh < 0) dh = -dh
            dt = pt[key] - et[key]; if (dt < 0) dt = -dt
            ref = et[key] < 0 ? -et[key] : et[key]
            ok = (dh <= 0.0005 * n[key]) && (dt <= 0.0005 * ref)
            if (!ok) bad = 1
            split(key, k, " ")
            if (k[2] == 1 && em[key] > 0 && pm[key] > 0) { logsum += log(pm[key] / em[key]); ones++ }
            if (dh <= 0.0005 * n[key] && !ok) tsum_only = 1
            printf "%-10s %7s %9d %9d %16.3f %16.3f %6s %9.2f %9.2f %7.3f\n", k[1], k[2], ph[key], eh[key], pt[key], et[key], ok ? "yes" : "NO", pm[key], em[key], (em[key] > 0 ? pm[key] / em[key] : 0)
        }
        if (ones > 0) printf "geometric mean of the 1-thread ratios: %.3f\n", exp(logsum / ones)
        if (tsum_only) print "note: a tsum that disagrees while the hits agree comes from grazing rays on an infinite plane (BENCHMARKS.md, \"Agreement\")"
        exit bad
    }
' "$work/p3trace.txt" "$work/embree.txt"
