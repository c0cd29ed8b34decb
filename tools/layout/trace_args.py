#!/usr/bin/env python3
"""Follows the render arguments from the CLI to the written file, file by file (issue 44).

    valgrind --tool=callgrind --compress-strings=no --compress-pos=no \\
        --callgrind-out-file=/tmp/render.cg target/debug/aperture render assets/demo.glb \\
        -o /tmp/t.exr --width 32 --height 18 --spp 1 --threads 1 --passes all
    python3 tools/layout/trace_args.py /tmp/render.cg [--start aperture::render_cmd::run]

The call graph is the one the run really took (callgrind, debug build: nothing inlined), each
caller's callees in the order of their call sites. A function *carries the arguments* when its
signature names one of the argument types (CARRIERS: what the command line fills) or it is a
method of one; closures count as the function that holds them. The walk starts at --start and
follows carrying calls, passing through functions that carry nothing (std, rayon, helpers) to
the carrying functions they reach. It passes only through our own functions: std's and
rayon's generic functions are shared by every caller (one node for all the closures they run),
and a closure's calls count as its enclosing function's anyway, wherever it runs. It prints every *stay* (a run of steps in one file) and, per
file, how often the arguments are handed into it by a call from another file (`calls in`) and
how often the walk comes back to it from a callee in another file (`returns`). Exit 1 when a
file is called into more than --max times (default 2).
"""

import argparse
import os
import re
import sys
from collections import defaultdict

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# The types the command line fills: clap's argument structs and the options they become.
CARRIERS = [
    "RenderArgs", "TracingArgs", "MaterialArgs", "TimeArgs", "SplitArgs", "LoadOptions",
    "RenderOptions", "AdaptiveOptions", "ExrOptions", "PngOptions", "BeforeLoad", "RenderPlan", "Sequence",
]
CLOSURE = re.compile(r"::\{\{closure\}\}.*$")


def parse_callgrind(path):
    """{fn: file} and {caller: [(line, callee)]} from an uncompressed callgrind file."""
    file_of, defined, calls = {}, {}, defaultdict(list)
    fl = fn = cfl = cfn = None
    pending = None
    with open(path, errors="replace") as f:
        for raw in f:
            line = raw.rstrip("\n")
            if pending is not None:
                site = line.split()[0] if line else "0"
                calls[fn].append((int(site) if site.isdigit() else 0, pending))
                pending = None
                continue
            if line.startswith("fl="):
                fl = line[3:]
            elif line.startswith("fn="):
                fn = line[3:]
                defined[fn] = fl
            elif line.startswith(("cfl=", "cfi=")):
                cfl = line[4:]
            elif line.startswith("cfn="):
                cfn = line[4:]
                # Without cfi=, the callee is in the caller's file (callgrind's format).
                file_of.setdefault(cfn, cfl or fl)
            elif line.startswith("calls="):
                pending = cfn
                cfl = None
    file_of.update(defined)  # where a function's own code is, when callgrind saw it run
    return file_of, calls


def set_root(root):
    global ROOT
    ROOT = root


def short_file(path):
    """The path inside the repository (or as given for std and dependencies)."""
    if path and path.startswith(ROOT + "/"):
        return path[len(ROOT) + 1:]
    return path or "?"


def ours(path):
    return path is not None and path.startswith(ROOT + "/crates/")


def carrying_fns():
    """(file, fn name) of every function whose parameters name a carrier type."""
    found = set()
    word = re.compile(r"\b(" + "|".join(CARRIERS) + r")\b")
    for base, _, names in os.walk(os.path.join(ROOT, "crates")):
        for name in names:
            if not name.endswith(".rs"):
                continue
            path = os.path.join(base, name)
            text = open(path, errors="replace").read()
            for m in re.finditer(r"\bfn\s+(\w+)\s*(<[^(]*?>)?\s*\(", text):
                depth, i = 1, m.end()
                while i < len(text) and depth:
                    depth += {"(": 1, ")": -1}.get(text[i], 0)
                    i += 1
                if word.search(text[m.end():i]):
                    found.add((path, m.group(1)))
    return found


def owner(fn):
    """A closure's enclosing function; any other function itself."""
    return CLOSURE.sub("", fn)


def is_carrier(fn, file_of, carriers):
    base = owner(fn)
    path = file_of.get(fn)
    if not ours(path):
        return False
    parts = base.split("::")
    if any(p in CARRIERS for p in parts[:-1]):
        return True
    return (path, parts[-1]) in carriers


def walk(start, file_of, calls, carriers):
    """The sequence of (file, fn, event) steps of the carrying walk from start."""
    steps = []
    # A closure's calls belong to its enclosing function, in the closure's place.
    merged = defaultdict(list)
    for caller, sites in calls.items():
        merged[owner(caller)].extend(sites)
    for caller in merged:
        merged[caller].sort(key=lambda s: s[0])

    memo = {}

    def reach(fn):
        """Carrying functions reached from fn through non-carrying ones, in call order."""
        if fn in memo:
            return memo[fn]
        memo[fn] = []  # a recursion back to fn adds nothing
        out, seen = [], {fn}
        for _, callee in merged.get(fn, []):
            target = owner(callee)
            if target in seen:
                continue
            seen.add(target)
            if is_carrier(callee, file_of, carriers):
                out.append(target)
            elif ours(file_of.get(callee)):
                out.extend(t for t in reach(target) if t not in seen and not seen.add(t))
        memo[fn] = out
        return out

    expanded = set()

    def visit(fn):
        """A function called again (another call site) is a step, its calls followed once."""
        path = short_file(file_of.get(fn))
        steps.append((path, fn, "call"))
        if fn in expanded:
            return
        expanded.add(fn)
        for callee in reach(fn):
            visit(callee)
            steps.append((path, fn, "return"))

    visit(start)
    return steps


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("callgrind")
    ap.add_argument("--start", default="aperture::render_cmd::run")
    ap.add_argument("--max", type=int, default=2)
    ap.add_argument("--root", default=ROOT, help="the source tree the binary was built from")
    args = ap.parse_args()
    set_root(os.path.abspath(args.root))
    file_of, calls = parse_callgrind(args.callgrind)
    if args.start not in file_of:
        sys.exit(f"trace_args: {args.start} is not in {args.callgrind}")
    steps = walk(args.start, file_of, calls, carrying_fns())
    stays, calls_in, returns = [], defaultdict(int), defaultdict(int)
    for path, fn, event in steps:
        if stays and stays[-1][0] == path:
            if fn not in stays[-1][1]:
                stays[-1][1].append(fn)
            continue
        stays.append((path, [fn]))
        (calls_in if event == "call" else returns)[path] += 1
    for i, (path, fns) in enumerate(stays, 1):
        names = ", ".join(owner(f).split("::")[-1] for f in fns)
        print(f"{i:3} {path}: {names}")
    files = sorted({p for p, _ in stays})
    print(f"\n{len(stays)} stays in {len(files)} files; per file: calls in / returns")
    bad = []
    for path in files:
        flag = "  <-- over" if calls_in[path] > args.max else ""
        print(f"  {calls_in[path]:2} / {returns[path]:2}  {path}{flag}")
        if calls_in[path] > args.max:
            bad.append(path)
    again = sum(calls_in.values()) + sum(returns.values()) - len(files)
    print(f"{again} entries into a file already left ({sum(returns.values())} of them returns)")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
