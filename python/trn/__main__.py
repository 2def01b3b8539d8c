# SPDX-License-Identifier: Apache-2.0
"""python -m trn --version: the package's version (that of libtrn_run.so and
`trn --version`); --gdal: whether GDAL's C library loads (files), and why not."""
from __future__ import annotations

import argparse
import sys
from typing import List, Optional

import trn


def main(argv: Optional[List[str]] = None) -> int:
    """The command: --version, or --gdal (exit 0 when libgdal loads, 1 when not)."""
    p = argparse.ArgumentParser(prog="python -m trn", description="The trn Python package.")
    p.add_argument("--version", action="store_true", help="print the version")
    p.add_argument("--gdal", action="store_true", help="say whether GDAL's C library loads (needed for files)")
    a = p.parse_args(argv)
    if a.gdal:
        ok, why = trn.gdal_available()
        print("gdal: yes" if ok else f"gdal: no: {why}")
        return 0 if ok else 1
    if a.version:
        print(f"trn {trn.__version__}")
        return 0
    p.print_help()
    return 0


if __name__ == "__main__":
    sys.exit(main())
