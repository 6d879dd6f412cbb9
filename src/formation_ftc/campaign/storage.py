"""The results store of one campaign: a directory with a manifest and one Parquet file per chunk.

Layout::

    DIR/manifest.json                 campaign spec, its hash, package version, run/chunk counts
    DIR/chunks/chunk-000012.parquet   one row per run of chunk 12 (inputs, seed, status, metrics)
    DIR/traces/run-000005.nc          optional decimated time history of run 5 (NetCDF, h5netcdf)
    DIR/report/                       written by ``formation-ftc campaign report``

Every file is written under a temporary name in the same directory and renamed with
:func:`os.replace` (atomic on POSIX), so a killed campaign leaves only whole chunk files; a chunk
file exists only once the chunk is finished (its traces are written before it). Resuming keeps every
finished chunk and computes the others. A directory that is not this campaign's -- another campaign's
manifest, an unreadable manifest or chunk, files we do not write -- is refused, never overwritten.
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import re
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow.parquet as pq

from formation_ftc.campaign.sampling import CampaignPlan
from formation_ftc.campaign.spec import CampaignError

__all__ = ["CampaignStore", "MANIFEST", "FORMAT", "atomic_write_bytes", "chunk_filename"]

MANIFEST = "manifest.json"
FORMAT = "formation-ftc-campaign"
FORMAT_VERSION = 1
_CHUNK_RE = re.compile(r"^chunk-(\d{6,})\.parquet$")
_TRACE_RE = re.compile(r"^run-(\d{6,})\.nc$")
_TMP_RE = re.compile(r"^\..+\.tmp-\d+$")
_TOP_LEVEL = {MANIFEST, "chunks", "traces", "report"}


def chunk_filename(chunk_id: int) -> str:
    return f"chunk-{chunk_id:06d}.parquet"


def trace_filename(run_id: int) -> str:
    return f"run-{run_id:06d}.nc"


def _tmp_path(path: Path) -> Path:
    return path.with_name(f".{path.name}.tmp-{os.getpid()}")


def _fsync_dir(d: Path) -> None:
    try:
        fd = os.open(d, os.O_RDONLY)
    except OSError:  # pragma: no cover - platform without directory fds
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover
        pass
    finally:
        os.close(fd)


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (temporary file, fsync, rename)."""
    tmp = _tmp_path(path)
    with open(tmp, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)
    _fsync_dir(path.parent)


def _package_version() -> str:
    from formation_ftc import __version__

    return __version__


def _flat(d: Any, prefix: str = "") -> dict[str, Any]:
    if isinstance(d, dict):
        out: dict[str, Any] = {}
        for k, v in d.items():
            out.update(_flat(v, f"{prefix}.{k}" if prefix else str(k)))
        return out
    return {prefix: d}


class CampaignStore:
    """Open with :meth:`prepare` (checks, writes nothing) then :meth:`initialize` (writes the manifest
    of a new campaign); :meth:`read` opens a store for reporting."""

    def __init__(self, root: Path, manifest: dict[str, Any], finished: set[int], is_new: bool):
        self.root = Path(root)
        self.manifest = manifest
        self._finished = set(finished)
        self.is_new = is_new

    # ------------------------------------------------------------------------------------ opening
    @staticmethod
    def manifest_for(plan: CampaignPlan) -> dict[str, Any]:
        return dict(
            format=FORMAT,
            format_version=FORMAT_VERSION,
            campaign=plan.name,
            spec_hash=plan.hash,
            package_version=_package_version(),
            created_utc=_dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
            spec=plan.spec.model_dump(mode="json"),
            plan=plan.summary(),
            input_columns=plan.input_columns(),
            swept=plan.swept(),
            sampled=plan.sampled(),
            n_runs=plan.n_runs,
            n_chunks=plan.n_chunks,
        )

    @staticmethod
    def _read_manifest(root: Path) -> dict[str, Any]:
        path = root / MANIFEST
        try:
            manifest = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise CampaignError(f"{path}: corrupt campaign manifest ({exc}); refusing to use or overwrite "
                                f"{root}") from None
        if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
            raise CampaignError(f"{path}: not a formation-ftc campaign manifest; refusing to use or "
                                f"overwrite {root}")
        if manifest.get("format_version") != FORMAT_VERSION:
            raise CampaignError(f"{path}: campaign format version {manifest.get('format_version')} is not "
                                f"{FORMAT_VERSION}; refusing to use it")
        for key in ("spec_hash", "n_chunks", "n_runs", "spec"):
            if key not in manifest:
                raise CampaignError(f"{path}: corrupt campaign manifest (no {key!r}); refusing to use it")
        return manifest

    @staticmethod
    def _scan(root: Path, n_chunks: int) -> set[int]:
        """Check the directory holds only our files; return the chunk ids present (stale temporary
        files of a killed run are removed)."""
        for entry in root.iterdir():
            if entry.name not in _TOP_LEVEL:
                raise CampaignError(f"{root}: unknown entry {entry.name!r} in a campaign directory; refusing "
                                    f"to write here (move it away or use another --out)")
        chunk_ids: set[int] = set()
        for sub, pattern in (("chunks", _CHUNK_RE), ("traces", _TRACE_RE)):
            d = root / sub
            if not d.exists():
                continue
            if not d.is_dir():
                raise CampaignError(f"{d}: expected a directory; refusing to use {root}")
            for f in d.iterdir():
                if _TMP_RE.match(f.name) and f.is_file():
                    f.unlink()  # an interrupted atomic write: never renamed, never counted
                    continue
                m = pattern.match(f.name)
                if not m or not f.is_file():
                    raise CampaignError(f"{f}: unknown file in a campaign directory; refusing to use {root}")
                if sub == "chunks":
                    cid = int(m.group(1))
                    if cid >= n_chunks:
                        raise CampaignError(f"{f}: chunk {cid} does not exist in this campaign "
                                            f"({n_chunks} chunks); refusing to use {root}")
                    chunk_ids.add(cid)
        return chunk_ids

    @classmethod
    def prepare(cls, root: str | Path, plan: CampaignPlan) -> CampaignStore:
        """Check ``root`` for ``plan`` (a new, empty or same-campaign directory); writes nothing."""
        root = Path(root)
        if root.exists() and not root.is_dir():
            raise CampaignError(f"{root}: exists and is not a directory")
        if not root.exists() or not any(root.iterdir()):
            return cls(root, cls.manifest_for(plan), set(), True)
        if not (root / MANIFEST).exists():
            raise CampaignError(f"{root}: not empty and has no {MANIFEST}: not a campaign directory; "
                                f"refusing to overwrite it")
        manifest = cls._read_manifest(root)
        if manifest["spec_hash"] != plan.hash:
            raise CampaignError(cls._difference(root, manifest, plan))
        if manifest.get("package_version") != _package_version():
            raise CampaignError(f"{root}: written by formation-ftc {manifest.get('package_version')}, this is "
                                f"{_package_version()}; resume with the same version or use a new directory")
        finished = cls._scan(root, int(manifest["n_chunks"]))
        for cid in sorted(finished):
            cls._check_chunk(root, cid, plan.chunk(cid).run_ids)
        return cls(root, manifest, finished, False)

    @staticmethod
    def _difference(root: Path, manifest: dict[str, Any], plan: CampaignPlan) -> str:
        old, new = _flat(manifest.get("spec", {})), _flat(plan.spec.model_dump(mode="json"))
        diffs = [f"{k}: {old.get(k, '<absent>')!r} there, {new.get(k, '<absent>')!r} here"
                 for k in sorted(set(old) | set(new)) if old.get(k) != new.get(k)]
        detail = "; ".join(diffs[:5]) if diffs else "the base scenario content differs"
        return (f"{root}: holds another campaign ({manifest.get('campaign')!r}, spec hash "
                f"{str(manifest['spec_hash'])[:12]}, this one {plan.hash[:12]}): {detail}. Refusing to mix "
                f"results; use another --out directory")

    @staticmethod
    def _check_chunk(root: Path, chunk_id: int, expected_runs: list[int]) -> None:
        path = root / "chunks" / chunk_filename(chunk_id)
        try:
            ids = pq.read_table(path, columns=["run_id"]).column("run_id").to_pylist()
        except Exception as exc:  # noqa: BLE001 - any read failure means a corrupt file
            raise CampaignError(f"{path}: corrupt chunk file ({type(exc).__name__}: {exc}); refusing to "
                                f"continue. Delete it to recompute that chunk") from None
        if ids != expected_runs:
            raise CampaignError(f"{path}: holds runs {ids[:3]}... but chunk {chunk_id} is runs "
                                f"{expected_runs[0]}..{expected_runs[-1]}; refusing to use this directory")

    def initialize(self) -> None:
        """Create the directory and manifest of a new campaign (no-op when resuming)."""
        if not self.is_new:
            return
        (self.root / "chunks").mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(self.root / MANIFEST, json.dumps(self.manifest, indent=2, sort_keys=True).encode())
        self.is_new = False

    @classmethod
    def read(cls, root: str | Path) -> CampaignStore:
        """Open an existing campaign directory for reading (report)."""
        root = Path(root)
        if not (root / MANIFEST).is_file():
            raise CampaignError(f"{root}: no {MANIFEST}; not a campaign directory")
        manifest = cls._read_manifest(root)
        finished = cls._scan(root, int(manifest["n_chunks"]))
        return cls(root, manifest, finished, False)

    # ------------------------------------------------------------------------------------- access
    def finished(self) -> set[int]:
        return set(self._finished)

    def chunk_path(self, chunk_id: int) -> Path:
        return self.root / "chunks" / chunk_filename(chunk_id)

    def write_chunk(self, chunk_id: int, table: pd.DataFrame, traces: dict[int, Any] | None = None) -> Path:
        """Write the traces, then the chunk's Parquet file (atomically; the chunk then counts as done)."""
        if chunk_id in self._finished:
            raise CampaignError(f"chunk {chunk_id} is already stored in {self.root}")
        for run_id, ds in sorted((traces or {}).items()):
            tdir = self.root / "traces"
            tdir.mkdir(exist_ok=True)
            path = tdir / trace_filename(run_id)
            tmp = _tmp_path(path)
            ds.to_netcdf(tmp, engine="h5netcdf")
            os.replace(tmp, path)
        path = self.chunk_path(chunk_id)
        tmp = _tmp_path(path)
        with open(tmp, "wb") as f:
            table.to_parquet(f, index=False, engine="pyarrow")
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
        _fsync_dir(path.parent)
        self._finished.add(chunk_id)
        return path

    def load_results(self) -> pd.DataFrame:
        """All finished runs, sorted by run id (columns: run_id, seed, status, input:*, metric:*, ...)."""
        frames = []
        for cid in sorted(self._finished):
            path = self.chunk_path(cid)
            try:
                frames.append(pd.read_parquet(path, engine="pyarrow"))
            except Exception as exc:  # noqa: BLE001
                raise CampaignError(f"{path}: corrupt chunk file ({exc})") from None
        if not frames:
            return pd.DataFrame(columns=["run_id", "status"])
        df = pd.concat(frames, ignore_index=True)
        return df.sort_values("run_id", kind="stable").reset_index(drop=True)

    def trace_path(self, run_id: int) -> Path:
        return self.root / "traces" / trace_filename(run_id)
