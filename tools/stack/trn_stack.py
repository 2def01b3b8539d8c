#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""trn_stack.py - worst-case stack depth of every public function, from the build.

GCC writes, next to each object compiled with -fstack-usage -fcallgraph-info=su,
a call-graph file <obj>.ci (VCG format): one node per function with its own
frame size in bytes and its qualifier (static / dynamic / dynamic,bounded), one
node without a size (shape: ellipse) per function called but not defined in
that translation unit, and one edge per call site. This tool joins the .ci files
of a build, and for every public function (one declared in the public headers)
computes

    worst(f) = frame(f) + max(worst(g) for every callee g of f)

which is exact for a call graph without cycles and without indirect calls: the
core has no recursion and calls through a pointer only where a public header
documents a caller's callback and its stack budget (trn_field's progress
callback), and the tool checks that rather than assumes it. It fails loudly (exit 1, one line per problem) when

  * the graph has a cycle (recursion, direct or mutual),
  * a function calls through a pointer (GCC's __indirect_call node), unless
    the externals file gives that function's indirect calls a budget with a
    line 'indirect:<function> bytes reason' (a documented callback: the
    caller's function must fit the budget, stated in the public header),
  * a frame is "dynamic" without a bound (alloca, VLA),
  * a callee is defined nowhere in the build and is not listed, with a stack
    budget and its reason, in the externals file (tools/stack/external.txt),
  * a public function's worst case exceeds the limit (TRN_STACK_LIMIT_BYTES,
    read from include/trn/trn_config.h unless --limit is given),
  * no public function was found at all (wrong build directory or flags).

Usage:
  trn_stack.py --build build/arm-none-eabi [--root .] [--limit N]
               [--headers 'include/trn/*.h' ...] [--sources 'src/*.c' ...]
               [--externals tools/stack/external.txt] [--function NAME]

--sources restricts the graph to functions defined in matching files (globs
relative to --root; default: src/**.c and port/proto/**.c), so test code in
the same build directory is ignored. --function prints just that function's
worst case (one integer), for tests.
"""
import argparse
import fnmatch
import glob
import os
import re
import sys

NODE_RE = re.compile(r'^node:\s*\{\s*title:\s*"([^"]+)"\s*label:\s*"([^"]*)"(.*)\}\s*$')
EDGE_RE = re.compile(r'^edge:\s*\{\s*sourcename:\s*"([^"]+)"\s*targetname:\s*"([^"]+)"(?:\s*label:\s*"([^"]*)")?')
SIZE_RE = re.compile(r'(\d+) bytes \(([a-z,]+)\)')
INDIRECT = "__indirect_call"


class Fn:
    def __init__(self, key, name, src, frame, qual, ci):
        self.key = key
        self.name = name
        self.src = src
        self.frame = frame
        self.qual = qual
        self.ci = ci
        self.callees = []  # keys or ('ext', name) or ('ind', site)


def parse_ci(path):
    """Return (defined: name -> (src, frame, qual), external: set, edges: [(a, b, site)])."""
    defined, external, edges = {}, set(), []
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            line = line.strip()
            m = NODE_RE.match(line)
            if m:
                title, label = m.group(1), m.group(2)
                parts = label.split("\\n")
                sm = SIZE_RE.search(label)
                if sm:
                    src = parts[1].rsplit(":", 2)[0] if len(parts) > 1 else "?"
                    defined[title] = (src, int(sm.group(1)), sm.group(2))
                else:
                    external.add(title)
                continue
            m = EDGE_RE.match(line)
            if m:
                edges.append((m.group(1), m.group(2), m.group(3) or ""))
    return defined, external, edges


def read_limit(config_h):
    with open(config_h, encoding="utf-8") as fh:
        text = fh.read()
    m = re.search(r'#\s*define\s+TRN_STACK_LIMIT_BYTES\s+\(?\s*(\d+)', text)
    if not m:
        sys.exit("trn_stack: TRN_STACK_LIMIT_BYTES not found in %s" % config_h)
    return int(m.group(1))


def public_names(root, patterns):
    """Identifiers declared as functions in the public headers."""
    names = set()
    for pat in patterns:
        for h in glob.glob(os.path.join(root, pat), recursive=True):
            with open(h, encoding="utf-8") as fh:
                text = fh.read()
            text = re.sub(r'/\*.*?\*/', ' ', text, flags=re.S)
            text = re.sub(r'//[^\n]*', ' ', text)
            text = re.sub(r'^\s*#[^\n]*(\\\n[^\n]*)*', ' ', text, flags=re.M)
            # a declaration: type words, then name(, then ...);
            for m in re.finditer(r'\b([A-Za-z_]\w*)\s*\(([^;{}()]|\([^()]*\))*\)\s*;', text):
                names.add(m.group(1))
    return names


def read_externals(path):
    ext = {}
    if not path or not os.path.exists(path):
        return ext
    with open(path, encoding="utf-8") as fh:
        for n, line in enumerate(fh, 1):
            s = line.split("#", 1)[0].strip()
            if not s:
                continue
            f = s.split(None, 2)
            if len(f) < 3 or not f[1].isdigit():
                sys.exit("trn_stack: %s:%d: want 'name bytes reason'" % (path, n))
            ext[f[0]] = int(f[1])
    return ext


def in_sources(src, root, patterns):
    a = os.path.realpath(src if os.path.isabs(src) else os.path.join(root, src))
    rel = os.path.relpath(a, os.path.realpath(root))
    for pat in patterns:
        if fnmatch.fnmatch(rel, pat):
            return True
    return False


def short(name, root):
    """GCC titles a static function 'path/file.c:name'; show it relative to root."""
    if ":" in name and os.path.isabs(name):
        return os.path.relpath(name, root)
    return name


def build_graph(ci_files, root, src_patterns):
    fns = {}          # key -> Fn
    by_name = {}      # name -> [keys]
    per_ci = []
    for ci in ci_files:
        defined, external, edges = parse_ci(ci)
        local = {}
        for name, (src, frame, qual) in defined.items():
            if not in_sources(src, root, src_patterns):
                continue
            key = name if name not in by_name else "%s::%s" % (ci, name)
            fn = Fn(key, name, src, frame, qual, ci)
            fns[key] = fn
            by_name.setdefault(name, []).append(key)
            local[name] = key
        per_ci.append((ci, local, edges))
    if not fns:
        return fns, by_name
    for ci, local, edges in per_ci:
        for a, b, site in edges:
            if a not in local:
                continue
            fn = fns[local[a]]
            if b == INDIRECT:
                fn.callees.append(("ind", site))
            elif b in local:
                fn.callees.append(local[b])
            elif b in by_name and len(by_name[b]) == 1:
                fn.callees.append(by_name[b][0])
            elif b in by_name:
                # Defined in several units (static there); an external call can
                # only reach a non-static one: take the largest to stay safe.
                fn.callees.append(("multi", b))
            else:
                fn.callees.append(("ext", b))
    return fns, by_name


def analyse(fns, by_name, externals):
    errors = []
    memo = {}
    path_of = {}
    state = {}

    def worst(key):
        if key in memo:
            return memo[key]
        fn = fns[key]
        if state.get(key) == 1:
            errors.append("cycle through %s (%s): recursion has no static bound" % (fn.name, fn.src))
            return 0
        state[key] = 1
        if fn.qual == "dynamic":
            errors.append("%s (%s): dynamic frame without a bound (alloca or VLA)" % (fn.name, fn.src))
        best, best_path = 0, []
        for c in fn.callees:
            if isinstance(c, tuple):
                kind, what = c
                if kind == "ind":
                    budget = externals.get("indirect:" + fn.name.rsplit(":", 1)[-1])
                    if budget is None:
                        errors.append("%s (%s): indirect call at %s cannot be bounded" % (fn.name, fn.src, what or "?"))
                        continue
                    w, p = budget, ["indirect[budget %d]" % budget]
                    if w > best:
                        best, best_path = w, p
                    continue
                if kind == "multi":
                    cands = [worst(k) for k in by_name[what]]
                    w, p = max(cands), ["%s(ambiguous)" % what]
                elif what in externals:
                    w, p = externals[what], ["%s[ext %d]" % (what, externals[what])]
                else:
                    errors.append("%s (%s): calls %s, which is not in the build and not in the externals file"
                                  % (fn.name, fn.src, what))
                    continue
            else:
                w = worst(c)
                p = path_of.get(c, [fns[c].name])
            if w > best:
                best, best_path = w, p
        state[key] = 2
        memo[key] = fn.frame + best
        path_of[key] = [fn.name] + best_path
        return memo[key]

    for key in sorted(fns):
        worst(key)
    # de-duplicate (a cycle is reported once per entry point otherwise)
    seen, uniq = set(), []
    for e in errors:
        if e not in seen:
            seen.add(e)
            uniq.append(e)
    return memo, path_of, uniq


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", required=True, help="build directory holding the .ci files")
    ap.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
    ap.add_argument("--limit", type=int, help="bytes; default TRN_STACK_LIMIT_BYTES of trn_config.h")
    ap.add_argument("--config", default="include/trn/trn_config.h")
    ap.add_argument("--headers", nargs="*", default=["include/trn/*.h", "port/include/**/*.h"])
    ap.add_argument("--sources", nargs="*", default=["src/*.c", "src/**/*.c", "port/proto/*.c", "port/proto/**/*.c"])
    ap.add_argument("--externals", default=None, help="default tools/stack/external.txt")
    ap.add_argument("--function", help="print only this function's worst case")
    ap.add_argument("--all", action="store_true", help="list every function, not just public ones")
    a = ap.parse_args(argv)

    root = os.path.realpath(a.root)
    externals = read_externals(a.externals or os.path.join(root, "tools/stack/external.txt"))
    ci_files = sorted(glob.glob(os.path.join(a.build, "**", "*.ci"), recursive=True))
    if not ci_files:
        sys.exit("trn_stack: no .ci files under %s (configure with TRN_STACK_USAGE=ON, GCC >= 10)" % a.build)
    fns, by_name = build_graph(ci_files, root, a.sources)
    memo, path_of, errors = analyse(fns, by_name, externals)

    if a.function:
        keys = by_name.get(a.function, [])
        if len(keys) != 1:
            sys.exit("trn_stack: function %s found %d times" % (a.function, len(keys)))
        for e in errors:
            print("trn_stack: ERROR " + e, file=sys.stderr)
        print(memo[keys[0]])
        return 1 if errors else 0

    limit = a.limit if a.limit is not None else read_limit(os.path.join(root, a.config))
    pub = public_names(root, a.headers)
    rows = [fns[k] for k in fns if a.all or fns[k].name in pub]
    if not any(fns[k].name in pub for k in fns):
        errors.append("no public function found in %s (sources %s)" % (a.build, " ".join(a.sources)))
    rows.sort(key=lambda f: (-memo[f.key], f.name))
    print("worst-case stack, bytes (limit %d = TRN_STACK_LIMIT_BYTES), from %d .ci files in %s"
          % (limit, len(ci_files), a.build))
    print("%-36s %6s %6s  %s" % ("function", "frame", "worst", "deepest call chain"))
    over = []
    for f in rows:
        w = memo[f.key]
        mark = ""
        if f.name in pub and w > limit:
            over.append(f)
            mark = "  OVER LIMIT"
        print("%-36s %6d %6d  %s%s" % (short(f.name, root), f.frame, w, " > ".join(short(x, root) for x in path_of[f.key]), mark))
    for f in over:
        errors.append("%s: worst case %d bytes > limit %d" % (f.name, memo[f.key], limit))
    for e in errors:
        print("trn_stack: ERROR " + e, file=sys.stderr)
    if errors:
        print("trn_stack: FAILED (%d problems)" % len(errors), file=sys.stderr)
        return 1
    print("trn_stack: ok: %d public functions, deepest %s = %d bytes; graph acyclic, indirect calls only budgeted callbacks"
          % (len(rows), rows[0].name if rows else "-", memo[rows[0].key] if rows else 0))
    return 0


if __name__ == "__main__":
    sys.exit(main())
