"""Bounded program caches (sim/runtime/lru.py): recency order, eviction of the least recently used."""

from collections import OrderedDict

from formation_ftc.sim.runtime.lru import lru_get, lru_put


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


class _SlowOrderedDict(OrderedDict):
    """An OrderedDict that gives the other threads the processor inside every recency update, so that
    an eviction can fall between a lookup and its update whenever nothing prevents it."""

    def move_to_end(self, key, last=True):
        import time

        time.sleep(0)
        super().move_to_end(key, last)


def test_concurrent_lookups_and_evictions_never_fail():
    """Threads looking up and evicting entries of one tiny cache at once: a lookup that finds an entry
    marks it recent although other threads evict entries all the time. Without the module's lock this
    raised KeyError (an entry evicted between ``get`` and ``move_to_end``) in every run."""
    import threading

    cache: OrderedDict = _SlowOrderedDict()
    errors: list[BaseException] = []

    def work(seed: int) -> None:
        try:
            for i in range(1_000):
                key = (seed + i) % 3
                if lru_get(cache, key) is None:
                    lru_put(cache, key, i + 1, 1)
        except BaseException as exc:  # noqa: BLE001 - reported by the assertion below
            errors.append(exc)

    threads = [threading.Thread(target=work, args=(s,)) for s in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors[:3]
    assert len(cache) <= 1
