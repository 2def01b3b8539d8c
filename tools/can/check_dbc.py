#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""check_dbc.py DBC VECTORS.json - cross-check the C encoders against cantools.

For every vector printed by trn_can_vectors (tools/can/can_vectors.c):
  1. cantools encodes the C raw signal values -> must give the C frame bytes;
  2. cantools decodes the C frame bytes -> must give the C raw signal values,
     and the scaled (physical) values must equal raw * scale + offset;
  3. the frame ID and length match the DBC message.
Exit 0 when all agree, 1 with one line per disagreement otherwise.
"""
import json
import sys

import cantools


def main(argv):
    if len(argv) != 3:
        print("usage: check_dbc.py DBC VECTORS.json", file=sys.stderr)
        return 2
    db = cantools.database.load_file(argv[1], strict=True)
    with open(argv[2], encoding="utf-8") as fh:
        vectors = json.load(fh)
    bad = 0
    per_msg = {}
    for i, v in enumerate(vectors):
        msg = db.get_message_by_name(v["msg"])
        data = bytes.fromhex(v["data"])
        where = f"vector {i} ({v['msg']} {v['data']})"
        if msg.frame_id != v["id"] or msg.length != v["dlc"]:
            print(f"{where}: DBC has id {msg.frame_id:#x} length {msg.length}, C {v['id']:#x} dlc {v['dlc']}")
            bad += 1
            continue
        if set(s.name for s in msg.signals) != set(v["raw"]):
            print(f"{where}: signal sets differ: DBC {sorted(s.name for s in msg.signals)} C {sorted(v['raw'])}")
            bad += 1
            continue
        try:
            enc = msg.encode(v["raw"], scaling=False, strict=False)
            if enc != data:
                print(f"{where}: cantools encodes {enc.hex()}")
                bad += 1
        except (ValueError, OverflowError, cantools.database.errors.Error) as exc:
            print(f"{where}: cantools cannot encode it: {exc}")
            bad += 1
        dec = msg.decode(data, decode_choices=False, scaling=False)
        if {k: int(x) for k, x in dec.items()} != v["raw"]:
            print(f"{where}: cantools decodes {dec}, C has {v['raw']}")
            bad += 1
        phys = msg.decode(data, decode_choices=False, scaling=True)
        for s in msg.signals:
            want = v["raw"][s.name] * s.scale + s.offset
            if abs(phys[s.name] - want) > 1e-9 * max(1.0, abs(want)):
                print(f"{where}: {s.name} physical {phys[s.name]} != {want}")
                bad += 1
        per_msg[v["msg"]] = per_msg.get(v["msg"], 0) + 1
    summary = ", ".join(f"{k} {n}" for k, n in sorted(per_msg.items()))
    print(f"check_dbc: {len(vectors)} vectors ({summary}); {bad} disagreements")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
