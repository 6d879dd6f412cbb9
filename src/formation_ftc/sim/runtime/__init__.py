"""The process runtime: the compilation cache and compiler tuning, switched on by :func:`configure`.

Importing :mod:`formation_ftc` changes one process-wide setting, the one JAX needs for float64
(``JAX_ENABLE_X64``, or ``jax_enable_x64`` when JAX is already imported). Everything here is opt-in:

* :func:`configure` -- what ``formation-ftc`` does for every command that computes, and what a Python
  user may call once at the start of a script -- switches on

  - JAX's persistent compilation cache in :func:`compilation_cache_dir` (``FORMATION_FTC_JAX_CACHE``,
    default ``~/.cache/formation_ftc/jax``, ``off`` to disable; one subdirectory per CPU-client thread
    count); programs that took at least ``JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS`` (default
    :data:`DEFAULT_CACHE_MIN_COMPILE_S`) to compile are kept;
  - the unrolled threefry lowering on the CPU (:func:`.xla.use_unrolled_threefry`: same random bits,
    faster noisy steps).

  It exports :data:`ENV_SWITCH` ``=on`` (and JAX's cache variables), so that worker processes the
  command starts (campaign and league pools, Dask local workers, paper workers) configure themselves
  the same way when they import the package.
* :mod:`.xla` -- the XLA:CPU compile options of the simulation programs (per compilation, never in the
  process-wide ``XLA_FLAGS``); :mod:`.lru` -- the bounded in-memory caches of programs.

**What protects the cache.** A cache entry is machine code that JAX runs when it loads it, and JAX's
entries carry no authentication: whoever can write to the cache directory, or swap it or one of its
parents, chooses the code the process runs and the numbers it prints. So the cache is used only while
every directory from it up to ``/`` is a real directory owned by this user or root and writable by no
one else (:func:`unsafe_directory`, after OpenSSH's ``StrictModes``), checked when :func:`configure`
opens it and again before every compilation that may read or write it (:func:`check_cache`); otherwise
it is off for the process, with one line on stderr naming the directory and the fix. The directories
the runtime creates are created 0700 whatever the umask.

Without :func:`configure` a program is compiled in each process (results are the same bits either way).
This module imports no JAX at import time: the command line answers ``--help`` without it.
"""

from __future__ import annotations

import contextlib
import os
import stat
import sys
from pathlib import Path

__all__ = [
    "configure",
    "configured",
    "compilation_cache_dir",
    "private_cache_dir",
    "check_cache",
    "cpu_threads",
    "schedulable_cpus",
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


#: JAX's monitoring event recorded just before it looks a program up in its persistent cache
_CACHE_READ_EVENT = "/jax/compilation_cache/compile_requests_use_cache"
#: the cache directory :func:`configure` handed to JAX (resolved, checked), None when there is none
_GUARDED: str | None = None
_LISTENING = False
_REPORTED: set[str] = set()


def _make_private(path: Path) -> None:
    """Create the missing directories of ``path``, each with mode 0700 whatever the umask (existing ones
    are left as they are)."""
    for d in reversed((path, *path.parents)):
        if not os.path.lexists(d):
            # made meanwhile by another process: left alone, and checked like any other
            with contextlib.suppress(FileExistsError):
                os.mkdir(d, 0o700)
                os.chmod(d, 0o700)  # mkdir's mode is masked by the umask


def unsafe_directory(path: str | os.PathLike[str], creating: bool = False) -> str | None:
    """Why the directory ``path`` (absolute, links resolved) may not hold a compilation cache, or None
    when it may. As OpenSSH's ``StrictModes`` checks the path of an ``authorized_keys`` file, every
    directory from ``path`` up to ``/`` must be a real directory (``lstat``: not a symbolic link) owned
    by this user or by root and writable by nobody else (no group or world write bit). One exception,
    which OpenSSH does not make: a root-owned sticky directory (``/tmp``, mode 1777) may be an ancestor
    when the directory right below it on the path is this user's and writable by nobody else -- in a
    sticky directory only an entry's owner (or root) may rename or remove it, so no one else can swap it.

    Parameters
    ----------
    path : str or os.PathLike
        The cache directory, absolute and without symbolic links (``os.path.realpath``).
    creating : bool, optional
        ``path`` is the directory in which this user is about to create the cache (mode 0700), so it
        may itself be a root-owned sticky directory such as ``/tmp``.

    Returns
    -------
    str or None
        The offending directory and what is wrong with it, or None.

    Examples
    --------
    >>> import os
    >>> import tempfile
    >>> from formation_ftc.sim.runtime import unsafe_directory
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     tmp = os.path.realpath(tmp)
    ...     os.mkdir(os.path.join(tmp, "cache"), 0o700)
    ...     fine = unsafe_directory(os.path.join(tmp, "cache"))
    ...     os.chmod(tmp, 0o770)  # the parent: its group could swap the cache directory
    ...     refused = unsafe_directory(os.path.join(tmp, "cache"))
    >>> fine, refused == f"{tmp} is writable by its group or by others"
    (None, True)
    """
    uid = os.geteuid()
    p = Path(path)
    if not p.is_absolute():
        return f"{p} is not an absolute path"
    # owner of the directory one level down the path (it passed); creating: the one about to be made
    below: int | None = uid if creating else None
    for d in (p, *p.parents):
        try:
            st = os.lstat(d)
        except OSError as exc:
            return f"{d} cannot be examined ({exc.strerror or exc})"
        if stat.S_ISLNK(st.st_mode):
            return f"{d} is a symbolic link"
        if not stat.S_ISDIR(st.st_mode):
            return f"{d} is not a directory"
        if st.st_uid not in (uid, 0):
            return f"{d} is owned by uid {st.st_uid}, neither by you nor by root"
        sticky_ancestor = st.st_uid == 0 and st.st_mode & stat.S_ISVTX and below == uid
        if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH) and not sticky_ancestor:
            return f"{d} is writable by its group or by others"
        below = st.st_uid
    return None


def _report(problem: str) -> None:
    """One line on stderr (once per problem and process): the cache is off, why, and the fix."""
    if problem in _REPORTED:
        return
    _REPORTED.add(problem)
    chmod = ""
    if problem.endswith(" is writable by its group or by others"):
        chmod = f"chmod go-w {problem.removesuffix(' is writable by its group or by others')}, or "
    with contextlib.suppress(OSError, ValueError, AttributeError):  # a closed or full stderr
        print(
            f"formation-ftc: compilation cache off: {problem} (fix: {chmod}set "
            "FORMATION_FTC_JAX_CACHE to a directory whose every parent is yours or root's and "
            "writable by no one else, or to off)",
            file=sys.stderr,
        )


def private_cache_dir(cache: str) -> str | None:
    """Create the compilation cache directory ``cache`` (missing directories mode 0700, whatever the
    umask), resolve its links once and check the resolved path (:func:`unsafe_directory`). A cached
    executable is machine code that JAX runs when it loads it, so a directory that anyone else could
    write to or swap is not used: the cache stays off, with one line on stderr.

    Parameters
    ----------
    cache : str
        Path of the cache directory.

    Returns
    -------
    str or None
        The resolved directory when it may be used, else None.

    Examples
    --------
    >>> import os
    >>> import tempfile
    >>> from formation_ftc.sim import runtime
    >>> with tempfile.TemporaryDirectory() as tmp:  # created 0700 at every level, owned by this user
    ...     ok = runtime.private_cache_dir(os.path.join(tmp, "a", "jax")) is not None
    ...     modes = [oct(os.stat(os.path.join(tmp, *p)).st_mode & 0o777) for p in (["a"], ["a", "jax"])]
    >>> ok, modes
    (True, ['0o700', '0o700'])
    """
    target = Path(os.path.abspath(cache))
    existing = next(d for d in (target, *target.parents) if os.path.lexists(d))
    # nothing is created under a directory that is already refused (a root-owned sticky directory such
    # as /tmp is not: only this user may rename or remove what it creates there, and the created
    # directory is checked again below)
    problem = unsafe_directory(os.path.realpath(existing), creating=existing != target)
    if problem is None:
        try:
            _make_private(target)
            resolved = os.path.realpath(cache, strict=True)
        except OSError as exc:
            problem = f"{cache} cannot be created ({exc.strerror or exc})"
        else:
            problem = unsafe_directory(resolved)
    if problem is not None:
        _report(problem)
        return None
    return resolved


def check_cache() -> bool:
    """Check again the cache directory :func:`configure` gave JAX (a few ``lstat`` calls) and switch
    the cache off for this process when it no longer passes (:func:`unsafe_directory`; one line on
    stderr). The first call also asks JAX to call this check before every compilation that reads its
    persistent cache (``jax.monitoring``). :func:`formation_ftc.sim.runtime.xla.jit` calls it whenever it
    makes a program.

    Returns
    -------
    bool
        True when a checked cache is in use.

    Examples
    --------
    >>> from formation_ftc.sim import runtime
    >>> cache = runtime.configure()
    >>> runtime.check_cache() == (cache is not None)
    True
    """
    global _LISTENING
    if _GUARDED is None:
        return False
    if not _LISTENING:
        import jax.monitoring

        jax.monitoring.register_event_listener(_before_cache_read)
        _LISTENING = True
    return _guard()


def _guard() -> bool:
    """Whether the guarded cache directory still passes :func:`unsafe_directory`; else switch it off."""
    problem = None if _GUARDED is None else unsafe_directory(_GUARDED)
    if problem is not None:
        _switch_off(problem)
    return _GUARDED is not None


def _before_cache_read(event: str, **_: object) -> None:
    """JAX's event listener: runs the check of :func:`check_cache` before each persistent-cache read."""
    if event == _CACHE_READ_EVENT:
        _guard()


def _switch_off(problem: str) -> None:
    """Stop using the persistent cache in this process and in the processes it starts (one line)."""
    global _GUARDED
    _GUARDED = None
    os.environ["FORMATION_FTC_JAX_CACHE"] = "off"
    os.environ.pop("JAX_COMPILATION_CACHE_DIR", None)
    from formation_ftc import _lazy_jax

    if _lazy_jax.loaded():  # a proxy (JAX not imported yet) reads the environment when it imports
        _set_jax_cache(None)
    _report(problem)


def _set_jax_cache(cache: str | None) -> None:
    """Point an imported JAX at ``cache`` (None: no cache). JAX opens its cache once per process and then
    reads it whatever its configuration says (``jax_compilation_cache_dir = None`` and
    ``jax_enable_compilation_cache = False`` are consulted only before that, jax 0.10.2,
    ``jax/_src/compilation_cache.py``): a change is applied by resetting the opened cache as well, so
    that the next compilation opens the new one, or none."""
    import jax
    from jax.experimental.compilation_cache import compilation_cache

    jax.config.update("jax_enable_compilation_cache", cache is not None)
    jax.config.update("jax_compilation_cache_dir", cache)
    compilation_cache.reset_cache()


def configure() -> str | None:
    """Switch the runtime on for this process and the processes it starts (see the module docstring);
    idempotent. Returns the compilation cache directory in use (None: no persistent cache).

    Returns
    -------
    str or None
        The cache directory (:func:`compilation_cache_dir` with its links resolved), or None.

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
    global _GUARDED
    os.environ[ENV_SWITCH] = "on"
    wanted = compilation_cache_dir()
    _GUARDED = cache = private_cache_dir(wanted) if wanted is not None else None
    if cache is not None:
        # also over one inherited from a parent process
        os.environ["JAX_COMPILATION_CACHE_DIR"] = cache
        os.environ.setdefault(
            "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", DEFAULT_CACHE_MIN_COMPILE_S
        )
    else:  # off, or refused: also when a parent process passed its cache directory down
        os.environ.pop("JAX_COMPILATION_CACHE_DIR", None)
        if wanted is not None:  # refused (one line): the processes this one starts stay quiet
            os.environ["FORMATION_FTC_JAX_CACHE"] = "off"
    from formation_ftc import _lazy_jax

    if _lazy_jax.loaded():  # JAX read its configuration already: set it directly (a proxy: not yet)
        _configure_jax(cache)
    return cache


def _configure_jax(cache: str | None) -> None:
    """Apply :func:`configure` to an imported JAX (the cache options and the threefry lowering)."""
    import jax

    from formation_ftc.sim.runtime.xla import use_unrolled_threefry

    # (dynamic options: not in the stubs)
    if getattr(jax.config, "jax_compilation_cache_dir", None) != cache or (
        cache is not None and not getattr(jax.config, "jax_enable_compilation_cache", True)
    ):
        _set_jax_cache(cache)
    if cache is not None:
        min_s = float(os.environ["JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"])  # set by configure
        jax.config.update("jax_persistent_cache_min_compile_time_secs", min_s)
        check_cache()
    use_unrolled_threefry()
