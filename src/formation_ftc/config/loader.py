"""Load, override, validate and dump scenario files (TOML, data only -- never code).

* :func:`read_raw` -- TOML text of a built-in scenario name or a file path -> ``(dict, source)``
* :func:`set_dotted` -- ``set_dotted(raw, "simulation.horizon", 100.0)`` (the ``--set`` mechanism)
* :func:`parse_override` -- ``"a.b=value"`` -> ``("a.b", value)`` (value parsed as a TOML value)
* :func:`validate` -- raw dict -> the method's pydantic schema instance, errors as :class:`ScenarioError`
* :func:`dump_toml` -- validated scenario -> TOML text
"""

from __future__ import annotations

import copy
import tomllib
from collections.abc import Iterable, Mapping
from importlib import resources
from pathlib import Path
from typing import Any

import tomli_w
from pydantic import ValidationError

__all__ = [
    "ScenarioError",
    "builtin_scenarios",
    "read_raw",
    "set_dotted",
    "get_dotted",
    "parse_override",
    "apply_overrides",
    "validate",
    "dump_toml",
]


class ScenarioError(ValueError):
    """A scenario that cannot be read or does not validate. The message names file and field."""


def _builtin_dir():
    return resources.files("formation_ftc") / "scenarios"


def builtin_scenarios() -> dict[str, str]:
    """Name -> TOML text of every built-in scenario."""
    out = {}
    for entry in sorted(_builtin_dir().iterdir(), key=lambda p: p.name):
        if entry.name.endswith(".toml"):
            out[entry.name[:-5]] = entry.read_text(encoding="utf-8")
    return out


def read_raw(name_or_path: str | Path) -> tuple[dict[str, Any], str]:
    """Parse a built-in scenario (by name) or a TOML file (by path)."""
    p = Path(name_or_path)
    if p.suffix == ".toml" or p.exists():
        if not p.is_file():
            raise ScenarioError(f"scenario file {str(p)!r} does not exist")
        text, source = p.read_text(encoding="utf-8"), str(p)
    else:
        builtin = builtin_scenarios()
        if str(name_or_path) not in builtin:
            raise ScenarioError(
                f"unknown scenario {str(name_or_path)!r}: not a file and not a built-in scenario "
                f"(built-in: {', '.join(builtin) or 'none'}; see `formation-ftc list`)"
            )
        text, source = builtin[str(name_or_path)], f"<built-in {name_or_path}>"
    try:
        return tomllib.loads(text), source
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{source}: invalid TOML: {exc}") from None


def get_dotted(raw: Mapping[str, Any], path: str) -> Any:
    node: Any = raw
    for part in path.split("."):
        if not isinstance(node, Mapping) or part not in node:
            raise KeyError(path)
        node = node[part]
    return node


def set_dotted(raw: dict[str, Any], path: str, value: Any) -> None:
    """Set ``raw[a][b]... = value`` creating intermediate tables; list items via integer parts."""
    parts = path.split(".")
    if not all(parts):
        raise ScenarioError(f"invalid dotted path {path!r}")
    node: Any = raw
    for part in parts[:-1]:
        if isinstance(node, list):
            node = node[_index(part, path)]
            continue
        if part not in node or not isinstance(node[part], dict | list):
            node[part] = {}
        node = node[part]
    last = parts[-1]
    if isinstance(node, list):
        node[_index(last, path)] = value
    else:
        node[last] = value


def _index(part: str, path: str) -> int:
    try:
        return int(part)
    except ValueError:
        raise ScenarioError(f"{path}: {part!r} indexes a list and must be an integer") from None


def parse_override(text: str) -> tuple[str, Any]:
    """``"a.b=1.5"`` -> ``("a.b", 1.5)``; the value is a TOML value, else a plain string."""
    if "=" not in text:
        raise ScenarioError(f"override {text!r} must look like dotted.path=value")
    path, value = text.split("=", 1)
    path = path.strip()
    try:
        parsed = tomllib.loads(f"v = {value.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        parsed = value.strip()
    return path, parsed


def apply_overrides(raw: dict[str, Any], overrides: Mapping[str, Any] | Iterable[str] | None) -> dict[str, Any]:
    """Copy of ``raw`` with overrides applied (mapping of dotted path -> value, or "path=value" strings)."""
    out = copy.deepcopy(raw)
    if not overrides:
        return out
    items = overrides.items() if isinstance(overrides, Mapping) else (parse_override(s) for s in overrides)
    for path, value in items:
        set_dotted(out, path, value)
    return out


def _format_validation_error(exc: ValidationError, source: str) -> str:
    lines = [f"{source}: invalid scenario ({exc.error_count()} error(s))"]
    for err in exc.errors():
        loc = ".".join(str(p) for p in err["loc"]) or "<root>"
        msg = err["msg"]
        if err["type"] == "extra_forbidden":
            msg = "unknown field (not part of this method's scenario schema)"
        lines.append(f"  field {loc}: {msg}")
    return "\n".join(lines)


def validate(raw: Mapping[str, Any], source: str = "<scenario>"):
    """Validate ``raw`` with the schema of the method named in ``[scenario].method``."""
    from formation_ftc.registry import get_method

    meta = raw.get("scenario") if isinstance(raw, Mapping) else None
    if not isinstance(meta, Mapping) or "method" not in meta:
        raise ScenarioError(f"{source}: field scenario.method is required (the method that simulates it)")
    try:
        method = get_method(str(meta["method"]))
    except KeyError as exc:
        raise ScenarioError(f"{source}: field scenario.method: {exc.args[0]}") from None
    try:
        return method.schema.model_validate(dict(raw))
    except ValidationError as exc:
        raise ScenarioError(_format_validation_error(exc, source)) from None
    except ValueError as exc:  # validators raising outside pydantic's wrapping
        raise ScenarioError(f"{source}: {exc}") from None


def dump_toml(scenario) -> str:
    """Resolved TOML of a validated scenario (None values omitted)."""
    return tomli_w.dumps(scenario.model_dump(mode="json", exclude_none=True))
