#!/usr/bin/env python3
"""Architecture metrics of the crate: long functions, the module import graph, typed errors.

Run from the repository root (or pass it as the first argument):

    python3 tools/arch_metrics.py [ROOT]

Prints
  (a) the functions longer than 150 lines in src/ and python/src/ (brace counting, as the
      before-stop hook measures them; `#[cfg(test)]` modules are not skipped, tests are
      listed with the rest);
  (b) the module import graph of src/ read from `use crate::…`, `crate::…` and `super::…`
      paths (comments stripped), at module granularity (a file, or a folder with a mod.rs);
      its cycles (strongly connected components of more than one module) and the imports
      that run upward through the layers below;
  (c) the number of `InvalidInput(` in src/ and python/src/, per file.

Standard library only.
"""

import os
import re
import sys
from collections import defaultdict

LONG = 150

# Layers, lowest first. A module belongs to the layer of its top-level name (`linalg::factor`
# → `linalg`). An import from a lower layer into a higher one is "upward". Names on one line
# share a layer (they may use each other, but circles are still reported).
LAYERS = [
    ["util"],
    ["error"],
    ["mesh", "dof", "material", "section"],
    ["fe"],
    ["linalg"],
    ["io"],
    ["element"],
    ["model"],
    ["assembly"],
    ["system"],
    ["post"],
    ["analysis"],
    ["input"],
    ["app"],
]
LAYER_OF = {name: i for i, names in enumerate(LAYERS) for name in names}


def rust_files(root, sub):
    base = os.path.join(root, sub)
    out = []
    for d, _, files in os.walk(base):
        for f in files:
            if f.endswith(".rs"):
                out.append(os.path.join(d, f))
    return sorted(out)


# ---------------------------------------------------------------- (a) long functions


def long_functions(root):
    rows = []
    for f in rust_files(root, "src") + rust_files(root, "python/src"):
        lines = open(f, encoding="utf-8", errors="replace").read().split("\n")
        for i, l in enumerate(lines):
            m = re.match(r"\s*(pub(\([^)]*\))?\s+)?fn\s+(\w+)", l)
            if not m:
                continue
            depth, started = 0, False
            j = i
            for j in range(i, len(lines)):
                c = re.sub(r"//.*", "", lines[j])
                depth += c.count("{") - c.count("}")
                started = started or "{" in c
                if started and depth <= 0:
                    break
                if not started and c.rstrip().endswith(";"):
                    break
            if started:
                rows.append((j - i + 1, f"{os.path.relpath(f, root)}:{i + 1} {m.group(3)}"))
    rows.sort(key=lambda r: (-r[0], r[1]))
    return [r for r in rows if r[0] > LONG]


# ---------------------------------------------------------------- (b) import graph


def module_of(root, path):
    """`src/linalg/factor.rs` → `linalg::factor`; `src/io/mod.rs` → `io`; lib.rs → ``."""
    rel = os.path.relpath(path, os.path.join(root, "src"))
    parts = rel[:-3].split(os.sep)
    if parts[-1] in ("mod", "lib"):
        parts = parts[:-1]
    return "::".join(parts)


def strip_comments(text):
    """Code without comments and with string literals emptied (one pass: a quote inside a
    comment or an apostrophe of a lifetime does not start a string)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            depth, i = 1, i + 2
            while i < n and depth:
                if text.startswith("/*", i):
                    depth, i = depth + 1, i + 2
                elif text.startswith("*/", i):
                    depth, i = depth - 1, i + 2
                else:
                    i += 1
        elif c == "r" and re.match(r'r#*"', text[i:i + 10]) and not (i and (text[i - 1].isalnum() or text[i - 1] == "_")):
            hashes = len(re.match(r'r(#*)"', text[i:]).group(1))
            end = text.find('"' + "#" * hashes, i + 2 + hashes)
            out.append('""')
            i = n if end < 0 else end + 1 + hashes
        elif c == '"':
            i += 1
            while i < n and text[i] != '"':
                i += 2 if text[i] == "\\" else 1
            out.append('""')
            i += 1
        elif c == "'":
            m = re.match(r"'(\\.|\\u\{[0-9a-fA-F]+\}|[^\\'])'", text[i:i + 12])
            if m:  # a char literal; otherwise a lifetime
                out.append("' '")
                i += len(m.group(0))
            else:
                out.append(c)
                i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def expand_use_tree(tree):
    """`a::{b, c::{d, e}}` → [`a::b`, `a::c::d`, `a::c::e`] (no `as`, no `self` suffix)."""
    tree = re.sub(r"\s+as\s+\w+", "", tree)
    tree = re.sub(r"\s+", "", tree)
    out = []

    def walk(prefix, s):
        # split s at top-level commas
        depth, start, items = 0, 0, []
        for k, ch in enumerate(s):
            if ch == "{":
                depth += 1
            elif ch == "}":
                depth -= 1
            elif ch == "," and depth == 0:
                items.append(s[start:k])
                start = k + 1
        items.append(s[start:])
        for it in items:
            if not it:
                continue
            b = it.find("{")
            if b >= 0 and it.endswith("}"):
                head = it[:b].rstrip(":")
                walk(prefix + ([head] if head else []), it[b + 1 : -1])
            else:
                segs = [p for p in it.split("::") if p]
                if segs and segs[-1] == "self":
                    segs = segs[:-1]
                out.append("::".join(prefix + segs))

    walk([], tree)
    return out


def resolve(path_segs, modules, here):
    """Longest prefix of `path_segs` (absolute, from the crate root) that is a module."""
    for n in range(len(path_segs), 0, -1):
        cand = "::".join(path_segs[:n])
        if cand in modules:
            return cand
    return ""  # the crate root (lib.rs)


def absolute(segs, here):
    """Turn `crate::…` / `super::…` / `self::…` segments into segments from the crate root."""
    if not segs:
        return None
    cur = here.split("::") if here else []
    if segs[0] == "crate":
        return segs[1:]
    if segs[0] in ("super", "self"):
        base = list(cur)
        k = 0
        while k < len(segs) and segs[k] in ("super", "self"):
            if segs[k] == "super" and base:
                base.pop()
            k += 1
        return base + segs[k:]
    return None


def root_reexports(root, modules):
    """Names lib.rs re-exports (`pub use error::{Error, Result}`) → the module they come from."""
    lib = os.path.join(root, "src", "lib.rs")
    out = {}
    if not os.path.exists(lib):
        return out
    text = strip_comments(open(lib, encoding="utf-8").read())
    for m in re.finditer(r"pub\s+use\s+([^;]+);", text):
        for p in expand_use_tree(m.group(1)):
            segs = p.split("::")
            if segs[0] == "crate":
                segs = segs[1:]
            mod = resolve(segs, modules, "")
            if mod:
                out[segs[-1]] = mod
    return out


def import_graph(root):
    files = rust_files(root, "src")
    mod_file = {module_of(root, f): f for f in files}
    bins = {m for m in mod_file if m == "main" or m.startswith("bin::")}
    modules = set(mod_file)
    reexp = root_reexports(root, modules)
    edges = defaultdict(set)  # from → {to}
    for mod, f in mod_file.items():
        if mod in bins or mod == "":
            continue
        text = strip_comments(open(f, encoding="utf-8", errors="replace").read())
        paths = []
        for m in re.finditer(r"\buse\s+((?:crate|super|self)\b[^;]*);", text):
            paths += expand_use_tree(m.group(1))
        # inline paths (not in a use): crate::a::b, super::x
        no_use = re.sub(r"\buse\s+[^;]*;", "", text)
        paths += re.findall(r"\b(?:crate|super)(?:::\w+)+", no_use)
        for p in paths:
            segs = absolute([s for s in p.split("::") if s], mod)
            if segs is None:
                continue
            target = resolve(segs, modules, mod)
            if target == "" and segs and segs[0] in reexp:
                target = reexp[segs[0]]
            if target and target != mod and not mod.startswith(target + "::") and not target.startswith(mod + "::"):
                edges[mod].add(target)
            elif target and target.startswith(mod + "::"):
                pass  # a module using its own children is not an edge
    return modules - bins - {""}, edges


def sccs(nodes, edges):
    """Tarjan's strongly connected components."""
    index, low, on, stack, out = {}, {}, set(), [], []
    counter = [0]
    sys.setrecursionlimit(10000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(edges.get(v, ())):
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
            out.append(sorted(comp))

    for v in sorted(nodes):
        if v not in index:
            visit(v)
    return [c for c in out if len(c) > 1]


def layer(mod):
    return LAYER_OF.get(mod.split("::")[0])


# ---------------------------------------------------------------- (c) InvalidInput


def invalid_input(root):
    per = {}
    for f in rust_files(root, "src") + rust_files(root, "python/src"):
        n = open(f, encoding="utf-8", errors="replace").read().count("InvalidInput(")
        if n:
            per[os.path.relpath(f, root)] = n
    return per


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.getcwd()

    rows = long_functions(root)
    print(f"(a) functions over {LONG} lines in src/ and python/src/: {len(rows)}")
    for n, w in rows:
        print(f"  {n:4d}  {w}")

    nodes, edges = import_graph(root)
    n_edges = sum(len(v) for v in edges.values())
    print(f"\n(b) module import graph of src/: {len(nodes)} modules, {n_edges} edges")
    for m in sorted(nodes):
        if edges.get(m):
            print(f"  {m} -> {', '.join(sorted(edges[m]))}")
    cyc = sccs(nodes, edges)
    print(f"  cycles (strongly connected components of size > 1): {len(cyc)}")
    for c in cyc:
        inner = [f"{a} -> {b}" for a in c for b in sorted(edges.get(a, ())) if b in c]
        print(f"    {{{', '.join(c)}}}: {'; '.join(inner)}")
    top = defaultdict(set)
    for a, bs in edges.items():
        for b in bs:
            ta, tb = a.split("::")[0], b.split("::")[0]
            if ta != tb:
                top[ta].add(tb)
    tcyc = sccs({m.split("::")[0] for m in nodes}, top)
    print(f"  cycles between top-level modules (folders): {len(tcyc)}")
    for c in tcyc:
        # The imports that close the circle: those against the layer order.
        against = [
            f"{a} -> {b}"
            for a in sorted(edges)
            for b in sorted(edges[a])
            if a.split("::")[0] in c
            and b.split("::")[0] in c
            and (layer(b) or 0) > (layer(a) or 0)
        ]
        print(f"    {{{', '.join(c)}}} closed by: {'; '.join(against)}")
    print("  layers, lowest first: " + " < ".join("/".join(l) for l in LAYERS))
    up = []
    for a in sorted(edges):
        for b in sorted(edges[a]):
            la, lb = layer(a), layer(b)
            if la is not None and lb is not None and lb > la:
                up.append(f"{a} -> {b}")
    print(f"  upward imports: {len(up)}")
    for u in up:
        print(f"    {u}")
    core_up = [u for u in up if not u.startswith("app")]
    print(f"  upward imports outside app/: {len(core_up)}")

    per = invalid_input(root)
    total = sum(per.values())
    core = sum(n for f, n in per.items() if not f.startswith(("src/app/", "src/main.rs", "python/")))
    print(f"\n(c) `InvalidInput(` in src/ and python/src/: {total} (core without app/, main.rs: {core})")
    for f, n in sorted(per.items(), key=lambda kv: (-kv[1], kv[0])):
        print(f"  {n:4d}  {f}")


if __name__ == "__main__":
    main()
