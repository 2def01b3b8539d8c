#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/profile/add_stack.py - add the worst-case stack of each stage to `trn profile --json`.

    trn profile --json > prof.json
    python3 tools/profile/add_stack.py prof.json --build build/arm-none-eabi > prof-stack.json

For every stage, `stack_bytes` = the largest worst-case stack (tools/stack/trn_stack.py
--function, docs/assurance.md) of the public functions the stage calls (its `functions` field),
from the `.ci` call-graph files of the given build (arm-none-eabi for the Cortex-R5F figures,
host-release for the host's). The result is the same JSON with `stack_bytes` and `stack_build`
added, on stdout; `trn_plot.py profile` prints the figure next to each bar.
"""
import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
STACK = os.path.join(HERE, "..", "stack", "trn_stack.py")


def worst(build, fn):
    p = subprocess.run([sys.executable, STACK, "--build", build, "--function", fn],
                       capture_output=True, text=True)
    out = p.stdout.strip().splitlines()
    if p.returncode != 0 or not out or not out[-1].isdigit():
        sys.exit(f"add_stack: trn_stack.py --function {fn} failed: {(p.stderr or p.stdout).strip()}")
    return int(out[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("profile_json")
    ap.add_argument("--build", required=True, help="build directory with .ci files (e.g. build/arm-none-eabi)")
    a = ap.parse_args()
    with open(a.profile_json) as f:
        prof = json.load(f)
    cache = {}
    for name, st in prof["stages"].items():
        fns = [x for x in st.get("functions", "").split(",") if x]
        if not fns:
            sys.exit(f"add_stack: stage {name} lists no functions (an old trn profile?)")
        for fn in fns:
            if fn not in cache:
                cache[fn] = worst(a.build, fn)
        st["stack_bytes"] = max(cache[fn] for fn in fns)
    prof["stack_build"] = a.build
    json.dump(prof, sys.stdout)
    sys.stdout.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
