# SPDX-License-Identifier: Apache-2.0
"""libtrn_run.so through ctypes: its flat ABI (python/trn_py.c), mirrored
here function by function. ctypes.CDLL releases the GIL for every call."""
from __future__ import annotations

import ctypes
import os
from typing import Any

_ERR_LEN = 1024
_NAME_LEN = 64

#: int (*)(void *user, uint32_t done, uint32_t total): the field's progress callback
PROGRESS_FN = ctypes.CFUNCTYPE(ctypes.c_int32, ctypes.c_void_p, ctypes.c_uint32, ctypes.c_uint32)

_F32P = ctypes.POINTER(ctypes.c_float)
_F64P = ctypes.POINTER(ctypes.c_double)


def _load() -> Any:
    here = os.path.dirname(os.path.abspath(__file__))
    path = os.environ.get("TRN_RUN_LIBRARY") or os.path.join(here, "libtrn_run.so")
    lib: Any = ctypes.CDLL(path)  # CDLL: the GIL is released during every call
    c_int, c_char_p, c_void_p, c_size_t = ctypes.c_int, ctypes.c_char_p, ctypes.c_void_p, ctypes.c_size_t
    sig = {
        "trn_py_version": (c_char_p, []),
        "trn_py_map_new": (c_void_p, []),
        "trn_py_map_free": (None, [c_void_p]),
        "trn_py_free": (None, [c_void_p]),
        "trn_py_options": (c_int, [c_char_p, ctypes.POINTER(c_void_p), c_char_p, c_size_t]),
        "trn_py_gdal": (c_int, [c_char_p, c_size_t]),
        "trn_py_raster_put": (c_int, [_F32P, c_int, c_int, c_int, _F64P, c_int, ctypes.c_double, c_char_p,
                                      c_char_p, c_char_p, c_size_t, c_char_p, c_size_t]),
        "trn_py_raster_name": (c_int, [c_char_p, c_size_t]),
        "trn_py_crs_wkt": (c_int, [c_char_p, ctypes.POINTER(c_void_p), c_char_p, c_size_t]),
        "trn_py_raster_drop": (None, [c_char_p]),
        "trn_py_raster_read": (c_int, [c_char_p, c_int, c_int, ctypes.POINTER(c_void_p), ctypes.POINTER(c_int),
                                       ctypes.POINTER(c_int), _F64P, ctypes.POINTER(c_void_p), c_char_p, c_size_t]),
        "trn_py_raster_write": (c_int, [c_char_p, _F32P, c_int, c_int, _F64P, c_char_p, c_char_p, c_size_t]),
    }
    common = [c_void_p, c_int, ctypes.POINTER(c_char_p), c_char_p]
    out = [ctypes.POINTER(c_void_p), c_char_p, c_size_t]
    sig["trn_py_localize"] = (c_int, common + out)
    sig["trn_py_select"] = (c_int, common + out)
    sig["trn_py_field"] = (c_int, common + [PROGRESS_FN, c_void_p] + out)
    for name, (res, args) in sig.items():
        fn = getattr(lib, name)
        fn.restype = res
        fn.argtypes = args
    return lib


lib: Any = _load()
ERR_LEN = _ERR_LEN
NAME_LEN = _NAME_LEN
F32P = _F32P
F64P = _F64P
