#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""make_fixture.py OUT_DIR - write the hand-made candump logs of tests/data/can.

An implementation independent of the C code (struct, zlib.crc32, its own
ISO-TP segmentation), following docs/can-protocol.md, so the golden output of
`trn can-decode` on these logs cross-checks the C decoder. Seeded: the same
files every run. Files:
  traffic.log  every message of ours, foreign traffic (other IDs, extended,
               remote, CAN FD, error frame) and two complete captures
  faults.log   captures broken on the bus: a lost consecutive frame, a
               corrupted byte (CRC), a lost segment, an N_Cr timeout, an
               invalid message of ours
  malformed.log  lines a parser must reject, each with its reason
"""
import os
import random
import struct
import sys
import zlib

T0_US = 1764000000 * 1000000


class Log:
    def __init__(self):
        self.lines = []
        self.t = T0_US  # integer microseconds: exact timestamps

    def frame(self, can_id, data, dt=0.001, ifname="vcan0", ext=False):
        self.t += round(dt * 1e6)
        ident = f"{can_id:08X}" if ext else f"{can_id:03X}"
        self.lines.append(f"({self.stamp()}) {ifname} {ident}#{data.hex().upper()}")

    def stamp(self, dt=0.0):
        t = self.t + round(dt * 1e6)
        return f"{t // 1000000}.{t % 1000000:06d}"

    def raw(self, text):
        self.lines.append(text)

    def write(self, path):
        with open(path, "w", encoding="ascii") as fh:
            fh.write("\n".join(self.lines) + "\n")


def capture_bytes(cid, time_ms, pan, tilt, state, faults, points):
    body = struct.pack("<BBHIhhBBH", 1, 0, cid, time_ms, pan, tilt, state, faults, len(points))
    for p in points:
        body += struct.pack("<hhh", *p)
    return body + struct.pack("<I", zlib.crc32(body) & 0xFFFFFFFF)


def segments(wire, cid, payload):
    count = (len(wire) + payload - 1) // payload
    return [struct.pack("<HBB", cid, i, count) + wire[i * payload:(i + 1) * payload] for i in range(count)]


def isotp_frames(msg):
    if len(msg) <= 7:
        return [bytes([len(msg)]) + msg]
    out = [bytes([0x10 | (len(msg) >> 8), len(msg) & 0xFF]) + msg[:6]]
    sn, off = 1, 6
    while off < len(msg):
        out.append(bytes([0x20 | (sn & 0xF)]) + msg[off:off + 7])
        sn, off = sn + 1, off + 7
    return out


def send_capture(log, wire, cid, payload, drop_cf=None, corrupt=None, drop_seg=None, stall=None):
    """Send a capture; drop_cf=(seg, frame) loses one CF, corrupt=(seg, frame, byte)
    flips bits, drop_seg loses a whole segment, stall=(seg, frame) waits 2 s."""
    for si, seg in enumerate(segments(wire, cid, payload)):
        if si == drop_seg:
            continue
        frames = isotp_frames(seg)
        for fi, fr in enumerate(frames):
            if drop_cf == (si, fi):
                continue
            if corrupt is not None and corrupt[:2] == (si, fi):
                fr = bytearray(fr)
                fr[corrupt[2]] ^= 0x5A
                fr = bytes(fr)
            dt = 2.0 if stall == (si, fi) else 0.0005
            log.frame(0x1A0, fr, dt)
            if fi == 0 and len(frames) > 1:
                log.frame(0x1A1, bytes([0x30, 0x00, 0x00]), 0.0002)  # FC CTS from the rover
            if stall == (si, fi):
                return


def points(rng, n):
    return [(rng.randint(-3000, 3000), rng.randint(-500, 1500), rng.randint(500, 20000)) for _ in range(n)]


def traffic(rng):
    log = Log()
    log.frame(0x701, struct.pack("<BBH", 1, 0, 12))             # MAST_HB ready
    log.frame(0x702, struct.pack("<BBH", 1, 0, 11))             # STEREO_HB ready
    log.frame(0x7DF, bytes.fromhex("0201000000000000"))         # foreign standard
    log.frame(0x18DAF110, bytes.fromhex("0322F190"), ext=True)  # foreign extended
    log.frame(0x120, struct.pack("<hhHBB", 7854, -3491, 5000, 1, 1))   # MAST_CMD move
    log.frame(0x121, struct.pack("<hhBBBB", 100, -50, 0x01, 0, 1, 17))  # moving
    log.raw(f"({log.stamp(0.001)}) vcan0 7DF#R")                  # remote, foreign
    log.raw(f"({log.stamp(0.002)}) vcan0 123##1DEADBEEF")          # CAN FD
    log.raw(f"({log.stamp(0.003)}) vcan0 20000040#0000000000000000")  # error frame (bus-off)
    log.t += 3000
    log.frame(0x121, struct.pack("<hhBBBB", 7854, -3491, 0x20, 0, 1, 18))  # in position
    log.frame(0x121, struct.pack("<hhBBBB", -32768, 32767, 0x12, 0x05, 1, 19))  # limits, faults
    log.frame(0x130, struct.pack("<HH", 41, 0))                 # CAPTURE_CMD
    wire = capture_bytes(41, 123456, 7854, -3491, 0x20, 0, points(rng, 120))
    send_capture(log, wire, 41, 300)                            # 3 segments
    log.frame(0x130, struct.pack("<HH", 42, 2))
    wire = capture_bytes(42, 123999, 7854, -3491, 0x20, 0, [(1, -2, 1000), (-32768, 32767, 0)])
    send_capture(log, wire, 42, 4091)                           # one segment, 32 bytes
    log.frame(0x1A1, bytes([0x31, 0x00, 0xF3]))                 # FC WAIT seen on the bus
    log.frame(0x701, struct.pack("<BBH", 3, 1, 13))             # MAST_HB fault
    return log


def faults(rng):
    log = Log()
    wire = capture_bytes(50, 1000, 0, -2000, 0, 0, points(rng, 60))
    send_capture(log, wire, 50, 4091, drop_cf=(0, 5))           # lost CF: wrong SN
    wire = capture_bytes(51, 2000, 0, -2000, 0, 0, points(rng, 60))
    send_capture(log, wire, 51, 4091, corrupt=(0, 7, 3))        # corrupted byte: CRC
    wire = capture_bytes(52, 3000, 0, -2000, 0, 0, points(rng, 120))
    send_capture(log, wire, 52, 300, drop_seg=1)                # lost segment
    wire = capture_bytes(53, 4000, 0, -2000, 0, 0, points(rng, 60))
    send_capture(log, wire, 53, 4091, stall=(0, 10))            # sender stalls: N_Cr
    log.t += 2000000
    log.frame(0x121, bytes.fromhex("000000004000010A"))         # reserved state bit set
    log.frame(0x120, bytes.fromhex("0000000000000003"))         # mode 3
    log.frame(0x702, bytes.fromhex("0100"))                     # heartbeat DLC 2
    wire = capture_bytes(54, 5000, 0, -2000, 0, 0, points(rng, 10))
    send_capture(log, wire, 54, 4091)                           # a good one afterwards
    return log


def malformed():
    log = Log()
    log.frame(0x701, struct.pack("<BBH", 1, 5, 100))
    for bad in [
        "1764000000.000100 vcan0 701#01050000",     # no parentheses
        "(1764000000.000200) vcan0 701:01050000",   # no '#'
        "(1764000000.000300) vcan0 70#01",          # 2-digit id
        "(1764000000.000400) vcan0 801#01",         # standard id above 0x7FF
        "(1764000000.000500) vcan0 701#0105000",    # odd hex digits
        "(1764000000.000600) vcan0 701#010500000000000000",  # 9 bytes
        "(1764000000.000700) vcan0 701#01G5",       # bad hex
        "(1764000000) vcan0 701#01",                # no fraction
        "(1764000000.000900) vcan0 701#01 extra",   # trailing garbage
        "(1764000000.001000)",                      # nothing after the time
    ]:
        log.raw(bad)
    log.raw("# a comment line is skipped")
    log.raw("")
    log.frame(0x702, struct.pack("<BBH", 2, 6, 101))
    return log


def main(argv):
    if len(argv) != 2:
        print("usage: make_fixture.py OUT_DIR", file=sys.stderr)
        return 2
    rng = random.Random(2026)
    traffic(rng).write(os.path.join(argv[1], "traffic.log"))
    faults(rng).write(os.path.join(argv[1], "faults.log"))
    malformed().write(os.path.join(argv[1], "malformed.log"))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
