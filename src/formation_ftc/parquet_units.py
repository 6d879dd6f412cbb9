"""Units in Parquet files: a ``units`` entry in the Arrow field metadata of every numeric column.

Every Parquet file formation-ftc writes -- campaign chunks (``chunks/chunk-NNNNNN.parquet``), the league's
``leaderboard/cells.parquet`` and ``leaderboard/runs.parquet`` -- is written by :func:`write_parquet`,
which gives each numeric (integer or floating-point) column the field metadata ``{"units": UNITS}``:

* a UDUNITS string (``"m"``, ``"m s-1"``, ``"N"``) for a physical quantity, ``"1"`` for a dimensionless
  one (identifiers, seeds, counts, fractions, pass rates);
* ``"unknown"`` (:data:`UNKNOWN`) where the package cannot tell: a sampled scenario input
  (``input:<path>``) has the unit of that scenario field, which ``formation-ftc show SCENARIO`` prints.

Text columns carry no units. Nothing else holds units (no pandas ``attrs``, no file-level metadata).
:func:`read_units` reads them back; with plain pyarrow::

    import pyarrow.parquet as pq
    units = {f.name: f.metadata[b"units"].decode() for f in pq.read_schema(path) if f.metadata}
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import IO, Any

import pandas as pd

from formation_ftc.errors import require_extra

#: the ``campaign`` extra (``pip install -e '.[campaign]'``)
pa = require_extra("pyarrow", "campaign", "Parquet files (campaigns, leagues)")
pq = require_extra("pyarrow.parquet", "campaign", "Parquet files (campaigns, leagues)")

__all__ = ["UNKNOWN", "read_units", "write_parquet"]

UNKNOWN = "unknown"


def _numeric(field: Any) -> bool:  # a pyarrow.Field
    return pa.types.is_integer(field.type) or pa.types.is_floating(field.type)


def write_parquet(
    df: pd.DataFrame,
    where: str | Path | IO[bytes],
    units: Mapping[str, str],
    *,
    metadata: Mapping[str, str] | None = None,
    **options: Any,
) -> None:
    """Write ``df`` (without its index) as Parquet with ``units[column]`` on every numeric column
    (:data:`UNKNOWN` for one not in ``units``) and ``metadata`` in the file's key-value metadata;
    ``options`` go to :func:`pyarrow.parquet.write_table`."""
    plain = df.copy(deep=False)
    plain.attrs = {}  # pyarrow would store them in the file ("pandas" metadata); units live in the fields
    table = pa.Table.from_pandas(plain, preserve_index=False)
    fields = [
        f.with_metadata({**(f.metadata or {}), b"units": units.get(f.name, UNKNOWN).encode()})
        if _numeric(f)
        else f
        for f in table.schema
    ]
    kv = {
        **(table.schema.metadata or {}),
        **{k.encode(): v.encode() for k, v in (metadata or {}).items()},
    }
    pq.write_table(table.cast(pa.schema(fields, metadata=kv)), where, **options)


def read_units(source: Any) -> dict[str, str]:
    """``{column: units}`` of a Parquet file (a path) or its ``pyarrow.Schema``, written by :func:`write_parquet`."""
    schema = source if isinstance(source, pa.Schema) else pq.read_schema(source)
    return {
        f.name: f.metadata[b"units"].decode()
        for f in schema
        if f.metadata and b"units" in f.metadata
    }
