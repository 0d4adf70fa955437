#!/usr/bin/env python3
"""The scale curve: the trace-throughput protocol on generated scenes of every size.

Generates `p3trace gen mount --level L` (2 * 4^L triangles) and `p3trace gen balls --depth D`
(the sphereflake) for the levels and depths asked for, runs the protocol of
../shared/bench/PROTOCOL.md on each with 1 thread, with `p3trace bench`, with Intel Embree
(../shared/bench/embree-compare, the best of its APIs and of its medium and high builds)
and, on the meshes, with tinybvh (../shared/bench/tinybvh-compare, triangles only), and prints
per scene:

- the ratio p3trace-best / the best anchor per ray set, their geometric mean and the lowest,
  and p3trace's and Embree's build time (each on the one thread it traces with) and peak
  memory;
- each tracer's Mrays/s per set, its build time and the peak resident memory of its
  process (the scene, the structure and the protocol's rays; `wait4`'s maxrss);
- with --renders, a whole Whitted render of the scene (its resolution, 1 spp, 1 thread):
  Embree's render time (../shared/bench/embree-render --best, its fastest mode) over
  p3trace's (`render --json`'s render_s), the least of --render-reps each.

With --rounds N every tracer runs N times per scene, in turn (p3trace, Embree, tinybvh, then
the renders, then again), and each figure is its tracer's best over the rounds: the fastest
Mrays/s per set, the least build and render time, the largest peak memory. A shared machine's
load comes and goes over minutes; rounds give each tracer the same spread of it.

Results are kept in DIR (default target/scale-curve), one file per scene, tracer and round
(`NAME.TRACER.txt`, then `NAME.TRACER.r2.txt` and on), with a last comment line
`# scale-curve peak_rss_kib K wall_s S`; --reuse reads a scene's results from there
instead of running it again, so a long curve can be resumed or redrawn. --plot
draws Mrays/s against the primitive count, one panel per ray set, one line per tracer and
family (matplotlib, scripts/requirements.txt). --markdown writes the tables for BENCHMARKS.md.

Exit status 1 when p3trace and Embree disagree on a set (PROTOCOL.md's rule: hits and tsum
within 0.05%), 2 for bad arguments or a tracer that fails.
"""

import argparse
import json
import math
import os
import re
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
SETS = ("primary", "shadow", "reflection")
TRACERS = ("p3trace", "embree", "tinybvh")
# p3trace in blue, Embree in orange (as in bench-chart.py), tinybvh in green.
COLOURS = {"p3trace": "#1f4e9c", "embree": "#c8560f", "tinybvh": "#2a8c4a"}
FAMILIES = {"mount": ("o", "-"), "balls": ("s", "--")}
TRAILER = re.compile(r"^# scale-curve peak_rss_kib (\d+) wall_s ([0-9.]+)$", re.M)
RENDER_TRAILER = re.compile(r"^# scale-curve render_s ([0-9.]+)$", re.M)


class Failure(Exception):
    """A bad argument or a tracer that failed: one line on stderr, exit status 2."""


def span(text):
    """'5-11' or '7' as a list of integers."""
    low, _, high = text.partition("-")
    try:
        low, high = int(low), int(high or low)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected N or N-M, found {text!r}") from None
    if low > high:
        raise argparse.ArgumentTypeError(f"{text!r} runs backwards")
    return list(range(low, high + 1))


def run(command, out_path):
    """Runs `command` with its output to `out_path`, appends the peak memory of the process
    and its children and the wall time, and returns the text."""
    start = time.monotonic()
    with open(out_path, "w") as out, open(str(out_path) + ".err", "w+") as err:
        try:
            process = subprocess.Popen(command, stdout=out, stderr=err)
        except OSError as e:
            raise Failure(f"{command[0]}: {e.strerror}") from None
        # wait4 reports the largest resident set of the process and of the children it
        # waited for (embree-compare's harness, tinybvh-compare's dump).
        _, status, usage = os.wait4(process.pid, 0)
        process.returncode = os.waitstatus_to_exitcode(status)
        err.seek(0)
        message = err.read().strip().splitlines()[-3:]
    wall = time.monotonic() - start
    if process.returncode != 0:
        raise Failure(f"{' '.join(map(str, command))} exited {process.returncode}: {' / '.join(message)}")
    with open(out_path, "a") as out:
        out.write(f"# scale-curve peak_rss_kib {usage.ru_maxrss} wall_s {wall:.1f}\n")
    return Path(out_path).read_text()


def parse(tracer, text, where):
    """The 1-thread best line per set, the build time and the peak memory of one result."""
    result = {"sets": {}, "build_s": None, "primitives": None}
    for line in text.splitlines():
        fields = line.split()
        if len(fields) == 7 and fields[1] == f"{tracer}-best" and fields[2] == "1":
            result["sets"][fields[0]] = {
                "rays": int(fields[3]),
                "hits": int(fields[4]),
                "tsum": float(fields[5]),
                "mrays": float(fields[6]),
            }
        elif tracer == "p3trace" and (m := re.match(r"# structure .*build_s ([0-9.]+)", line)):
            result["build_s"] = float(m[1])
        elif tracer == "p3trace" and (m := re.match(r"# geometry (\d+) bounded objects?, (\d+) planes?", line)):
            result["primitives"] = int(m[1]) + int(m[2])
        elif tracer == "embree" and (m := re.match(r"# build_s ([0-9.]+) \(quality medium", line)):
            result["build_s"] = float(m[1])
        elif tracer == "tinybvh" and (m := re.match(r"# build_s bvh8cpu ([0-9.]+)", line)):
            result["build_s"] = float(m[1])
    trailer = TRAILER.search(text)
    if not trailer or set(result["sets"]) != set(SETS):
        raise Failure(f"{where}: not a complete {tracer} result: a {tracer}-best line at 1 thread "
                      "for every ray set, and the peak memory, are needed")
    result["peak_mib"] = int(trailer[1]) / 1024
    return result


def agree(ours, theirs):
    """PROTOCOL.md's agreement rule for one set: hits within 0.05% of the rays, tsums
    within 0.05% of each other."""
    hits_ok = abs(ours["hits"] - theirs["hits"]) <= 0.0005 * ours["rays"]
    tsum_ok = abs(ours["tsum"] - theirs["tsum"]) <= 0.0005 * abs(theirs["tsum"])
    return hits_ok and tsum_ok


def kept(name, round_):
    """The file name of round `round_`'s result of `name` (a scene and tracer)."""
    return f"{name}.txt" if round_ == 1 else f"{name}.r{round_}.txt"


def best_of(rounds):
    """One tracer's results of several rounds as one: each figure at its best."""
    best = dict(rounds[0])
    best["sets"] = {s: max((r["sets"][s] for r in rounds), key=lambda x: x["mrays"]) for s in SETS}
    builds = [r["build_s"] for r in rounds if r["build_s"] is not None]
    best["build_s"] = min(builds) if builds else None
    best["peak_mib"] = max(r["peak_mib"] for r in rounds)
    return best


def measure(args, family, size):
    """Generates one scene and returns {tracer: result} for the tracers that take it, each
    the best of its --rounds."""
    name = f"{family}_{size}"
    scene = args.dir / f"{name}.p3f"
    flag = "--level" if family == "mount" else "--depth"
    if not (args.reuse and scene.exists()):
        subprocess.run([args.p3trace, "gen", family, flag, str(size), "--no-env", "-o", scene], check=True)
    commands = {"p3trace": [args.p3trace, "bench"]}
    if args.embree:
        commands["embree"] = [args.embree]
    if args.tinybvh and family == "mount":
        commands["tinybvh"] = [args.tinybvh]
    rounds = {tracer: [] for tracer in commands}
    render_times = []
    for round_ in range(1, args.rounds + 1):
        for tracer, command in commands.items():
            path = args.dir / kept(f"{name}.{tracer}", round_)
            text = path.read_text() if args.reuse and path.exists() else None
            if text is None or not TRAILER.search(text):
                print(f"scale-curve: {name}: {tracer}, round {round_}", file=sys.stderr, flush=True)
                text = run(command + [scene, "--threads", "1", "--reps", str(args.reps)], path)
            rounds[tracer].append(parse(tracer, text, path))
        if args.renders:
            render_times.append(renders(args, name, scene, round_))
    results = {tracer: best_of(r) for tracer, r in rounds.items()}
    if args.renders:
        results["p3trace"]["render"] = min(t["embree"] for t in render_times) / min(
            t["p3trace"] for t in render_times
        )
    return name, family, results


def least_render(tracer, text, where):
    """The least render time of one tracer's render results."""
    times = []
    for line in text.splitlines():
        if tracer == "p3trace" and line.startswith("{"):
            times.append(float(json.loads(line)["render_s"]))
        elif tracer == "embree" and len(fields := line.split()) == 8 and fields[4] == "best":
            times.append(float(fields[5]))
    if not times:
        raise Failure(f"{where}: no render time in the {tracer} render result")
    return min(times)


def renders(args, name, scene, round_):
    """p3trace's and Embree's least render times of round `round_`, each kept in DIR as its
    runs' output and a last line `# scale-curve render_s S`."""
    least = {}
    for tracer in ("p3trace", "embree"):
        path = args.dir / kept(f"{name}.render.{tracer}", round_)
        text = path.read_text() if args.reuse and path.exists() else None
        if text is None or not RENDER_TRAILER.search(text):
            print(f"scale-curve: {name}: {tracer} render, round {round_}", file=sys.stderr, flush=True)
            if tracer == "p3trace":
                image = args.dir / f"{name}.png"
                command = [args.p3trace, "render", scene, "--threads", "1", "--accel", "bvh",
                           "--no-skybox", "-q", "-o", image, "--json", "-"]
                # Each run's document on a line of its own, without the memory trailer.
                runs = [TRAILER.sub("", run(command, path)) for _ in range(args.render_reps)]
                text = "".join(json.dumps(json.loads(r)) + "\n" for r in runs)
            else:
                command = [args.embree_render, scene, "--threads", "1", "--best", "--reps", str(args.render_reps)]
                text = run(command, path)
            text += f"# scale-curve render_s {least_render(tracer, text, path)}\n"
            path.write_text(text)
        least[tracer] = float(RENDER_TRAILER.search(text)[1])
    return least


def geomean(values):
    return math.exp(sum(map(math.log, values)) / len(values))


def both(results, field, form):
    """`field` of p3trace's result, then of Embree's where it ran, as 'A / B'."""
    return " / ".join(
        "-" if results[t][field] is None else form.format(results[t][field])
        for t in ("p3trace", "embree")
        if t in results
    )


def tables(rows):
    """The Markdown tables: ratios, then each tracer's figures."""
    with_renders = any("render" in results["p3trace"] for _, _, results in rows)
    out = [
        "| scene | primitives | primary | shadow | reflection | geomean | lowest | build s | peak MiB |"
        + (" render |" if with_renders else ""),
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|" + ("---:|" if with_renders else ""),
    ]
    for name, _, results in rows:
        ours = results["p3trace"]
        ratios = []
        cells = []
        for ray_set in SETS:
            anchors = [(r["sets"][ray_set]["mrays"], t) for t, r in results.items() if t != "p3trace"]
            if not anchors:
                cells.append("-")
                continue
            best, who = max(anchors)
            ratio = ours["sets"][ray_set]["mrays"] / best
            ratios.append(ratio)
            cells.append(f"{ratio:.2f} ({who[0].upper()})")
        summary = [f"{geomean(ratios):.2f}", f"{min(ratios):.2f}"] if ratios else ["-", "-"]
        summary += [both(results, "build_s", "{:.3f}"), both(results, "peak_mib", "{:.0f}")]
        if with_renders:
            render = ours.get("render")
            summary.append("-" if render is None else f"{render:.2f}")
        out.append(f"| {name} | {ours['primitives']:,} | " + " | ".join(cells + summary) + " |")
    out += [
        "",
        "| scene | tracer | primary | shadow | reflection | build s | peak MiB |",
        "|---|---|---:|---:|---:|---:|---:|",
    ]
    for name, _, results in rows:
        for tracer, r in results.items():
            rates = " | ".join(f"{r['sets'][s]['mrays']:.2f}" for s in SETS)
            build = "-" if r["build_s"] is None else f"{r['build_s']:.3f}"
            out.append(f"| {name} | {tracer} | {rates} | {build} | {r['peak_mib']:.0f} |")
    return "\n".join(out) + "\n"


def plot(rows, path, title):
    try:
        import matplotlib
    except ImportError:
        raise Failure("matplotlib is missing: python3 -m pip install -r scripts/requirements.txt") from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(SETS), figsize=(13, 4.4), dpi=100, layout="constrained")
    for ax, ray_set in zip(axes, SETS):
        for family, (marker, style) in FAMILIES.items():
            for tracer in TRACERS:
                points = sorted(
                    (r["p3trace"]["primitives"], r[tracer]["sets"][ray_set]["mrays"])
                    for _, f, r in rows
                    if f == family and tracer in r
                )
                if points:
                    xs, ys = zip(*points)
                    label = f"{tracer}, gen {family}"
                    ax.plot(xs, ys, style, marker=marker, color=COLOURS[tracer], label=label)
        ax.set_xscale("log")
        ax.set_ylim(bottom=0)
        ax.set_title(ray_set, fontsize=10)
        ax.set_xlabel("primitives")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("Mrays/s, 1 thread (higher is better)")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=len(labels), fontsize=8, frameon=False)
    fig.suptitle(title, fontsize=10)
    try:
        fig.savefig(path)
    except (OSError, ValueError) as e:
        raise Failure(f"{path}: cannot write: {e}") from None


def main(argv=None):
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--mount", type=span, default=span("5-11"), metavar="L-M",
                        help="levels of gen mount (default 5-11; at 12 tinybvh needs some 40 GiB: --tinybvh '')")
    parser.add_argument("--balls", type=span, default=span("4-6"), metavar="D-E",
                        help="depths of gen balls (default 4-6)")
    parser.add_argument("--no-mount", action="store_true", help="no meshes")
    parser.add_argument("--no-balls", action="store_true", help="no sphereflakes")
    parser.add_argument("--reps", type=int, default=7, help="passes per set; the best counts (default 7)")
    parser.add_argument("--rounds", type=int, default=1,
                        help="runs of every tracer per scene, in turn; the best counts (default 1)")
    parser.add_argument("--dir", type=Path, default=REPO / "target" / "scale-curve",
                        help="where the scenes and results go (default target/scale-curve)")
    parser.add_argument("--reuse", action="store_true",
                        help="read the results DIR holds instead of running again")
    parser.add_argument("--p3trace", type=Path,
                        help="the binary (default: cargo build --release, then target/release/p3trace)")
    shared = Path(os.environ.get("P3TRACE_SHARED", REPO.parent / "shared"))
    parser.add_argument("--embree", default=str(shared / "bench" / "embree-compare"),
                        help="the Embree anchor command ('' for none)")
    parser.add_argument("--tinybvh", default=str(shared / "bench" / "tinybvh-compare"),
                        help="the tinybvh anchor command ('' for none)")
    parser.add_argument("--renders", action="store_true",
                        help="also time a whole render of each scene against embree-render's")
    parser.add_argument("--render-reps", type=int, default=3,
                        help="renders per tracer and scene; the least time counts (default 3)")
    parser.add_argument("--embree-render", default=str(shared / "bench" / "embree-render"),
                        help="the Embree render command, for --renders")
    parser.add_argument("--plot", type=Path, help="draw the curve into this PNG")
    parser.add_argument("--title", default="The protocol's ray sets against scene size",
                        help="the plot's title")
    parser.add_argument("--markdown", type=Path, help="also write the tables to this file")
    args = parser.parse_args(argv)
    try:
        if args.p3trace is None:
            build = ["cargo", "build", "--release", "--quiet", "--manifest-path", REPO / "Cargo.toml"]
            subprocess.run(build, check=True)
            args.p3trace = REPO / "target" / "release" / "p3trace"
        for anchor in ("embree", "tinybvh"):
            command = getattr(args, anchor)
            if command and not os.access(command, os.X_OK):
                print(f"scale-curve: {command} is not there: no {anchor} figures", file=sys.stderr)
                setattr(args, anchor, None)
        if args.rounds < 1:
            raise Failure(f"--rounds {args.rounds}: at least 1")
        if args.renders and not os.access(args.embree_render, os.X_OK):
            raise Failure(f"--renders: {args.embree_render} is not there")
        args.dir.mkdir(parents=True, exist_ok=True)
        scenes = ([] if args.no_mount else [("mount", n) for n in args.mount]) + (
            [] if args.no_balls else [("balls", n) for n in args.balls]
        )
        rows = [measure(args, family, size) for family, size in scenes]
        text = tables(rows)
        print(text, end="")
        if args.markdown:
            args.markdown.write_text(text)
        if args.plot:
            plot(rows, args.plot, args.title)
    except Failure as e:
        print(f"scale-curve: {e}", file=sys.stderr)
        return 2
    except subprocess.CalledProcessError as e:
        print(f"scale-curve: {e}", file=sys.stderr)
        return 2
    disagree = [
        f"{name} {s}"
        for name, _, results in rows
        if "embree" in results
        for s in SETS
        if not agree(results["p3trace"]["sets"][s], results["embree"]["sets"][s])
    ]
    if disagree:
        print(f"scale-curve: p3trace and Embree disagree on {', '.join(disagree)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
