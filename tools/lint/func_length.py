#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/lint/func_length.py [--max N] [--enforce DIR ...] [ROOT] - function lengths.

Counts every C function definition in the *.c, *.h and *.cpp files under src/, port/
and tools/ of ROOT (default: the repository holding this script) from its
signature line (the first line of the declaration: return type and name) to
its closing brace: the closing brace's line number minus the signature's (a
function whose signature is on line 10 and whose brace closes on line 110 is
100 lines long). Prints each function over the limit (--max,
default 100) as FILE:FUNCTION:LENGTH, the enforced ones first. Exits 1 when a
function over the limit lies under an enforced directory (--enforce, default
tools/; repeatable) and is not excused by --allow FILE:FUNCTION (repeatable;
printed as a note), else 0; the others are printed as notes. CTest
`func_length` runs this (issue 15: each command split into parse, run and
report, no function over 100 lines in tools/).

The parser is deliberately small: comments, string and character literals
and preprocessor lines are blanked first; a '{' at file scope opens a
function when the text before it (since the previous ';', '}' or
preprocessor line at file scope) ends with ')' and is not an initializer
('=' outside parentheses) or a struct / union / enum body.
"""
import argparse
import os
import re
import sys

SCAN_DIRS = ("src", "port", "tools")


def blank(text):
    """Comments, literals and preprocessor lines replaced by spaces (newlines kept)."""
    out = []
    i, n = 0, len(text)
    line_start = True
    while i < n:
        c = text[i]
        if line_start and c in " \t":
            out.append(c)
            i += 1
            continue
        if line_start and c == "#":
            # preprocessor line, with backslash continuations
            while i < n:
                if text[i] == "\\" and i + 1 < n and text[i + 1] == "\n":
                    out.append("  \n"[1:])
                    out.append("\n")
                    i += 2
                    continue
                if text[i] == "\n":
                    break
                out.append(" ")
                i += 1
            continue
        line_start = False
        if c == "\n":
            out.append(c)
            line_start = True
            i += 1
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(c + " " * (j - i - 2) + (c if j - i >= 2 else ""))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def functions(text):
    """(name, first line, length) of each function definition in C source text."""
    src = blank(text)
    line_of = []
    line = 1
    for ch in src:
        line_of.append(line)
        if ch == "\n":
            line += 1
    found = []
    depth = 0
    chunk_start = 0          # start of the current file-scope declaration
    open_at = None           # (name, first line) of the function being read
    for i, ch in enumerate(src):
        if ch == "{":
            if depth == 0:
                decl = src[chunk_start:i]
                open_at = None
                stripped = decl.strip()
                if stripped.endswith(")") and not re.search(r"\b(struct|union|enum)\b[^()]*$", stripped):
                    head = stripped.split("(", 1)[0]
                    if "=" not in head:
                        m = re.search(r"([A-Za-z_]\w*)\s*$", head)
                        if m:
                            first = chunk_start + (len(decl) - len(decl.lstrip()))
                            open_at = (m.group(1), line_of[first])
            depth += 1
        elif ch == "}":
            depth -= 1
            if depth == 0:
                if open_at is not None:
                    name, first = open_at
                    found.append((name, first, line_of[i] - first))
                    open_at = None
                chunk_start = i + 1
        elif ch == ";" and depth == 0:
            chunk_start = i + 1
    return found


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--max", type=int, default=100)
    ap.add_argument("--enforce", action="append", default=None,
                    help="directory (relative to ROOT) where a long function fails (default tools)")
    ap.add_argument("--allow", action="append", default=[],
                    help="FILE:FUNCTION excused from the limit (printed as a note)")
    ap.add_argument("--all", action="store_true", help="print every function with its length")
    ap.add_argument("root", nargs="?",
                    default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
    args = ap.parse_args()
    enforce = [d.rstrip("/") + "/" for d in (args.enforce or ["tools"])]
    root = os.path.normpath(args.root)
    over_enf, over_note, count = [], [], 0
    allowed = set(args.allow)
    for top in SCAN_DIRS:
        for dirpath, dirnames, filenames in os.walk(os.path.join(root, top)):
            dirnames.sort()
            for fn in sorted(filenames):
                if not fn.endswith((".c", ".h", ".cpp")):
                    continue
                path = os.path.join(dirpath, fn)
                rel = os.path.relpath(path, root).replace(os.sep, "/")
                with open(path, encoding="utf-8", errors="replace") as f:
                    text = f.read()
                for name, first, length in functions(text):
                    count += 1
                    if args.all:
                        print(f"{rel}:{name}:{length}")
                    if length > args.max:
                        hit = f"{rel}:{name}:{length}"
                        enforced = any(rel.startswith(d) for d in enforce)
                        if enforced and f"{rel}:{name}" not in allowed:
                            over_enf.append(hit)
                        else:
                            over_note.append(hit + (", excused by --allow" if enforced else ", not enforced"))
    for hit in over_enf:
        print(f"func_length: {hit} (over {args.max} lines)")
    for hit in over_note:
        name_len, why = hit.split(", ", 1)
        print(f"func_length: note: {name_len} (over {args.max} lines, {why})")
    where = ", ".join(d.rstrip("/") for d in enforce)
    if over_enf:
        print(f"func_length: {len(over_enf)} function(s) in {where} over {args.max} lines")
        return 1
    print(f"func_length: {count} functions in {', '.join(SCAN_DIRS)}; none in {where} over {args.max} lines"
          + (f" ({len(over_note)} elsewhere)" if over_note else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
