"""How the API's result objects show in Jupyter (``_repr_html_``) and at a Python prompt (``__repr__``).

A scenario (:class:`formation_ftc.config.base.ScenarioBase`), the conditions of
:func:`formation_ftc.api.check` (:class:`formation_ftc.api.Conditions`), the metrics of
:func:`formation_ftc.api.simulate_with_metrics` (:class:`formation_ftc.api.Metrics`) and a campaign's
outcome (:class:`formation_ftc.campaign.runner.CampaignOutcome`) render as one small card: a title, a
few labelled fields and a table. The HTML comes from one Jinja2 template with autoescaping, so names,
descriptions and statements a user wrote (``<``, ``&``, quotes) show as text and never as markup. The
result datasets are ``xarray.Dataset`` objects: xarray draws them, with the ``units`` and ``long_name``
every variable carries (:func:`formation_ftc.cf.apply_cf`).

Numbers are shown with four significant digits (:func:`number`), a quantity with its unit
(:func:`quantity`, ``"600 s"``).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable, Sequence
from typing import Any

__all__ = [
    "Cell",
    "card_html",
    "card_text",
    "text_table",
    "number",
    "quantity",
    "holds_cell",
    "condition_row",
    "CONDITION_COLUMNS",
]

#: a table cell: its text, or ``(text, CSS colour)``
Cell = str | tuple[str, str]

_TEMPLATE = """\
<div class="formation-ftc-card">
<div><strong>{{ title }}</strong>{% if subtitle %} &mdash; {{ subtitle }}{% endif %}</div>
{% if fields %}<table>
{% for label, value in fields %}<tr><th style="text-align:left">{{ label }}</th>\
<td style="text-align:left">{{ value }}</td></tr>
{% endfor %}</table>
{% endif %}{% if columns %}<table>
<thead><tr>{% for c in columns %}<th style="text-align:left">{{ c }}</th>{% endfor %}</tr></thead>
<tbody>
{% for row in rows %}<tr>{% for text, colour in row %}<td style="text-align:left\
{% if colour %}; color:{{ colour }}{% endif %}">{{ text }}</td>{% endfor %}</tr>
{% endfor %}</tbody>
</table>
{% endif %}{% if note %}<div>{{ note }}</div>
{% endif %}</div>
"""


@functools.cache
def _template():
    from jinja2 import Environment

    return Environment(autoescape=True, keep_trailing_newline=True).from_string(_TEMPLATE)


def number(value: Any) -> str:
    """``value`` for display: four significant digits for a float (``"nan"``, ``"inf"`` as such), an
    integer with thousands separators, anything else as text."""
    if isinstance(value, bool) or value is None:
        return str(value)
    if isinstance(value, int):
        return f"{value:,}"
    try:
        x = float(value)
    except (TypeError, ValueError):
        return str(value)
    return f"{x:.4g}" if math.isfinite(x) else str(x)


def quantity(value: Any, units: str | None) -> str:
    """``"600 s"``: :func:`number` of ``value`` and its unit (none for ``""``, ``"1"`` or None)."""
    text = number(value)
    return f"{text} {units}" if units and units != "1" else text


def holds_cell(holds: bool | None, unproven: bool = False) -> tuple[str, str]:
    """The ``holds`` cell of a condition: yes (green), NO (red), unproven (amber) or n/a."""
    if holds is None:
        return ("unproven", "#a60") if unproven else ("n/a", "")
    return ("yes", "#070") if holds else ("NO", "#b00")


#: the columns of a table of conditions (:func:`condition_row`)
CONDITION_COLUMNS = ("condition", "reference", "value", "requirement", "holds", "basis", "required")


def condition_row(c: Any) -> list[Cell]:
    """The row of a :class:`~formation_ftc.registry.Condition` in a table of :data:`CONDITION_COLUMNS`."""
    head = [str(c.name), str(c.reference), str(c.value), str(c.requirement)]
    return [*head, holds_cell(c.holds, c.unproven), str(c.basis), "yes" if c.required else "info"]


def _cells(row: Sequence[Cell]) -> list[tuple[str, str]]:
    return [c if isinstance(c, tuple) else (str(c), "") for c in row]


def card_html(
    title: str,
    subtitle: str = "",
    fields: Iterable[tuple[str, str]] = (),
    columns: Sequence[str] = (),
    rows: Iterable[Sequence[Cell]] = (),
    note: str = "",
) -> str:
    """One card as an HTML fragment (what ``_repr_html_`` returns); every text is escaped.

    Parameters
    ----------
    title, subtitle : str
        The card's heading (the subtitle after a dash; none when empty).
    fields : iterable of (str, str)
        Labelled values shown above the table.
    columns : sequence of str
        The table's column headings (no table when empty).
    rows : iterable of sequences of str or (str, str)
        The table's rows: a cell's text, or its text and CSS colour.
    note : str
        A line below the table.

    Returns
    -------
    str
        The HTML fragment.

    Examples
    --------
    >>> html = card_html("a < b", fields=[("horizon", "600 s")], columns=["x"], rows=[["<i>"]])
    >>> "a &lt; b" in html and "&lt;i&gt;" in html and "<i>" not in html
    True
    """
    return _template().render(
        title=title,
        subtitle=subtitle,
        fields=list(fields),
        columns=list(columns),
        rows=[_cells(r) for r in rows],
        note=note,
    )


def card_text(
    title: str,
    fields: Iterable[tuple[str, str]] = (),
    columns: Sequence[str] = (),
    rows: Iterable[Sequence[Cell]] = (),
    note: str = "",
) -> str:
    """The same card as plain text (for ``__repr__``): the title, ``label: value`` lines, then the table
    in aligned columns.

    Parameters
    ----------
    title : str
        The first line.
    fields : iterable of (str, str)
        Labelled values, one line each.
    columns : sequence of str
        The table's column headings (no table when empty).
    rows : iterable of sequences of str or (str, str)
        The table's rows (colours are dropped).
    note : str
        A last line.

    Returns
    -------
    str
        The text, lines separated by ``"\\n"``.

    Examples
    --------
    >>> print(card_text("Metrics", columns=["metric", "value"], rows=[["dv", "0.1"]]))
    Metrics
      metric  value
      dv      0.1
    """
    lines = [title]
    lines += [f"  {label}: {value}" for label, value in fields]
    if columns:
        lines += text_table(columns, rows, indent="  ")
    if note:
        lines.append(f"  {note}")
    return "\n".join(lines)


def text_table(
    columns: Sequence[str], rows: Iterable[Sequence[Cell]], indent: str = ""
) -> list[str]:
    """The lines of a plain-text table: the ``columns`` headings, then ``rows`` (colours dropped), each
    column as wide as its widest cell, two spaces between columns, every line after ``indent``.

    Examples
    --------
    >>> text_table(["metric", "value"], [["dv", ("0.1", "#070")]])
    ['metric  value', 'dv      0.1']
    """
    table = [list(columns)] + [[t for t, _ in _cells(r)] for r in rows]
    widths = [max(len(r[k]) for r in table) for k in range(len(columns))]
    return [
        indent + "  ".join(v.ljust(w) for v, w in zip(r, widths, strict=True)).rstrip()
        for r in table
    ]
