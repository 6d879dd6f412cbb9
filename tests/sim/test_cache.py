"""Bounded program caches (sim/cache.py): recency order, eviction of the least recently used."""

from collections import OrderedDict

from formation_ftc.sim.cache import lru_get, lru_put


def test_least_recently_used_entry_is_dropped_first():
    cache: OrderedDict = OrderedDict()
    assert lru_put(cache, "a", 1, 2) == 1
    lru_put(cache, "b", 2, 2)
    assert lru_get(cache, "a") == 1  # a is now the most recent, b the oldest
    lru_put(cache, "c", 3, 2)
    assert list(cache) == ["a", "c"] and lru_get(cache, "b") is None
    lru_put(cache, "a", 10, 2)  # replacing a value keeps it the most recent
    lru_put(cache, "d", 4, 2)
    assert list(cache) == ["a", "d"] and cache["a"] == 10
