# SPDX-License-Identifier: Apache-2.0
"""The TypedDicts of trn's results (trn.Map.localize, select, field) and the
type aliases of its arguments; see trn/_types.py."""
from ._types import *  # noqa: F401,F403
from ._types import __all__  # noqa: F401
