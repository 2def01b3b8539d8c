#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Tests of trn_stack.py (run by tools/test.d/40-stack.sh; also `python3 -m unittest`).

1. The figure for a small call chain equals the hand count from its
   arm-none-eabi disassembly (test/handcount.c, -O2, Cortex-R5 ARM mode):
       hc_leaf: sub sp, sp, #24                       -> 24 bytes
       hc_mid:  push {lr} (4) + sub sp, sp, #44 (44)  -> 48 bytes
       hc_top:  push {lr} (4) + sub sp, sp, #12 (12)  -> 16 bytes
   worst(hc_mid) = 48 + 24 = 72; worst(hc_top) = 16 + max(72, 24) = 88.
   If GCC changes its code generation, this test fails and the hand count
   has to be redone from `arm-none-eabi-objdump -d`.
   The same for one core function, trn_grid_f32_sub (16 bytes, see the test).
2. Recursion (direct and mutual), a call through a pointer, an unknown
   external callee and a public function over the limit each make the tool
   fail with a message naming the problem.
"""
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
TOOL = os.path.join(HERE, "trn_stack.py")
ARM_FLAGS = ["-mcpu=cortex-r5", "-mfpu=vfpv3-d16", "-mfloat-abi=hard", "-marm"]


def compile_c(cc, flags, src_text, name, tmp):
    src = os.path.join(tmp, name + ".c")
    if src_text is not None:
        with open(src, "w") as fh:
            fh.write(src_text)
    subprocess.run([cc, "-std=c99", "-O2", "-c", "-fstack-usage", "-fcallgraph-info=su"] + flags +
                   [src, "-o", os.path.join(tmp, name + ".o")], check=True, cwd=tmp)


def run_tool(tmp, *args):
    p = subprocess.run([sys.executable, TOOL, "--build", tmp, "--root", tmp, "--sources", "*.c",
                        "--externals", os.path.join(tmp, "none.txt")] + list(args),
                       capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


class HandCount(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="trn_stack_")

    def tearDown(self):
        shutil.rmtree(self.tmp)

    @unittest.skipUnless(shutil.which("arm-none-eabi-gcc"), "arm-none-eabi-gcc not installed")
    def test_arm_hand_count(self):
        shutil.copy(os.path.join(HERE, "test", "handcount.c"), self.tmp)
        compile_c("arm-none-eabi-gcc", ARM_FLAGS, None, "handcount", self.tmp)
        for fn, want in (("hc_leaf", 24), ("hc_mid", 72), ("hc_top", 88)):
            rc, out, err = run_tool(self.tmp, "--function", fn)
            self.assertEqual(rc, 0, err)
            self.assertEqual(int(out.strip()), want, fn)

    @unittest.skipUnless(os.path.isdir(os.path.join(HERE, "..", "..", "build", "arm-none-eabi")),
                         "arm-none-eabi preset not built")
    def test_core_function_hand_count(self):
        # trn_grid_f32_sub on the Cortex-R5 (arm-none-eabi preset, -O2 -marm),
        # from `arm-none-eabi-objdump -d .../grid.c.obj`:
        #   push {r4, r5, r6, lr}          16 bytes, no sub sp
        #   bl trn_grid_f32_check          a leaf without push or sub sp: 0
        # worst = 16 + 0 = 16. Recount if grid.c or the compiler changes.
        root = os.path.realpath(os.path.join(HERE, "..", ".."))
        p = subprocess.run([sys.executable, TOOL, "--build", os.path.join(root, "build", "arm-none-eabi"),
                            "--root", root, "--function", "trn_grid_f32_sub"],
                           capture_output=True, text=True)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertEqual(int(p.stdout.strip()), 16)

    def expect_fail(self, text, needle, *args):
        compile_c("gcc", [], text, "t", self.tmp)
        rc, out, err = run_tool(self.tmp, "--limit", "100000", *args)
        self.assertEqual(rc, 1, out + err)
        self.assertIn(needle, err)

    def test_direct_recursion_fails(self):
        self.expect_fail("int f(int n);\nint f(int n) { return n > 1 ? f(n - 1) * f(n - 2) + n : 1; }\n",
                         "cycle through f")

    def test_mutual_recursion_fails(self):
        self.expect_fail("int f(int n); int g(int n);\n"
                         "__attribute__((noinline)) int g(int n) { return n > 0 ? f(n - 2) * 3 : 1; }\n"
                         "__attribute__((noinline)) int f(int n) { return n > 0 ? g(n - 1) + n : 0; }\n",
                         "cycle through")

    def test_indirect_call_fails(self):
        self.expect_fail("int f(int (*p)(int));\nint f(int (*p)(int)) { return p(3) + 1; }\n",
                         "indirect call")

    def test_unknown_external_fails(self):
        self.expect_fail("void ext(void);\nvoid f(void);\nvoid f(void) { ext(); ext(); }\n",
                         "calls ext, which is not in the build")

    def test_over_limit_fails(self):
        hdr = os.path.join(self.tmp, "pub.h")
        with open(hdr, "w") as fh:
            fh.write("int f(int a);\n")
        compile_c("gcc", [], "int f(int a);\nint f(int a) { volatile int b[64]; b[a & 63] = a; return b[3]; }\n",
                  "t", self.tmp)
        rc, out, err = run_tool(self.tmp, "--limit", "64", "--headers", "pub.h")
        self.assertEqual(rc, 1, out + err)
        self.assertIn("f: worst case", err)
        rc, out, err = run_tool(self.tmp, "--limit", "4096", "--headers", "pub.h")
        self.assertEqual(rc, 0, out + err)


if __name__ == "__main__":
    unittest.main()
