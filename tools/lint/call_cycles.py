#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/lint/call_cycles.py --build DIR [--build DIR ...] [--root ROOT] [--sources GLOB ...] [--list]

Fails when the calls between the core's source files go round in a circle
(issue 35: the localization stack's calls go one way; docs/architecture.md,
"The localization stack").

The call graph is GCC's own, not a parse of the C: every object of the core
is compiled with -fcallgraph-info=su (cmake/TrnStackUsage.cmake), which writes
<obj>.ci next to it: one node per function defined in that translation unit
(its label holds the defining file), one node per function it calls but does
not define, and one edge per call site (tools/stack/trn_stack.py reads the
same files for the stack bound). This tool joins the .ci files of each build
directory given, keeps the translation units whose source matches --sources
(default src/*.c, relative to --root), and draws an edge from file A to file B
when a function compiled in A calls a function that A does not define and B
does (defined non-locally: a name defined in several units is resolved
through the objects' symbol tables when it is static in all but one, else
reported). Functions of a header (static inline) count as the including
file's. Calls through a pointer are not edges (trn_stack.py bounds them).

Exit 0 when the file graph is acyclic (with --list, its edges are printed,
each with one call that makes it); 1 when it has a cycle: each strongly
connected set of files is printed as one cycle A -> B -> ... -> A, each step
with one call that makes it; 2 on a usage or input problem (no .ci files, an
unresolvable callee). Build directories are usually build/host (Debug -O0:
no call is folded away) and build/arm-none-eabi; tools/test.d/49-calls.sh runs
it on both.
"""
import argparse
import fnmatch
import glob
import os
import re
import shutil
import subprocess
import sys

NODE_RE = re.compile(r'^node:\s*\{\s*title:\s*"([^"]+)"\s*label:\s*"([^"]*)"(.*)\}\s*$')
EDGE_RE = re.compile(r'^edge:\s*\{\s*sourcename:\s*"([^"]+)"\s*targetname:\s*"([^"]+)"(?:\s*label:\s*"([^"]*)")?')
SIZE_RE = re.compile(r'\d+ bytes \(')
INDIRECT = "__indirect_call"


class Unit:
    """One translation unit's .ci: its source file, what it defines, its calls out."""

    def __init__(self, ci, src):
        self.ci = ci
        self.src = src          # path relative to root
        self.defined = set()    # names defined here (static or not)
        self.calls = []         # (caller, callee, site) with callee not defined here


def parse_ci(path):
    """(defined: {name: source file}, edges: [(caller, callee, site)])."""
    defined, edges = {}, []
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            line = line.strip()
            m = NODE_RE.match(line)
            if m:
                title, label = m.group(1), m.group(2)
                parts = label.split("\\n")
                if SIZE_RE.search(label) and len(parts) > 1:
                    defined[title] = parts[1].rsplit(":", 2)[0]
                continue
            m = EDGE_RE.match(line)
            if m:
                edges.append((m.group(1), m.group(2), m.group(3) or ""))
    return defined, edges


def rel(path, root):
    a = os.path.realpath(path if os.path.isabs(path) else os.path.join(root, path))
    return os.path.relpath(a, root)


def matches(relpath, patterns):
    return any(fnmatch.fnmatch(relpath, p) for p in patterns)


def read_units(ci_files, root, patterns):
    """The units whose main source (the .c among its definitions) matches patterns."""
    units = []
    for ci in ci_files:
        defined, edges = parse_ci(ci)
        srcs = sorted({rel(s, root) for s in defined.values() if s.endswith(".c")})
        if not srcs:
            continue
        if len(srcs) > 1:
            # a .c that #includes another .c: the unit is named by the .ci's own name
            base = os.path.basename(ci)[:-len(".ci")]
            base = base[:-len(".o")] if base.endswith(".o") else base
            srcs = [s for s in srcs if os.path.basename(s) == base] or srcs[:1]
        if not matches(srcs[0], patterns):
            continue
        u = Unit(ci, srcs[0])
        u.defined = set(defined)
        u.calls = [(a, b, site) for a, b, site in edges if a in defined and b not in defined and b != INDIRECT]
        units.append(u)
    return units


def global_symbols(obj):
    """Names the object defines with external linkage (nm), or None if unreadable."""
    nm = shutil.which("nm")
    if not nm or not os.path.exists(obj):
        return None
    p = subprocess.run([nm, "--defined-only", "-g", "-P", obj], capture_output=True, text=True)
    if p.returncode != 0:
        return None
    return {ln.split()[0] for ln in p.stdout.splitlines() if ln.split()}


def file_graph(units):
    """({file: {file: (caller, callee, site)}}, problems): one witness call per edge."""
    owners = {}
    for u in units:
        for name in u.defined:
            owners.setdefault(name, []).append(u)
    graph = {u.src: {} for u in units}
    problems = []
    globals_cache = {}
    for u in units:
        for a, b, site in u.calls:
            cands = owners.get(b, [])
            if len(cands) > 1:
                keep = []
                for c in cands:
                    if c.ci not in globals_cache:
                        globals_cache[c.ci] = global_symbols(c.ci[:-len(".ci")] + ".o")
                    g = globals_cache[c.ci]
                    if g is None or b in g:
                        keep.append(c)
                cands = keep
            if not cands:
                continue  # libc, libm, the compiler's runtime: outside the sources
            if len(cands) > 1:
                problems.append("%s: %s calls %s, defined in %s: cannot tell which" %
                                (u.src, a, b, ", ".join(sorted(c.src for c in cands))))
                continue
            dst = cands[0].src
            if dst != u.src and dst not in graph[u.src]:
                graph[u.src][dst] = (a, b, site)
    return graph, problems


def strong_components(graph):
    """Tarjan's strongly connected components, each a sorted list; iterative."""
    index, low, on, stack, out = {}, {}, set(), [], []
    counter = [0]
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            advanced = False
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph.get(w, {})))))
                    advanced = True
                    break
                if w in on:
                    low[v] = min(low[v], index[w])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                out.append(sorted(comp))
    return out


def cycle_in(graph, comp):
    """One cycle through the component's first file, staying inside it (BFS back to it)."""
    members = set(comp)
    start = comp[0]
    prev = {}
    frontier = [start]
    seen = {start}
    while frontier:
        nxt = []
        for v in frontier:
            for w in sorted(graph[v]):
                if w not in members:
                    continue
                if w == start:
                    path = [v]
                    while path[-1] != start:
                        path.append(prev[path[-1]])
                    path.reverse()
                    return path + [start]
                if w not in seen:
                    seen.add(w)
                    prev[w] = v
                    nxt.append(w)
        frontier = nxt
    return [start, start]


def bare(name):
    """GCC titles a static function '/path/file.c:name': just the name."""
    return name.rsplit(":", 1)[-1] if os.path.isabs(name) else name


def check(graph, out=sys.stdout):
    """Prints every cycle; returns how many strongly connected sets have one."""
    n = 0
    for comp in strong_components(graph):
        if len(comp) < 2:
            continue
        n += 1
        cyc = cycle_in(graph, comp)
        print("call_cycles: cycle among %d files {%s}: %s" % (len(comp), ", ".join(comp), " -> ".join(cyc)), file=out)
        for a, b in zip(cyc, cyc[1:]):
            caller, callee, site = graph[a][b]
            print("    %s -> %s: %s calls %s (%s)" % (a, b, bare(caller), callee, os.path.basename(site)), file=out)
    return n


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", action="append", required=True, help="build directory holding .ci files (repeatable)")
    ap.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
    ap.add_argument("--sources", nargs="*", default=["src/*.c"], help="globs relative to --root (default src/*.c)")
    ap.add_argument("--list", action="store_true", help="print the file graph's edges")
    a = ap.parse_args(argv)
    root = os.path.realpath(a.root)
    worst = 0
    for b in a.build:
        ci_files = sorted(glob.glob(os.path.join(b, "**", "*.ci"), recursive=True))
        if not ci_files:
            print("call_cycles: no .ci files under %s (configure with TRN_STACK_USAGE=ON, GCC >= 10)" % b, file=sys.stderr)
            return 2
        units = read_units(ci_files, root, a.sources)
        if not units:
            print("call_cycles: no unit of %s matches %s under %s" % (b, " ".join(a.sources), root), file=sys.stderr)
            return 2
        graph, problems = file_graph(units)
        for p in problems:
            print("call_cycles: " + p, file=sys.stderr)
        if problems:
            return 2
        n_edges = sum(len(v) for v in graph.values())
        if a.list:
            for src in sorted(graph):
                for dst in sorted(graph[src]):
                    caller, callee, _ = graph[src][dst]
                    print("%s -> %s (%s calls %s)" % (src, dst, bare(caller), callee))
        n = check(graph)
        if n:
            print("call_cycles: FAILED: %d circle(s) of calls between files in %s" % (n, b), file=sys.stderr)
            worst = 1
        else:
            print("call_cycles: ok: %d files, %d calling pairs, no circle (%s)" % (len(graph), n_edges, b))
    return worst


if __name__ == "__main__":
    sys.exit(main())
