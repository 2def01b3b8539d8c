#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""retval_audit.py - every documented status of every public function is asserted by a test.

For each function declared in the public headers (include/trn/*.h,
port/include/**/*.h) the statuses named in its doc comment (@retval and
@return lines: TRN_OK, TRN_E_*) are collected; "as <function>" inherits that
function's list. Then the tests (tests/test_*.c, and the kernel tests tests/integration/kt_*.c
that run the Linux port in a VM, stage 50-kernel) are split into statements; a
status counts as tested for F when a statement calls F( and names the status,
or assigns F's result (st = F(...)) and one of the next four statements names
the status. Prints the missing (function, status) pairs and exits 1 if any.
A heuristic on the text, not a proof: it catches a status nobody asserts.
A status no test can provoke is listed, with its reason, as a `retval` line of
tools/analysis/deviations.txt; a listed status that is tested (or no longer
documented) fails the audit too, so the list cannot go stale.
"""
import glob
import os
import re
import sys

ROOT = os.path.realpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
STATUS = re.compile(r'\bTRN_(?:OK|E_[A-Z]+)\b')


def documented():
    docs = {}
    inherit = {}
    for h in sorted(glob.glob(os.path.join(ROOT, "include/trn/*.h")) +
                    glob.glob(os.path.join(ROOT, "port/include/**/*.h"), recursive=True)):
        text = open(h, encoding="utf-8").read()
        for m in re.finditer(r'/\*\*((?:[^*]|\*(?!/))*)\*/\s*([^;{}]*?)\b(trn_\w+)\s*\(', text):
            comment, name = m.group(1), m.group(3)
            if "#define" in m.group(2) or "typedef" in m.group(2):
                continue
            lines = [l for l in comment.splitlines() if "@retval" in l or "@return" in l or
                     l.strip().startswith("*") and STATUS.search(l)]
            block = "\n".join(lines)
            sts = set(STATUS.findall(block))
            am = re.search(r'@retval\s+as\s+(trn_\w+)', comment)
            if am:
                inherit[name] = am.group(1)
            if sts or am:
                docs[name] = sts
    for name, base in inherit.items():
        docs[name] |= docs.get(base, set())
    return docs


def tested():
    seen = {}
    for t in sorted(glob.glob(os.path.join(ROOT, "tests/test_*.c")) +
                    glob.glob(os.path.join(ROOT, "tests/integration/kt_*.c"))):
        text = open(t, encoding="utf-8").read()
        text = re.sub(r'/\*.*?\*/', ' ', text, flags=re.S)
        text = re.sub(r'\\\n', ' ', text)  # a #define continued on further lines is one line
        # a test's shorthand macro for a long call, #define SEL(a, ...) trn_select(a, ...),
        # counts as a call of the function it expands to
        for alias, target in re.findall(r'^#define\s+(\w+)\([^)]*\)\s+(trn_\w+)\s*\(', text, flags=re.M):
            text = re.sub(r'^#define\s+' + alias + r'\b.*$', ' ', text, flags=re.M)
            text = re.sub(r'\b' + alias + r'\s*\(', target + '(', text)
        stmts = text.split(";")
        for i, s in enumerate(stmts):
            for m in re.finditer(r'\b(trn_\w+)\s*\(', s):
                f = m.group(1)
                found = set(STATUS.findall(s))
                if re.search(r'\b\w+\s*=\s*' + re.escape(f) + r'\s*\(', s):
                    for nxt in stmts[i + 1:i + 5]:
                        found |= set(STATUS.findall(nxt))
                seen.setdefault(f, set()).update(found)
    return seen


def exempt():
    """(function, status) pairs no host or VM test can provoke, each with its
    reason, from the `retval` lines of tools/analysis/deviations.txt."""
    out = {}
    with open(os.path.join(ROOT, "tools/analysis/deviations.txt"), encoding="utf-8") as f:
        for line in f:
            parts = line.split(None, 3)
            if len(parts) == 4 and parts[0] == "retval":
                func, _, st = parts[1].partition(":")
                out[(func, st)] = parts[3].strip()
    return out


def main():
    docs, seen, ex = documented(), tested(), exempt()
    missing = []
    exempted = 0
    for f in sorted(docs):
        for st in sorted(docs[f]):
            if st not in seen.get(f, set()):
                if (f, st) in ex:
                    exempted += 1
                else:
                    missing.append((f, st))
    stale = [k for k in ex if k[1] in seen.get(k[0], set()) or k[1] not in docs.get(k[0], set())]
    total = sum(len(v) for v in docs.values())
    for f, st in missing:
        print("retval_audit: %s documents %s, no test asserts it" % (f, st))
    for f, st in sorted(stale):
        print("retval_audit: deviations.txt exempts %s:%s, which is tested or not documented: "
              "remove the line" % (f, st))
    print("retval_audit: %d functions, %d documented statuses, %d without a test, "
          "%d exempt (deviations.txt)" % (len(docs), total, len(missing), exempted))
    return 1 if missing or stale else 0


if __name__ == "__main__":
    sys.exit(main())
