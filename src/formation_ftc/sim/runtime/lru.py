"""Bounded caches of compiled programs: ``cachetools.LRUCache`` (least recently used dropped first)
behind one lock, so that a long session (a notebook, a campaign service, a test run) does not hold
every executable it ever compiled, and runs started from several threads share the caches safely.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Hashable
from typing import TypeVar

from cachetools import LRUCache

__all__ = ["LRUCache", "kept"]

V = TypeVar("V")

_LOCK = threading.Lock()


def kept(cache: LRUCache, key: Hashable, build: Callable[[], V]) -> V:
    """``cache[key]`` (marked most recently used), or ``build()`` stored there on a miss (built
    outside the lock: two threads may build the same entry once each; the later is kept).

    Parameters
    ----------
    cache : cachetools.LRUCache
        The bounded cache.
    key : hashable
        The entry's key.
    build : callable
        ``build()`` -> the value, called on a miss only.

    Returns
    -------
    Any
        The kept value.

    Examples
    --------
    >>> cache = LRUCache(maxsize=2)
    >>> [kept(cache, k, lambda k=k: k.upper()) for k in "abca"]
    ['A', 'B', 'C', 'A']
    >>> sorted(cache)  # "b" was the least recently used when "a" came back
    ['a', 'c']
    """
    with _LOCK:
        value = cache.get(key)
    if value is None:
        value = build()
        with _LOCK:
            cache[key] = value
    return value
