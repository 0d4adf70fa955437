#!/usr/bin/env bash
# The screenshot of docs/view.md: `p3trace view` on the showcase, under an X server of its
# own (Xvfb), turned by a left drag of 60 pixels to the right and 20 down, once converged;
# the window's picture as a PNG (xwd, then the Python standard library).
#
#   scripts/view-screenshot.sh                            # builds the release binary, writes docs/view.png
#   P3TRACE=path/to/p3trace OUT=file.png scripts/view-screenshot.sh
#
# Needs Xvfb, xdotool and xwd (as .ci/run installs them). The picture is deterministic:
# tests/integration/view.rs holds docs/view.png's pixels to this script's.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
if [[ -z "${P3TRACE:-}" ]]; then
    (cd "$root" && cargo build --release --quiet)
    P3TRACE="$root/target/release/p3trace"
fi
out="${OUT:-$root/docs/view.png}"
work=$(mktemp -d)
exec 3< <(exec Xvfb -displayfd 1 -screen 0 800x600x24 -nolisten tcp -noreset 2>/dev/null)
xvfb=$!
read -r -u 3 number
export DISPLAY=":$number"
viewer=
finish() {
    [[ -n "$viewer" ]] && kill "$viewer" 2>/dev/null
    kill -TERM "$xvfb" 2>/dev/null
    rm -rf "$work"
}
trap finish EXIT
"$P3TRACE" view "$root/scenes/showcase.p3f" --resolution 480x360 >/dev/null 2>"$work/log" &
viewer=$!
# Waits (10 s at most) until the window's title matches $1.
title_says() {
    for _ in $(seq 200); do
        if xdotool getwindowname "$window" 2>/dev/null | grep -q "$1"; then return 0; fi
        sleep 0.05
    done
    echo "view-screenshot: the title never said '$1'" >&2
    cat "$work/log" >&2
    exit 1
}
for _ in $(seq 200); do
    window=$(xdotool search --name '^showcase\.p3f' 2>/dev/null | head -1) && [[ -n "$window" ]] && break
    sleep 0.05
done
title_says '| 9/9 spp'
xdotool mousemove --window "$window" 200 200
sleep 0.2
xdotool mousedown 1
sleep 0.2
xdotool mousemove_relative -- 60 20
sleep 0.2
xdotool mouseup 1
sleep 0.2
title_says '| 9/9 spp'
xwd -silent -id "$window" > "$work/window.xwd"
python3 - "$work/window.xwd" "$out" <<'PY'
import struct, sys, zlib
data = open(sys.argv[1], "rb").read()
f = struct.unpack(">25I", data[:100])
header, width, height, lsb, bpp, line = f[0], f[4], f[5], f[7] == 0, f[11], f[12]
masks, colours = f[14:17], f[19]
assert bpp in (24, 32), bpp
pixels = data[header + 12 * colours:]
step, rows = bpp // 8, []
for y in range(height):
    row = bytearray([0])  # filter type: none
    for x in range(width):
        raw = pixels[y * line + x * step:y * line + (x + 1) * step]
        p = int.from_bytes(raw, "little" if lsb else "big")
        for m in masks:
            row.append((p & m) >> (m & -m).bit_length() - 1)
    rows.append(bytes(row))
def chunk(kind, body):
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
png += chunk(b"IDAT", zlib.compress(b"".join(rows), 9)) + chunk(b"IEND", b"")
open(sys.argv[2], "wb").write(png)
PY
xdotool key --window "$window" Escape 2>/dev/null || true
wait "$viewer"
viewer=
echo "view-screenshot: wrote $out"
