""" "Did you mean ...?" for mistyped scenario names, method names and scenario fields.

Pure helpers (standard library only) used by the command line: :func:`close_matches` ranks names by
similarity (:mod:`difflib`), :func:`unknown_fields` walks a raw scenario dict against a JSON Schema
(the one ``formation-ftc schema METHOD`` prints) and returns every field the schema does not allow,
with the allowed names that look most like it.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

__all__ = ["close_matches", "did_you_mean", "UnknownField", "unknown_fields", "schema_paths"]


def close_matches(
    word: str, candidates: Iterable[str], n: int = 3, cutoff: float = 0.6
) -> list[str]:
    """Up to ``n`` candidates most similar to ``word`` (similarity ratio >= ``cutoff``), best first."""
    cands = list(dict.fromkeys(str(c) for c in candidates))
    found = difflib.get_close_matches(word, cands, n=n, cutoff=cutoff)
    if not found:  # a prefix or a substring is a good hint too ("li2020" -> "li2020-thm1")
        found = [c for c in cands if c.startswith(word) or (len(word) >= 4 and word in c)][:n]
    return found


def did_you_mean(word: str, candidates: Iterable[str]) -> str:
    """``" (did you mean 'x' or 'y'?)"`` or ``""`` when nothing is close."""
    found = close_matches(word, candidates)
    return f" (did you mean {' or '.join(map(repr, found))}?)" if found else ""


@dataclass(frozen=True)
class UnknownField:
    """A field at dotted path ``path`` that the schema does not allow; ``suggestions`` are allowed
    names at the same level that look like it; ``allowed`` all names allowed there."""

    path: str
    suggestions: tuple[str, ...]
    allowed: tuple[str, ...]

    def message(self) -> str:
        hint = did_you_mean(self.path.rsplit(".", 1)[-1], self.suggestions)
        return f"unknown field {self.path}{hint}"


def _resolve(schema: Mapping[str, Any], root: Mapping[str, Any]) -> list[Mapping[str, Any]]:
    """The object schemas ``schema`` may stand for ($ref followed, anyOf/oneOf/allOf flattened)."""
    if "$ref" in schema:
        ref = str(schema["$ref"])
        node: Any = root
        for part in ref.lstrip("#/").split("/"):
            node = node[part]
        return _resolve(node, root)
    out: list[Mapping[str, Any]] = []
    for key in ("anyOf", "oneOf", "allOf"):
        for sub in schema.get(key, []):
            out.extend(_resolve(sub, root))
    if "properties" in schema or schema.get("type") == "object":
        out.append(schema)
    return out


def unknown_fields(
    raw: Mapping[str, Any],
    schema: Mapping[str, Any],
    root: Mapping[str, Any] | None = None,
    prefix: str = "",
) -> list[UnknownField]:
    """Every key of ``raw`` (recursively through tables) that the JSON Schema does not allow.

    Only objects that forbid extra keys (``additionalProperties: false``) report unknown keys; a key
    allowed by any alternative of a union counts as allowed.
    """
    root = schema if root is None else root
    options = _resolve(schema, root)
    if not options or not isinstance(raw, Mapping):
        return []
    allowed: dict[str, list[Mapping[str, Any]]] = {}
    closed = all(o.get("additionalProperties", True) is False for o in options)
    for o in options:
        for name, sub in o.get("properties", {}).items():
            allowed.setdefault(name, []).append(sub)
    out: list[UnknownField] = []
    for key, value in raw.items():
        path = f"{prefix}{key}"
        if key not in allowed:
            if closed:
                names = tuple(sorted(allowed))
                out.append(UnknownField(path, tuple(close_matches(str(key), names)), names))
            continue
        if isinstance(value, Mapping):
            subs = [s for sub in allowed[key] for s in _resolve(sub, root)]
            if subs:
                out.extend(unknown_fields(value, {"anyOf": subs}, root, prefix=f"{path}."))
    return out


def schema_paths(
    schema: Mapping[str, Any],
    root: Mapping[str, Any] | None = None,
    prefix: str = "",
    depth: int = 0,
) -> list[str]:
    """Every dotted field path a JSON Schema allows (tables followed, lists not), sorted."""
    root = schema if root is None else root
    out: set[str] = set()
    if depth > 8:
        return []
    for o in _resolve(schema, root):
        for name, sub in o.get("properties", {}).items():
            path = f"{prefix}{name}"
            out.add(path)
            out.update(schema_paths(sub, root, f"{path}.", depth + 1))
    return sorted(out)
