#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tests/cli/test_can_decode.py - `trn can-decode` on the shared parser (CTest `cli_can_decode`).

    python3 tests/cli/test_can_decode.py PATH/TO/trn tests/data/can

The text output is checked byte for byte against reviewed golden files by the
CTest `can_decode_logs` (tools/can/test_can_decode.sh). This test checks what
the command line adds around it: --help from the option table, --json (one
JSON object, parsed with the json module, agreeing with the text output line
for line and with its summary), and each bad-input class getting one line
`trn can-decode: <reason>` on stderr, nothing on stdout and its exit status.
Plain python3 (no GDAL).
"""
import os
import re
import sys

import clitest  # tests/cli/, the script's own directory

TRN = os.path.abspath(sys.argv[1])
DATA = os.path.abspath(sys.argv[2])
H = clitest.Harness(TRN, sub=("can-decode",))
check, run, expect_error = H.check, H.run, H.expect_error


def log(name):
    return os.path.join(DATA, name)


# ---- --help: generated from the table, LOG listed, statuses 0-2 -------------
for args in (("--help",), ("--bogus-first", "--help"), (log("traffic.log"), "-h")):
    rc, out, err = run(*args)
    check(rc == 0 and out.startswith("usage: trn can-decode [--strict] [--n-cr-ms MS] [--json] LOG\n")
          and err == "", f"can-decode {' '.join(args)}: usage ({rc}, {out[:80]!r}, {err!r})")
    check("arguments:\n  LOG " in out and "--n-cr-ms MS" in out and "(default 1000) [1..60000]" in out,
          f"can-decode --help lists LOG and --n-cr-ms with its default and range: {out!r}")
    check("exit status: 0 ok, 1 bad input" in out and ", 3 " not in out, "can-decode --help: exit statuses")

# ---- --json against the text output -----------------------------------------
SUMMARY = re.compile(r"summary: lines=(\d+) ours=(\d+) foreign=(\d+) \(fd=(\d+) error_frames=(\d+) "
                     r"remote=(\d+)\) malformed=(\d+) invalid_msgs=(\d+) captures_ok=(\d+) "
                     r"capture_errors=(\d+) isotp_errors=(\d+)\n$")
KEYS = ("lines", "ours", "foreign", "fd", "error_frames", "remote", "malformed", "invalid_msgs",
        "captures_ok", "capture_errors", "isotp_errors")

for name, extra, want_rc in (("traffic.log", (), 0), ("faults.log", (), 0), ("faults.log", ("--strict",), 1),
                             ("malformed.log", (), 1), ("sim_capture.log", ("--strict",), 0)):
    label = f"can-decode {' '.join(extra)} --json {name}"
    rc_t, text, err_t = run(*extra, log(name))
    rc, out, err = run(*extra, "--json", log(name))
    check(rc == rc_t == want_rc, f"{label}: exit {rc} (text {rc_t}), want {want_rc}")
    check(err == err_t, f"{label}: stderr differs from the text mode's: {err!r} vs {err_t!r}")
    check(out.count("\n") == 1 and out.endswith("}\n"), f"{label}: not one line of JSON")
    try:
        obj = __import__("json").loads(out)
    except ValueError as e:
        check(False, f"{label}: not valid JSON ({e}): {out[:200]!r}")
        continue
    H.check_version(obj, label)
    check(obj.get("log") == log(name) and obj.get("strict") == bool(extra) and obj.get("n_cr_ms") == 1000,
          f"{label}: log, strict, n_cr_ms: {obj.get('log')!r} {obj.get('strict')!r} {obj.get('n_cr_ms')!r}")
    m = SUMMARY.search(text)
    check(m is not None, f"{label}: text summary line: {text[-300:]!r}")
    summ = obj.get("summary", {})
    if m:
        for k, v in zip(KEYS, m.groups()):
            check(summ.get(k) == int(v), f"{label}: summary {k} = {summ.get(k)!r}, text says {v}")
    events = obj.get("events", [])
    frames = [e for e in events if e.get("event") == "frame"]
    check(len(frames) == summ.get("ours"), f"{label}: {len(frames)} frame events, ours = {summ.get('ours')}")
    # every frame line of the text, in order: the same time, interface, id and message
    heads = re.findall(r"^\((\d+)\.(\d{6})\) (\S+) ([0-9A-F]{3}) ([A-Z_]+) ", text, re.M)
    got = [(str(e["sec"]), f"{e['usec']:06d}", e["ifname"], f"{e['id']:03X}", e["msg"]) for e in frames]
    check(got == heads, f"{label}: frames differ from the text lines: {got[:3]} vs {heads[:3]}")
    # the nested lines: errors, segments, captures
    for key, pat in (("isotp_error", r"^  isotp error (\w+)$"), ("capture_error", r"^  capture error (\w+)$")):
        check([e[key] for e in frames if key in e] == re.findall(pat, text, re.M),
              f"{label}: {key} events differ from the text")
    segs = re.findall(r"^  segment id=(\d+) index=(\d+)/(\d+) bytes=(\d+)$", text, re.M)
    check([tuple(str(e["segment"][k]) for k in ("id", "index", "count", "bytes")) for e in frames
           if "segment" in e] == segs, f"{label}: segments differ from the text")
    caps = re.findall(r"^  capture id=(\d+) points=(\d+) time_ms=(\d+) .* crc=0x([0-9A-F]{8}) ok$", text, re.M)
    check([(str(e["capture"]["id"]), str(e["capture"]["points"]), str(e["capture"]["time_ms"]),
            f"{e['capture']['crc']:08X}") for e in frames if "capture" in e] == caps,
          f"{label}: captures differ from the text")
    invalid = re.findall(r"^\(\S+\) \S+ \S+ \S+ invalid \(dlc (\d+):((?: [0-9A-F]{2})*)\)$", text, re.M)
    check([(str(e["dlc"]), e["data"]) for e in frames if e.get("valid") is False]
          == [(d, h.replace(" ", "")) for d, h in invalid], f"{label}: invalid messages differ from the text")
    timeouts = re.findall(r"^\((\d+)\.(\d{6})\) isotp error (\w+): capture transfer idle", text, re.M)
    check([(str(e["sec"]), f"{e['usec']:06d}", e["error"]) for e in events
           if e.get("event") == "isotp_timeout"] == timeouts, f"{label}: timeouts differ from the text")
    malformed = re.findall(r"^.*:(\d+): (.*)$", err, re.M)
    check([(str(e["line"]), e["reason"]) for e in events if e.get("event") == "malformed"] == malformed,
          f"{label}: malformed events differ from stderr")
    check(("log ends inside a capture transfer" in text)
          == any(e.get("event") == "incomplete_capture" for e in events), f"{label}: incomplete capture")
    check(summ.get("protocol_errors") == (rc == 1 if extra else summ.get("protocol_errors")),
          f"{label}: protocol_errors agrees with --strict's exit status")

# decoded fields of a known message (traffic.log's MAST_CMD line of the text output)
rc, out, _ = run("--json", log("traffic.log"))
obj = __import__("json").loads(out) if rc == 0 else {}
cmd = [e for e in obj.get("events", []) if e.get("msg") == "MAST_CMD"]
check(bool(cmd) and cmd[0].get("valid") is True and cmd[0].get("pan_rad") == 0.7854
      and cmd[0].get("tilt_rad") == -0.3491 and cmd[0].get("mode") == "MOVE",
      f"traffic.log MAST_CMD decoded in JSON: {cmd[:1]}")
st = [e for e in obj.get("events", []) if e.get("msg") == "MAST_STATUS"]
check(bool(st) and st[0].get("state") == ["MOVING"] and st[0].get("faults") == [],
      f"traffic.log MAST_STATUS bits in JSON: {st[:1]}")
# standard input: the same object but for "log"
with open(log("traffic.log")) as f:
    import subprocess
    p = subprocess.run([TRN, "can-decode", "--json", "-"], stdin=f, capture_output=True, text=True)
obj_in = __import__("json").loads(p.stdout) if p.returncode == 0 else {}
check(obj_in.get("log") == "-" and {**obj_in, "log": None} == {**obj, "log": None},
      "can-decode --json - (standard input) gives the file's object")

# ---- each bad-input class: one line, nothing on stdout, its exit status -----
for json_flag in ((), ("--json",)):
    expect_error(2, "missing argument 'LOG'", *json_flag)
    expect_error(2, "unknown option '--bogus'", *json_flag, "--bogus", log("traffic.log"))
    expect_error(2, "unknown option '-x'", *json_flag, "-x", log("traffic.log"))
    expect_error(2, "unexpected argument", *json_flag, log("traffic.log"), log("faults.log"))
    expect_error(1, "cannot open", *json_flag, log("does-not-exist.log"))
    expect_error(1, "--n-cr-ms: 0 is out of range [1..60000]", *json_flag, "--n-cr-ms", "0", log("traffic.log"))
    expect_error(1, "--n-cr-ms: '1e3' is not an integer", *json_flag, "--n-cr-ms", "1e3", log("traffic.log"))
    expect_error(2, "missing value for", *json_flag, log("traffic.log"), "--n-cr-ms")
    expect_error(2, "option given twice", *json_flag, "--strict", "--strict", log("traffic.log"))
    expect_error(2, "option takes no value", "--json=1", log("traffic.log"))
# `--` ends the options: a log named like an option
rc, out, err = run("--", "--strict")
check(rc == 1 and err.startswith("trn can-decode: cannot open '--strict'"), f"can-decode -- --strict: {rc} {err!r}")
# --n-cr-ms=V and a short N_Cr: faults.log's idle transfer times out sooner
rc, out, err = run("--n-cr-ms=1", log("faults.log"))
check(rc == 0 and "capture transfer idle for more than 1 ms" in out, f"can-decode --n-cr-ms=1: {rc} {out[-300:]!r}")

sys.exit(H.finish("cli_can_decode"))
