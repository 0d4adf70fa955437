#!/usr/bin/env python3
"""Where a function's inlined code spends its instructions, by source line.

Reads a callgrind profile made with `--dump-instr=yes` and puts each instruction's own
cost at the outermost frame of SOURCE (a file, or every file of a folder) in the
instruction's inline chain (addr2line -i): the line of SOURCE whose statement the
instruction serves, however deeply the compiler inlined what that statement calls. Where
that line calls a function named by `--expand` (one inlined whole, such as
`shade_depth`'s call of a stage), the next frame of SOURCE inside it is taken instead,
and so on down. Instructions without a frame of SOURCE are grouped by
the function they lie in (or, inside another crate's function, by the outermost line of
the project's own sources inlined there), so that the groups add up to the whole run.

BENCHMARKS.md's shading budget comes from it:

    valgrind --tool=callgrind --dump-instr=yes --callgrind-out-file=cg.out \\
      target/portable/release/p3trace render SCENE --threads 1 --accel bvh --no-skybox -q -o x.png
    scripts/inline-lines.py cg.out target/portable/release/p3trace src/render/stream/ \\
      --expand shade_depth --expand trace_hits --expand shade_lit --expand spawn

Needs binutils' addr2line and a binary with line tables (the release profile has them), and
valgrind the portable build (CONTRIBUTING.md) where the CPU has AVX-512.
"""

import argparse
import collections
import os
import re
import subprocess
import sys


def own_costs(profile):
    """Each (instruction address, function name)'s own cost in a callgrind profile."""
    names = {}
    costs = collections.Counter()
    function = "?"
    address = 0
    after_calls = False
    cost_field = None  # the cost's column, after the positions

    def named(text):
        match = re.match(r"\((\d+)\)(?: (.*))?", text)
        if not match:
            return text
        if match.group(2):
            names[match.group(1)] = match.group(2)
        return names.get(match.group(1), "?")

    def position(token, previous):
        if token == "*":
            return previous
        if token[0] in "+-":
            return previous + int(token, 0)
        return int(token, 0)

    with open(profile, errors="replace") as lines:
        for line in lines:
            if line.startswith("positions:"):
                positions = line.split()[1:]
                if positions[:1] != ["instr"]:
                    return costs  # no instruction addresses: made without --dump-instr=yes
                cost_field = len(positions)
            elif line.startswith("fn="):
                function = named(line[3:].strip())
            elif line.startswith("cfn="):
                named(line[4:].strip())
            elif line.startswith("calls="):
                after_calls = True  # the next cost line is the call's inclusive cost
            elif cost_field and (line[:1].isdigit() or line[:1] in "+-*"):
                fields = line.split()
                address = position(fields[0], address)
                if after_calls:
                    after_calls = False
                    continue
                costs[(address, function)] += int(fields[cost_field])
    return costs


def perf_costs(data, binary):
    """Each (instruction address, function name)'s samples in a `perf record` of `binary`;
    samples in libraries as (None, their function), in the kernel as (None, "kernel")."""
    def symbols(*flags):
        listing = subprocess.run(["nm", "--defined-only", "--no-sort", *flags, binary],
                                 capture_output=True, text=True, check=True).stdout
        return [line.split(" ", 2) for line in listing.splitlines()]
    names = {}
    for (address, _, raw), (_, _, plain) in zip(symbols(), symbols("-C")):
        names[raw] = (int(address, 16), plain)
    script = subprocess.run(["perf", "script", "-i", data, "-F", "ip,sym,symoff,dso",
                             "--no-demangle"], capture_output=True, text=True, check=True).stdout
    costs = collections.Counter()
    for line in script.splitlines():
        match = re.match(r"\s*[0-9a-f]+ (.+)\+0x([0-9a-f]+) \((.*)\)$", line)
        if match and match.group(1) in names and match.group(3).endswith(binary.split("/")[-1]):
            start, name = names[match.group(1)]
            costs[(start + int(match.group(2), 16), name)] += 1
        elif match and match.group(3) == "[kernel.kallsyms]":
            costs[(None, "kernel")] += 1
        else:
            costs[(None, match.group(1) if match else "unknown")] += 1
    return costs


def inline_chains(binary, addresses):
    """Each address's inline chain, innermost frame first, as "path:line" strings."""
    chains = {}
    addresses = sorted(addresses)
    for start in range(0, len(addresses), 4000):
        chunk = addresses[start : start + 4000]
        output = subprocess.run(
            ["addr2line", "-a", "-i", "-e", binary] + [hex(a) for a in chunk],
            capture_output=True,
            text=True,
            check=True,
        ).stdout
        current = None
        for line in output.splitlines():
            if line.startswith("0x"):
                current = int(line, 16)
                chains[current] = []
            else:
                chains[current].append(re.sub(r" \(discriminator \d+\)", "", line))
    return chains


def source_files(source):
    """The files of SOURCE: itself, or the Rust files of the folder, as paths from it."""
    if not os.path.isdir(source):
        return [source]
    folder = source.rstrip("/") + "/"
    return sorted(folder + name for name in os.listdir(folder) if name.endswith(".rs"))


def source_file(path, files):
    """The file of `files` that the frame's `path` names, or None."""
    return next((f for f in files if path.endswith(f)), None)


def call_lines(files, functions):
    """The lines of `files` ("path:number") that call one of `functions`."""
    if not functions:
        return set()
    call = re.compile(r"\b(" + "|".join(map(re.escape, functions)) + r")\(")
    calls = set()
    for source in files:
        with open(source) as text:
            calls |= {f"{source}:{number}" for number, line in enumerate(text, 1)
                      if call.search(line) and not re.search(r"\bfn\s", line)}
    return calls


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("profile", help="callgrind output made with --dump-instr=yes")
    parser.add_argument("binary", help="the profiled binary")
    parser.add_argument("source", help="the source file (or folder) whose lines to group by")
    parser.add_argument("--expand", action="append", default=[], metavar="FUNCTION",
                        help="look inside SOURCE's calls of FUNCTION (repeatable)")
    parser.add_argument("--top", type=int, default=40, help="groups to print (40)")
    parser.add_argument("--perf", action="store_true",
                        help="PROFILE is a `perf record` of BINARY: samples, not instructions")
    parser.add_argument("--stages", metavar="FILE",
                        help="sum the groups into the stages of FILE (scripts/stream-stages.txt)")
    args = parser.parse_args()

    costs = perf_costs(args.profile, args.binary) if args.perf else own_costs(args.profile)
    if not costs:
        sys.exit(f"inline-lines: no costs in {args.profile} (made with --dump-instr=yes?)")
    chains = inline_chains(args.binary, {address for address, _ in costs if address is not None})
    files = source_files(args.source)
    expand = call_lines(files, args.expand)
    groups = collections.Counter()
    for (address, function), cost in costs.items():
        chain = chains.get(address, [])
        lines = []
        for path, number in (f.rsplit(":", 1) for f in chain):
            file = source_file(path, files)
            if file:
                lines.append(f"{file}:{number}")
        if not lines:
            groups[outside_group(function, chain, args.source)] += cost
            continue
        i = len(lines) - 1
        while i > 0 and lines[i] in expand:
            i -= 1
        groups[lines[i]] += cost
    total = sum(groups.values())
    unit = "samples" if args.perf else "instructions"
    print(f"{total:,} {unit} in all")
    if args.stages:
        print_stages(groups, read_stages(args.stages), files, args.top, unit)
        return
    for group, cost in groups.most_common(args.top):
        print(f"{cost / 1e6:10.1f} M {100 * cost / total:5.1f}%  {group}")


def outside_group(function, chain, source):
    """The group of an instruction without a frame of SOURCE: its function, or where that
    is another crate's (an iterator's fold, a thread pool's loop, into which the compiler
    inlined the project's code), the innermost line of its inline chain in the file of the
    chain's outermost frame of the project's own sources, as "[path:line]" from the source
    folder of SOURCE on (render/mod.rs's lines, inside rayon's loop over the tiles)."""
    if function.startswith(("p3trace::", "<p3trace::")):
        return f"[{function}]"
    root = source.split("/")[0] + "/"  # "src/"
    own = [f for f in chain if f"/{root}" in f and "/.cargo/" not in f and "/rustc/" not in f]
    if not own:
        return f"[{function}]"
    outer_file = own[-1].rsplit(":", 1)[0]
    line = next(f for f in own if f.rsplit(":", 1)[0] == outer_file)
    return "[" + root + line.split(f"/{root}", 1)[1] + "]"


def read_stages(path):
    """The (stage, compiled regex) pairs of a stage file, in its order."""
    stages = []
    with open(path) as lines:
        for number, line in enumerate(lines, 1):
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            stage, sep, pattern = line.partition(": ")
            if not sep:
                sys.exit(f"inline-lines: {path}:{number}: expected 'stage: regex'")
            stages.append((stage, re.compile(pattern)))
    return stages


def print_stages(groups, stages, files, top, unit):
    """Each stage's cost and share of the groups outside stage "-", then the
    groups no stage takes."""
    source_lines = {}
    for source in files:
        with open(source) as text:
            source_lines[source] = [line.strip() for line in text]
    sums = collections.Counter()
    unassigned = collections.Counter()
    for group, cost in groups.items():
        file, _, number = group.rpartition(":")
        if file in source_lines:
            subject = source_lines[file][int(number) - 1] if number.isdigit() else "?"
        else:
            subject = group
        stage = next((name for name, pattern in stages if pattern.search(subject)), None)
        if stage is None:
            unassigned[group] += cost
        else:
            sums[stage] += cost
    loop = sum(groups.values()) - sums["-"]
    print(f"{loop:,} {unit} in the stages' loop (all but stage -)")
    def amount(cost):
        return f"{cost / 1e6:10.1f} M" if unit == "instructions" else f"{cost:12,}"
    for stage, cost in sums.most_common():
        if stage != "-":
            print(f"{amount(cost)} {100 * cost / loop:5.1f}%  {stage}")
    rest = sum(unassigned.values())
    print(f"{amount(rest)} {100 * rest / loop:5.1f}%  unassigned:")
    for group, cost in unassigned.most_common(top):
        print(f"    {amount(cost)}  {group}")


if __name__ == "__main__":
    main()
