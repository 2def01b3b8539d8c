#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/docs/check_words.py - the repository speaks of the project alone.

Fails (exit 1) when a tracked file's text, or its path, holds a word that
belongs to how the project was worked on rather than to what it is: the
names of working periods and of the people doing them, numbered rounds of
data sets, and the phrase that said who had run what. The fact behind such a
word is what a reader needs ("held-out DEMs, chosen before any run, never
used for tuning"), so the check names the line and the word to replace.

    python3 tools/docs/check_words.py            # every file `git ls-files` lists
    python3 tools/docs/check_words.py FILE...    # these files only (the check's own test)

Precision: each rule is a whole-word regular expression (case-insensitive),
so "rounding", "ground 2", "round(x)" and "sessionless" pass. A use that is
legitimate in its context is allowed by an entry of tools/docs/words-allow.txt:
`PATH<TAB>REGEX`, the regex matched against the line around the word (e.g.
pytest's fixture scope, or the word inside a quoted title). An entry that
allows nothing is stale and fails the check too, so the list cannot grow
silently. The rules and the allow list live in this directory, which is why
its three files (this one, the list and the check's test) are not read.
"""
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
ALLOW_FILE = os.path.join(HERE, "words-allow.txt")

# (name, pattern): what is banned; names are what the report says.
RULES = [
    ("session", r"\bsessions?\b"),
    ("helper", r"\bhelpers?\b"),
    ("round-N", r"\brounds?[- ]?[0-9]+\b"),
    ("Nth round", r"\b(?:first|second|third|fourth|fifth|sixth|seventh|eighth|ninth|tenth|"
                  r"next|previous|earlier|later)\s+rounds?\b"),
    ("ran nothing", r"\bran\s+nothing\s+on\b"),
]
RULES = [(name, re.compile(p, re.I)) for name, p in RULES]

# The checker's own files state the rules, so they are not read.
SELF = {"tools/docs/check_words.py", "tools/docs/words-allow.txt", "tools/docs/test_check_words.py"}


def load_allow(path):
    """[(path, compiled regex, line number in the list)]"""
    out = []
    if not os.path.exists(path):
        return out
    with open(path, encoding="utf-8") as f:
        for n, line in enumerate(f, 1):
            line = line.rstrip("\n")
            if not line.strip() or line.lstrip().startswith("#"):
                continue
            if "\t" not in line:
                raise SystemExit(f"{path}:{n}: expected PATH<TAB>REGEX")
            p, rx = line.split("\t", 1)
            out.append((p.strip(), re.compile(rx.strip(), re.I), n))
    return out


def tracked_files(root):
    r = subprocess.run(["git", "-C", root, "ls-files", "-z"], capture_output=True, check=True)
    return [p for p in r.stdout.decode("utf-8").split("\0") if p]


def read_text(path):
    """The file's text, or None for a binary file (a NUL byte in its first 8 KiB)."""
    with open(path, "rb") as f:
        data = f.read()
    if b"\0" in data[:8192]:
        return None
    return data.decode("utf-8", errors="replace")


def check(files, root, allow):
    """[(path, line number, rule name, line)] of the findings; marks used allow entries."""
    used = set()
    found = []
    for rel in files:
        hits = [(0, rel.replace("_", " "))]  # the path itself, as line 0 ("_" separates words)
        full = os.path.join(root, rel)
        if os.path.isfile(full):
            text = read_text(full)
            if text is not None:
                hits += list(enumerate(text.splitlines(), 1))
        for n, line in hits:
            for name, rx in RULES:
                for m in rx.finditer(line):
                    ok = False
                    for i, (ap, arx, _) in enumerate(allow):
                        if ap == rel and arx.search(line):
                            used.add(i)
                            ok = True
                    if not ok:
                        found.append((rel, n, name, line.strip()))
    return found, used


def main(argv):
    allow = load_allow(ALLOW_FILE)
    if argv:
        files = [os.path.relpath(os.path.abspath(a), ROOT) if os.path.exists(a) else a for a in argv]
        root = ROOT
        check_stale = False
    else:
        files = [f for f in tracked_files(ROOT) if f not in SELF]
        root = ROOT
        check_stale = True
    found, used = check(files, root, allow)
    for rel, n, name, line in found:
        where = f"{rel}:{n}" if n else f"{rel} (path)"
        print(f"{where}: '{name}': {line[:160]}")
    stale = [(ap, n) for i, (ap, _, n) in enumerate(allow) if i not in used] if check_stale else []
    for ap, n in stale:
        print(f"tools/docs/words-allow.txt:{n}: allows nothing in {ap} (remove the entry)")
    if found or stale:
        print(f"check_words: {len(found)} finding(s), {len(stale)} stale allow entr(y/ies); "
              "say what the fact is instead (e.g. 'held-out DEMs, chosen before any run, "
              "never used for tuning')", file=sys.stderr)
        return 1
    print(f"check_words: {len(files)} files, no banned word")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
