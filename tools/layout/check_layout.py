#!/usr/bin/env python3
"""The workspace's layout rules, checked: no two source files import each other (directly or
round a longer circle), none between crates, no file over 600 lines, no function over 80.

    python3 tools/layout/check_layout.py            # report; exit 1 when a rule is broken
    python3 tools/layout/check_layout.py --graph    # also print every file's imports

A file *imports* another when it names an item of it: `use crate::a::b`, `super::x`, a path
`crate::a::X` in code, or a path through another workspace crate (`aperture_scene::X`). A
`pub use` re-export counts as an import of the file that makes it: a path through it imports the
re-exporting file, and that file's `pub use` imports the defining one (so a re-export cannot hide
a circle). `mod x;` declares a child; it is not an import. Comments and string literals are
ignored. Functions are measured from the line of `fn` to the line of their closing brace. A file
may list functions whose length is their speed (SIMD kernels) in a comment
`// layout: long-fn NAME (why)`; those are reported, not failed.
"""

import os
import re
import sys
from collections import defaultdict

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MAX_FILE = 600
MAX_FN = 80
SOURCE_DIRS = ["crates", "tests", "benches", "fuzz/harness"]


def strip_comments_and_strings(text):
    """The text with comments and string/char literals blanked (line count kept)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            i = j
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append("\n" * text.count("\n", i, j))
            i = j
        elif c == "r" and re.match(r'r#*"', text[i:i + 10]) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'r(#*)"', text[i:])
            end = text.find('"' + m.group(1), i + len(m.group(0)))
            end = n if end < 0 else end + 1 + len(m.group(1))
            out.append('""' + "\n" * text.count("\n", i, end))
            i = end
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            out.append('""' + "\n" * text.count("\n", i, j))
            i = j + 1
        elif c == "'":
            m = re.match(r"'(\\.[^']*|[^'\\])'", text[i:])
            if m:
                out.append("' '")
                i += len(m.group(0))
            else:
                out.append(c)
                i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


class Crate:
    def __init__(self, name, src_dir, root_file):
        self.name = name
        self.src_dir = src_dir
        self.root_file = root_file
        self.modules = {}  # module path tuple -> file
        self.files = {}  # file -> module path tuple
        self.inline = defaultdict(set)  # file -> inline `mod x {` names (same file)


def crate_name_of(cargo_toml):
    with open(cargo_toml) as f:
        m = re.search(r'^name\s*=\s*"([^"]+)"', f.read(), re.M)
    return m.group(1).replace("-", "_") if m else None


def discover_modules(crate, file, path):
    crate.modules[path] = file
    crate.files[file] = path
    with open(file) as f:
        text = strip_comments_and_strings(f.read())
    base = os.path.dirname(file)
    stem = os.path.splitext(os.path.basename(file))[0]
    is_dir_owner = stem in ("lib", "main", "mod") or file == crate.root_file
    child_dir = base if is_dir_owner else os.path.join(base, stem)
    for m in re.finditer(r'(?:#\[path\s*=\s*""\]\s*)?(?:pub(?:\([^)]*\))?\s+)?mod\s+(\w+)\s*;', text):
        name = m.group(1)
        for cand in (os.path.join(child_dir, name + ".rs"), os.path.join(child_dir, name, "mod.rs")):
            if os.path.exists(cand):
                discover_modules(crate, cand, path + (name,))
                break
    for m in re.finditer(r'(?:pub(?:\([^)]*\))?\s+)?mod\s+(\w+)\s*\{', text):
        crate.inline[file].add(m.group(1))


def find_crates():
    crates = []
    for top in SOURCE_DIRS:
        top_dir = os.path.join(ROOT, top)
        for dirpath, dirnames, filenames in os.walk(top_dir):
            dirnames[:] = [d for d in dirnames if d not in ("target", "corpus")]
            if "Cargo.toml" not in filenames:
                continue
            name = crate_name_of(os.path.join(dirpath, "Cargo.toml"))
            roots = []
            for r in ("src/lib.rs", "src/main.rs"):
                if os.path.exists(os.path.join(dirpath, r)):
                    roots.append(os.path.join(dirpath, r))
            for sub in ("tests", "benches", "examples", "src/bin"):
                d = os.path.join(dirpath, sub)
                if os.path.isdir(d):
                    for f in sorted(os.listdir(d)):
                        if f.endswith(".rs"):
                            roots.append(os.path.join(d, f))
                        elif os.path.exists(os.path.join(d, f, "main.rs")):
                            roots.append(os.path.join(d, f, "main.rs"))
            for r in roots:
                label = name if r.endswith(("src/lib.rs",)) else name + ":" + os.path.relpath(r, dirpath)
                c = Crate(label, os.path.dirname(r), r)
                discover_modules(c, r, ())
                crates.append(c)
    return crates


USE_RE = re.compile(r"\buse\s+([^;]+);")
PATH_RE = re.compile(r"\b((?:crate|super|self|aperture_\w+)(?:\s*::\s*(?:\w+|\{))+)")


def expand_use(tree):
    """`a::{b, c::{d, e}}` -> [a::b, a::c::d, a::c::e]."""
    tree = re.sub(r"\s+", "", tree)
    out = []

    def walk(prefix, s):
        parts, depth, cur = [], 0, ""
        for ch in s:
            if ch == "{":
                depth += 1
            elif ch == "}":
                depth -= 1
            if ch == "," and depth == 0:
                parts.append(cur)
                cur = ""
            else:
                cur += ch
        if cur:
            parts.append(cur)
        for p in parts:
            m = re.match(r"^(.*?)::\{(.*)\}$", p)
            if p.startswith("{") and p.endswith("}"):
                walk(prefix, p[1:-1])
            elif m:
                walk(prefix + m.group(1).split("::"), m.group(2))
            else:
                p = re.sub(r"\bas\b.*$", "", p)
                out.append(prefix + [x for x in p.split("::") if x])

    walk([], tree)
    return out


def absolute(crate, mpath, parts):
    """A path as written in module `mpath` -> (crate label or None, absolute module path)."""
    if parts[0] == "crate":
        return (crate.name, tuple(parts[1:]))
    if parts[0] == "self":
        return (crate.name, mpath + tuple(parts[1:]))
    if parts[0] == "super":
        up = list(mpath)
        i = 0
        while i < len(parts) and parts[i] == "super":
            up = up[:-1]
            i += 1
        return (crate.name, tuple(up) + tuple(parts[i:]))
    if parts[0].startswith("aperture_"):
        return (parts[0], tuple(parts[1:]))
    # A bare path: a child module of this one, if there is one.
    if (mpath + (parts[0],)) in crate.modules:
        return (crate.name, mpath + tuple(parts))
    return None


def resolve(by_name, target):
    """An absolute path -> the file of its deepest module: the file that defines the item, or
    the one that re-exports it (a re-export is not followed; that file imports the item)."""
    if target is None:
        return None
    cname, parts = target
    crate = by_name.get(cname)
    if crate is None:
        return None
    best = ()
    for i in range(len(parts), -1, -1):
        if tuple(parts[:i]) in crate.modules:
            best = tuple(parts[:i])
            break
    return crate.modules[best]


def imports_of(crates, by_name):
    graph = defaultdict(set)
    for c in crates:
        for file, mpath in c.files.items():
            with open(file) as f:
                text = strip_comments_and_strings(f.read())
            spans = inline_spans(text)
            depth_at = lambda o: sum(1 for a, b in spans if a <= o < b)
            paths = []
            for m in USE_RE.finditer(text):
                # A `pub use` too: the file that re-exports an item imports it.
                d = depth_at(m.start())
                paths.extend(lift(p, d) for p in expand_use(m.group(1)))
            body = USE_RE.sub(lambda m: " " * len(m.group(0)), text)
            for m in PATH_RE.finditer(body):
                p = re.sub(r"\s+", "", m.group(1)).rstrip(":{").split("::")
                paths.append(lift([x for x in p if x], depth_at(m.start())))
            locals_ = {}
            for m in USE_RE.finditer(text):
                for p in expand_use(m.group(1)):
                    if p and p[-1] not in ("*", "self"):
                        locals_[p[-1]] = p
            for p in paths:
                if not p:
                    continue
                if p[0] not in ("crate", "super", "self") and not p[0].startswith("aperture_"):
                    if (mpath + (p[0],)) not in c.modules:
                        continue
                if p[-1] == "self":
                    p = p[:-1]
                tgt = resolve(by_name, absolute(c, mpath, p))
                if tgt and tgt != file:
                    graph[file].add(tgt)
    return graph


def inline_spans(text):
    """(start, end) offsets of the bodies of inline `mod x { … }` blocks."""
    spans = []
    for m in re.finditer(r"\bmod\s+\w+\s*\{", text):
        depth, j = 1, m.end()
        while j < len(text) and depth:
            depth += {"{": 1, "}": -1}.get(text[j], 0)
            j += 1
        spans.append((m.end(), j))
    return spans


def lift(p, depth):
    """A path written `depth` inline modules deep, as seen from the file's own module: its
    leading `super`s climb out of the inline modules first (`[]` when it stays in the file)."""
    if not p or depth == 0:
        return p
    if p[0] == "self":
        return []
    k = 0
    while k < len(p) and p[k] == "super":
        k += 1
    if k == 0:
        return p
    if k <= depth:
        return []
    return ["super"] * (k - depth) + p[k:]


def sccs(graph):
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]
    sys.setrecursionlimit(10000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in list(graph):
        if v not in index:
            visit(v)
    return out


def long_functions(file):
    with open(file) as f:
        raw = f.read()
    text = strip_comments_and_strings(raw)
    allowed = set(re.findall(r"//\s*layout:\s*long-fn\s+(\w+)", raw))
    lines = text.split("\n")
    out = []
    fn_re = re.compile(r"^\s*(?:pub(?:\([^)]*\))?\s+)?(?:(?:const|async|unsafe|extern\s+\"\w*\")\s+)*fn\s+(\w+)")
    for i, line in enumerate(lines):
        m = fn_re.match(line)
        if not m:
            continue
        # Find the body's opening brace (or a `;` for a declaration without a body).
        depth, j, started, nest = 0, i, False, 0
        while j < len(lines):
            seg = lines[j] if j != i else line[m.end():]
            for ch in seg:
                # A `;` inside the signature's brackets (`[f32; 4]`) does not end it.
                if not started and ch in "([":
                    nest += 1
                elif not started and ch in ")]":
                    nest -= 1
                if ch == ";" and not started and depth == 0 and nest == 0:
                    break
                if ch == "{":
                    depth += 1
                    started = True
                elif ch == "}":
                    depth -= 1
                    if started and depth == 0:
                        break
            else:
                j += 1
                continue
            break
        if not started:
            continue
        length = j - i + 1
        if length > MAX_FN:
            out.append((m.group(1), i + 1, length, m.group(1) in allowed))
    return out


def main():
    show_graph = "--graph" in sys.argv
    crates = find_crates()
    by_name = {c.name: c for c in crates}
    graph = imports_of(crates, by_name)
    rel = lambda f: os.path.relpath(f, ROOT)
    failed = False

    if show_graph:
        for f in sorted(graph):
            print(rel(f), "->", ", ".join(sorted(rel(t) for t in graph[f])))

    circles = sccs(graph)
    print(f"import circles between files: {len(circles)}")
    for comp in circles:
        print("  circle: " + " <-> ".join(rel(f) for f in comp))
        failed = True

    crate_of = {}
    for c in crates:
        for f in c.files:
            crate_of.setdefault(f, c.name.split(":")[0])
    cgraph = defaultdict(set)
    for f, ts in graph.items():
        for t in ts:
            if crate_of.get(f) != crate_of.get(t):
                cgraph[crate_of[f]].add(crate_of[t])
    ccircles = sccs(cgraph)
    print(f"import circles between crates: {len(ccircles)}")
    for comp in ccircles:
        print("  circle: " + " <-> ".join(comp))
        failed = True

    all_files = sorted({f for c in crates for f in c.files})
    big = []
    for f in all_files:
        with open(f) as h:
            n = h.read().count("\n")
        if n > MAX_FILE:
            big.append((n, f))
    print(f"files over {MAX_FILE} lines: {len(big)}")
    for n, f in sorted(big, reverse=True):
        print(f"  {rel(f)}: {n}")
        failed = True

    longs, kernels = [], []
    for f in all_files:
        for name, line, length, allowed in long_functions(f):
            (kernels if allowed else longs).append((length, f"{rel(f)}:{line} {name}"))
    print(f"functions over {MAX_FN} lines: {len(longs)} (+{len(kernels)} listed kernels)")
    for n, where in sorted(longs, reverse=True):
        print(f"  {where}: {n}")
        failed = True
    for n, where in sorted(kernels, reverse=True):
        print(f"  kernel {where}: {n}")
    print(f"files read: {len(all_files)}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
