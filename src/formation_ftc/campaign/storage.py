"""The results store of one campaign: a directory with a manifest and one Parquet file per chunk.

Layout::

    DIR/manifest.json                 campaign spec, its hash, package version, run/chunk counts and
                                      the SHA-256 of every chunk file (``chunk_sha256``)
    DIR/.lock                         advisory lock of the process writing the campaign (host, PID)
    DIR/chunks/chunk-000012.parquet   one row per run of chunk 12 (inputs, seed, status, metrics; units
                                      as in :mod:`formation_ftc.parquet_units`)
    DIR/traces/run-000005.nc          optional decimated time history of run 5 (NetCDF, h5netcdf; CF-1.10
                                      and provenance attributes as a ``result.nc``)
    DIR/report/                       written by ``formation-ftc campaign report``

Every file is written under a temporary name in the same directory and renamed with
:func:`os.replace` (:func:`formation_ftc.atomic.atomic_write`), so a killed campaign leaves only whole
chunk files; a chunk file exists only once the chunk is finished (its traces are written before it). Resuming keeps every
finished chunk and computes the others. A directory that is not this campaign's -- another campaign's
manifest, an unreadable manifest or chunk, files we do not write -- is refused, never overwritten.

Safety against concurrent writers and silent corruption:

* one writer per directory: :meth:`CampaignStore.initialize` takes an exclusive lock on ``DIR/.lock``
  (:class:`filelock.FileLock`: ``flock`` on POSIX) and writes the holder's host and PID into it; a second
  ``campaign run`` on the same directory is refused with that host and PID. The operating system
  releases the lock when its process dies, so the lock of a killed run is taken over by the next one
  (its stale host/PID text is simply overwritten);
* temporary files (``.NAME.tmp-PID``) are never touched by a scan; only the lock holder removes them;
* the SHA-256 of each chunk file is recorded in the manifest before the chunk file is renamed into
  place (and Parquet page checksums are written). Resuming recomputes a chunk whose content does not
  match (reported on stderr, never used); ``campaign report`` refuses a directory with such a chunk.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import errno
import functools
import hashlib
import io
import json
import os
import re
import socket
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import filelock
import pandas as pd

from formation_ftc.atomic import atomic_write
from formation_ftc.campaign.sampling import CampaignPlan
from formation_ftc.campaign.spec import CampaignError, _flatten
from formation_ftc.cf import apply_cf, write_netcdf
from formation_ftc.errors import require_extra
from formation_ftc.parquet_units import read_units, write_parquet
from formation_ftc.provenance import provenance
from formation_ftc.runout import TMP_RE, oserror_as

#: Parquet I/O: the ``campaign`` extra (``pip install -e '.[campaign]'``)
pq = require_extra("pyarrow.parquet", "campaign", "campaign and league storage (Parquet files)")

__all__ = [
    "CampaignStore",
    "MANIFEST",
    "LOCK",
    "FORMAT",
    "chunk_filename",
    "sha256_file",
]

MANIFEST = "manifest.json"
FORMAT = "formation-ftc-campaign"
FORMAT_VERSION = 2
LOCK = ".lock"
_CHUNK_RE = re.compile(r"^chunk-(\d{6,})\.parquet$")
_TRACE_RE = re.compile(r"^run-(\d{6,})\.nc$")
_TOP_LEVEL = {MANIFEST, LOCK, "chunks", "traces", "report"}
_ROOT_TMP_RE = re.compile(r"^\.manifest\.json\.tmp-\d+$")
#: integer bookkeeping columns of a chunk (identifiers, indices, seeds): dimensionless
_COUNT_COLUMNS = ("run_id", "chunk_id", "grid_index", "replicate", "seed")


def chunk_filename(chunk_id: int) -> str:
    return f"chunk-{chunk_id:06d}.parquet"


def sha256_file(path: Path) -> str:
    """Hex SHA-256 of a file's bytes."""
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()


def _package_version() -> str:
    from formation_ftc import __version__

    return __version__


def _utc_now() -> str:
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")


class CampaignStore:
    """Open with :meth:`prepare` (checks, writes nothing) then :meth:`initialize` (writes the manifest
    of a new campaign); :meth:`read` opens a store for reporting."""

    def __init__(self, root: Path, manifest: dict[str, Any], is_new: bool = False):
        self.root = Path(root)
        self.manifest = manifest
        self._finished: set[int] = set()  # chunks verified or written by this store
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
            created_utc=_utc_now(),
            spec=plan.spec.model_dump(mode="json"),
            plan=plan.summary(),
            input_columns=plan.input_columns(),
            swept=plan.swept(),
            sampled=plan.sampled(),
            n_runs=plan.n_runs,
            n_chunks=plan.n_chunks,
            chunk_sha256={},
        )

    @staticmethod
    def _read_manifest(root: Path) -> dict[str, Any]:
        path = root / MANIFEST
        try:
            manifest = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise CampaignError(
                f"{path}: corrupt campaign manifest ({exc}); refusing to use or overwrite {root}"
            ) from None
        if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
            raise CampaignError(
                f"{path}: not a formation-ftc campaign manifest; refusing to use or "
                f"overwrite {root}"
            )
        if manifest.get("format_version") != FORMAT_VERSION:
            raise CampaignError(
                f"{path}: campaign format version {manifest.get('format_version')} is not "
                f"{FORMAT_VERSION}; refusing to use it"
            )
        if not isinstance(manifest.get("chunk_sha256", {}), dict):
            raise CampaignError(f"{path}: corrupt campaign manifest (chunk_sha256 is not a table)")
        for key in ("spec_hash", "n_chunks", "n_runs", "spec", "chunk_sha256"):
            if key not in manifest:
                raise CampaignError(
                    f"{path}: corrupt campaign manifest (no {key!r}); refusing to use it"
                )
        return manifest

    def _scan(self) -> list[int]:
        """Check the directory holds only our files; return the chunk ids present, in order (temporary
        files are left to :meth:`_remove_temporaries`)."""
        root, n_chunks = self.root, int(self.manifest["n_chunks"])
        for entry in root.iterdir():
            if entry.name not in _TOP_LEVEL and not _ROOT_TMP_RE.match(entry.name):
                raise CampaignError(
                    f"{root}: unknown entry {entry.name!r} in a campaign directory; refusing "
                    f"to write here (move it away or use another --out)"
                )
        chunk_ids: set[int] = set()
        for sub, pattern in (("chunks", _CHUNK_RE), ("traces", _TRACE_RE)):
            d = root / sub
            if not d.exists():
                continue
            if not d.is_dir():
                raise CampaignError(f"{d}: expected a directory; refusing to use {root}")
            for f in d.iterdir():
                if TMP_RE.match(f.name) and f.is_file():
                    continue  # a write in progress or interrupted: never counted; only the lock holder removes it
                m = pattern.match(f.name)
                if not m or not f.is_file():
                    raise CampaignError(
                        f"{f}: unknown file in a campaign directory; refusing to use {root}"
                    )
                if sub == "chunks":
                    cid = int(m.group(1))
                    if cid >= n_chunks:
                        raise CampaignError(
                            f"{f}: chunk {cid} does not exist in this campaign "
                            f"({n_chunks} chunks); refusing to use {root}"
                        )
                    chunk_ids.add(cid)
        return sorted(chunk_ids)

    @classmethod
    def prepare(cls, root: str | Path, plan: CampaignPlan) -> CampaignStore:
        """Check ``root`` for ``plan`` (a new, empty or same-campaign directory); writes nothing."""
        return _opened(lambda r: cls._prepare(r, plan), root, "results directory")

    @classmethod
    def _prepare(cls, root: Path, plan: CampaignPlan) -> CampaignStore:
        if root.exists() and not root.is_dir():
            raise CampaignError(f"{root}: exists and is not a directory")
        if not root.exists() or not any(e.name != LOCK for e in root.iterdir()):
            return cls(root, cls.manifest_for(plan), is_new=True)
        if not (root / MANIFEST).exists():
            raise CampaignError(
                f"{root}: not empty and has no {MANIFEST}: not a campaign directory; "
                f"refusing to overwrite it"
            )
        manifest = cls._read_manifest(root)
        if manifest["spec_hash"] != plan.hash:
            raise CampaignError(cls._difference(root, manifest, plan))
        if manifest.get("package_version") != _package_version():
            raise CampaignError(
                f"{root}: written by formation-ftc {manifest.get('package_version')}, this is "
                f"{_package_version()}; resume with the same version or use a new directory"
            )
        store = cls(root, manifest)
        for cid in store._scan():
            if problem := store.verify_chunk(cid):  # reported and recomputed, never used
                print(f"warning: {problem}; chunk {cid} will be recomputed", file=sys.stderr)
                continue
            store._check_chunk(cid, plan.chunk(cid).run_ids)
            store._finished.add(cid)
        return store

    @staticmethod
    def _difference(root: Path, manifest: dict[str, Any], plan: CampaignPlan) -> str:
        spec = manifest.get("spec", {})
        old = _flatten(spec) if isinstance(spec, dict) else {"": spec}
        new = _flatten(plan.spec.model_dump(mode="json"))
        diffs = [
            f"{k}: {old.get(k, '<absent>')!r} there, {new.get(k, '<absent>')!r} here"
            for k in sorted(set(old) | set(new))
            if old.get(k) != new.get(k)
        ]
        detail = "; ".join(diffs[:5]) if diffs else "the base scenario content differs"
        return (
            f"{root}: holds another campaign ({manifest.get('campaign')!r}, spec hash "
            f"{str(manifest['spec_hash'])[:12]}, this one {plan.hash[:12]}): {detail}. Refusing to mix "
            f"results; use another --out directory"
        )

    def _check_chunk(self, chunk_id: int, expected_runs: list[int]) -> None:
        path = self.chunk_path(chunk_id)
        try:
            ids = pq.read_table(path, columns=["run_id"]).column("run_id").to_pylist()
        except Exception as exc:  # noqa: BLE001 - any read failure means a corrupt file
            raise CampaignError(
                f"{path}: corrupt chunk file ({type(exc).__name__}: {exc}); refusing to "
                f"continue. Delete it to recompute that chunk"
            ) from None
        if ids != expected_runs:
            raise CampaignError(
                f"{path}: holds runs {ids[:3]}... but chunk {chunk_id} is runs "
                f"{expected_runs[0]}..{expected_runs[-1]}; refusing to use this directory"
            )

    def initialize(self) -> None:
        """Take the directory's lock, then create the directory and manifest of a new campaign (when
        resuming: re-read the manifest under the lock). Call :meth:`close` to release the lock."""
        self.acquire_lock()
        if not self.is_new:
            if (self.root / MANIFEST).is_file():
                self.manifest = self._read_manifest(self.root)
            self._remove_temporaries()
            return
        if (self.root / MANIFEST).exists():
            self.close()
            raise CampaignError(
                f"{self.root}: another process created a campaign here meanwhile; run again"
            )
        (self.root / "chunks").mkdir(parents=True, exist_ok=True)
        self._write_manifest()
        self.is_new = False

    def _write_manifest(self) -> None:
        atomic_write(self.root / MANIFEST, json.dumps(self.manifest, indent=2, sort_keys=True))

    # ------------------------------------------------------------------------------------ locking
    _lock: filelock.BaseFileLock | None = None

    def acquire_lock(self) -> None:
        """Exclusive lock on ``DIR/.lock`` (:mod:`filelock`, non-blocking); CampaignError naming the
        holder when another process has it."""
        if self._lock is not None:
            return
        path = self.root / LOCK
        lock = filelock.FileLock(path, timeout=0, mode=0o644, thread_local=False)
        try:
            self.root.mkdir(parents=True, exist_ok=True)
            lock.acquire()
        except filelock.Timeout:
            raise CampaignError(
                f"{self.root}: in use by another campaign run ({_lock_holder_text(path)}); wait for "
                f"it to finish or stop it, or use another --out"
            ) from None
        except OSError as exc:
            if not path.is_file():
                raise CampaignError(
                    f"{self.root}: cannot create the lock file {LOCK} ({exc.strerror or exc}); "
                    f"is the directory writable?"
                ) from None
            raise CampaignError(
                f"{self.root}: the file system refuses advisory locks on {LOCK} "
                f"({exc.strerror or exc}); use a results directory on a local disk or on "
                f"a file system with locking"
            ) from None
        # any text left in the file is a dead holder's (the kernel released its lock): taken over
        text = json.dumps(dict(host=socket.gethostname(), pid=os.getpid(), since_utc=_utc_now()))
        try:
            path.write_text(text, encoding="utf-8")  # the same file (inode): the lock stays
        except OSError as exc:
            lock.release()
            if exc.errno in (errno.ENOSPC, errno.EDQUOT):  # a full disk: exit status 3, one line
                raise OSError(exc.errno, exc.strerror, str(path)) from None
            raise CampaignError(
                f"{self.root}: cannot write the lock file {LOCK} ({exc.strerror or exc})"
            ) from None
        self._lock = lock

    def close(self) -> None:
        """Release the directory lock (idempotent)."""
        lock, self._lock = self._lock, None
        if lock is not None:
            with contextlib.suppress(OSError):
                (self.root / LOCK).write_bytes(b"")  # no holder named once released
            lock.release()

    def _remove_temporaries(self) -> None:
        """Remove interrupted atomic writes (only called while holding the lock: no other writer)."""
        for sub in ("chunks", "traces"):
            d = self.root / sub
            if d.is_dir():
                for f in d.iterdir():
                    if TMP_RE.match(f.name) and f.is_file():
                        f.unlink(missing_ok=True)
        for f in self.root.iterdir():
            if _ROOT_TMP_RE.match(f.name):
                f.unlink(missing_ok=True)

    # --------------------------------------------------------------------------------- checksums
    def verify_chunk(self, chunk_id: int) -> str:
        """ "" when chunk ``chunk_id``'s file matches its recorded SHA-256, else what is wrong."""
        path = self.chunk_path(chunk_id)
        want = self.manifest.get("chunk_sha256", {}).get(str(chunk_id))
        if want is None:
            return f"{path}: no checksum recorded in {MANIFEST}"
        try:
            got = sha256_file(path)
        except OSError as exc:
            return f"{path}: cannot be read ({exc.strerror or exc})"
        if got != want:
            return f"{path}: content does not match its checksum (SHA-256 {got[:12]}..., recorded {want[:12]}...)"
        return ""

    @classmethod
    def read(cls, root: str | Path) -> CampaignStore:
        """Open an existing campaign directory for reading (report)."""
        return _opened(cls._read, root, "campaign directory")

    @classmethod
    def _read(cls, root: Path) -> CampaignStore:
        if not (root / MANIFEST).is_file():
            raise CampaignError(f"{root}: no {MANIFEST}; not a campaign directory")
        manifest = cls._read_manifest(root)
        store = cls(root, manifest)
        bad = []
        for cid in store._scan():
            if str(cid) not in manifest["chunk_sha256"]:
                continue  # being written right now (its checksum comes first): not finished yet
            if problem := store.verify_chunk(cid):
                bad.append(problem)
            else:
                store._finished.add(cid)
        if bad:
            raise CampaignError(
                f"{root}: {len(bad)} corrupt chunk file(s), refusing to report them: {bad[0]}"
                f"{' (and more)' if len(bad) > 1 else ''}. Run `formation-ftc campaign run` on "
                f"this directory again to recompute them"
            )
        return store

    # ------------------------------------------------------------------------------------- access
    def finished(self) -> set[int]:
        return set(self._finished)

    def chunk_path(self, chunk_id: int) -> Path:
        return self.root / "chunks" / chunk_filename(chunk_id)

    def write_chunk(
        self, chunk_id: int, table: pd.DataFrame, traces: dict[int, Any] | None = None
    ) -> Path:
        """Write the traces, then the chunk's Parquet file (atomically; the chunk then counts as done)."""
        if chunk_id in self._finished:
            raise CampaignError(f"chunk {chunk_id} is already stored in {self.root}")
        for run_id, ds in sorted((traces or {}).items()):
            (self.root / "traces").mkdir(exist_ok=True)
            trace = functools.partial(write_netcdf, self._cf_trace(ds))
            atomic_write(self.root / "traces" / f"run-{run_id:06d}.nc", trace)
        path = self.chunk_path(chunk_id)
        buf = io.BytesIO()
        # metric units come from the runner (``table.attrs["metric_units"]``); inputs: see parquet_units
        units = {**dict.fromkeys(_COUNT_COLUMNS, "1"), **table.attrs.get("metric_units", {})}
        write_parquet(table, buf, units, write_page_checksum=True)
        data = buf.getvalue()
        # the checksum is recorded first: a chunk file never exists without one
        self.manifest["chunk_sha256"][str(chunk_id)] = hashlib.sha256(data).hexdigest()
        self._write_manifest()
        atomic_write(path, data)
        self._finished.add(chunk_id)
        return path

    def _cf_trace(self, ds):
        """A run's trace with the provenance and CF-1.10 metadata of a ``result.nc`` (:mod:`formation_ftc.cf`)."""
        prov = provenance()
        methods = sorted(set(self.manifest.get("plan", {}).get("methods", [])))
        ds = ds.copy()
        ds.attrs = {**prov, **ds.attrs, "method": " or ".join(methods)}
        return apply_cf(
            ds,
            scenario_name=str(ds.attrs.get("scenario_name", "")),
            method=ds.attrs["method"],
            description=f"trace of run {ds.attrs.get('run_id')} of campaign {ds.attrs.get('campaign')!r}",
            created_utc=prov["created_utc"],
            version=prov["version_formation-ftc"],
        )

    def units(self) -> dict[str, str]:
        """Column -> units of the finished chunks (:func:`formation_ftc.parquet_units.read_units`)."""
        out: dict[str, str] = {}
        for cid in sorted(self._finished):
            out.update(read_units(self.chunk_path(cid)))
        return out

    def load_results(self) -> pd.DataFrame:
        """All finished runs, sorted by run id (columns: run_id, seed, status, input:*, metric:*, ...)."""
        frames = []
        for cid in sorted(self._finished):
            path = self.chunk_path(cid)
            try:
                frames.append(pq.read_table(path, page_checksum_verification=True).to_pandas())
            except Exception as exc:  # noqa: BLE001
                raise CampaignError(f"{path}: corrupt chunk file ({exc})") from None
        if not frames:
            return pd.DataFrame(columns=["run_id", "status"])
        df = pd.concat(frames, ignore_index=True)
        return df.sort_values("run_id", kind="stable").reset_index(drop=True)


def _opened(open_: Callable[[Path], CampaignStore], root: str | Path, what: str) -> CampaignStore:
    """``open_(Path(root))``, an OSError or ValueError (not a CampaignError) as "unusable ``what``"."""
    with oserror_as(CampaignError, f"{_short(root)}: unusable {what}", (OSError, ValueError)):
        return open_(Path(root))


def _short(path: str | Path) -> str:
    text = str(path)
    return text if len(text) <= 120 else text[:100] + "..."


def _lock_holder_text(path: Path) -> str:
    """Host, PID and start of the process named in a lock file, or "holder unknown"."""
    try:
        info = json.loads(path.read_text(encoding="utf-8", errors="replace")[:4096])
        return f"host {info.get('host')}, PID {info.get('pid')}, since {info.get('since_utc')}"
    except (OSError, ValueError, AttributeError):
        return "holder unknown"
