"""Output directory of ``formation-ftc run``: checked before the run, written atomically after it.

* :func:`check_out_dir` -- refuse, before anything is computed, an empty path, a path that is a file or
  a device (``/dev/null``), a directory that cannot be written, and an existing non-empty directory
  that is not a previous ``run`` result (unless ``force``);
* :func:`staged_output` -- the result, metrics and figures are written into a temporary sibling
  directory ``.NAME.tmp-PID`` which then replaces ``DIR`` by renames, so ``DIR`` always holds one whole
  run (the new one, or the previous one when anything failed); a marker file lists what a run wrote;
  on a full disk (:data:`DISK_FULL`) the staging directory is removed and an ``OSError`` naming ``DIR``
  is raised (exit status 3 with one line, :func:`formation_ftc.exitcodes.run_guarded`);
* :func:`plot_view` -- above :data:`MAX_PLOT_SPACECRAFT` spacecraft the figures show an evenly spaced
  subset (``result.nc`` keeps every spacecraft).
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import re
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from formation_ftc.atomic import atomic_write
from formation_ftc.errors import InputError

__all__ = [
    "OutputError",
    "DISK_FULL",
    "MARKER",
    "MAX_PLOT_SPACECRAFT",
    "check_out_dir",
    "staged_output",
    "plot_view",
    "is_run_result",
    "add_to_marker",
    "TMP_RE",
    "oserror_as",
    "existing_dir",
]

#: ``errno`` values of a write that found no space: the disk is full, or the user's quota is used up
DISK_FULL = frozenset({errno.ENOSPC, errno.EDQUOT})
#: file in a run directory listing what the run wrote (so a rerun may replace exactly that)
MARKER = ".formation-ftc-run.json"
#: most spacecraft drawn one line each in the figures of ``run`` [-]
MAX_PLOT_SPACECRAFT = 16
#: a temporary file of an atomic write (``.NAME.tmp-PID``, :func:`formation_ftc.atomic.temporary_name`)
TMP_RE = re.compile(r"^\..+\.tmp-\d+$")


def _plot_limit() -> int:
    """MAX_PLOT_SPACECRAFT, or ``$FORMATION_FTC_MAX_PLOT_SPACECRAFT`` when it is a positive integer."""
    text = os.environ.get("FORMATION_FTC_MAX_PLOT_SPACECRAFT", "").strip()
    if not text:
        return MAX_PLOT_SPACECRAFT
    if not text.isdigit() or int(text) < 1:
        raise OutputError(
            f"FORMATION_FTC_MAX_PLOT_SPACECRAFT={text!r}: expected a positive integer"
        )
    return int(text)


_RESULT_SUFFIXES = {".nc", ".json", ".png", ".svg", ".pdf", ".html"}


class OutputError(InputError):
    """An output path that cannot or must not be written."""


def is_run_result(d: Path) -> bool:
    """Whether directory ``d`` holds only what a previous ``formation-ftc run`` wrote."""
    entries = {e.name for e in d.iterdir()}
    marker = d / MARKER
    if marker.is_file():
        try:
            written = set(json.loads(marker.read_text(encoding="utf-8")).get("files", []))
        except (OSError, ValueError, AttributeError):
            return False
        return entries <= written | {MARKER}
    # a result written before the marker existed: result.nc + metrics.json and figures only
    return {"result.nc", "metrics.json"} <= entries and all(
        (d / e).is_file() and Path(e).suffix in _RESULT_SUFFIXES for e in entries
    )


@contextlib.contextmanager
def oserror_as(error: type[InputError], message: str, catch: Any = OSError) -> Iterator[None]:
    """An OSError (or what ``catch``, exception classes, names) inside raised as ``error`` (exit code
    2): ``message`` and the system's reason; an ``error`` passes as it is.

    Examples
    --------
    >>> with oserror_as(OutputError, "--out x: unusable path"):
    ...     open("/nonexistent-dir/x")
    Traceback (most recent call last):
    ...
    formation_ftc.runout.OutputError: --out x: unusable path (No such file or directory)
    """
    try:
        yield
    except catch as exc:
        if isinstance(exc, error):
            raise
        raise error(f"{message} ({getattr(exc, 'strerror', None) or exc})") from None


def existing_dir(out: Path, what: str, error: type[InputError], advice: str) -> bool:
    """Whether ``out`` exists; one that is not a directory (a file, a device, a socket, a broken link)
    is refused with ``error``: ``what: exists and is a file; advice``.

    Examples
    --------
    >>> existing_dir(Path("/nonexistent-dir"), "--out x", OutputError, "give a directory")
    False
    """
    if not (out.exists() or out.is_symlink()):
        return False
    if not out.is_dir():
        kind = "a file" if out.is_file() else "not a directory (a device, socket or broken link)"
        raise error(f"{what}: exists and is {kind}; {advice}")
    return True


def check_out_dir(out: str | os.PathLike, force: bool = False) -> Path:
    """Validate ``--out`` before any computation; returns the path. Raises :class:`OutputError`."""
    from formation_ftc.config.loader import short_text

    text = os.fspath(out)
    with oserror_as(OutputError, f"--out {short_text(text)}: unusable path", (OSError, ValueError)):
        _plot_limit()  # a bad FORMATION_FTC_MAX_PLOT_SPACECRAFT is reported before the run, not after
        if not text.strip():
            raise OutputError("--out: empty path; give the output directory, e.g. --out out/run1")
        if "\x00" in text:
            raise OutputError(f"--out {text!r}: NUL character in the path")
        d = Path(text)
        if d.is_symlink() and d.is_dir():
            d = d.resolve()  # write where the link points; the link itself stays
        if existing_dir(d, f"--out {text}", OutputError, "give a directory"):
            with oserror_as(OutputError, f"--out {text}: cannot be read"):
                entries = list(d.iterdir())
            if entries and not force and not is_run_result(d):
                raise OutputError(
                    f"--out {text}: is not empty and is not the result of an earlier `formation-ftc "
                    f"run` (it holds e.g. {sorted(e.name for e in entries)[:3]}); use another "
                    f"directory, or --force to replace its content"
                )
        # the nearest existing ancestor must be a writable directory (the staging sibling goes there)
        anc = next(p for p in d.absolute().parents if p.exists())
        if not anc.is_dir():
            raise OutputError(f"--out {text}: {anc} is not a directory")
        probe = anc / f".formation-ftc-probe-{os.getpid()}"
        with _creating(d, f"--out {text}: cannot write in {anc}", "; choose a writable directory"):
            probe.mkdir()
            probe.rmdir()
        return d


@contextlib.contextmanager
def _creating(out_dir: Path, message: str, advice: str = "") -> Iterator[None]:
    """An OSError inside raised as the one of a full disk naming ``out_dir`` (:func:`_no_space`), or else
    as an :class:`OutputError`: ``message``, the system's reason in parentheses, ``advice``."""
    try:
        yield
    except OSError as exc:
        if exc.errno in DISK_FULL:
            raise _no_space(exc, out_dir) from None
        raise OutputError(f"{message} ({exc.strerror or exc}){advice}") from None


def _no_space(exc: OSError, out_dir: Path) -> OSError:
    """The ``OSError`` of a full disk, naming ``out_dir`` and what it holds now."""
    kept = "it keeps its earlier result" if out_dir.exists() else "nothing was written"
    return OSError(exc.errno, kept, str(out_dir))


@contextlib.contextmanager
def staged_output(out_dir: Path) -> Iterator[Path]:
    """Yield a fresh temporary sibling of ``out_dir``; on success it replaces ``out_dir`` (renames),
    on any exception it is removed and ``out_dir`` is left untouched. A write that finds the disk full
    (:data:`DISK_FULL`) raises an ``OSError`` whose ``filename`` is ``out_dir``."""
    out_dir = Path(out_dir)
    parent = out_dir.absolute().parent
    stage = parent / f".{out_dir.name}.tmp-{os.getpid()}"
    with _creating(out_dir, f"--out {out_dir}: cannot create a directory in {parent}"):
        parent.mkdir(parents=True, exist_ok=True)
        if stage.exists():
            shutil.rmtree(stage)
        stage.mkdir()
    try:
        yield stage
        files = sorted(p.relative_to(stage).as_posix() for p in stage.rglob("*") if p.is_file())
        (stage / MARKER).write_text(json.dumps({"files": files}, indent=1), encoding="utf-8")
        _swap_into_place(stage, out_dir)
    except BaseException as exc:
        shutil.rmtree(stage, ignore_errors=True)
        if isinstance(exc, OSError) and exc.errno in DISK_FULL:
            raise _no_space(exc, out_dir) from None
        raise


def add_to_marker(d: Path, names: list[str]) -> None:
    """Add ``names`` (files written into the run directory ``d`` later, by ``formation-ftc plot``) to
    its marker, so that a later ``run --out d`` may replace them; nothing when ``d`` has no marker."""
    marker = Path(d) / MARKER
    try:
        files = json.loads(marker.read_text(encoding="utf-8")).get("files", [])
    except (OSError, ValueError, AttributeError):
        return
    atomic_write(marker, json.dumps({"files": sorted({*files, *names})}, indent=1))


def _swap_into_place(stage: Path, out_dir: Path) -> None:
    old = None
    if out_dir.exists():
        old = out_dir.with_name(f".{out_dir.name}.old-{os.getpid()}")
        if old.exists():
            shutil.rmtree(old)
        os.replace(out_dir, old)
    try:
        os.replace(stage, out_dir)
    except BaseException:
        if old is not None:
            os.replace(old, out_dir)  # put the previous result back
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def plot_view(ds: Any, max_spacecraft: int | None = None) -> tuple[Any, str]:
    """``ds`` reduced to at most ``max_spacecraft`` evenly spaced spacecraft for plotting, and a note
    ("" when nothing was dropped)."""
    import numpy as np

    limit = _plot_limit() if max_spacecraft is None else max_spacecraft
    n = int(ds.sizes.get("spacecraft", 0)) if hasattr(ds, "sizes") else 0
    if limit <= 0 or n <= limit:
        return ds, ""
    keep = np.unique(np.linspace(0, n - 1, limit).round().astype(int))
    return ds.isel(spacecraft=keep), (
        f"figures show {len(keep)} of {n} spacecraft (evenly spaced); result.nc holds all of them"
    )
