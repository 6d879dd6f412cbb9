"""Shared by the examples: the reduced size switch used in CI and the documentation build.

Run any example at full size with ``python examples/NN_name.py``; with ``--quick`` or
``FORMATION_FTC_EXAMPLES_QUICK=1`` it runs a smaller version of the same computation (fewer runs,
shorter horizons) in seconds.
"""

from __future__ import annotations

import os
import sys

QUICK = os.environ.get("FORMATION_FTC_EXAMPLES_QUICK", "") not in ("", "0") or "--quick" in sys.argv


def size(full, quick):
    """``full`` normally, ``quick`` in the reduced (CI / documentation) mode."""
    return quick if QUICK else full
