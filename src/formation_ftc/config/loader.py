"""Load, override, validate and dump scenario files (TOML, data only -- never code).

* :func:`read_raw` -- TOML text of a built-in scenario name or a file path -> ``(dict, source)``
* :func:`set_dotted` -- ``set_dotted(raw, "simulation.horizon", 100.0)`` (the ``--set`` mechanism)
* :func:`parse_override` -- ``"a.b=value"`` -> ``("a.b", value)`` (value parsed as a TOML value)
* :func:`validate` -- raw dict -> the method's pydantic schema instance, errors as :class:`ScenarioError`
* :func:`dump_toml` -- validated scenario -> TOML text

Every failure (unreadable or non-UTF-8 file, invalid or too deeply nested TOML, a bad override, a
schema error, an exception raised by a validator) is a :class:`ScenarioError` naming the file, the
field and the reason.
"""

from __future__ import annotations

import copy
import tomllib
from collections.abc import Callable, Iterable, Mapping
from importlib import resources
from importlib.resources.abc import Traversable
from pathlib import Path
from typing import Any

import tomli_w
from pydantic import ValidationError

from formation_ftc.config.base import validation_message
from formation_ftc.errors import InputError

__all__ = [
    "ScenarioError",
    "builtin_scenarios",
    "builtin_tomls",
    "read_raw",
    "read_named_toml",
    "set_dotted",
    "get_dotted",
    "parse_override",
    "apply_overrides",
    "validate",
    "dump_toml",
    "parse_toml",
    "read_text_file",
    "path_exists",
    "short_text",
    "MAX_NESTING",
    "MAX_FILE_BYTES",
]

#: deepest nesting of tables/arrays accepted in a scenario or campaign file [-]
MAX_NESTING = 32
#: largest scenario or campaign file read [bytes]
MAX_FILE_BYTES = 16 * 2**20


class ScenarioError(InputError):
    """A scenario that cannot be read or does not validate. The message names file and field."""


def builtin_scenarios() -> dict[str, str]:
    """Name -> TOML text of every built-in scenario."""
    return builtin_tomls(resources.files("formation_ftc") / "scenarios")


def builtin_tomls(folder: Traversable) -> dict[str, str]:
    """Name (file name without ``.toml``) -> text of every ``*.toml`` file of a package ``folder``, in
    name order ({} when the folder does not exist)."""
    if not folder.is_dir():
        return {}
    entries = sorted(folder.iterdir(), key=lambda p: p.name)
    return {e.name[:-5]: e.read_text(encoding="utf-8") for e in entries if e.name.endswith(".toml")}


def _nesting_depth(obj: Any) -> int:
    """Deepest nesting of dicts/lists in ``obj`` (iterative, so it cannot overflow the stack)."""
    deepest, stack = 0, [(obj, 0)]
    while stack:
        node, d = stack.pop()
        if isinstance(node, dict | list):
            d += 1
            deepest = max(deepest, d)
            if d <= MAX_NESTING + 1:
                stack.extend((v, d) for v in (node.values() if isinstance(node, dict) else node))
    return deepest


def parse_toml(text: str, source: str, error: type[InputError] = ScenarioError) -> dict[str, Any]:
    """TOML text -> dict; invalid or too deeply nested TOML raises ``error`` naming ``source``."""
    too_deep = (
        f"{source}: TOML nested more than {MAX_NESTING} levels deep (tables/arrays); flatten it"
    )
    if text.count("[") + text.count("{") > MAX_NESTING and _bracket_depth(text) > MAX_NESTING:
        raise error(too_deep)
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{source}: invalid TOML: {exc}") from None
    except RecursionError:
        raise error(f"{source}: TOML nested too deeply (at most {MAX_NESTING} levels)") from None
    if _nesting_depth(raw) > MAX_NESTING:
        raise error(too_deep)
    return raw


def _bracket_depth(text: str) -> int:
    """Upper bound of the bracket nesting of TOML text (brackets inside strings counted too)."""
    depth = deepest = 0
    for ch in text:
        if ch in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif ch in "]}":
            depth = max(0, depth - 1)
    return deepest


def short_text(text: object, limit: int = 80) -> str:
    """``repr`` of ``text`` cut to about ``limit`` characters (for messages about user input)."""
    r = repr(str(text))
    return r if len(r) <= limit else r[: limit - 5] + "...'"


def path_exists(
    path: str | Path, kind: str = "scenario", error: type[InputError] = ScenarioError
) -> bool:
    """Whether ``path`` exists; a path text the system refuses (too long, NUL) raises ``error``."""
    try:
        return Path(path).exists()
    except (OSError, ValueError) as exc:
        reason = getattr(exc, "strerror", None) or str(exc)
        raise error(f"invalid {kind} path {short_text(path)}: {reason}") from None


def read_text_file(
    path: Path, kind: str = "scenario", error: type[InputError] = ScenarioError
) -> str:
    """UTF-8 text of a user file; unreadable, not a file or not UTF-8 raises ``error`` naming it."""
    name = short_text(path)
    if not path_exists(path, kind, error):
        raise error(f"{kind} file {name} does not exist")
    if not path.is_file():
        raise error(f"{kind} file {name} is not a regular file")
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise error(f"{kind} file {name} cannot be read ({exc.strerror or exc})") from None
    if size > MAX_FILE_BYTES:
        raise error(
            f"{kind} file {name} is {size / 2**20:.0f} MiB; at most "
            f"{MAX_FILE_BYTES // 2**20} MiB of TOML is accepted (put large data in arrays elsewhere)"
        )
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise error(f"{kind} file {str(path)!r} cannot be read ({exc.strerror or exc})") from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(
            f"{kind} file {str(path)!r} is not UTF-8 text (byte {exc.start}: {exc.reason})"
        ) from None


def read_raw(name_or_path: str | Path) -> tuple[dict[str, Any], str]:
    """Parse a built-in scenario (by name) or a TOML file (by path)."""
    if isinstance(name_or_path, str) and (not name_or_path or "\x00" in name_or_path):
        raise ScenarioError(f"invalid scenario name or path {name_or_path!r}")
    return read_named_toml(
        name_or_path, "scenario", builtin_scenarios, "built-in", "; see `formation-ftc list`"
    )


def read_named_toml(
    name_or_path: str | Path,
    kind: str,
    builtin: Callable[[], Mapping[str, str]],
    label: str,
    hint: str = "",
    error: type[InputError] = ScenarioError,
) -> tuple[dict[str, Any], str]:
    """``(dict, source)`` of the TOML file ``name_or_path`` (a ``.toml`` name or an existing path), else
    of the built-in ``kind`` of that name (``builtin()``: name -> text; source ``<LABEL NAME>``); every
    failure raises ``error`` naming the file (``hint`` ends the message of an unknown name)."""
    p = Path(name_or_path)
    if p.suffix == ".toml" or path_exists(p, kind, error):
        text, source = read_text_file(p, kind, error), str(p)
    else:
        texts = builtin()
        if str(name_or_path) not in texts:
            raise error(
                f"unknown {kind} {short_text(name_or_path)}: not a file and not a built-in {kind} "
                f"(built-in: {', '.join(texts) or 'none'}{hint})"
            )
        text, source = texts[str(name_or_path)], f"<{label} {name_or_path}>"
    return parse_toml(text, source, error), source


def get_dotted(raw: Mapping[str, Any], path: str) -> Any:
    node: Any = raw
    for part in path.split("."):
        if not isinstance(node, Mapping) or part not in node:
            raise KeyError(path)
        node = node[part]
    return node


def set_dotted(raw: dict[str, Any], path: str, value: Any) -> None:
    """Set ``raw[a][b]... = value`` creating missing intermediate tables; list items via integer parts.

    A list index must be a non-negative integer naming an existing item; a path cannot go through a
    number or a string (``spacecraft.mass.0.x`` when ``mass[0]`` is a number is an error).
    """
    parts = path.split(".")
    if not all(p.strip() for p in parts):
        raise ScenarioError(f"invalid dotted path {path!r} (empty part)")
    node: Any = raw
    for depth, part in enumerate(parts[:-1]):
        if isinstance(node, list):
            node = node[_index(part, path, len(node))]
        else:
            node = node.setdefault(part, {})
        if not isinstance(node, dict | list):
            where = ".".join(parts[: depth + 1])
            raise ScenarioError(
                f"override {path}: {where} is a {_kind(node)}, not a table or a list; "
                f"it has no field {parts[depth + 1]!r}"
            )
    key = _index(parts[-1], path, len(node)) if isinstance(node, list) else parts[-1]
    node[key] = value


def _kind(v: Any) -> str:
    if isinstance(v, bool):
        return "boolean"
    return "number" if isinstance(v, int | float) else type(v).__name__


def _index(part: str, path: str, length: int) -> int:
    if not (part.isascii() and part.isdigit()):
        raise ScenarioError(
            f"override {path}: {part!r} indexes a list and must be a non-negative integer "
            f"(0 ... {length - 1})"
        )
    k = int(part)
    if k >= length:
        raise ScenarioError(
            f"override {path}: index {k} is out of range; the list has {length} item(s) "
            f"(indices 0 ... {length - 1})"
        )
    return k


def parse_override(text: str) -> tuple[str, Any]:
    """``"a.b=1.5"`` -> ``("a.b", 1.5)``; the value is exactly one TOML value, else a plain string.

    A value that is not valid TOML is taken as a string (so ``--set f=1 - 0.1*t`` works) unless it
    looks like TOML (starts with a quote, bracket or brace) or holds a line break; a value followed by
    more TOML (``1\nother = 2``) is refused.
    """
    if "=" not in text:
        raise ScenarioError(f"override {text!r} must look like dotted.path=value")
    path, value = text.split("=", 1)
    path, value = path.strip(), value.strip()
    if not path:
        raise ScenarioError(f"override {text!r}: empty dotted path")
    if not value:
        raise ScenarioError(
            f"--set {path}: empty value (give a number, a quoted string, a list or a table)"
        )
    if any(c in value for c in "\n\r\x00"):
        raise ScenarioError(
            f"--set {path}: the value must be a single TOML value on one line, got {value!r}"
        )
    try:
        doc = tomllib.loads(f"v = {value}")
    except tomllib.TOMLDecodeError as exc:
        if value[0] in "[{\"'":
            raise ScenarioError(f"--set {path}: invalid TOML value {value!r} ({exc})") from None
        return path, value
    except RecursionError:
        raise ScenarioError(f"--set {path}: value nested too deeply") from None
    if _nesting_depth(doc["v"]) > MAX_NESTING:
        raise ScenarioError(f"--set {path}: value nested more than {MAX_NESTING} levels deep")
    return path, doc["v"]


def apply_overrides(
    raw: dict[str, Any], overrides: Mapping[str, Any] | Iterable[str] | None
) -> dict[str, Any]:
    """Copy of ``raw`` with overrides applied (mapping of dotted path -> value, or "path=value" strings)."""
    if _nesting_depth(raw) > MAX_NESTING:
        raise ScenarioError(f"scenario nested more than {MAX_NESTING} levels deep (tables/arrays)")
    out = copy.deepcopy(raw)
    if not overrides:
        return out
    items = overrides.items() if isinstance(overrides, Mapping) else map(parse_override, overrides)
    for path, value in items:
        set_dotted(out, path, value)
    return out


def validate(raw: Mapping[str, Any], source: str = "<scenario>", *, build: bool = True):
    """Validate ``raw`` with the schema of the method named in ``[scenario].method`` (default
    ``"composed"``).

    ``build=False`` checks every field of every section (the same checks and messages) but does not
    assemble the method's loop to check that its parts fit (``formation-ftc show``): no JAX is
    imported. The default also builds it, as ``check``, ``run`` and campaigns need."""
    from formation_ftc.registry import get_method

    meta = raw.get("scenario") if isinstance(raw, Mapping) else None
    if not isinstance(meta, Mapping):
        raise ScenarioError(
            f"{source}: a [scenario] table is required (its name; optionally method, description, "
            "paper)"
        )
    try:
        method = get_method(str(meta.get("method", "composed")))
    except KeyError as exc:
        raise ScenarioError(f"{source}: field scenario.method: {exc.args[0]}") from None
    if _nesting_depth(raw) > MAX_NESTING:
        raise ScenarioError(f"{source}: nested more than {MAX_NESTING} levels deep (tables/arrays)")
    try:
        return method.schema.model_validate(dict(raw), context=None if build else {"build": False})
    except ValidationError as exc:
        raise ScenarioError(
            validation_message(
                exc,
                f"{source}: invalid scenario",
                "unknown field (not part of this method's scenario schema)",
            )
        ) from None
    # raised outside pydantic's wrapping
    except (ValueError, TypeError, ArithmeticError, RecursionError) as exc:
        raise ScenarioError(f"{source}: invalid scenario ({type(exc).__name__}: {exc})") from None


def dump_toml(scenario) -> str:
    """Resolved TOML of a validated scenario (None values omitted)."""
    return tomli_w.dumps(scenario.model_dump(mode="json", exclude_none=True))
