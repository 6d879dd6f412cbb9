"""Shared by the examples: the reduced size switch used in CI and the documentation build, and the
saving of their figures.

Run any example at full size with ``python examples/NN_name.py``; with ``--quick`` or
``FORMATION_FTC_EXAMPLES_QUICK=1`` it runs a smaller version of the same computation (fewer runs,
shorter horizons) in seconds. Run as a script, an example writes each figure to
``examples/figures/NN_name_<figure>.png`` and prints where (:func:`save_figure`); the documentation
build (``docs/hooks/run_example.py``) captures the figures itself and sets
``FORMATION_FTC_EXAMPLES_SAVE=0``, which writes nothing.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

QUICK = os.environ.get("FORMATION_FTC_EXAMPLES_QUICK", "") not in ("", "0") or "--quick" in sys.argv


def size(full, quick):
    """``full`` normally, ``quick`` in the reduced (CI / documentation) mode."""
    return quick if QUICK else full


def save_figure(fig, name: str):
    """Write ``fig`` (matplotlib) to ``figures/<example>_<name>.png`` next to the running example and
    print the path; returns it (None when ``FORMATION_FTC_EXAMPLES_SAVE=0``: nothing written)."""
    if os.environ.get("FORMATION_FTC_EXAMPLES_SAVE", "1").strip() in ("0", ""):
        return None
    caller = sys._getframe(1).f_globals.get("__file__") or sys.argv[0] or "example"  # noqa: SLF001
    script = Path(caller).resolve()
    path = script.parent / "figures" / f"{script.stem}_{name}.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100, bbox_inches="tight")
    print(f"figure saved to {path}")
    return path
