"""The composed scenario's JSON Schema as shipped with the package, so that ``formation-ftc schema
composed`` prints it without importing every catalog's section models (issue 37 item 2: text commands
under 0.3 s; generating it takes about 0.3 s of imports and pydantic schema building).

``composed.schema.json`` beside this module holds the schema, the package modules that generating it
imported and a SHA-256 fingerprint of their sources. :func:`composed_schema` returns the shipped
schema only while that fingerprint still matches the installed sources; otherwise (an edited checkout)
it generates the schema afresh, so the printed schema is never stale. A test compares the shipped
file with a fresh generation; refresh it with::

    python -m formation_ftc.shipped_schema
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

__all__ = ["SCHEMA_FILE", "composed_schema", "shipped_schema", "write_schema_file"]

#: the shipped schema (package data)
SCHEMA_FILE = Path(__file__).with_name("composed.schema.json")
_ROOT = Path(__file__).resolve().parent  # the package directory: sources are relative to it


def _home_files() -> list[str]:
    """The component homes present in the package, ``components/<kind>/<name>.py``: a new one adds a
    type to the schema before anything imports it."""
    return sorted(
        p.relative_to(_ROOT).as_posix() for p in (_ROOT / "components").glob("*/[!_]*.py")
    )


def _fingerprint(sources: list[str]) -> str:
    """SHA-256 over the relative path and bytes of each source file and over the list of component
    homes present (raises OSError if a source is gone)."""
    digest = hashlib.sha256()
    for rel in sources:
        digest.update(rel.encode())
        digest.update((_ROOT / rel).read_bytes())
    digest.update("\n".join(_home_files()).encode())
    return digest.hexdigest()


def shipped_schema(path: Path = SCHEMA_FILE) -> dict[str, Any] | None:
    """The schema stored in ``path`` if its fingerprint matches the installed sources, else None."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        current = _fingerprint(list(data["sources"]))
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return data["schema"] if current == data.get("fingerprint") else None


def composed_schema() -> dict[str, Any]:
    """JSON Schema of a composed scenario file: the shipped copy when current, else generated.

    Returns
    -------
    dict
        Equal to :func:`formation_ftc.methods.composed.composed_json_schema`'s result.

    Examples
    --------
    >>> "controller" in composed_schema()["properties"]
    True
    """
    schema = shipped_schema()
    if schema is None:
        from formation_ftc.methods.composed import composed_json_schema

        schema = composed_json_schema()
    return schema


def write_schema_file(path: Path = SCHEMA_FILE) -> Path:
    """Generate the schema and write it, with its sources and fingerprint, to ``path``.

    Run in a fresh interpreter (``python -m formation_ftc.shipped_schema``): the
    sources are the package modules loaded once the schema is generated, so every module that could
    change it is fingerprinted.
    """
    import sys

    from formation_ftc.methods.composed import composed_json_schema

    schema = composed_json_schema()
    sources = sorted(
        Path(str(m.__file__)).resolve().relative_to(_ROOT).as_posix()
        for name, m in list(sys.modules.items())
        if (name == "formation_ftc" or name.startswith("formation_ftc."))
        and getattr(m, "__file__", None)
        and Path(str(m.__file__)).resolve().is_relative_to(_ROOT)
    )
    data = {"fingerprint": _fingerprint(sources), "sources": sources, "schema": schema}
    path.write_text(json.dumps(data, separators=(",", ":")) + "\n", encoding="utf-8")  # compact
    return path


if __name__ == "__main__":
    print(f"wrote {write_schema_file()}")
