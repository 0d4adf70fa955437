#!/usr/bin/env python3
"""Draws a bar chart (PNG) of trace throughput, p3trace against Intel Embree.

Reads the results of the trace-throughput protocol (../shared/bench/PROTOCOL.md):
`p3trace bench SCENE --json FILE` objects, `p3trace bench SCENE` text output, and the
text output of ../shared/bench/embree-compare. Text results are lines
`ray-set api threads rays hits tsum mrays_per_s` plus '#' comments; the scene comes from
the '# scene PATH' comment (JSON: the "scene" field), and a scene's p3trace and Embree
files are paired by that name (its file name without '.p3f'), so the files may be given
in any order.

The chart has one group of bars per scene and ray set (primary, shadow, reflection) at
one thread count: p3trace-best and embree-best (with --all-apis also every single API),
in Mrays/s, each group labelled with the ratio p3trace-best / embree-best.

Exit status 2, with a message naming the file (and line), when an input is malformed or
incomplete or the chart cannot be written; 1 when matplotlib is missing.
The Python packages it needs are pinned in scripts/requirements.txt.
"""

import argparse
import datetime
import json
import math
import os
import re
import sys

TRACERS = ("p3trace", "embree")
# Each tracer's APIs in this order with --all-apis (the part after 'p3trace-', 'embree-').
API_ORDER = ("best", "single", "packet8", "packet16", "stream")
# Protocol order first; a ray set the protocol does not name goes after these.
SET_ORDER = ("primary", "shadow", "reflection")
TEXT_FIELDS = "ray-set api threads rays hits tsum mrays_per_s"
# (JSON key, type) of one result, in the order of the text line's fields.
FIELDS = (
    ("ray_set", str),
    ("api", str),
    ("threads", int),
    ("rays", int),
    ("hits", int),
    ("tsum", float),
    ("mrays_per_s", float),
)
JSON_TYPES = {str: "a string", int: "an integer", float: "a number"}


class InputError(Exception):
    """A user's mistake: printed as one line, exit status 2, no traceback."""


class Results:
    """What one file says: its scene, tracer, CPU, passes and result lines."""

    def __init__(self, path):
        self.path = path
        self.scene = None
        self.cpu = None
        self.reps = None
        self.structure = None
        # (ray_set, api, threads) -> Mrays/s
        self.mrays = {}
        self.tracer = None

    def add(self, where, ray_set, api, threads, mrays):
        tracer = api.split("-", 1)[0]
        if tracer not in TRACERS or "-" not in api:
            raise InputError(f"{where}: unknown api '{api}' (expected p3trace-* or embree-*)")
        if self.tracer not in (None, tracer):
            raise InputError(f"{where}: {api} line in a file of {self.tracer} results")
        if threads < 1 or not math.isfinite(mrays) or mrays < 0:
            raise InputError(f"{where}: threads must be >= 1 and mrays_per_s a finite number >= 0")
        if (ray_set, api, threads) in self.mrays:
            raise InputError(f"{where}: a second '{ray_set} {api} {threads}' result")
        self.tracer = tracer
        self.mrays[(ray_set, api, threads)] = mrays


def scene_key(name):
    """'../shared/scenes/balls_high.p3f' and 'balls_high.p3f' both name 'balls_high'."""
    base = os.path.basename(name.strip())
    return base[:-4] if base.endswith(".p3f") else base


def parse_text(path, text):
    r = Results(path)
    for number, line in enumerate(text.splitlines(), 1):
        where = f"{path}:{number}"
        fields = line.split()
        if not fields:
            continue
        if fields[0].startswith("#"):
            comment = line.lstrip()[1:].strip()
            # The comments of both p3trace bench and embree_p3f.c:
            # '# scene PATH', '# cpu MODEL, N logical CPUs; best of R passes',
            # and p3trace's '# structure NAME, build_s S'.
            if m := re.fullmatch(r"scene\s+(.+)", comment):
                r.scene = scene_key(m.group(1))
            elif m := re.fullmatch(r"cpu\s+(.+), \d+ logical CPUs?; best of (\d+) pass(es)?", comment):
                r.cpu, r.reps = m.group(1), int(m.group(2))
            elif m := re.fullmatch(r"structure\s+(.+), build_s \S+", comment):
                r.structure = m.group(1)
            continue
        if len(fields) != len(FIELDS):
            raise InputError(
                f"{where}: expected the {len(FIELDS)} fields '{TEXT_FIELDS}', "
                f"got {len(fields)}: {line.strip()!r}"
            )
        try:
            values = [kind(field) for (_, kind), field in zip(FIELDS, fields)]
        except ValueError:
            raise InputError(
                f"{where}: expected '{TEXT_FIELDS}' with numbers, got {line.strip()!r}"
            ) from None
        ray_set, api, threads, _, _, _, mrays = values
        r.add(where, ray_set, api, threads, mrays)
    return r


def parse_json(path, text):
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as e:
        raise InputError(f"{path}:{e.lineno}:{e.colno}: invalid JSON: {e.msg}") from None
    if not isinstance(doc, dict):
        raise InputError(f"{path}: expected one JSON object, as 'p3trace bench --json' writes")
    r = Results(path)
    if not isinstance(doc.get("scene"), str):
        raise InputError(f"{path}: no \"scene\" string")
    r.scene = scene_key(doc["scene"])
    # CPU, passes and structure only label the chart: take them when they are there.
    cpu = doc.get("cpu")
    if isinstance(cpu, dict) and isinstance(cpu.get("model"), str):
        r.cpu = cpu["model"]
    if isinstance(doc.get("reps"), int):
        r.reps = doc["reps"]
    structure = doc.get("structure")
    if isinstance(structure, dict) and isinstance(structure.get("name"), str):
        r.structure = structure["name"]
    lines = doc.get("lines")
    if not isinstance(lines, list):
        raise InputError(f"{path}: no \"lines\" list")
    for i, entry in enumerate(lines):
        where = f"{path}: lines[{i}]"
        if not isinstance(entry, dict):
            raise InputError(f"{where}: expected an object")
        for key, kind in FIELDS:
            value = entry.get(key)
            # JSON has one number type: an integer is a fine float, a bool is no number.
            ok = isinstance(value, kind) or (kind is float and isinstance(value, int))
            if not ok or isinstance(value, bool):
                raise InputError(f"{where}: \"{key}\" must be {JSON_TYPES[kind]}, got {json.dumps(value)}")
        r.add(where, entry["ray_set"], entry["api"], entry["threads"], float(entry["mrays_per_s"]))
    return r


def read_results(path):
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"{path}: cannot read: {e.strerror if isinstance(e, OSError) else e}") from None
    r = parse_json(path, text) if text.lstrip().startswith("{") else parse_text(path, text)
    if r.scene is None:
        raise InputError(f"{path}: no '# scene NAME' comment, so its scene is unknown")
    if r.tracer is None:
        raise InputError(f"{path}: no result lines '{TEXT_FIELDS}'")
    return r


def pair_by_scene(results):
    """{scene: {tracer: Results}}, in the order the scenes first appear."""
    scenes = {}
    for r in results:
        sides = scenes.setdefault(r.scene, {})
        if r.tracer in sides:
            first = sides[r.tracer].path
            raise InputError(f"{r.path}: a second {r.tracer} file for scene {r.scene} (first: {first})")
        sides[r.tracer] = r
    for scene, sides in scenes.items():
        for tracer in TRACERS:
            if tracer not in sides:
                other = next(iter(sides.values()))
                raise InputError(f"{other.path}: scene {scene} has no {tracer} file to compare with")
    return scenes


def groups(scenes, threads, apis):
    """One (label, {api: Mrays/s}, ratio) per scene and ray set."""
    out = []
    for scene, sides in scenes.items():
        sets = {s for r in sides.values() for (s, _, t) in r.mrays if t == threads}
        if not sets:
            path = sides["p3trace"].path
            raise InputError(f"{path}: no results with {threads} thread(s) for scene {scene}")
        for ray_set in sorted(sets, key=lambda s: (SET_ORDER + (s,)).index(s)):
            values = {}
            for api in apis:
                r = sides[api.split("-", 1)[0]]
                if (ray_set, api, threads) in r.mrays:
                    values[api] = r.mrays[(ray_set, api, threads)]
            for tracer in TRACERS:
                if f"{tracer}-best" not in values:
                    raise InputError(f"{sides[tracer].path}: no '{ray_set} {tracer}-best {threads}' line")
            embree = values["embree-best"]
            ratio = values["p3trace-best"] / embree if embree > 0 else math.nan
            out.append((f"{scene}\n{ray_set}", values, ratio))
    return out


def draw(rows, apis, title, out, labels):
    # Imported here, so that malformed input is reported even without matplotlib. Agg
    # draws to files without a display, as on CI and on headless machines.
    try:
        import matplotlib
    except ImportError:
        sys.exit("bench-chart: matplotlib is missing: python3 -m pip install -r scripts/requirements.txt")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    # p3trace in blues, Embree in oranges; the best of each tracer darkest.
    palette = {
        "p3trace-best": "#1f4e9c",
        "p3trace-single": "#9ab8e6",
        "p3trace-packet8": "#5b86c9",
        "p3trace-stream": "#c9d9f2",
        "embree-best": "#c8560f",
        "embree-single": "#f7c79a",
        "embree-packet8": "#f1a45f",
        "embree-packet16": "#e8843a",
        "embree-stream": "#fbe2c8",
    }
    width = 0.8 / len(apis)
    # "constrained" makes room for the legend below the axes, where it hides no bar.
    size = (max(6.0, 1.2 * len(rows) + 1.5), 5)
    fig, ax = plt.subplots(figsize=size, dpi=100, layout="constrained")
    for k, api in enumerate(apis):
        xs = [i + (k - (len(apis) - 1) / 2) * width for i, (_, v, _) in enumerate(rows) if api in v]
        ys = [v[api] for (_, v, _) in rows if api in v]
        ax.bar(xs, ys, width, label=labels.get(api, api), color=palette.get(api, "#888888"))
    top = max(v for (_, values, _) in rows for v in values.values())
    for i, (_, values, ratio) in enumerate(rows):
        if not math.isnan(ratio):
            ax.annotate(
                f"{ratio:.2f}x",
                (i, max(values.values())),
                xytext=(0, 4),
                textcoords="offset points",
                ha="center",
                fontsize=9,
                fontweight="bold",
            )
    ax.set_ylim(0, top * 1.12)  # room for the ratios above the tallest bars
    ax.set_xticks(range(len(rows)), [label for (label, _, _) in rows], fontsize=8)
    ax.set_ylabel("Mrays/s (higher is better)")
    ax.set_title(title, fontsize=10)
    ax.grid(axis="y", alpha=0.3)
    ax.set_axisbelow(True)
    # One legend row per tracer: matplotlib fills the columns top to bottom, so the
    # entries go in p3trace/Embree pairs, a blank where one tracer has fewer APIs.
    entries = {api: entry for api, *entry in zip(apis, *ax.get_legend_handles_labels())}
    by_tracer = [[a for a in apis if a.startswith(t + "-")] for t in TRACERS]
    columns = max(map(len, by_tracer))
    blank = [Patch(visible=False), ""]
    pairs = [entries[r[c]] if c < len(r) else blank for c in range(columns) for r in by_tracer]
    fig.legend(
        *zip(*pairs),
        loc="outside lower center",
        ncol=columns,
        fontsize=8,
        title="above each group: p3trace-best / embree-best",
        title_fontsize=8,
        frameon=False,
    )
    try:
        fig.savefig(out)
    except OSError as e:
        raise InputError(f"{out}: cannot write: {e.strerror}") from None
    except ValueError as e:  # an unknown image format, from the file name's extension
        raise InputError(f"{out}: {e}") from None


def api_key(api):
    """Sorts p3trace's APIs before Embree's, each tracer's in API_ORDER."""
    tracer, kind = api.split("-", 1)
    return (TRACERS.index(tracer), (API_ORDER + (kind,)).index(kind), kind)


def main(argv=None):
    parser = argparse.ArgumentParser(
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="example:\n  scripts/bench-chart.py --out docs/bench-chart.png --threads 1 \\\n"
        "    p3trace-balls_high.json embree-balls_high.txt p3trace-mount.txt embree-mount.txt",
    )
    parser.add_argument(
        "files",
        nargs="+",
        metavar="FILE",
        help="a p3trace result (bench --json output or bench text output) or an Embree result "
        "(embree-compare output); each scene needs one of each, paired by the scene name",
    )
    parser.add_argument("--out", "-o", required=True, metavar="PNG", help="the chart to write")
    parser.add_argument(
        "--threads", type=int, default=1, metavar="N", help="the thread count to chart (default 1)"
    )
    parser.add_argument(
        "--all-apis",
        action="store_true",
        help="also draw each API (single rays, packets, streams), not only each tracer's best",
    )
    parser.add_argument(
        "--date",
        default=datetime.date.today().isoformat(),
        help="the date of the measurements, for the title (default today)",
    )
    args = parser.parse_args(argv)
    try:
        scenes = pair_by_scene([read_results(path) for path in args.files])
        results = [r for sides in scenes.values() for r in sides.values()]
        # Each tracer's APIs as the files give them, with its best first.
        apis = ["p3trace-best", "embree-best"]
        if args.all_apis:
            seen = {api for r in results for (_, api, _) in r.mrays}
            apis = sorted(seen | set(apis), key=api_key)
        rows = groups(scenes, args.threads, apis)
        cpus = sorted({r.cpu for r in results if r.cpu})
        if len(cpus) > 1:
            # Ratios across machines mean little; say so, but still draw.
            cpu_list = "; ".join(cpus)
            print(f"bench-chart: warning: the files come from different CPUs: {cpu_list}", file=sys.stderr)
        reps = {r.reps for r in results if r.reps}
        title = (
            f"Trace throughput, p3trace against Embree, {args.threads} thread{'s' if args.threads > 1 else ''}"
            + (f", best of {reps.pop()} passes" if len(reps) == 1 else "")
            + f"\n{' / '.join(cpus) or 'unknown CPU'}, {args.date}"
        )
        # The legend names p3trace's structure when every file agrees on it.
        structures = {r.structure for r in results if r.tracer == "p3trace" and r.structure}
        labels = {}
        if len(structures) == 1:
            labels["p3trace-best"] = f"p3trace-best, {structures.pop()}"
        draw(rows, apis, title, args.out, labels)
    except InputError as e:
        print(f"bench-chart: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
