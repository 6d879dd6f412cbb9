"""Consistent matplotlib style for every figure the toolkit writes (edge layer: import only from
``papers/``, ``report/`` and the CLI). Uses the non-interactive Agg backend.

Matplotlib is imported on the first figure, not with this module: a process that only simulates or
checks (a campaign worker, ``formation-ftc check``) does not pay its import (about 0.3 s).
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import matplotlib.pyplot as plt
    from matplotlib.typing import RcKeyType

__all__ = ["plt", "new_figure", "save_figure", "SPACECRAFT_COLORS"]

SPACECRAFT_COLORS = [
    "#1f77b4",
    "#d62728",
    "#2ca02c",
    "#9467bd",
    "#ff7f0e",
    "#8c564b",
    "#e377c2",
    "#17becf",
]


@functools.cache
def _pyplot():
    """``matplotlib.pyplot`` on the Agg backend (imported once, on first use)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as pyplot

    return pyplot


@functools.cache
def _style() -> dict[RcKeyType, Any]:
    import matplotlib

    return {
        "figure.dpi": 110,
        "savefig.dpi": 130,
        "font.size": 9,
        "axes.grid": True,
        "grid.alpha": 0.3,
        "axes.titlesize": 10,
        "legend.fontsize": 8,
        "lines.linewidth": 1.2,
        "axes.prop_cycle": matplotlib.cycler(color=SPACECRAFT_COLORS),  # type: ignore[attr-defined]  # not in the stubs
    }


def __getattr__(name: str) -> Any:
    if name == "plt":  # ``from formation_ftc.plotting import plt``: pyplot, imported now
        return _pyplot()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def new_figure(
    nrows: int = 1,
    ncols: int = 1,
    *,
    width: float = 6.4,
    height: float | None = None,
    sharex: bool = True,
    title: str | None = None,
):
    """Figure and axes with the package style; height defaults to 2.2 in per row."""
    pyplot = _pyplot()
    with pyplot.rc_context(_style()):
        fig, axes = pyplot.subplots(
            nrows, ncols, figsize=(width, height or 1.0 + 2.2 * nrows), sharex=sharex, squeeze=False
        )
    if title:
        fig.suptitle(title)
    return fig, axes


def save_figure(fig, path: str | Path) -> Path:
    """Save as PNG (tight layout) and close the figure."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    pyplot = _pyplot()
    with pyplot.rc_context(_style()):
        fig.tight_layout()
        fig.savefig(path)
    pyplot.close(fig)
    return path
