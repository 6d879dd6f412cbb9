"""The HTML pages of formation-ftc (run page, reproduction report, league leaderboard) are Jinja2
templates in ``formation_ftc/report/templates/``: one base template (``base.html.j2``), one style sheet
(``style.css``, inlined into every page), one template per page. Autoescaping is on: every value is
HTML-escaped unless it is :class:`markupsafe.Markup` (plotly's own figure markup is the only such
value)."""

from __future__ import annotations

import functools
import math
from typing import Any

import jinja2

__all__ = ["render", "fmt"]


def fmt(value: Any, digits: int = 3) -> str:
    """A table cell: floats with ``digits`` significant digits, a missing or non-finite number as "-".

    Examples
    --------
    >>> fmt(0.012345), fmt(0.012345, 6), fmt(float("nan")), fmt(None), fmt(700), fmt("lqr")
    ('0.0123', '0.012345', '-', '-', '700', 'lqr')
    """
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.{digits}g}" if math.isfinite(value) else "-"
    return str(value)


@functools.cache
def _environment() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.PackageLoader("formation_ftc.report", "templates"),
        autoescape=True,
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    env.filters["fmt"] = fmt
    return env


def render(template: str, **context: Any) -> str:
    """The text of page template ``template`` (e.g. ``"run.html.j2"``) with ``context``."""
    return _environment().get_template(template).render(**context)
