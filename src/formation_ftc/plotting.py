"""Consistent matplotlib style for every figure the toolkit writes (edge layer: import only from
``papers/``, ``report/`` and the CLI). Uses the non-interactive Agg backend.

Matplotlib is imported on the first figure, not with this module: a process that only simulates or
checks (a campaign worker, ``formation-ftc check``) does not pay its import (about 0.3 s).
"""

from __future__ import annotations

import contextlib
import contextvars
import functools
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import matplotlib.pyplot as plt
    from matplotlib.typing import RcKeyType

__all__ = ["plt", "new_figure", "save_figure", "figure_format", "FORMATS", "SPACECRAFT_COLORS"]

#: file formats :func:`save_figure` writes (``formation-ftc plot --format``)
FORMATS = ("png", "svg", "pdf")
_FORMAT: contextvars.ContextVar[str | None] = contextvars.ContextVar("figure_format", default=None)

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


@contextlib.contextmanager
def figure_format(fmt: str) -> Iterator[None]:
    """Within the block, :func:`save_figure` writes ``fmt`` (one of :data:`FORMATS`) in place of PNG:
    ``a.png`` becomes ``a.svg`` (every figure maker of the package saves through it).

    Parameters
    ----------
    fmt : str
        ``"png"``, ``"svg"`` or ``"pdf"``.
    """
    if fmt not in FORMATS:
        raise ValueError(f"figure format {fmt!r}: expected one of {', '.join(FORMATS)}")
    token = _FORMAT.set(fmt)
    try:
        yield
    finally:
        _FORMAT.reset(token)


def save_figure(fig, path: str | Path) -> Path:
    """Save (tight layout) and close the figure, in the format of ``path``'s suffix (the figure makers
    write PNG) or, within :func:`figure_format`, in that format (the suffix replaced). Returns the path
    written."""
    path = Path(path)
    fmt = _FORMAT.get()
    if fmt is not None:
        path = path.with_suffix(f".{fmt}")
    path.parent.mkdir(parents=True, exist_ok=True)
    pyplot = _pyplot()
    with pyplot.rc_context(_style()):
        fig.tight_layout()
        fig.savefig(path)
    pyplot.close(fig)
    return path
