#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Tests of call_cycles.py (run by tools/test.d/49-calls.sh; also `python3 -m unittest`).

Tiny fake programs of three or four C files, compiled with GCC's
-fcallgraph-info=su as the build does, so that the tool reads real .ci files:

1. a.c -> b.c -> c.c (one way): exit 0, and --list shows both edges;
2. the same with c.c calling back into a.c: exit 1, the cycle a -> b -> c -> a
   printed with a call for each step;
3. two files that each define a static function of the same name, one of
   them also calling the other file: no false edge from the static name;
4. the graph functions on a hand-made graph: a cycle in a component of two
   beside an acyclic rest, and a self-contained acyclic graph.
"""
import io
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
TOOL = os.path.join(HERE, "call_cycles.py")
sys.path.insert(0, HERE)
import call_cycles  # noqa: E402

CC = shutil.which("gcc") or shutil.which("cc")


def build(tmp, files):
    """Writes src/<name>.c for each entry and compiles it into obj/ with .ci files."""
    os.makedirs(os.path.join(tmp, "src"))
    os.makedirs(os.path.join(tmp, "obj"))
    for name, text in files.items():
        src = os.path.join(tmp, "src", name + ".c")
        with open(src, "w") as fh:
            fh.write(text)
        subprocess.run([CC, "-std=c99", "-O0", "-c", "-fcallgraph-info=su", src,
                        "-o", os.path.join(tmp, "obj", name + ".c.o")],
                       check=True, cwd=os.path.join(tmp, "obj"))


def run(tmp, *extra):
    p = subprocess.run([sys.executable, TOOL, "--build", os.path.join(tmp, "obj"), "--root", tmp] + list(extra),
                       capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


ONE_WAY = {
    "a": "int fb(int);\nint fa(int x) { return fb(x) + 1; }\n",
    "b": "int fc(int);\nint fb(int x) { return fc(x) * 2; }\n",
    "c": "int fc(int x) { return x - 3; }\n",
}


@unittest.skipUnless(CC, "no C compiler")
class FromGcc(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="call_cycles_")

    def tearDown(self):
        shutil.rmtree(self.tmp)

    def test_one_way_passes(self):
        build(self.tmp, ONE_WAY)
        rc, out, err = run(self.tmp, "--list")
        self.assertEqual(rc, 0, out + err)
        self.assertIn("src/a.c -> src/b.c (fa calls fb)", out)
        self.assertIn("src/b.c -> src/c.c (fb calls fc)", out)
        self.assertIn("3 files, 2 calling pairs, no circle", out)

    def test_cycle_fails_and_is_named(self):
        files = dict(ONE_WAY)
        files["c"] = "int fa(int);\nint fc(int x) { return x > 0 ? fa(x - 1) : 0; }\n"
        build(self.tmp, files)
        rc, out, err = run(self.tmp)
        self.assertEqual(rc, 1, out + err)
        self.assertIn("src/a.c -> src/b.c -> src/c.c -> src/a.c", out)
        self.assertIn("src/c.c -> src/a.c: fc calls fa", out)
        self.assertIn("FAILED", err)

    def test_static_namesake_is_no_edge(self):
        files = {
            "a": "int fb(int);\nstatic int h(int x) { return x + 1; }\nint fa(int x) { return h(fb(x)); }\n",
            "b": "static int h(int x) { return x * 2; }\nint fb(int x) { return h(x); }\n",
        }
        build(self.tmp, files)
        rc, out, err = run(self.tmp, "--list")
        self.assertEqual(rc, 0, out + err)
        self.assertNotIn("src/b.c -> src/a.c", out)
        self.assertIn("src/a.c -> src/b.c", out)

    def test_no_ci_files_is_an_error(self):
        os.makedirs(os.path.join(self.tmp, "obj"))
        rc, out, err = run(self.tmp)
        self.assertEqual(rc, 2)
        self.assertIn("no .ci files", err)


class OnAGraph(unittest.TestCase):
    def test_cycle_found(self):
        g = {"x": {"y": ("f", "g", "")}, "y": {"x": ("g", "f", ""), "z": ("g", "h", "")}, "z": {}}
        buf = io.StringIO()
        self.assertEqual(call_cycles.check(g, out=buf), 1)
        self.assertIn("x -> y -> x", buf.getvalue())

    def test_acyclic(self):
        g = {"x": {"y": ("f", "g", ""), "z": ("f", "h", "")}, "y": {"z": ("g", "h", "")}, "z": {}}
        buf = io.StringIO()
        self.assertEqual(call_cycles.check(g, out=buf), 0)
        self.assertEqual(buf.getvalue(), "")


if __name__ == "__main__":
    unittest.main()
