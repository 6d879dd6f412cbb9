"""Conditions as typed JSON (``check --json``, ``reproduce --json``): the numbers a condition's
statement gives, read from the text its method prints (``"max Re(eig) = -0.09989 1/s"`` -> value
-0.09989, units ``1/s``), and its requirement as a bound when it is a plain comparison."""

from __future__ import annotations

import re
from typing import Any

__all__ = ["condition_json", "quantities"]

_NUM = r"[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?(?![\w.+-])"
_UNIT_ATOM = r"(?:kg|rad|deg|Hz|m|s|N|J|W)(?:\^-?\d+)?"
_UNIT = rf"(?:1/)?{_UNIT_ATOM}(?:[ /*]{_UNIT_ATOM})*(?![\w^/])"
#: one clause of a condition's statement: ``[NAME = ]VALUE [UNITS]`` (VALUE a number, a list of numbers,
#: True or False; NAME without "=" or ":" and not ending in a relation such as "<=")
_CLAUSE = re.compile(
    rf"(?:(?P<name>[^=:]+?)(?<![<>!])\s*[=:]\s*)?"
    rf"(?P<value>\[\s*{_NUM}(?:\s*,\s*{_NUM})*\s*\]|{_NUM}|True|False)"
    rf"(?:\s+(?P<units>{_UNIT}))?"
)
#: a requirement that is a plain comparison with a number: ``< -2.9e-13 (rounding margin)``
_BOUND = re.compile(
    rf"(?P<relation><=|>=|<|>|=)\s*(?P<value>{_NUM})(?:\s+(?P<units>{_UNIT}))?\s*(?:$|[(,;])"
)


def _closing(text: str, start: int) -> int:
    """Index of the bracket that closes the one at ``start`` (the last index when it is not closed)."""
    pair = {"(": ")", "[": "]"}[text[start]]
    depth = 0
    for k in range(start, len(text)):
        depth += (text[k] == text[start]) - (text[k] == pair)
        if depth == 0:
            return k
    return len(text) - 1


def _clauses(text: str, remark: bool = False) -> list[tuple[str, bool]]:
    """``text`` cut at top-level ``", "`` and ``"; "`` into ``(clause, in_remark)``: a parenthesised
    remark after a space gives clauses of its own (after the clause it follows, ``in_remark`` True);
    brackets of lists, function calls and leading expressions are kept whole."""
    out: list[tuple[str, bool]] = []
    cur: list[str] = []
    remarks: list[tuple[str, bool]] = []

    def close() -> None:
        if "".join(cur).strip():
            out.append(("".join(cur).strip(), remark))
        out.extend(remarks)
        cur.clear()
        remarks.clear()

    k = 0
    while k < len(text):
        ch = text[k]
        if ch in "([":
            end = _closing(text, k)
            if ch == "(" and k > 0 and text[k - 1] == " ":
                remarks.extend(_clauses(text[k + 1 : end], remark=True))
            else:
                cur.append(text[k : end + 1])
            k = end + 1
            continue
        if ch in ",;" and text[k + 1 : k + 2] in (" ", ""):
            close()
        else:
            cur.append(ch)
        k += 1
    close()
    return out


def _value(text: str) -> Any:
    if text in ("True", "False"):
        return text == "True"
    if text.startswith("["):
        return [float(v) for v in text.strip("[] ").split(",")]
    return float(text)


def quantities(statement: str) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """The numbers a condition's statement gives (``"max Re(eig) = -0.09989 1/s"`` ->
    ``[{"name": "max Re(eig)", "value": -0.09989, "units": "1/s"}]``), as printed by its method: every
    clause ``[NAME = ]NUMBER [UNITS]`` (or a list of numbers, or True/False); other clauses are skipped.
    Also those of them outside parenthesised remarks."""
    out, main = [], []
    for clause, in_remark in _clauses(statement):
        m = _CLAUSE.fullmatch(clause)
        if m:
            out.append({"name": m["name"], "value": _value(m["value"]), "units": m["units"]})
            if not in_remark:
                main.append(out[-1])
    return out, main


def condition_json(c) -> dict[str, Any]:
    """One condition with typed values (docs/cli.md, ``check --json``)."""
    d = c.as_dict()
    found, main = quantities(d["value"])
    # the statement's value: its one quantity outside remarks ("max eig = -1e-08 (lambda = 1e-08)");
    # None when it states several side by side ("e_s = 0.03 m, T = 1.07e-05 m") or none
    single = main[0] if len(main) == 1 else None
    m = _BOUND.match(d["requirement"].strip())
    bound = m and {"relation": m["relation"], "value": float(m["value"]), "units": m["units"]}
    return {
        "name": d["name"],
        "reference": d["reference"],
        "value": single["value"] if single else None,
        "units": single["units"] if single else None,
        "value_text": d["value"],
        "quantities": found,
        "requirement": d["requirement"],
        "bound": bound,
        "holds": d["holds"],
        "unproven": bool(c.unproven),
        "required": d["required"],
        "basis": d["basis"],
        "detail": d["detail"],
    }
