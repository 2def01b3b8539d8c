# SPDX-License-Identifier: Apache-2.0
"""The words check itself (tools/docs/check_words.py): it must fail on each
banned word in a file and pass the legitimate neighbours of those words."""
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
CHECK = os.path.join(HERE, "check_words.py")


def run_on(text, name="sample.md"):
    with tempfile.TemporaryDirectory() as d:
        p = os.path.join(d, name)
        with open(p, "w", encoding="utf-8") as f:
            f.write(text)
        r = subprocess.run([sys.executable, CHECK, p], capture_output=True, text=True)
        return r.returncode, r.stdout


class CheckWords(unittest.TestCase):
    def test_banned_words_fail(self):
        for line in ("Measured in session 19.", "Sessions 3 and 4 moved it.",
                     "found by a helper", "two helpers ran it", "the round-3 DEMs",
                     "Round 2 DEMs", "rounds 4-6", "the second round of fuzzing",
                     "who ran nothing on them"):
            rc, out = run_on(f"first line\n{line}\n")
            self.assertEqual(rc, 1, f"not caught: {line!r}")
            self.assertIn(":2:", out, f"no line number for {line!r}: {out!r}")

    def test_legitimate_neighbours_pass(self):
        text = ("Rounding to the nearest cell, round(x) and lround.\n"
                "Flat ground 2 m below the camera; a background 3 cells wide.\n"
                "A sessionless protocol; the helpful default; rounded 2 ways.\n"
                "Around 3 cells; a round trip; ground-truth.\n")
        rc, out = run_on(text)
        self.assertEqual(rc, 0, out)

    def test_path_is_checked(self):
        rc, out = run_on("clean\n", name="session_notes.md")
        self.assertEqual(rc, 1)
        self.assertIn("(path)", out)

    def test_binary_file_skipped(self):
        with tempfile.TemporaryDirectory() as d:
            p = os.path.join(d, "blob.bin")
            with open(p, "wb") as f:
                f.write(b"\0\1session\0")
            r = subprocess.run([sys.executable, CHECK, p], capture_output=True, text=True)
            self.assertEqual(r.returncode, 0, r.stdout)


if __name__ == "__main__":
    unittest.main()
