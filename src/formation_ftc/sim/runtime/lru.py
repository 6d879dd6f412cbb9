"""Bounded caches of compiled programs: least recently used entries are dropped first.

A long session (a notebook, a campaign service, a test run) builds many programs; keeping every
executable it ever compiled makes its memory grow without bound. :func:`lru_get` and :func:`lru_put`
keep an ``OrderedDict`` in recency order and cap its size. Both hold one lock while they touch the
dictionary, so runs started from several threads (a thread pool in a notebook, a threaded executor)
never see an entry disappear between the lookup and the recency update.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Hashable
from typing import Any, TypeVar

__all__ = ["lru_get", "lru_put"]

V = TypeVar("V")

_LOCK = threading.Lock()


def lru_get(cache: OrderedDict, key: Hashable) -> Any:
    """``cache[key]`` marked as most recently used, or None when absent.

    Parameters
    ----------
    cache : collections.OrderedDict
        The cache, in recency order.
    key : hashable
        The key.

    Returns
    -------
    Any
        The value, or None.

    Examples
    --------
    >>> from collections import OrderedDict
    >>> from formation_ftc.sim.runtime.lru import lru_get
    >>> cache = OrderedDict(a=1, b=2)
    >>> lru_get(cache, "a"), lru_get(cache, "z")
    (1, None)
    >>> list(cache)  # "a" is now the most recently used
    ['b', 'a']
    """
    with _LOCK:
        value = cache.get(key)
        if value is not None:
            cache.move_to_end(key)
        return value


def lru_put(cache: OrderedDict, key: Hashable, value: V, max_kept: int) -> V:
    """Store ``value`` as the most recently used entry and drop the oldest beyond ``max_kept``.

    Parameters
    ----------
    cache : collections.OrderedDict
        The cache, in recency order.
    key : hashable
        The key.
    value : Any
        The value.
    max_kept : int
        Most entries kept.

    Returns
    -------
    Any
        ``value``.

    Examples
    --------
    >>> from collections import OrderedDict
    >>> from formation_ftc.sim.runtime.lru import lru_put
    >>> cache = OrderedDict()
    >>> for k in "abc":
    ...     _ = lru_put(cache, k, k.upper(), max_kept=2)
    >>> dict(cache)
    {'b': 'B', 'c': 'C'}
    """
    with _LOCK:
        cache[key] = value
        cache.move_to_end(key)
        while len(cache) > max_kept:
            cache.popitem(last=False)
        return value
