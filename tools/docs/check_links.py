#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/docs/check_links.py - every relative link and anchor in the tracked
Markdown files resolves.

For each `[text](target)` and `![alt](target)` outside code (fenced blocks and
`inline code` are skipped), and each reference definition `[id]: target`:
  - http(s):, mailto: and other URL schemes are not fetched (no network);
  - a path is resolved against the linking file's folder and must exist in
    the working tree (a file or a folder);
  - `#anchor` (alone, or after a .md path) must be a heading of that file, by
    GitHub's rule (lower case; punctuation other than '-' and '_' dropped;
    spaces to '-'; a repeated heading gets -1, -2, ...), or an explicit
    `<a id="...">` / `<a name="...">` in it.

    python3 tools/docs/check_links.py           # every tracked *.md
    python3 tools/docs/check_links.py FILE...   # these files (the check's own test)

Exit 1 with `FILE:LINE: reason` per broken link.
"""
import os
import re
import subprocess
import sys
import urllib.parse

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

LINK = re.compile(r"(!?)\[((?:[^\[\]]|\[[^\]]*\])*)\]\(\s*<?([^)\s>]*)>?(?:\s+\"[^\"]*\")?\s*\)")
REFDEF = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s+.*)?$")
HEADING = re.compile(r"^\s{0,3}(#{1,6})\s+(.*?)\s*#*\s*$")
ANCHOR_TAG = re.compile(r"<a\s+(?:id|name)=\"([^\"]+)\"", re.I)
FENCE = re.compile(r"^\s{0,3}(```|~~~)")
SCHEME = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*:")


def slug(text):
    """GitHub's anchor for a heading's text."""
    t = re.sub(r"`([^`]*)`", r"\1", text)               # code spans keep their text
    t = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", t)     # links keep their text
    t = re.sub(r"<[^>]+>", "", t)                        # inline HTML dropped
    t = t.strip().lower()
    t = re.sub(r"[^\w\- ]", "", t)                       # punctuation dropped (unicode letters kept)
    return t.replace(" ", "-")


def lines_outside_code(text, blank_code=True):
    """(line number, line) of the lines outside fenced code, inline code blanked
    unless blank_code is false."""
    fence = None
    for n, line in enumerate(text.splitlines(), 1):
        m = FENCE.match(line)
        if m:
            if fence is None:
                fence = m.group(1)
            elif m.group(1) == fence:
                fence = None
            continue
        if fence is None and not blank_code:
            yield n, line
        elif fence is None:
            yield n, re.sub(r"(`+)(.+?)\1", lambda c: " " * len(c.group(0)), line)


_anchor_cache = {}


def anchors(path):
    if path not in _anchor_cache:
        with open(path, encoding="utf-8") as f:
            text = f.read()
        seen = {}
        out = set()
        for _, line in lines_outside_code(text, blank_code=False):
            m = HEADING.match(line)
            if m:
                s = slug(m.group(2))
                k = seen.get(s, 0)
                out.add(s if k == 0 else f"{s}-{k}")
                seen[s] = k + 1
        out.update(ANCHOR_TAG.findall(text))
        _anchor_cache[path] = out
    return _anchor_cache[path]


def check_target(src, target):
    """None if target resolves from src (a path), else the reason."""
    if not target or SCHEME.match(target):
        return None
    path, _, frag = target.partition("#")
    path = urllib.parse.unquote(path)
    if path:
        full = os.path.normpath(os.path.join(os.path.dirname(src), path))
        if not os.path.exists(full):
            return f"no such file: {path}"
    else:
        full = src
    if frag:
        if os.path.isdir(full) or not full.endswith(".md"):
            return None  # anchors into non-Markdown files are not checked
        if urllib.parse.unquote(frag) not in anchors(full):
            return f"no heading or anchor '#{frag}' in {os.path.relpath(full, ROOT)}"
    return None


def check_file(path):
    with open(path, encoding="utf-8") as f:
        text = f.read()
    bad = []
    for n, line in lines_outside_code(text):
        targets = [m.group(3) for m in LINK.finditer(line)]
        m = REFDEF.match(line)
        if m:
            targets.append(m.group(1))
        for t in targets:
            why = check_target(path, t)
            if why:
                bad.append((n, why))
    return bad


def main(argv):
    if argv:
        files = [os.path.abspath(a) for a in argv]
    else:
        r = subprocess.run(["git", "-C", ROOT, "ls-files", "-z", "--", "*.md"], capture_output=True,
                           check=True)
        files = [os.path.join(ROOT, p) for p in r.stdout.decode().split("\0") if p]
    total = 0
    nbad = 0
    for f in files:
        bad = check_file(f)
        for n, why in bad:
            print(f"{os.path.relpath(f, ROOT)}:{n}: {why}")
        nbad += len(bad)
        total += 1
    if nbad:
        print(f"check_links: {nbad} broken link(s)", file=sys.stderr)
        return 1
    print(f"check_links: {total} Markdown files, every relative link and anchor resolves")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
