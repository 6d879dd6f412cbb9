"""The process runtime: compilation caches and compiler tuning, switched on by :func:`configure`.

Importing :mod:`formation_ftc` changes one process-wide setting, the one JAX needs for float64
(``JAX_ENABLE_X64``, or ``jax_enable_x64`` when JAX is already imported). Everything here is opt-in:

* :func:`configure` -- what ``formation-ftc`` does for every command that computes, and what a Python
  user may call once at the start of a script -- switches on

  - JAX's persistent compilation cache in :func:`compilation_cache_dir` (``FORMATION_FTC_JAX_CACHE``,
    default ``~/.cache/formation_ftc/jax``, ``off`` to disable; one subdirectory per CPU-client thread
    count), used only while it is this user's alone (:func:`private_cache_dir`); programs that took at
    least ``JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS`` (default :data:`DEFAULT_CACHE_MIN_COMPILE_S`)
    to compile are kept;
  - the on-disk program cache beside it (:mod:`.program_cache`: a warm process neither traces nor
    lowers a closed loop it ran before);
  - the unrolled threefry lowering on the CPU (:func:`.xla.use_unrolled_threefry`: same random bits,
    faster noisy steps).

  It exports :data:`ENV_SWITCH` ``=on`` (and JAX's cache variables), so that worker processes the
  command starts (campaign and league pools, Dask local workers, paper workers) configure themselves
  the same way when they import the package.
* :mod:`.xla` -- the XLA:CPU compile options of the simulation programs (per compilation, never in the
  process-wide ``XLA_FLAGS``); :mod:`.lru` -- the bounded in-memory caches of programs.

Without :func:`configure` a program is compiled in each process (results are the same bits either way).
This module imports no JAX at import time: the command line answers ``--help`` without it.
"""

from __future__ import annotations

import os
import stat
import sys
from pathlib import Path

__all__ = [
    "configure",
    "configured",
    "compilation_cache_dir",
    "private_cache_dir",
    "cpu_threads",
    "schedulable_cpus",
    "owned_and_private",
    "unsafe_directory",
    "ENV_SWITCH",
    "DEFAULT_CACHE_MIN_COMPILE_S",
]

#: set to ``on`` by :func:`configure` (and so inherited by the processes it starts); a process whose
#: environment has it configures itself when it imports the package
ENV_SWITCH = "FORMATION_FTC_RUNTIME"

#: the persistent cache keeps programs that took at least this long [s] to compile (JAX's default is 1 s):
#: every simulation program (0.4-2.6 s) but not the eager operations (< 0.05 s), so that a second
#: ``reproduce all`` loads what the first compiled (warm compile phases 16.4 -> 12.8 s, 1 s -> 0.2 s)
DEFAULT_CACHE_MIN_COMPILE_S = "0.2"


def schedulable_cpus() -> int:
    """CPUs this process may run on (its affinity mask; the CPU count where there is none).

    Returns
    -------
    int
        Number of CPUs (>= 1).

    Examples
    --------
    >>> from formation_ftc.sim import runtime
    >>> runtime.schedulable_cpus() >= 1
    True
    """
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def cpu_threads() -> int:
    """Threads of JAX's CPU client in this process: ``PJRT_NPROC`` when set (JAX reads it when the client
    starts), else JAX's default, one per CPU this process may run on.

    Returns
    -------
    int
        Thread count (>= 1).

    Examples
    --------
    >>> import os
    >>> from unittest import mock
    >>> from formation_ftc.sim import runtime
    >>> with mock.patch.dict(os.environ, {"PJRT_NPROC": "3"}):
    ...     runtime.cpu_threads()
    3
    >>> with mock.patch.dict(os.environ, {"PJRT_NPROC": ""}):
    ...     runtime.cpu_threads() == runtime.schedulable_cpus()
    True
    """
    value = os.environ.get("PJRT_NPROC", "").strip()
    if value.isdigit() and int(value) > 0:
        return int(value)
    return schedulable_cpus()


def configured() -> bool:
    """Whether :func:`configure` ran in this process or in the process that started it.

    Returns
    -------
    bool
        True when :data:`ENV_SWITCH` is ``on`` in the environment.

    Examples
    --------
    >>> import os
    >>> from unittest import mock
    >>> from formation_ftc.sim import runtime
    >>> with mock.patch.dict(os.environ, {runtime.ENV_SWITCH: "on"}):
    ...     runtime.configured()
    True
    >>> with mock.patch.dict(os.environ, {runtime.ENV_SWITCH: ""}):
    ...     runtime.configured()
    False
    """
    return os.environ.get(ENV_SWITCH, "").strip().lower() == "on"


def compilation_cache_dir() -> str | None:
    """The persistent compilation cache directory :func:`configure` uses (None: off).

    ``FORMATION_FTC_JAX_CACHE`` (default ``~/.cache/formation_ftc/jax``; ``off`` disables it), one
    subdirectory per CPU-client thread count: XLA partitions some loops by the thread count when it
    compiles, so a program compiled with 2 threads can round differently from the same program compiled
    with 1, and JAX's cache key does not record the count. Keyed this way, a process never loads a
    program compiled for another thread count (another machine sharing the home directory, or
    ``PJRT_NPROC`` set differently).

    Returns
    -------
    str or None
        The directory, or None when the cache is off.

    Examples
    --------
    >>> import os
    >>> from unittest import mock
    >>> from formation_ftc.sim import runtime
    >>> with mock.patch.dict(os.environ, {"FORMATION_FTC_JAX_CACHE": "/scratch/jax", "PJRT_NPROC": "2"}):
    ...     runtime.compilation_cache_dir()
    '/scratch/jax/cpu-threads-2'
    >>> with mock.patch.dict(os.environ, {"FORMATION_FTC_JAX_CACHE": "off"}):
    ...     print(runtime.compilation_cache_dir())
    None
    """
    cache = os.environ.get(
        "FORMATION_FTC_JAX_CACHE", str(Path.home() / ".cache" / "formation_ftc" / "jax")
    )
    if not cache or cache.lower() == "off":
        return None
    return str(Path(cache) / f"cpu-threads-{cpu_threads()}")


_UNSAFE_REPORTED: set[str] = set()


def private_cache_dir(cache: str) -> bool:
    """Create the compilation cache ``cache`` (new directories mode 0700) and check that it and its parent
    are real directories owned by this user and writable by nobody else. A cached executable is machine
    code that JAX runs when it loads it, so a directory that another user could write to is not used
    (the cache stays off, with one line on stderr).

    Parameters
    ----------
    cache : str
        Path of the cache directory.

    Returns
    -------
    bool
        True when the directory may be used.

    Examples
    --------
    >>> import os
    >>> import tempfile
    >>> from formation_ftc.sim import runtime
    >>> with tempfile.TemporaryDirectory() as tmp:  # created 0700, owned by this user
    ...     ok = runtime.private_cache_dir(os.path.join(tmp, "jax"))
    ...     mode = oct(os.stat(os.path.join(tmp, "jax")).st_mode & 0o777)
    >>> ok, mode
    (True, '0o700')
    """
    unsafe = unsafe_directory(Path(cache))
    if unsafe is not None and cache not in _UNSAFE_REPORTED:
        _UNSAFE_REPORTED.add(cache)
        try:
            print(
                f"formation-ftc: compilation cache off: {unsafe} is not a directory owned by this user "
                "and writable by it alone (set FORMATION_FTC_JAX_CACHE to a directory of your own, or to off)",
                file=sys.stderr,
            )
        except (OSError, ValueError):  # a closed or full stderr
            pass
    return unsafe is None


def owned_and_private(st: os.stat_result) -> bool:
    """Whether a file or directory (its ``os.lstat``) is owned by this process's effective user and
    writable by nobody else (no group or world write bit): what a cache may trust.

    Parameters
    ----------
    st : os.stat_result
        The file's or directory's status (``os.lstat``, ``os.fstat``).

    Returns
    -------
    bool
        True when this user owns it and nobody else may write it.

    Examples
    --------
    >>> import os
    >>> import tempfile
    >>> from formation_ftc.sim.runtime import owned_and_private
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     mine = owned_and_private(os.lstat(tmp))
    ...     os.chmod(tmp, 0o777)
    ...     shared = owned_and_private(os.lstat(tmp))
    >>> mine, shared
    (True, False)
    """
    return st.st_uid == os.geteuid() and not st.st_mode & (stat.S_IWGRP | stat.S_IWOTH)


def unsafe_directory(path: Path) -> Path | str | None:
    """Create ``path`` (new directories mode 0700) and check it and its parent: real directories (not
    links) that :func:`owned_and_private` trusts. Returns None when both pass, else the first one that
    does not (or the error's text when they cannot be created or read).

    Parameters
    ----------
    path : Path
        The directory to create and check.

    Returns
    -------
    Path, str or None
        None when ``path`` and its parent may be trusted; else the first directory that may not, or the
        text of the error that kept them from being created or read.

    Examples
    --------
    >>> import os
    >>> import tempfile
    >>> from pathlib import Path
    >>> from formation_ftc.sim.runtime import unsafe_directory
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     fine = unsafe_directory(Path(tmp) / "cache")
    ...     os.chmod(tmp, 0o777)  # the parent: anyone could swap the cache directory
    ...     refused = unsafe_directory(Path(tmp) / "cache") == Path(tmp)
    >>> fine, refused
    (None, True)
    """
    try:
        path.mkdir(mode=0o700, parents=True, exist_ok=True)
        for p in (path.parent, path):
            st = os.lstat(p)
            if not stat.S_ISDIR(st.st_mode) or not owned_and_private(st):
                return p
    except OSError as exc:  # cannot be created or read
        return str(exc)
    return None


def configure() -> str | None:
    """Switch the runtime on for this process and the processes it starts (see the module docstring);
    idempotent. Returns the compilation cache directory in use (None: no persistent cache).

    Returns
    -------
    str or None
        The cache directory (see :func:`compilation_cache_dir`), or None.

    Examples
    --------
    Idempotent: a second call in a configured process (as here) changes nothing.

    >>> from formation_ftc.sim import runtime
    >>> cache = runtime.configure()
    >>> runtime.configured()
    True
    >>> cache is None or cache.endswith(f"cpu-threads-{runtime.cpu_threads()}")
    True
    """
    os.environ[ENV_SWITCH] = "on"
    cache = compilation_cache_dir()
    if cache is not None and private_cache_dir(cache):
        # also over one inherited from a parent process
        os.environ["JAX_COMPILATION_CACHE_DIR"] = cache
        os.environ.setdefault(
            "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", DEFAULT_CACHE_MIN_COMPILE_S
        )
    else:  # off, or not private: also when a parent process passed its cache directory down
        cache = None
        os.environ.pop("JAX_COMPILATION_CACHE_DIR", None)
    from formation_ftc import _lazy_jax

    if _lazy_jax.loaded():  # JAX read its configuration already: set it directly (a proxy: not yet)
        _configure_jax(cache)
    return cache


def _configure_jax(cache: str | None) -> None:
    """Apply :func:`configure` to an imported JAX (the cache options and the threefry lowering)."""
    import jax

    from formation_ftc.sim.runtime.xla import use_unrolled_threefry

    jax.config.update("jax_compilation_cache_dir", cache)
    if cache is not None:
        min_s = os.environ.get(
            "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", DEFAULT_CACHE_MIN_COMPILE_S
        )
        jax.config.update("jax_persistent_cache_min_compile_time_secs", float(min_s))
    use_unrolled_threefry()
