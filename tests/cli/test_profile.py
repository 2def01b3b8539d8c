#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tests/cli/test_profile.py - `trn profile` end to end (CTest `cli_profile`,
and `profile_instructions` with --instructions).

    python3 tests/cli/test_profile.py PATH/TO/trn WORKDIR [--instructions] [--stack-build DIR]

Checks the JSON (every stage with wall_ms, wall_max_ms >= wall_ms,
workspace_bytes >= scratch_bytes), the workspace figures against sizes
computed here from the configuration, the table, the budget file parser
(each error class names the file and line, exit 1, one stderr line), and
--check's exit status (0 within budget, 3 over, 2 without --budget), the
height matcher's stages and --dem FILE (a DEM written by `trn terrain`).
With --stack-build DIR (a build with GCC's .ci files): tools/profile/add_stack.py
gives every stage a stack figure, localize's equal to trn_stack.py's for trn_localize_dem.
With --instructions: two runs under callgrind give identical instruction
counts for every stage (height_rest exactly height_localize minus its three parts); exit 77 (CTest: skipped) when valgrind is missing.
Never asserts on wall time.
"""
import json
import os
import shutil
import subprocess
import sys

import clitest  # noqa: E402  (tests/cli/, the script's own directory)

TRN = os.path.abspath(sys.argv[1])
WORK = os.path.abspath(sys.argv[2])
INSTR = "--instructions" in sys.argv[3:]
STACK_BUILD = sys.argv[sys.argv.index("--stack-build") + 1] if "--stack-build" in sys.argv[3:] else None
STAGES = ["highpass_occupancy", "chamfer", "map_build", "prob_map", "select",
          "local_occupancy", "search", "peak_fit", "localize",
          "height_map_build", "height_search", "height_refine", "height_failure",
          "height_rest", "height_localize"]
H_PARTS = ["height_search", "height_refine", "height_failure"]
BASE = ["--map-cells", "128", "--local-cells", "32", "--max-range-m", "4"]
SMALL = BASE + ["--window-cells", "10", "--runs", "3"]
H = clitest.Harness(TRN, sub=("profile",), timeout=600)
check, run, expect_error = H.check, H.run, H.expect_error


def write(name, text):
    path = os.path.join(WORK, name)
    with open(path, "w") as f:
        f.write(text)
    return path


def instructions_test():
    if shutil.which("valgrind") is None:
        print("SKIP: valgrind not installed (bash tools/setup.sh profile)")
        sys.exit(77)
    counts = []
    for _ in range(2):
        rc, out, err = run(*SMALL, "--instructions", "--json", timeout=1200)
        check(rc == 0, f"--instructions: exit {rc}: {err.strip()}")
        if rc != 0:
            return
        st = json.loads(out)["stages"]
        for s in STAGES:
            check(isinstance(st[s].get("instructions"), int) and (st[s]["instructions"] > 0 or s == "height_rest"),
                  f"--instructions: stage {s} has no positive instruction count: {st[s]}")
        # height_rest is the whole height localization minus its parts, exactly
        c = {s: st[s].get("instructions") for s in STAGES}
        check(c["height_rest"] == c["height_localize"] - sum(c[s] for s in H_PARTS),
              f"--instructions: height_rest is not height_localize minus its parts: {c}")
        counts.append({s: st[s].get("instructions") for s in STAGES})
    check(counts[0] == counts[1], f"instruction counts differ between two runs: {counts}")
    # The whole localization contains a search and a local occupancy; a map build its parts.
    c = counts[0]
    check(c["localize"] > c["search"] and c["localize"] > c["local_occupancy"],
          f"localize counts fewer instructions than its parts: {c}")
    check(c["map_build"] > c["highpass_occupancy"] + c["chamfer"],
          f"map_build counts fewer instructions than its parts: {c}")
    # the whole height localization refines and scores every pose at least once
    check(c["height_localize"] > c["height_refine"] + c["height_failure"],
          f"height_localize counts fewer instructions than its refinement and failure parts: {c}")
    print("instructions:", json.dumps(c))


def main():
    os.makedirs(WORK, exist_ok=True)
    if INSTR:
        instructions_test()
        return finish()

    # JSON with every stage.
    rc, out, err = run(*SMALL, "--json")
    check(rc == 0, f"--json: exit {rc}: {err.strip()}")
    j = json.loads(out)
    H.check_version(j, "profile --json")
    cfg = j["config"]
    check(cfg["map_cells"] == 128 and cfg["local_cells"] == 32 and cfg["window_cells"] == 10,
          f"config echo wrong: {cfg}")
    check(cfg["poses"] == 21 * 21, f"poses {cfg['poses']}, want 441")
    check(cfg["candidates"] > 0, "no candidates")
    check(list(j["stages"].keys()) == STAGES, f"stages {list(j['stages'])}, want {STAGES}")
    for s in STAGES:
        e = j["stages"][s]
        check((e["wall_ms"] > 0 or s == "height_rest") and e["wall_max_ms"] >= e["wall_ms"],
              f"{s}: wall times {e}")
        check(e["workspace_bytes"] >= e["scratch_bytes"] >= 0, f"{s}: bytes {e}")
        check("instructions" not in e, f"{s}: instructions without --instructions")
        check("budget_ms" not in e, f"{s}: budget without --budget")
    # Workspace of the stages whose outputs are plain volumes, from the configuration.
    n, nz = 128, cfg["height_bins"]
    st = j["stages"]
    check(st["chamfer"]["workspace_bytes"] == n * n * nz, f"chamfer bytes {st['chamfer']}")
    check(st["prob_map"]["workspace_bytes"] - st["prob_map"]["scratch_bytes"] == n * n * nz * 4,
          f"prob_map output bytes {st['prob_map']}")
    check(st["highpass_occupancy"]["workspace_bytes"] - st["highpass_occupancy"]["scratch_bytes"]
          == n * n * 4 + n * n * nz, f"highpass_occupancy bytes {st['highpass_occupancy']}")
    check(st["peak_fit"]["workspace_bytes"] == 0, "peak_fit needs no workspace")
    # the height search's output is the ln L grid, one double per pose; its scratch the pose
    # score's (src/height_score.c: 72 bytes a local cell, 32 x 32 here, and the carve's rounding)
    hs = st["height_search"]
    check(hs["workspace_bytes"] - hs["scratch_bytes"] == 21 * 21 * 8
          and 32 * 32 * 72 <= hs["scratch_bytes"] <= 32 * 32 * 72 + 256,
          f"height_search bytes {hs}")
    check(st["height_localize"]["scratch_bytes"] > st["height_search"]["workspace_bytes"],
          f"height_localize scratch {st['height_localize']}")
    # height_rest: the whole's median minus the parts' medians
    rest = st["height_localize"]["wall_ms"] - sum(st[s]["wall_ms"] for s in H_PARTS)
    check(abs(st["height_rest"]["wall_ms"] - rest) <= 1e-6 * max(1.0, abs(rest)),
          f"height_rest {st['height_rest']['wall_ms']} != whole - parts {rest}")
    check(cfg["height_matcher_bins"] >= 16 and cfg["height_matcher_status"] == "ok"
          and cfg["height_matcher_error_cells"] < 1.5,
          f"the height matcher's localization: {cfg}")
    check(st["search"]["scratch_bytes"] > 0 and st["localize"]["scratch_bytes"] > st["search"]["scratch_bytes"],
          f"search / localize scratch: {st['search']} {st['localize']}")
    # A larger window needs a larger search workspace; the map does not change.
    rc, out2, err = run(*BASE, "--window-cells", "20", "--runs", "1", "--json")
    j2 = json.loads(out2) if rc == 0 else None
    check(j2 is not None and j2["stages"]["search"]["scratch_bytes"] > st["search"]["scratch_bytes"],
          "search workspace does not grow with the window")
    check(j2 is not None and j2["stages"]["map_build"]["workspace_bytes"] == st["map_build"]["workspace_bytes"],
          "map workspace changed with the window")

    # Table.
    rc, out, err = run(*SMALL)
    check(rc == 0 and all(s in out for s in STAGES), f"table: exit {rc}, stages missing: {out}")

    # Budget file: a generous one passes --check, a tight one fails it.
    ok = write("ok.txt", "# generous\nscale 1\n" + "".join(f"{s} 100000\n" for s in STAGES))
    rc, out, err = run(*SMALL, "--budget", ok, "--check", "--json")
    check(rc == 0, f"--check within budget: exit {rc}: {err.strip()}")
    jb = json.loads(out) if rc == 0 else {"budget": {}, "stages": {}}
    check(jb["budget"].get("scale") == 1 and jb["budget"].get("over_budget") == 0, f"budget echo {jb['budget']}")
    for s in STAGES:
        e = jb["stages"].get(s, {})
        check(e.get("budget_ms") == 100000 and e.get("over") is False and 0 < e.get("share", -1) < 1,
              f"{s}: budget fields {e}")
    tight = write("tight.txt", "scale 1000   # a slow target\nselect 0.001\nlocalize 100000\n")
    rc, out, err = run(*SMALL, "--budget", tight, "--check")
    check(rc == 3, f"--check over budget: exit {rc}, want 3")
    sel = [l for l in out.splitlines() if l.startswith("select ")]
    check(len(sel) == 1 and "OVER BUDGET" in sel[0], f"select row not marked: {sel}")
    loc = [l for l in out.splitlines() if l.startswith("localize ")]
    check(len(loc) == 1 and "OVER" not in loc[0], f"localize row marked: {loc}")
    check("1 stage(s) over budget" in out, "over-budget count missing")
    rc, out, err = run(*SMALL, "--budget", tight)
    check(rc == 0, f"over budget without --check: exit {rc}, want 0")
    rc, out, err = run(*SMALL, "--budget", tight, "--json")
    jt = json.loads(out)
    check(jt["stages"]["select"]["over"] is True and jt["budget"]["over_budget"] == 1, "json over flag")
    check("budget_ms" not in jt["stages"]["chamfer"], "a stage without a budget got one")
    rc, out, err = run(*SMALL, "--check")
    check(rc == 2 and "--budget" in err, f"--check without --budget: exit {rc}: {err!r}")
    example = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "profile",
                           "budget-example.txt")
    rc, out, err = run(*BASE, "--runs", "1", "--budget", example)
    check(rc == 0 and "scale 40" in out, f"example budget file: exit {rc}: {err.strip()}")

    # Parser errors: file and line named.
    cases = [
        ("noscale.txt", "select 10\n", "noscale.txt: no 'scale F' line"),
        ("unknown.txt", "scale 2\n\n# c\nselekt 10\n", "unknown.txt:4: unknown stage 'selekt'"),
        ("dup.txt", "scale 2\nsearch 1\nsearch 2\n", "dup.txt:3: stage 'search' again (first on line 2)"),
        ("dupscale.txt", "scale 2\nscale 3\n", "dupscale.txt:2: second 'scale' (first on line 1)"),
        ("nan.txt", "scale 2\nchamfer 1O\n", "nan.txt:2: '1O' is not a number"),
        ("neg.txt", "scale 2\nchamfer -1\n", "neg.txt:2: budget -1 ms of 'chamfer' outside"),
        ("zero.txt", "scale 0\n", "zero.txt:1: scale 0 outside"),
        ("inf.txt", "scale inf\n", "inf.txt:1: 'inf' is not a number"),
        ("fields.txt", "scale 2\nchamfer 1 2\n", "fields.txt:2: expected two fields"),
        ("one.txt", "scale 2\nchamfer\n", "one.txt:2: expected two fields"),
    ]
    for name, text, needle in cases:
        path = write(name, text)
        expect_error(1, needle, *SMALL, "--budget", path)
    expect_error(1, "cannot open", *SMALL, "--budget", os.path.join(WORK, "missing.txt"))
    expect_error(1, "too small", "--map-cells", "64", "--local-cells", "64")
    rc, out, err = run("--runs", "0")
    check(rc == 1 and "--runs" in err, f"--runs 0: exit {rc}: {err!r}")
    # --instructions without valgrind on PATH: a one-line reason naming the package.
    p = subprocess.run([TRN, "profile", *BASE, "--runs", "1", "--instructions"], capture_output=True, text=True,
                       timeout=600, env={**os.environ, "PATH": "/nonexistent"})
    check(p.returncode == 1 and "needs valgrind" in p.stderr and len(p.stderr.splitlines()) == 1
          and p.stdout == "", f"--instructions without valgrind: exit {p.returncode}: {p.stderr!r}")
    rc, out, err = run("--bogus")
    check(rc == 2, f"--bogus: exit {rc}")
    dem_test()
    if STACK_BUILD:
        stack_test(out_json=os.path.join(WORK, "prof.json"))
    plot_test(jt)
    rc, out, err = run("--help")
    check(rc == 0 and "--budget" in out and "--instructions" in out, "--help")
    return finish()


def dem_test():
    """--dem FILE: a DEM file instead of the synthetic terrain, in its own cell."""
    expect_error(1, "missing.tif", *SMALL, "--dem", os.path.join(WORK, "missing.tif"))
    tif = os.path.join(WORK, "dem.tif")
    p = subprocess.run([TRN, "terrain", "--out", tif, "--size-cells", "160", "--cell-m", "2",
                        "--min-diameter-m", "1", "--max-diameter-m", "2", "--relief-m", "5", "--seed", "4"], capture_output=True, text=True, timeout=300)
    if p.returncode != 0 and "GDAL" in p.stderr:
        print("SKIP --dem: trn terrain cannot write a GeoTIFF here:", p.stderr.strip())
        return
    check(p.returncode == 0, f"trn terrain for --dem: {p.stderr.strip()}")
    rc, out, err = run(*SMALL, "--dem", tif, "--json")
    check(rc == 0, f"--dem: exit {rc}: {err.strip()}")
    if rc != 0:
        return
    j = json.loads(out)
    cfg = j["config"]
    check(cfg["dem"] == tif and cfg["cell_m"] == 2 and cfg["map_cells"] == 128,
          f"--dem config echo: {cfg}")
    check(list(j["stages"].keys()) == STAGES, f"--dem stages {list(j['stages'])}")
    check(j["stages"]["height_localize"]["wall_ms"] > 0, f"--dem height_localize: {j['stages']}")
    expect_error(1, "smaller than --map-cells 256", "--map-cells", "256", "--dem", tif)


def plot_test(prof):
    """trn_plot.py profile draws a PNG from the JSON, with and without a budget."""
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
    py = "/usr/bin/python3" if os.path.exists("/usr/bin/python3") else sys.executable
    probe = subprocess.run([py, "-c", "import matplotlib, numpy; from osgeo import gdal"], capture_output=True)
    if probe.returncode != 0:
        print("SKIP plot: no matplotlib / numpy / osgeo for", py, "(bash tools/setup.sh plot)")
        return
    for name, data in (("budget", prof), ("plain", {k: v for k, v in prof.items() if k != "budget"})):
        if name == "plain":
            data = json.loads(json.dumps(data))
            for st in data["stages"].values():
                for k in ("budget_ms", "target_ms", "target_max_ms", "share", "over"):
                    st.pop(k, None)
        src = write(f"plot-{name}.json", json.dumps(data))
        png = os.path.join(WORK, f"plot-{name}.png")
        if os.path.exists(png):
            os.remove(png)
        p = subprocess.run([py, os.path.join(root, "tools", "plot", "trn_plot.py"), "profile", src, "--out", png],
                           capture_output=True, text=True, timeout=300)
        ok = p.returncode == 0 and os.path.exists(png)
        if ok:
            with open(png, "rb") as f:
                ok = f.read(8) == b"\x89PNG\r\n\x1a\n"
        check(ok, f"trn_plot.py profile ({name}): exit {p.returncode}: {p.stderr.strip()}")
    bad = write("plot-bad.json", "{}")
    p = subprocess.run([py, os.path.join(root, "tools", "plot", "trn_plot.py"), "profile", bad, "--out",
                        os.path.join(WORK, "bad.png")], capture_output=True, text=True, timeout=300)
    check(p.returncode != 0 and "not `trn profile --json` output" in p.stderr, f"bad plot input: {p.stderr!r}")


def stack_test(out_json):
    """add_stack.py: each stage's stack_bytes = the largest trn_stack.py figure of its functions."""
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
    whole = subprocess.run([sys.executable, os.path.join(root, "tools", "stack", "trn_stack.py"), "--build",
                            STACK_BUILD], capture_output=True, text=True)
    if whole.returncode != 0:
        # add_stack.py needs a clean call graph; the stack stage (tools/test.d/40-stack.sh) owns that.
        first = (whole.stderr or whole.stdout).strip().splitlines()[:1]
        print(f"SKIP stack figures: trn_stack.py fails on {STACK_BUILD}: {first}")
        return
    rc, out, err = run(*BASE, "--runs", "1", "--json")
    check(rc == 0, f"json for add_stack: {err.strip()}")
    with open(out_json, "w") as f:
        f.write(out)
    p = subprocess.run([sys.executable, os.path.join(root, "tools", "profile", "add_stack.py"), out_json,
                        "--build", STACK_BUILD], capture_output=True, text=True)
    check(p.returncode == 0, f"add_stack.py: exit {p.returncode}: {p.stderr.strip()}")
    if p.returncode != 0:
        return
    j = json.loads(p.stdout)
    for s in STAGES:
        check(j["stages"][s].get("stack_bytes", 0) > 0, f"{s}: no stack_bytes")
    q = subprocess.run([sys.executable, os.path.join(root, "tools", "stack", "trn_stack.py"), "--build", STACK_BUILD,
                        "--function", "trn_localize_dem"], capture_output=True, text=True)
    check(q.returncode == 0 and j["stages"]["localize"]["stack_bytes"] == int(q.stdout.split()[-1]),
          f"localize stack {j['stages']['localize'].get('stack_bytes')} != trn_stack.py {q.stdout!r}")
    # map_build calls the whole global chain, so it needs at least what highpass_occupancy needs
    check(j["stages"]["map_build"]["stack_bytes"] >= j["stages"]["chamfer"]["stack_bytes"],
          f"map_build stack below chamfer's: {j['stages']}")


def finish():
    return H.finish("test_profile")


if __name__ == "__main__":
    sys.exit(main())
