"""JAX imported on first use: proxies for ``jax`` and ``jax.numpy`` in the process of a command that
rarely needs JAX (``formation-ftc check``).

``import jax`` costs about 1 s, and ``check`` builds a scenario's closed loop from components whose
modules import JAX at the top, yet evaluates most conditions with numpy and scipy. :func:`install` puts
two proxy modules into ``sys.modules`` before those modules are imported: ``import jax`` and
``import jax.numpy as jnp`` then bind a proxy, and the first attribute a proxy cannot serve itself
imports the real JAX (once, also with several threads), which the proxies delegate to from then on.
Before that import a proxy serves only what needs no JAX:

* the module attributes the import system reads (``__spec__``, ``__path__``, ``__file__``, ...), the
  real modules' own, found without importing them;
* ``jax.numpy`` (the ``jax.numpy`` proxy) and ``jax.config.update`` (buffered, applied in order right
  after the real import);
* ``jax.Array`` for ``isinstance`` and ``issubclass``, which scipy and matplotlib ask of every array
  while ``jax`` is in ``sys.modules``: False until JAX is imported (no JAX array exists before), the real
  class's answer after;
* :func:`call_when_imported`: :func:`formation_ftc.sim.components.component` registers its pytree
  classes with it, at the real import, before anything else can use JAX.

Anything else -- ``jax.jit``, ``jnp.zeros``, ``jax.config.jax_enable_x64``, ``import jax.lax``,
``help(jax)`` -- imports the real JAX first and answers from it. The real import takes the proxies out
of ``sys.modules`` first: JAX's own imports and every later ``import jax`` get the real modules; the
proxies bound before keep delegating. It runs as the import of a private module
(:data:`_IMPORTER`), so that threads wait for it on the import system's own locks. Used only where
:func:`install` is called (the command line's ``check``); everywhere else JAX is imported as usual.

Examples
--------
In a fresh interpreter (the proxies are installed only where JAX is not imported yet)::

    from formation_ftc import _lazy_jax
    _lazy_jax.install()             # True
    import jax.numpy as jnp         # the proxy: JAX not imported
    _lazy_jax.loaded()              # False
    jnp.zeros(3)                    # imports JAX: Array([0., 0., 0.], dtype=float64)
    _lazy_jax.loaded()              # True
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import sys
import threading
from collections.abc import Callable
from types import ModuleType
from typing import Any

__all__ = ["install", "loaded", "is_proxy", "call_when_imported"]

_NAMES = ("jax", "jax.numpy")
#: the module whose import is the real import of JAX (found by :class:`_Finder` only)
_IMPORTER = "_formation_ftc_real_jax"

#: the real modules, set as soon as imported (before the buffered work is applied)
_real: dict[str, ModuleType] = {}
#: True once the real JAX is imported and the buffered work applied: the proxies' fast path
_ready = False
#: guards the buffers below (never held while importing or calling out)
_buffer_lock = threading.Lock()
#: what to apply to the real ``jax`` once imported: the configuration updates first, then the calls
_pending_config: list[Callable[[ModuleType], Any]] = []
_pending_calls: list[Callable[[ModuleType], Any]] = []
_flushed = False  # the buffers are applied: a new item is applied at once


def _import_real() -> ModuleType:
    """The real ``jax``: imported on the first call (by importing :data:`_IMPORTER`, which another
    thread's call waits for, and a call from within that import returns at once)."""
    if not _ready:
        importlib.import_module(_IMPORTER)  # waits for another thread's; at once within this one's
        while "jax" not in _real:  # another thread's import failed: this one fails the same way
            importlib.import_module(_IMPORTER)
    return _real["jax"]


def _next_buffered() -> Callable[[ModuleType], Any] | None:
    """The next buffered function to apply to the real ``jax`` (configuration updates before calls),
    or None once both buffers are empty (from then on :data:`_flushed`)."""
    global _flushed
    with _buffer_lock:
        for pending in (_pending_config, _pending_calls):
            if pending:
                return pending.pop(0)
        _flushed = True
        return None


class _RealImport(importlib.abc.Loader):
    """Executing :data:`_IMPORTER`: the proxies leave ``sys.modules``, JAX is imported, the buffered
    configuration updates and calls are applied in order."""

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> None:
        return None  # the default module

    def exec_module(self, module: ModuleType) -> None:
        global _ready
        for name in _NAMES:
            if is_proxy(sys.modules.get(name)):
                del sys.modules[name]
        jax = importlib.import_module("jax")
        _real["jax.numpy"] = importlib.import_module("jax.numpy")
        _real["jax"] = jax
        while (apply := _next_buffered()) is not None:
            apply(jax)
        _ready = True
        if _FINDER in sys.meta_path:
            sys.meta_path.remove(_FINDER)


class _Submodule(importlib.abc.Loader):
    """``import jax.<name>`` under a proxy: the real JAX is imported first, then the submodule as usual
    (or as JAX's import left it); the import system gets that module unchanged."""

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        _import_real()
        module = importlib.import_module(spec.name)
        spec.loader_state = module.__spec__
        return module

    def exec_module(self, module: ModuleType) -> None:
        # the import system set this loader's spec on the module: put back the module's own
        module.__spec__ = module.__spec__.loader_state  # type: ignore[union-attr]


class _Finder(importlib.abc.MetaPathFinder):
    """Finds :data:`_IMPORTER`, and the submodules of a proxy."""

    def find_spec(
        self, fullname: str, path: Any, target: ModuleType | None = None
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname == _IMPORTER:
            return importlib.util.spec_from_loader(fullname, _RealImport())
        if is_proxy(sys.modules.get(fullname.rpartition(".")[0])):  # not during the real import
            return importlib.util.spec_from_loader(fullname, _Submodule())
        return None


class _Proxy(ModuleType):
    """A stand-in for the module ``jax`` or ``jax.numpy`` (module docstring)."""

    def __init__(self, name: str, spec: importlib.machinery.ModuleSpec) -> None:
        super().__init__(name)
        # what the import system and introspection read, as the real module has it
        self.__dict__.update(
            __spec__=spec,
            __loader__=spec.loader,
            __package__=name,
            __file__=spec.origin,
            __path__=list(spec.submodule_search_locations or []),
        )
        del self.__dict__["__doc__"]  # the real one (the property below)

    @property  # type: ignore[misc]  # a data descriptor, so that it wins over the class docstring
    def __doc__(self) -> str | None:  # type: ignore[override]
        return getattr(self._module(), "__doc__", None)

    def _module(self) -> ModuleType:
        _import_real()
        return _real[self.__name__]

    def __getattr__(self, attr: str) -> Any:
        if not _ready and self.__name__ == "jax":
            if attr == "numpy":
                return _PROXIES["jax.numpy"]
            if attr == "config":
                return _CONFIG
            if attr == "Array":
                return _Array
        return getattr(self._module(), attr)

    def __setattr__(self, attr: str, value: Any) -> None:
        setattr(self._module(), attr, value)

    def __delattr__(self, attr: str) -> None:
        delattr(self._module(), attr)

    def __dir__(self) -> list[str]:
        return dir(self._module())


class _Config:
    """``jax.config`` before the real import: ``update`` is buffered; anything else imports JAX."""

    def update(self, name: str, value: Any) -> None:
        with _buffer_lock:
            if not _flushed:
                _pending_config.append(lambda jax: jax.config.update(name, value))
                return
        _import_real().config.update(name, value)

    def __getattr__(self, attr: str) -> Any:
        return getattr(_import_real().config, attr)


class _ArrayType(type):
    """The metaclass of :class:`_Array`: type checks answered without JAX until it is imported."""

    def __instancecheck__(cls, obj: object) -> bool:
        jax = _real.get("jax")
        return jax is not None and isinstance(obj, jax.Array)

    def __subclasscheck__(cls, sub: type) -> bool:
        jax = _real.get("jax")
        return jax is not None and issubclass(sub, jax.Array)

    def __getattr__(cls, attr: str) -> Any:
        return getattr(_import_real().Array, attr)


class _Array(metaclass=_ArrayType):
    """``jax.Array`` before the real import, for type checks: nothing is a JAX array before JAX is
    imported (``isinstance(x, jax.Array)``, which scipy and matplotlib ask of every array while JAX is in
    ``sys.modules``, is False); the real class's answer after."""


_Array.__module__ = "jax"
_Array.__name__ = _Array.__qualname__ = "Array"
_FINDER = _Finder()
_CONFIG = _Config()
_PROXIES: dict[str, _Proxy] = {}


def install() -> bool:
    """Put the proxies for ``jax`` and ``jax.numpy`` into ``sys.modules``, where neither is imported
    (nor installed as a proxy) yet and JAX is installed.

    Returns
    -------
    bool
        True when installed now (False: JAX imported or the proxies installed before, or JAX missing).
    """
    with _buffer_lock:
        if _PROXIES or any(name in sys.modules for name in _NAMES):
            return False
        jax_spec = importlib.util.find_spec("jax")
        if jax_spec is None or not jax_spec.submodule_search_locations:
            return False
        numpy_spec = importlib.machinery.PathFinder.find_spec(
            "jax.numpy", list(jax_spec.submodule_search_locations)
        )
        if numpy_spec is None:
            return False
        _PROXIES["jax"] = _Proxy("jax", jax_spec)
        _PROXIES["jax.numpy"] = _Proxy("jax.numpy", numpy_spec)
        sys.meta_path.insert(0, _FINDER)
        sys.modules.update(_PROXIES)
        return True


def is_proxy(module: object) -> bool:
    """Whether ``module`` is one of the proxies (which may have imported the real JAX since).

    Parameters
    ----------
    module : object
        A module, e.g. ``sys.modules.get("jax")``.

    Returns
    -------
    bool
        True for a proxy.
    """
    return isinstance(module, _Proxy)


def loaded() -> bool:
    """Whether the real JAX is imported in this process (installed proxies that have not imported it
    yet do not count).

    Returns
    -------
    bool
        True once ``jax`` is imported.

    Examples
    --------
    >>> import jax
    >>> from formation_ftc import _lazy_jax
    >>> _lazy_jax.loaded()
    True
    """
    module = sys.modules.get("jax")
    return _ready or (module is not None and not is_proxy(module))


def call_when_imported(fn: Callable[[ModuleType], Any]) -> None:
    """``fn(jax)`` now, or, while the proxies stand in for JAX, right after the real import (before
    anything else can use JAX).

    Parameters
    ----------
    fn : callable
        Called with the real ``jax`` module.
    """
    with _buffer_lock:
        if _PROXIES and not _flushed:
            _pending_calls.append(fn)
            return
    fn(_import_real() if _PROXIES else importlib.import_module("jax"))
