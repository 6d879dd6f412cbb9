"""Compiled simulation programs kept on disk under a key known before tracing.

JAX's persistent compilation cache (on by default, :mod:`formation_ftc._jax`) saves XLA's compile,
but it finds a program by a hash of the lowered module: every process still traces the closed loop
and lowers it before it can look the executable up. For a closed loop that costs 0.1-0.5 s per program
(the batched Mehrabian programs 0.4-0.6 s), and it is most of what a warm ``reproduce`` spends in its
compile phase. This module keys a program by what determines it *before* tracing and keeps its
serialized executable (``jax.experimental.serialize_executable``) in ``programs/`` beside JAX's cache:

* the program: its kind (a single run, a batch, a grid) and the compiled scenario's ``static_key`` --
  the tree definition of the closed loop with every static field (components, metrics, step counts,
  fold block) and the shape and dtype of every leaf (:func:`formation_ftc.sim.components.structure_key`);
* the arguments: tree definition, shape, dtype and weak type of every leaf;
* the code that traces it: a digest of every ``.py`` file of the installed ``formation_ftc`` package;
  an object of a class (or a function) defined outside the package and the libraries it builds on (a
  plugin component) makes the program *not* cacheable here -- its code is not in the digest -- and it
  is traced as before;
* everything else the trace or the executable depends on: Python, JAX, jaxlib and numpy versions, every
  JAX configuration value and the thread-local ones in force (``jax.default_matmul_precision(...)``
  blocks), the backend and its devices, the CPU's feature flags, ``XLA_FLAGS``,
  ``PJRT_NPROC`` (also in the directory name of the cache) and the package's compile-option switch
  (:data:`formation_ftc.sim.runtime.xla.ENV_SWITCH`).

What is stored: an executable XLA compiled in this process (zlib-compressed), and only when every
custom call in it is a LAPACK call (``jnp.linalg.solve``), whose bindings are initialised before any
load -- JAX initialises them while it lowers a program that uses them, and a process that loads such a
program without lowering one would call a null pointer. Not stored: an executable JAX loaded from its
own persistent cache, since XLA:CPU (jaxlib 0.10.2) serializes such an executable without its compiled
kernels; that program is stored the next time XLA compiles it (a cold cache, a new JAX, a changed
program).

Safety. Loading an executable runs its machine code, so an entry is trusted only when this user wrote
it: ``programs/`` is created with mode 0700 and is used only while it and its parent are real
directories owned by this user and writable by nobody else (otherwise the cache is off, with one
:class:`UnsafeCacheWarning`); entries are written 0600, atomically, as ``MAGIC | key | tag | body``,
where the tag is an HMAC-SHA256 over the key and the body with a per-user secret (``programs/hmac-key``,
32 random bytes, 0600). A file that is a link, not owned by this user, writable by others, fails its
tag, or carries another program's key (an entry copied under another name) is removed without being
interpreted. The body holds no pickle of the package's: the argument tree is rebuilt from the call's
arguments, the result tree is stored as JSON (built-in containers and the package's named tuples; a
program whose result tree has other classes is not stored), and the executable is JAX's serialized form. An entry that loads but fails on
its first call -- whatever the error -- is removed and the program compiled afresh.

A key that cannot be formed, an entry that cannot be read and a write that fails all fall back to the
ordinary ``jax.jit`` path (trace, lower, compile or load from JAX's cache); an unreadable entry is
removed. A loaded executable is the one that was compiled, so its results are bit for bit those of a
program traced in this process (``tests/sim/runtime/test_program_cache.py`` compares two processes).

A process that replaces package functions at run time (``monkeypatch``, a debugger) changes what a
trace would produce without changing the source digest: switch the cache off there.
``FORMATION_FTC_PROGRAM_CACHE=off`` does; it is also off when JAX's persistent cache is
(``FORMATION_FTC_JAX_CACHE=off``). Measured on 2 cores (docs/performance.md): warm ``reproduce
mehrabian`` compile phase 5.4 -> 1.8 s.
"""

from __future__ import annotations

import functools
import hashlib
import hmac
import io
import json
import os
import pickle
import platform
import re
import secrets
import stat
import sys
import threading
import types
import warnings
import zlib
from collections.abc import Callable, Hashable
from pathlib import Path
from typing import Any

import jax
import numpy as np

from formation_ftc.sim.runtime import owned_and_private, unsafe_directory

__all__ = [
    "ENV_SWITCH",
    "CachedProgram",
    "UnsafeCacheWarning",
    "directory",
    "program_key",
    "load_or_compile",
]

#: environment variable that switches the program cache off (``off``, ``0``, ``false`` or ``no``)
ENV_SWITCH = "FORMATION_FTC_PROGRAM_CACHE"
#: layout of an entry; raised when it changes, so that old entries are never read
FORMAT = 2

#: top-level modules whose classes and functions may appear in a key: the package (whose code is in the
#: digest), the standard library pieces dataclasses and pytrees are made of, and the numeric libraries
#: (whose versions are in the key)
_TRUSTED_ROOTS = frozenset(
    {
        "formation_ftc",
        "builtins",
        "numpy",
        "jax",
        "jaxlib",
        "collections",
        "functools",
        "operator",
        "_operator",
        "enum",
        "copyreg",
        "typing",
        "dataclasses",
        "types",
        "math",
        "fractions",
        "decimal",
        "_collections",
        "datetime",
        "pathlib",
    }
)


class Uncacheable(Exception):
    """A program whose key would not determine it (code from outside the package, an unpicklable part)."""


def _enabled() -> bool:
    return os.environ.get(ENV_SWITCH, "").strip().lower() not in {"off", "0", "false", "no"}


def directory() -> Path | None:
    """Where entries are kept: ``programs/`` inside JAX's persistent compilation cache directory of this
    process, or None when either cache is off.

    Returns
    -------
    pathlib.Path or None
        The folder, or None.

    Examples
    --------
    >>> import os
    >>> from unittest import mock
    >>> from formation_ftc.sim.runtime import program_cache
    >>> with mock.patch.dict(os.environ, {program_cache.ENV_SWITCH: "off"}):
    ...     print(program_cache.directory())
    None
    """
    if not _enabled():
        return None
    # a dynamic option: not in the stubs
    base = getattr(jax.config, "jax_compilation_cache_dir", None)
    return Path(base) / "programs" if base else None


class _KeyPickler(pickle.Pickler):
    """A pickler that refuses objects whose class (or which, as a function or class) comes from a module
    outside :data:`_TRUSTED_ROOTS`."""

    def reducer_override(self, obj: Any) -> Any:
        if isinstance(obj, type | types.FunctionType | types.BuiltinFunctionType):
            module = getattr(obj, "__module__", None) or ""
        else:
            module = type(obj).__module__ or ""
        if module.split(".")[0] not in _TRUSTED_ROOTS:
            raise Uncacheable(
                f"{module}.{getattr(obj, '__qualname__', type(obj).__qualname__)} is defined "
                "outside formation_ftc"
            )
        return NotImplemented


def _dumps(obj: Any) -> bytes:
    buf = io.BytesIO()
    pickler = _KeyPickler(buf, protocol=5)
    # no memo: equal objects give equal bytes whether or not they are the same object in this process
    # (a shared shape tuple would otherwise be written once and referenced, and the key would differ)
    pickler.fast = True
    try:
        pickler.dump(obj)
    except Uncacheable:
        raise
    except Exception as exc:  # a lambda, a local class, an open handle: no stable name to key by
        raise Uncacheable(f"{type(exc).__name__}: {exc}") from exc
    return buf.getvalue()


_DIGEST: dict[tuple, str] = {}


def _source_digest() -> str:
    """SHA-256 over the relative path and bytes of every ``.py`` file of the installed package; read
    again when a file's size or modification time changed (an editable install being edited)."""
    root = Path(__file__).resolve().parents[2]  # the formation_ftc package
    paths = sorted(root.rglob("*.py"))
    stamp = tuple((str(p), st.st_size, st.st_mtime_ns) for p in paths for st in (p.stat(),))
    digest = _DIGEST.get(stamp)
    if digest is None:
        h = hashlib.sha256()
        for path in paths:
            h.update(str(path.relative_to(root)).encode())
            h.update(b"\0")
            h.update(path.read_bytes())
            h.update(b"\0")
        digest = h.hexdigest()
        _DIGEST.clear()
        _DIGEST[stamp] = digest
    return digest


@functools.cache
def _cpu_flags() -> str:
    """The CPU's feature flags (Linux ``/proc/cpuinfo``), else the processor name: an executable is
    machine code for the CPU that compiled it."""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith(("flags", "Features")):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _trace_context() -> tuple:
    """The thread-local JAX settings a trace depends on (what ``jax.jit`` keys its own cache by:
    ``with jax.default_matmul_precision(...)`` and the like, which :data:`jax.config.values` does not
    show). JAX's internal API; without it nothing is keyed. An object that prints its address (the
    axis environment, empty outside ``vmap``) counts by its type."""
    try:
        from jax._src import config as jax_config

        values = jax_config.trace_context()
    except Exception as exc:  # noqa: BLE001 - another JAX layout
        raise Uncacheable(f"JAX's trace context is not readable: {exc}") from exc
    return tuple(type(v).__qualname__ if " at 0x" in repr(v) else repr(v) for v in values)


def _environment() -> tuple:
    """What, besides the program, decides the trace and the executable (see the module docstring)."""
    import jaxlib

    from formation_ftc.sim.runtime import xla

    devices = jax.devices()
    return (
        FORMAT,
        sys.version,
        jax.__version__,
        jaxlib.__version__,
        np.__version__,
        platform.machine(),
        _cpu_flags(),
        jax.default_backend(),
        tuple(d.device_kind for d in devices),
        len(devices),
        tuple(sorted((k, repr(v)) for k, v in jax.config.values.items())),
        _trace_context(),
        os.environ.get("XLA_FLAGS", ""),
        os.environ.get("PJRT_NPROC", ""),
        os.environ.get(xla.ENV_SWITCH, ""),
        _source_digest(),
    )


def _signature(args: tuple) -> tuple:
    """Tree definition and (shape, dtype, weak type) of every leaf of ``args``: what a jitted function
    retraces on."""
    leaves, treedef = jax.tree_util.tree_flatten(args)
    avals = []
    for x in leaves:
        aval = jax.api_util.shaped_abstractify(x)
        avals.append((tuple(aval.shape), str(aval.dtype), bool(getattr(aval, "weak_type", False))))
    return treedef, tuple(avals)


def program_key(kind: str, parts: Hashable, args: tuple) -> str | None:
    """Hex digest naming the program ``kind``/``parts`` applied to ``args``, or None when it cannot be
    keyed safely (:class:`Uncacheable`).

    Parameters
    ----------
    kind : str
        Kind of program (``"run"``, ``"batch"``, ``"grid"``, ...).
    parts : hashable
        What names the program within its kind (e.g. the compiled scenario's ``static_key``).
    args : tuple
        The call's arguments.

    Returns
    -------
    str or None
        64 hexadecimal digits (SHA-256), or None.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.sim.runtime.program_cache import program_key
    >>> key = program_key("doc-example", ("double", 1), (np.arange(3.0),))
    >>> len(key), key == program_key("doc-example", ("double", 1), (np.ones(3),))  # same shapes
    (64, True)
    >>> key == program_key("doc-example", ("double", 1), (np.arange(4.0),))
    False
    """
    try:
        payload = _dumps((kind, parts, _signature(args), _environment()))
    except Exception:  # noqa: BLE001 - Uncacheable, or an environment that cannot be read: no key
        return None
    return hashlib.sha256(payload).hexdigest()


#: custom calls a stored program may contain: LAPACK (``jnp.linalg.solve`` / ``inv``: ``getrf``,
#: ``trsm``), whose library pointers :func:`_prepare_custom_calls` initialises before a load. JAX sets
#: them up while it lowers a program that uses them; a process that loads such a program without
#: lowering one calls a null pointer (a crash, measured with jaxlib 0.10.2). A program with any other
#: custom call is not stored.
_CUSTOM_CALL_PREFIXES = ("lapack_",)
_CUSTOM_CALL = re.compile(r'custom_call_target="([^"]+)"')


@functools.cache
def _prepare_custom_calls() -> bool:
    """Initialise the LAPACK bindings of jaxlib's CPU custom calls (what lowering a solve does first);
    False when this jaxlib lacks the entry point (then nothing is loaded or stored)."""
    try:
        from jaxlib import lapack

        lapack.prepare_lapack_call("getrf", np.float64)
    except Exception:  # noqa: BLE001 - another jaxlib layout: the program cache stays unused
        return False
    return True


def _storable(exe: Any) -> bool:
    """Whether every custom call of ``exe`` is one :func:`_prepare_custom_calls` prepares."""
    try:
        text = exe.as_text()
    except Exception:  # noqa: BLE001 - no HLO text: cannot check, do not store
        return False
    return all(t.startswith(_CUSTOM_CALL_PREFIXES) for t in _CUSTOM_CALL.findall(text or ""))


#: the first bytes of an entry: a name and the layout (:data:`FORMAT`)
MAGIC = b"formation-ftc program cache\x00" + bytes([FORMAT])
_KEY_LEN = 64  # hex SHA-256 of the program key
_TAG_LEN = 32  # HMAC-SHA256
_SECRET_FILE = "hmac-key"
_SECRET_LEN = 32


_WARNED: set[str] = set()


def _warn_once(message: str) -> None:
    if message not in _WARNED:
        _WARNED.add(message)
        warnings.warn(message, UnsafeCacheWarning, stacklevel=3)


class UnsafeCacheWarning(UserWarning):
    """The program cache's directory or key file is not this user's alone: the cache is not used."""


def _safe_folder(folder: Path) -> bool:
    """Create ``folder`` (mode 0700) and check it and its parent (:func:`~formation_ftc.sim.runtime.unsafe_directory`).
    A folder that fails is never read, written or cleaned."""
    unsafe = unsafe_directory(folder)
    if unsafe is not None:
        if isinstance(unsafe, Path):
            _warn_once(
                f"program cache off: {unsafe} is not a directory owned by this user and writable by "
                "it alone (delete it, or set FORMATION_FTC_JAX_CACHE to a directory of your own)"
            )
        return False
    try:
        if stat.S_IMODE(os.lstat(folder).st_mode) != 0o700:
            # ours and private: an entry directory of an earlier version (0755)
            os.chmod(folder, 0o700)
    except OSError:
        return False
    return True


def _read_private(path: Path, size: int | None = None, *, secret: bool = False) -> bytes | None:
    """The bytes of ``path`` if it is a regular file (not a link) owned by this user and writable by it
    alone -- with ``secret``, also readable by it alone -- (and, with ``size``, exactly that long);
    else None."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
    except OSError:
        return None
    try:
        st = os.fstat(fd)
        if (
            not stat.S_ISREG(st.st_mode)
            or not owned_and_private(st)
            or (secret and st.st_mode & (stat.S_IRWXG | stat.S_IRWXO))
        ):
            return None
        with os.fdopen(fd, "rb", closefd=False) as f:
            data = f.read()
        return data if size is None or len(data) == size else None
    except OSError:
        return None
    finally:
        os.close(fd)


def _write_private(path: Path, data: bytes, *, replace: bool = True) -> bool:
    """Write ``data`` to ``path`` atomically, mode 0600: a reader sees no file or the whole file. With
    ``replace=False`` an existing file wins (False is returned)."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{threading.get_ident()}.tmp")
    try:
        fd = os.open(
            tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o600
        )
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        if replace:
            os.replace(tmp, path)
        else:
            try:
                os.link(tmp, path)  # fails when another process made it first
            except FileExistsError:
                return False
        return True
    except OSError:
        return False
    finally:
        tmp.unlink(missing_ok=True)


_SECRETS: dict[Path, bytes] = {}


def _secret(folder: Path) -> bytes | None:
    """This user's key for authenticating entries: ``folder/hmac-key``, 32 random bytes, mode 0600, made
    on first use. A key file that is not this user's alone is replaced (every entry signed with it then
    fails authentication and is removed)."""
    secret = _SECRETS.get(folder)
    if secret is None:
        path = folder / _SECRET_FILE
        secret = _read_private(path, _SECRET_LEN, secret=True)
        if secret is None:
            if path.exists() or path.is_symlink():
                path.unlink(missing_ok=True)
            _write_private(path, secrets.token_bytes(_SECRET_LEN), replace=False)
            # ours, or the one another process made first
            secret = _read_private(path, _SECRET_LEN, secret=True)
        if secret is None:
            return None
        _SECRETS[folder] = secret
    return secret


def _tag(secret: bytes, key: str, body: bytes) -> bytes:
    return hmac.new(secret, MAGIC + key.encode() + body, hashlib.sha256).digest()


_BUILTIN_NODES: dict[str, type] = {"tuple": tuple, "list": list, "dict": dict, "None": type(None)}


def _tree_to_json(tree: Any) -> Any:
    """A result tree as JSON data: ``null`` for a leaf, ``[node type, dict keys or null, children]``
    otherwise. Node types are the built-in containers and named tuples of :data:`_TRUSTED_ROOTS`
    modules (``module:qualname``); anything else raises :class:`Uncacheable`."""
    data = tree.node_data()
    if data is None:
        return None
    cls, aux = data
    names = {v: k for k, v in _BUILTIN_NODES.items()}
    if cls in names:
        name = names[cls]
    elif (
        issubclass(cls, tuple)
        and hasattr(cls, "_fields")
        and cls.__module__.split(".")[0] in _TRUSTED_ROOTS
    ):
        name = f"{cls.__module__}:{cls.__qualname__}"
    else:
        raise Uncacheable(f"result tree node {cls!r}")
    if cls is dict:
        if not all(isinstance(k, str) for k in aux):
            raise Uncacheable("a result dictionary with keys that are not strings")
        aux = list(aux)
    elif aux is not None:
        raise Uncacheable(f"result tree node {cls!r} with node data")
    return [name, aux, [_tree_to_json(c) for c in tree.children()]]


def _tree_from_json(node: Any) -> Any:
    """Inverse of :func:`_tree_to_json` (imports only modules of :data:`_TRUSTED_ROOTS`)."""
    import importlib

    tu = jax.tree_util
    if node is None:
        return tu.tree_structure(0)
    name, aux, children = node
    cls: Any = _BUILTIN_NODES.get(name)
    if cls is None:
        module, qualname = name.split(":")
        if module.split(".")[0] not in _TRUSTED_ROOTS:
            raise ValueError(f"untrusted node type {name}")
        cls = importlib.import_module(module)
        for part in qualname.split("."):
            cls = getattr(cls, part)
        if not (isinstance(cls, type) and issubclass(cls, tuple) and hasattr(cls, "_fields")):
            raise ValueError(f"{name} is not a named tuple")
    return tu.PyTreeDef.from_node_data_and_children(
        tu.default_registry, (cls, aux), [_tree_from_json(c) for c in children]
    )


def _load(path: Path, key: str, secret: bytes, args: tuple) -> Any | None:
    """The executable stored in ``path`` for ``key``, or None. Nothing of the file is interpreted before
    its authentication tag (HMAC-SHA256 with this user's key over the key and the body) verifies and
    the key written in it equals ``key``: a file that another user placed or altered, or an entry copied
    under another program's name, is removed unread. The entry holds no pickle of ours -- the argument
    tree is rebuilt from ``args``, the result tree is JSON -- and JAX reads the executable."""
    from jax.experimental import serialize_executable

    blob = _read_private(path)
    if blob is None:
        if path.exists() or path.is_symlink():
            path.unlink(missing_ok=True)  # not a private regular file of this user's
        return None
    head = len(MAGIC) + _KEY_LEN
    stored_key = blob[len(MAGIC) : head].decode("ascii", "replace")
    tag, body = blob[head : head + _TAG_LEN], blob[head + _TAG_LEN :]
    if (
        not blob.startswith(MAGIC)
        or stored_key != key
        or not hmac.compare_digest(tag, _tag(secret, key, body))
    ):
        path.unlink(missing_ok=True)
        return None
    try:
        raw = zlib.decompress(body)
        n = int.from_bytes(raw[:4], "big")
        out_tree = _tree_from_json(json.loads(raw[4 : 4 + n]))
        in_tree = jax.tree_util.tree_structure((args, {}))
        return serialize_executable.deserialize_and_load(raw[4 + n :], in_tree, out_tree)
    except Exception:  # noqa: BLE001 - ours, but not loadable here: forget it, compile instead
        path.unlink(missing_ok=True)
        return None


def _store(path: Path, key: str, secret: bytes, exe: Any) -> None:
    """Write ``exe`` to ``path`` (mode 0600, atomically) with its key and tag. A program whose result
    tree has nodes :func:`_tree_to_json` cannot write is not stored."""
    from jax.experimental import serialize_executable

    try:
        serialized, _in_tree, out_tree = serialize_executable.serialize(exe)
        tree = json.dumps(_tree_to_json(out_tree)).encode()
        body = zlib.compress(len(tree).to_bytes(4, "big") + tree + serialized, 1)
        _write_private(path, MAGIC + key.encode() + _tag(secret, key, body) + body)
    except Exception:  # noqa: BLE001 - the cache is an optimisation only (not serializable, disk full, ...)
        pass


_WRITES = threading.local()


def _count_jax_cache_write(event: str, **kwargs: Any) -> None:
    # JAX records this event when it writes an executable XLA has just compiled to its persistent cache
    # (never for one it loaded from there or found in its in-memory cache)
    if event == "/jax/compilation_cache/cache_misses":
        _WRITES.count = getattr(_WRITES, "count", 0) + 1


jax.monitoring.register_event_listener(_count_jax_cache_write)


def load_or_compile(jitted: Any, kind: str, parts: Hashable, args: tuple) -> Any:
    """The executable of ``jitted`` (a ``jax.jit`` function) for ``args``: loaded from :func:`directory`
    when an authenticated entry for (``kind``, ``parts``, ``args``) is there, else
    ``jitted.lower(*args).compile()``.

    Stored only when XLA compiled it during this call -- JAX signals that by writing it to its own cache
    (``/jax/compilation_cache/cache_misses``). An executable JAX loaded from its persistent cache, or
    kept in memory after such a load, is not: XLA:CPU (jaxlib 0.10.2) serializes a deserialized
    executable without its compiled kernels, and loading that fails ("Function ... not found"). Such a
    program is stored the next time XLA compiles it.

    Parameters
    ----------
    jitted : jax.stages.Wrapped
        A ``jax.jit`` function.
    kind : str
        Kind of program, part of the key.
    parts : hashable
        What names the program within its kind; together with ``kind`` it must determine ``jitted``.
    args : tuple
        The call's arguments.

    Returns
    -------
    Any
        A compiled executable, called with ``*args``.

    Examples
    --------
    >>> import jax
    >>> import numpy as np
    >>> from formation_ftc.sim.runtime.program_cache import load_or_compile
    >>> exe = load_or_compile(jax.jit(lambda x: 2.0 * x), "doc-example", ("double", 1), (np.arange(3.0),))
    >>> np.asarray(exe(np.arange(3.0)))
    array([0., 2., 4.])
    """
    folder = directory()
    if folder is not None and not (_prepare_custom_calls() and _safe_folder(folder)):
        folder = None
    secret = _secret(folder) if folder is not None else None
    key = program_key(kind, parts, args) if secret is not None else None
    path = folder / f"{key}.bin" if folder is not None and key is not None else None
    if path is not None and secret is not None and key is not None:
        exe = _load(path, key, secret, args)
        if exe is not None:
            return _CheckedOnFirstCall(exe, path, lambda: jitted.lower(*args).compile())
    writes = getattr(_WRITES, "count", 0)
    exe = jitted.lower(*args).compile()
    if (
        path is not None
        and secret is not None
        and key is not None
        and getattr(_WRITES, "count", 0) > writes
        and _storable(exe)
    ):
        _store(path, key, secret, exe)
    return exe


#: JAX settings under which a call goes through ``jax.jit`` itself (op-by-op execution, NaN / Inf checks)
_DEBUG_FLAGS = ("jax_disable_jit", "jax_debug_nans", "jax_debug_infs")


class _CheckedOnFirstCall:
    """A loaded executable whose first call waits for its results: an entry that loads but fails to run
    (a kernel missing from it, ``NOT_FOUND`` from XLA, or any other error) is removed, and the program
    compiled and run the ordinary way instead; an error of the freshly compiled program is the
    computation's own and is raised. Later calls go straight to the executable that worked."""

    def __init__(self, exe: Any, path: Path, compile_fresh: Callable[[], Any]) -> None:
        self._exe = exe
        self._path = path
        self._compile_fresh: Callable[[], Any] | None = compile_fresh

    def __call__(self, *args: Any) -> Any:
        if self._compile_fresh is None:  # checked
            return self._exe(*args)
        try:
            out = jax.block_until_ready(self._exe(*args))
        except Exception:  # noqa: BLE001 - whatever the stored program did, trust the compiler instead
            self._path.unlink(missing_ok=True)
            self._exe = self._compile_fresh()
            out = self._exe(*args)
        self._compile_fresh = None  # (it holds the arguments it was made with: a batch's arrays)
        return out


class CachedProgram:
    """A ``jax.jit`` function whose executables come from :func:`load_or_compile`: called like it, one
    executable per argument signature (tree definition, shapes, dtypes, weak types), kept in memory;
    ``lower`` is the jitted function's own. ``kind`` and ``parts`` name the program in the key."""

    def __init__(self, jitted: Callable[..., Any], kind: str, parts: Hashable) -> None:
        self.jitted = jitted
        self.kind = kind
        self.parts = parts
        self._executables: dict[tuple, Any] = {}

    def kept(self, *args: Any) -> bool:
        """Whether the executable for ``args`` is already kept here (no load or compile needed)."""
        return _signature(args) in self._executables

    def executable(self, *args: Any) -> Any:
        """The compiled executable for ``args`` (loaded, compiled or kept from an earlier call)."""
        sig = _signature(args)
        exe = self._executables.get(sig)
        if exe is None:
            exe = self._executables.setdefault(
                sig, load_or_compile(self.jitted, self.kind, self.parts, args)
            )
        return exe

    def __call__(self, *args: Any) -> Any:
        if any(getattr(jax.config, flag, False) for flag in _DEBUG_FLAGS):
            return self.jitted(*args)  # JAX's debugging modes act in jax.jit's own call path
        return self.executable(*args)(*args)

    def lower(self, *args: Any) -> Any:
        return self.jitted.lower(*args)  # type: ignore[attr-defined]  # a jax.jit function
