#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/docs/gen_cli_reference.py - the command-line reference, docs/cli/,
one page per `trn` command, written by `trn` itself from the option tables
that print its --help (tools/trn/cli.c, cli_usage_markdown), so the pages
cannot drift from the program:

    docs/cli/README.md      `trn --help-markdown`        (the commands, commands.def)
    docs/cli/<command>.md   `trn <command> --help-markdown`

    python3 tools/docs/gen_cli_reference.py [--trn build/host-release/trn]           # write
    python3 tools/docs/gen_cli_reference.py [--trn build/host-release/trn] --check   # compare

--check exits 1, naming each page that differs, is missing or belongs to no
command, when docs/cli/ is not what this build of `trn` writes (a new option,
a changed default, a new command: write the pages again and commit them).
"""
import argparse
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
OUT = os.path.join(ROOT, "docs", "cli")


def run(trn, *args):
    r = subprocess.run([trn, *args], capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"gen_cli_reference: `{trn} {' '.join(args)}` exited {r.returncode}: {r.stderr.strip()}")
    return r.stdout


def pages(trn):
    """{file name: text} of every page this trn writes."""
    index = run(trn, "--help-markdown")
    out = {"README.md": index}
    for name in re.findall(r"^\| \[`([^`]+)`\]\(\1\.md\) \|", index, re.M):
        out[f"{name}.md"] = run(trn, name, "--help-markdown")
    if len(out) < 2:
        raise SystemExit("gen_cli_reference: `trn --help-markdown` lists no command")
    return out


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trn", default=os.path.join(ROOT, "build", "host-release", "trn"))
    ap.add_argument("--check", action="store_true")
    a = ap.parse_args(argv)
    if not os.access(a.trn, os.X_OK):
        print(f"gen_cli_reference: no trn at {a.trn} (cmake --build --preset host-release --target trn_cli)",
              file=sys.stderr)
        return 1
    want = pages(a.trn)
    have = sorted(f for f in os.listdir(OUT) if f.endswith(".md")) if os.path.isdir(OUT) else []
    if a.check:
        bad = []
        for f, text in want.items():
            p = os.path.join(OUT, f)
            if not os.path.exists(p):
                bad.append(f"docs/cli/{f}: missing")
            elif open(p, encoding="utf-8").read() != text:
                bad.append(f"docs/cli/{f}: differs from `trn {f[:-3] if f != 'README.md' else ''} --help-markdown`")
        bad += [f"docs/cli/{f}: no such command" for f in have if f not in want]
        for b in bad:
            print(b)
        if bad:
            print("gen_cli_reference: docs/cli/ is not current; write it again with "
                  "python3 tools/docs/gen_cli_reference.py and commit it", file=sys.stderr)
            return 1
        print(f"gen_cli_reference: docs/cli/ is current ({len(want)} pages)")
        return 0
    os.makedirs(OUT, exist_ok=True)
    for f in have:
        if f not in want:
            os.remove(os.path.join(OUT, f))
    for f, text in want.items():
        with open(os.path.join(OUT, f), "w", encoding="utf-8") as fh:
            fh.write(text)
    print(f"gen_cli_reference: wrote {len(want)} pages into docs/cli/")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
