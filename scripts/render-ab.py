#!/usr/bin/env python3
"""Times two or more p3trace binaries on one render, as a ratio with an interval.

Each round runs every binary once, in turn (the order reversed every other round), on
one CPU (`taskset`, where there is one to spare), rendering SCENE with 1 thread, the
SAH BVH and no skybox; it reads the render time alone (`render_s` of `--json -`), not
loading or building. For each binary it prints the least, the first quartile, the
median and the mean of its faster half of rounds (the slower half holds what the
neighbours on a shared machine took); for each binary after the first, the first's
faster-half mean over its own, with a 95% bootstrap interval (2,000 resamples, fixed
seed). The same binary twice gives 1.000 within about 0.5% at 20 rounds on a quiet
machine: below that, instruction counts (callgrind) tell where work went, not whether
time did. The images of the first round must be the same bytes, or it says so.

Usage: scripts/render-ab.py [--rounds N] [--spp N] [--resolution WxH] [--cpu C]
                            SCENE BINARY_A BINARY_B [BINARY ...]
e.g.   scripts/render-ab.py ../shared/scenes/mount_very_high.p3f old/p3trace \\
           target/release/p3trace
Exit status 2 when a render fails or prints no render time.
"""

import argparse
import hashlib
import json
import os
import random
import shutil
import statistics
import subprocess
import sys
import tempfile


def faster_half_mean(times):
    faster = sorted(times)[: max(len(times) // 2, 1)]
    return sum(faster) / len(faster)


def render(binary, args, image, pin):
    command = [binary, "render", args.scene, "--threads", "1", "--accel", "bvh",
               "--no-skybox", "-q", "--spp", str(args.spp), "-o", image, "--json", "-"]
    if args.resolution:
        command += ["--resolution", args.resolution]
    run = subprocess.run(pin + command, capture_output=True, text=True)
    try:
        return float(json.loads(run.stdout)["render_s"])
    except (ValueError, KeyError, TypeError):
        print(f"render-ab: {binary} failed (exit {run.returncode}): {run.stderr.strip()[-300:]}",
              file=sys.stderr)
        sys.exit(2)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=20, help="rounds (20)")
    parser.add_argument("--spp", type=int, default=16, help="samples per pixel (16)")
    parser.add_argument("--resolution", help="WxH (the scene's own)")
    parser.add_argument("--cpu", type=int, default=1, help="the CPU to pin to (1)")
    parser.add_argument("scene")
    parser.add_argument("binaries", nargs="+")
    args = parser.parse_args()
    if len(args.binaries) < 2:
        parser.error("give two binaries or more")
    if args.rounds < 2:
        parser.error("give two rounds or more")
    cpus = os.cpu_count() or 1
    pin = ["taskset", "-c", str(args.cpu)] if shutil.which("taskset") and cpus > 1 else []
    times = {i: [] for i in range(len(args.binaries))}
    digests = {}
    with tempfile.TemporaryDirectory() as out:
        for round_ in range(args.rounds):
            order = list(times) if round_ % 2 == 0 else list(times)[::-1]
            for i in order:
                image = os.path.join(out, f"{i}.png")
                times[i].append(render(args.binaries[i], args, image, pin))
                if round_ == 0:
                    with open(image, "rb") as file:
                        digests[i] = hashlib.sha256(file.read()).hexdigest()
    width = max(len(b) for b in args.binaries)
    for i, binary in enumerate(args.binaries):
        t = sorted(times[i])
        print(f"{binary:{width}}  least {t[0]:.4f} s  quartile {t[len(t) // 4]:.4f} s  "
              f"median {statistics.median(t):.4f} s  faster half {faster_half_mean(t):.4f} s")
    rng = random.Random(1)
    first = args.binaries[0]
    for i in range(1, len(args.binaries)):
        ratio = faster_half_mean(times[0]) / faster_half_mean(times[i])
        resampled = sorted(
            faster_half_mean(rng.choices(times[0], k=len(times[0])))
            / faster_half_mean(rng.choices(times[i], k=len(times[i])))
            for _ in range(2000))
        print(f"{first} / {args.binaries[i]}: {ratio:.4f} "
              f"(95%: {resampled[50]:.4f} - {resampled[1949]:.4f})")
    if len(set(digests.values())) > 1:
        print("render-ab: the images differ", file=sys.stderr)


if __name__ == "__main__":
    main()
