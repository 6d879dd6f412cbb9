"""Bounded program caches (sim/runtime/lru.py): ``kept`` on a ``cachetools.LRUCache`` drops the least
recently used entry first, and threads sharing one cache never see an entry vanish mid-lookup."""

from __future__ import annotations

import threading
import time

from formation_ftc.sim.runtime.lru import LRUCache, kept


def test_least_recently_used_entry_is_dropped_first():
    cache: LRUCache = LRUCache(maxsize=2)
    built: list[str] = []

    def build(key: str):
        return lambda: built.append(key) or key.upper()

    assert kept(cache, "a", build("a")) == "A"
    kept(cache, "b", build("b"))
    assert kept(cache, "a", build("a")) == "A"  # a hit: a is now the most recent, b the oldest
    kept(cache, "c", build("c"))
    assert sorted(cache) == ["a", "c"]
    kept(cache, "b", build("b"))  # dropped before: built again
    assert built == ["a", "b", "c", "b"]


class _SlowLRUCache(LRUCache):
    """An LRUCache that gives the other threads the processor between a lookup's membership test and
    its read, so that an eviction can fall in between whenever nothing prevents it."""

    def __contains__(self, key):
        found = super().__contains__(key)
        time.sleep(0)
        return found


def test_concurrent_lookups_and_evictions_never_fail():
    """Threads looking up and evicting the entries of a one-entry cache at once: a lookup that finds an
    entry reads it although other threads evict entries all the time. Without the module's lock this
    raises KeyError (an entry evicted between ``in`` and the read) in every run."""
    cache = _SlowLRUCache(maxsize=1)
    errors: list[BaseException] = []

    def work(seed: int) -> None:
        try:
            for i in range(1_000):  # each key twice in a row: the second lookup finds it
                key = (seed + i // 2) % 3
                assert kept(cache, key, lambda key=key: key + 1) == key + 1
        except BaseException as exc:  # noqa: BLE001 - reported by the assertion below
            errors.append(exc)

    threads = [threading.Thread(target=work, args=(s,)) for s in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors[:3]
    assert len(cache) <= 1
