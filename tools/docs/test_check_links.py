# SPDX-License-Identifier: Apache-2.0
"""The link check itself (tools/docs/check_links.py): broken paths and
anchors fail, good ones and links inside code pass."""
import os
import subprocess
import sys
import tempfile
import unittest

CHECK = os.path.join(os.path.dirname(os.path.abspath(__file__)), "check_links.py")


def run(files):
    with tempfile.TemporaryDirectory() as d:
        paths = []
        for name, text in files.items():
            p = os.path.join(d, name)
            os.makedirs(os.path.dirname(p), exist_ok=True)
            with open(p, "w", encoding="utf-8") as f:
                f.write(text)
            paths.append(p)
        r = subprocess.run([sys.executable, CHECK, paths[0]], capture_output=True, text=True)
        return r.returncode, r.stdout


class CheckLinks(unittest.TestCase):
    def test_good_links_pass(self):
        rc, out = run({"a.md": "# Top\n## The `trn` tool: usage\n## Top\n"
                               "[x](b/c.md#what-it-does) [y](#the-trn-tool-usage) [z](#top-1)\n"
                               "[w](https://example.org/nowhere) ![f](b)\n"
                               "```\n[not a link](missing.md)\n```\n`[code](missing.md)`\n",
                       "b/c.md": "## What it does\n"})
        self.assertEqual(rc, 0, out)

    def test_missing_file_fails(self):
        rc, out = run({"a.md": "intro\n[x](nothere.md)\n"})
        self.assertEqual(rc, 1)
        self.assertIn("a.md:2: no such file: nothere.md", out)

    def test_missing_anchor_fails(self):
        rc, out = run({"a.md": "# Top\n[x](b.md#gone) [y](#top) [z](#nope)\n", "b.md": "# Here\n"})
        self.assertEqual(rc, 1)
        self.assertIn("'#gone'", out)
        self.assertIn("'#nope'", out)
        self.assertNotIn("'#top'", out)


if __name__ == "__main__":
    unittest.main()
