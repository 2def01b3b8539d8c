#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""make_seeds.py - write the seed corpora of the protocol and mast harnesses
(tests/fuzz/corpus/{can_msg,isotp,capture,can_log,mast}/), each file one
meaningful input laid out as the harness reads it (see each fuzz_*.c).
Run from anywhere; rewrites those five directories. The files are committed,
so this script documents how they were made."""
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def write(target, name, data):
    d = os.path.join(HERE, "corpus", target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


# ---- can_msg: sel, dlc, [flags], 8 data bytes, float ----------------------
def can_msg(name, sel, dlc, data, rad=0.5, flags=None):
    b = bytes([sel, dlc])
    if flags is not None:
        b += bytes([flags])
    b += bytes(data).ljust(8, b"\0") + struct.pack("<f", rad)
    write("can_msg", name, b)


can_msg("mast_cmd", 0, 8, [0x10, 0x27, 0xF0, 0xD8, 0xE8, 0x03, 7, 1], 1.0)
can_msg("mast_status", 1, 8, [0x10, 0x27, 0, 0, 0x21, 0, 7, 42], -0.25)
can_msg("capture_cmd", 2, 4, [5, 0, 0, 16], 3.2767)
can_msg("mast_hb", 3, 4, [1, 9, 0x10, 0], float("nan"))
can_msg("stereo_hb", 4, 4, [3, 255, 0xFF, 0xFF], 3.3)
can_msg("bad_mode", 0, 8, [0, 0, 0, 0, 0, 0, 0, 3], -3.27685)
can_msg("reserved_bits", 1, 8, [0, 0, 0, 0, 0xC0, 0, 0, 0], 1e30)
can_msg("ext_flag", 0x30, 8, [0] * 8, 0.0, flags=1)
can_msg("foreign_id", 7, 8, [0x34, 0x12, 0, 0, 1, 2, 3, 4], -0.0)

# ---- isotp: now_ms i32, cap u16, bs, stmin, ncr; ops -----------------------
def isotp_hdr(cap=4095, bs=0, stmin=0, ncr=250, now=0):
    return struct.pack("<iH", now, cap - 7) + bytes([bs, stmin, ncr])


def raw_frame(data, dlc=None, dt=1):
    data = bytes(data)
    return bytes([0, len(data) if dlc is None else dlc]) + data.ljust(8, b"\0") + bytes([dt])


write("isotp", "single_frames", isotp_hdr() + raw_frame([3, 1, 2, 3], 4) + raw_frame([7, 1, 2, 3, 4, 5, 6, 7], 8))
write("isotp", "ff_cf", isotp_hdr(bs=2) + raw_frame([0x10, 20, 1, 2, 3, 4, 5, 6]) +
      raw_frame([0x21, 7, 8, 9, 10, 11, 12, 13]) + raw_frame([0x22, 14, 15, 16, 17, 18, 19, 20]))
write("isotp", "wrong_sn", isotp_hdr() + raw_frame([0x10, 20, 1, 2, 3, 4, 5, 6]) +
      raw_frame([0x23, 7, 8, 9, 10, 11, 12, 13]))
write("isotp", "timeout", isotp_hdr(ncr=2) + raw_frame([0x10, 20, 1, 2, 3, 4, 5, 6]) + bytes([1, 200]))
write("isotp", "overflow", isotp_hdr(cap=64) + raw_frame([0x11, 0x00, 1, 2, 3, 4, 5, 6]))
write("isotp", "fc_and_bad", isotp_hdr() + raw_frame([0x30, 8, 20], 3) + raw_frame([0x40], 1) + raw_frame([], 0))
write("isotp", "message", isotp_hdr() + bytes([2]) + struct.pack("<H", 99) + bytes([7, 5]))
write("isotp", "message_big", isotp_hdr(cap=200) + bytes([2]) + struct.pack("<H", 300) + bytes([1, 1]))
write("isotp", "loopback", isotp_hdr() + bytes([3]) + struct.pack("<H", 199) + bytes([9, 2, 0x01, 100, 100]) +
      bytes([10] * 80))
write("isotp", "loopback_sf", isotp_hdr() + bytes([3]) + struct.pack("<H", 4) + bytes([1, 0, 0, 50, 50, 0, 0]))

# ---- capture ---------------------------------------------------------------
def capture_bytes(cid, n, t=123456, pan=100, tilt=-200):
    body = struct.pack("<BBHIhhBBH", 1, 0, cid, t, pan, tilt, 0x21, 0, n)
    for i in range(n):
        body += struct.pack("<hhh", i * 7, i - 3, 1000 + i)
    return body + struct.pack("<I", zlib.crc32(body) & 0xFFFFFFFF)


def segments(wire, cid, payload):
    chunks = [wire[i:i + payload] for i in range(0, len(wire), payload)]
    return [struct.pack("<HBB", cid, k, len(chunks)) + c for k, c in enumerate(chunks)]


def raw_capture_input(segs):
    b = bytes([0])
    for s in segs:
        b += struct.pack("<H", len(s)) + s
    return b


w = capture_bytes(7, 10)
write("capture", "raw_one_segment", raw_capture_input(segments(w, 7, 4091)))
write("capture", "raw_three_segments", raw_capture_input(segments(w, 7, 30)))
write("capture", "raw_missing", raw_capture_input([s for k, s in enumerate(segments(w, 7, 20)) if k != 1]))
bad = bytearray(w)
bad[20] ^= 0x40
write("capture", "raw_crc", raw_capture_input(segments(bytes(bad), 7, 40)))
write("capture", "raw_restart", raw_capture_input(segments(w, 7, 30)[:2] + segments(capture_bytes(8, 3), 8, 30)))


def structured(cid, n, payload, ops):
    b = bytes([1]) + struct.pack("<HihhBBH", cid, 5000, 10, -10, 1, 0, n)
    b += bytes((i * 13) & 0xFF for i in range(n)) + struct.pack("<H", payload - 1)
    return b + bytes(ops)


write("capture", "structured_in_order", structured(3, 40, 64, [0] * 8))
write("capture", "structured_edits", structured(3, 40, 50, [0, 2, 0, 1, 0, 3, 0, 0]))
write("capture", "structured_flip", structured(3, 12, 30, [0, 4, 20, 0, 0x10, 0]))
write("capture", "structured_cut_abort", structured(9, 100, 100, [0, 5, 3, 7, 0, 6, 0]))

# ---- can_log: real candump -l lines ---------------------------------------
lines = {
    "data": "(1764000000.000500) vcan0 1A0#1180320000010100\n",
    "fc": "(1764000000.000700) vcan0 1A1#300000",
    "dots": "(1764000000.1) can0 121#01.02.03.04.05.06.07.08 R\n",
    "ext": "(1700000000.123456) vcan0 12345678#DEADBEEF",
    "rtr": "(1700000000.123456) vcan0 123#R8",
    "fd": "(1700000000.123456) vcan0 123##1112233",
    "error": "(1700000000.123456) vcan0 20000080#0000000000000000",
    "comment": "# candump log\n",
    "bad_hex": "(1700000000.123456) vcan0 123#0G",
    "odd": "(1700000000.123456) vcan0 123#012",
    "long_if": "(1700000000.123456) averyveryverylongname0 123#01",
    "empty_data": "(1.000001) x 7FF#",
}
for k, v in lines.items():
    write("can_log", k, v.encode())

# ---- mast: mode, geometry, pose, target, angles, points, dem --------------
def u16(x):
    return struct.pack("<H", x)


def sane_mast(name, vals, npts, pts, tail):
    b = bytes([1]) + b"".join(u16(v) for v in vals) + bytes([npts]) + b"".join(u16(v) for v in pts) + bytes(tail)
    write("mast", name, b)


# 21 geometry/pose/target/angle values at mid-range (32768 = middle)
sane_mast("centre", [32768] * 10 + [40000, 20000] + [32768] * 4 + [50000, 32768, 32768, 32768, 32768], 3,
          [32768, 32768, 1000] * 3, u16(20000) + bytes([10, 10, 3, 8, 8]))
sane_mast("ahead", [32768, 32768, 60000, 40000, 40000, 40000, 30000, 30000, 0, 65535, 0, 65535,
                    32768, 32768, 32768, 32768, 60000, 32768, 20000, 32768, 20000], 8,
          [(i * 5000) % 65536 for i in range(24)], u16(5000) + bytes([4, 12, 0, 15, 15]))
raw = bytes([0]) + struct.pack("<12f", 0.5, 0, 1.2, 0.1, 0.2, 0.05, 0.1, 0.0, -3.1, 3.1, -1.5, 1.5)
raw += struct.pack("<4f", 10.0, -5.0, 0.3, 0.7) + struct.pack("<3f", 12.0, 1.0, 0.0) + struct.pack("<2f", 0.3, -0.4)
raw += bytes([2]) + struct.pack("<6f", 0.0, 0.0, 5.0, float("nan"), 1.0, 3e38) + struct.pack("<f", 0.1) + bytes([5, 5, 3, 10, 10])
write("mast", "raw_mixed", raw)
write("mast", "raw_huge", bytes([0]) + struct.pack("<21f", *([3.4e38] * 21)) + bytes([4]) + struct.pack("<13f", *([1e-45] * 13)))
