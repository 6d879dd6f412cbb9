"""Per-run random streams of a campaign, derived for many runs at once (same numbers as numpy).

Every random number of a campaign run comes from :class:`numpy.random.SeedSequence` keyed by the
campaign seed and a spawn key (see :mod:`formation_ftc.campaign.sampling`): the run seed is
``SeedSequence(seed, spawn_key=(key, 0)).generate_state(1)[0] >> 1`` and a sampled field is drawn
from ``default_rng(SeedSequence(seed, spawn_key=(key, 1, crc32(path))))``. Building one
``SeedSequence`` and one ``Generator`` per run and field costs tens of microseconds of Python each;
this module computes the same integers for a whole array of keys with a few dozen numpy operations:

* :func:`seed_states` -- NumPy's ``SeedSequence`` entropy mixing and ``generate_state`` (32-bit
  multiply-xorshift hashing, the hash constants advance identically for every key, so every step is
  one vector operation over the keys);
* :func:`pcg64_states` -- ``PCG64`` seeded from those words (128-bit LCG ``s <- s a + c`` emulated
  with pairs of 64-bit words);
* :func:`first_doubles` -- the first ``Generator.random()`` / ``uniform`` double of each stream
  (XSL-RR output, ``(x >> 11) 2**-53``);
* :func:`generators` -- one reused ``Generator`` positioned at each run's state in turn, for
  distributions whose draw is not a single double (integers, unweighted choice): NumPy itself draws.

Integer arithmetic only, so the results are bit-identical to NumPy's by construction;
:func:`available` nevertheless compares them with NumPy once per process (a future NumPy changing
its seeding would make the callers fall back to the per-run objects rather than change numbers).
"""

from __future__ import annotations

import functools
from collections.abc import Iterator, Sequence

import numpy as np

__all__ = ["available", "seed_states", "pcg64_states", "first_doubles", "run_seeds", "generators"]

_M32 = 0xFFFFFFFF
_INIT_A = 0x43B0D7E5
_MULT_A = 0x931E8875
_INIT_B = 0x8B51F9DD
_MULT_B = 0x58F38DED
_MIX_MULT_L = 0xCA01F9DD
_MIX_MULT_R = 0x4973F715
_POOL = 4
_U32 = np.uint32
_U64 = np.uint64
#: PCG64's 128-bit LCG multiplier (high, low 64-bit words)
_PCG_MULT = (_U64(2549297995355413924), _U64(4865540595714422341))


def _int_words(n: int) -> list[int]:
    """NumPy's ``_int_to_uint32_array``: little-endian 32-bit words of a non-negative integer."""
    if n < 0:
        raise ValueError("entropy and spawn keys must be non-negative")
    return [(n >> shift) & _M32 for shift in range(0, max(n.bit_length(), 1), 32)]


def _hashmix(value: np.ndarray, hc: list[int]) -> np.ndarray:
    value = value ^ _U32(hc[0])
    hc[0] = (hc[0] * _MULT_A) & _M32
    value = value * _U32(hc[0])
    return value ^ (value >> _U32(16))


def _mix(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    r: np.ndarray = _U32(_MIX_MULT_L) * x - _U32(_MIX_MULT_R) * y
    return r ^ (r >> _U32(16))


def seed_states(entropy: int, keys: np.ndarray, suffix: Sequence[int], n_words: int) -> np.ndarray:
    """``SeedSequence(entropy, spawn_key=(key, *suffix)).generate_state(n_words, uint32)`` per key.

    ``keys``: non-negative integers below ``2**32`` (one 32-bit word each). Returns ``(len(keys),
    n_words)`` uint32.
    """
    keys = np.asarray(keys, dtype=np.int64)
    n = keys.shape[0]
    if n and (keys.min() < 0 or keys.max() > _M32):
        raise ValueError("spawn keys must lie in [0, 2**32)")
    run = _int_words(int(entropy))
    run += [0] * max(0, _POOL - len(run))  # spawn key present: entropy padded to the pool size
    words: list[np.ndarray | int] = [*run, keys.astype(np.uint32)]
    for s in suffix:
        words += _int_words(int(s))
    cols = [w if isinstance(w, np.ndarray) else np.full(n, w, dtype=np.uint32) for w in words]
    hc = [_INIT_A]
    pool = [
        _hashmix(cols[i] if i < len(cols) else np.zeros(n, np.uint32), hc) for i in range(_POOL)
    ]
    for i_src in range(_POOL):
        for i_dst in range(_POOL):
            if i_src != i_dst:
                pool[i_dst] = _mix(pool[i_dst], _hashmix(pool[i_src], hc))
    for i_src in range(_POOL, len(cols)):
        for i_dst in range(_POOL):
            pool[i_dst] = _mix(pool[i_dst], _hashmix(cols[i_src], hc))
    out = np.empty((n, n_words), dtype=np.uint32)
    hb = _INIT_B
    for i in range(n_words):
        v = pool[i % _POOL] ^ _U32(hb)
        hb = (hb * _MULT_B) & _M32
        v = v * _U32(hb)
        out[:, i] = v ^ (v >> _U32(16))
    return out


def _mul64(a: np.ndarray, b: np.uint64) -> tuple[np.ndarray, np.ndarray]:
    """Full 128-bit product of uint64 ``a`` and the constant ``b``: (high, low) words."""
    m = _U64(_M32)
    s32 = _U64(32)
    a0, a1 = a & m, a >> s32
    b0, b1 = b & m, b >> s32
    p00, p01, p10, p11 = a0 * b0, a0 * b1, a1 * b0, a1 * b1
    mid = (p00 >> s32) + (p01 & m) + (p10 & m)
    lo = (p00 & m) | (mid << s32)
    hi = p11 + (p01 >> s32) + (p10 >> s32) + (mid >> s32)
    return hi, lo


def _step(
    hi: np.ndarray, lo: np.ndarray, inc_hi: np.ndarray, inc_lo: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """One PCG64 LCG step ``s <- s a + c`` (mod 2**128)."""
    ph, pl = _mul64(lo, _PCG_MULT[1])
    ph = ph + lo * _PCG_MULT[0] + hi * _PCG_MULT[1]
    new_lo = pl + inc_lo
    carry = (new_lo < pl).astype(np.uint64)
    return ph + inc_hi + carry, new_lo


def pcg64_states(words: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """State of ``PCG64(seed_sequence)`` right after seeding, from ``generate_state(8, uint32)``
    words ``(n, 8)``: (state high, state low, increment high, increment low) uint64 arrays."""
    w = words.astype(np.uint64)
    # generate_state(4, uint64)
    s_hi, s_lo, i_hi, i_lo = (w[:, 2 * k] | (w[:, 2 * k + 1] << _U64(32)) for k in range(4))
    inc_hi = (i_hi << _U64(1)) | (i_lo >> _U64(63))
    inc_lo = (i_lo << _U64(1)) | _U64(1)
    zero = np.zeros_like(s_hi)
    hi, lo = _step(zero, zero, inc_hi, inc_lo)
    lo2 = lo + s_lo
    hi = hi + s_hi + (lo2 < lo).astype(np.uint64)
    hi, lo = _step(hi, lo2, inc_hi, inc_lo)
    return hi, lo, inc_hi, inc_lo


def first_doubles(entropy: int, keys: np.ndarray, suffix: Sequence[int]) -> np.ndarray:
    """The first ``Generator.random()`` of ``default_rng(SeedSequence(entropy, spawn_key=(key,
    *suffix))))`` for every key, float64 in [0, 1)."""
    hi, lo, inc_hi, inc_lo = pcg64_states(seed_states(entropy, keys, suffix, 8))
    hi, lo = _step(hi, lo, inc_hi, inc_lo)
    x = hi ^ lo
    rot = hi >> _U64(58)
    out = (x >> rot) | (x << ((_U64(64) - rot) & _U64(63)))
    return (out >> _U64(11)).astype(np.float64) * (1.0 / 9007199254740992.0)


def run_seeds(entropy: int, keys: np.ndarray) -> np.ndarray:
    """31-bit run seeds ``SeedSequence(entropy, spawn_key=(key, 0)).generate_state(1)[0] >> 1`` (int64)."""
    return (seed_states(entropy, keys, (0,), 1)[:, 0] >> _U32(1)).astype(np.int64)


def generators(
    entropy: int, keys: np.ndarray, suffix: Sequence[int]
) -> Iterator[np.random.Generator]:
    """One ``Generator`` per key, positioned as ``default_rng(SeedSequence(entropy, spawn_key=(key,
    *suffix)))`` (the same object, re-positioned at each step: use it before advancing)."""
    hi, lo, inc_hi, inc_lo = pcg64_states(seed_states(entropy, keys, suffix, 8))
    bitgen = np.random.PCG64(0)
    gen = np.random.Generator(bitgen)
    for h, l_, ih, il in zip(
        hi.tolist(), lo.tolist(), inc_hi.tolist(), inc_lo.tolist(), strict=True
    ):
        bitgen.state = {
            "bit_generator": "PCG64",
            "state": {"state": (h << 64) | l_, "inc": (ih << 64) | il},
            "has_uint32": 0,
            "uinteger": 0,
        }
        yield gen


@functools.cache
def available() -> bool:
    """True when this module reproduces the installed NumPy (checked once per process on a few keys)."""
    try:
        return _self_check()
    except Exception:  # noqa: BLE001 - any surprise: the callers use NumPy's objects
        return False


def _self_check() -> bool:
    keys = np.array([0, 1, 2, 7, 1000, 123456, 2**31 + 5, 2**32 - 2])
    for entropy, suffix in ((2026, (1, 0xDEADBEEF)), (2**40 + 3, (1, 0)), (0, ())):
        seqs = [np.random.SeedSequence(entropy, spawn_key=(int(k), *suffix)) for k in keys]
        ref_words = [ss.generate_state(8) for ss in seqs]
        if not np.array_equal(seed_states(entropy, keys, suffix, 8), np.array(ref_words)):
            return False
        ref = [np.random.default_rng(ss).random() for ss in seqs]
        if not np.array_equal(first_doubles(entropy, keys, suffix), np.array(ref)):
            return False
        ints = [int(g.integers(0, 1000)) for g in generators(entropy, keys, suffix)]
        ref_i = [int(np.random.default_rng(ss).integers(0, 1000)) for ss in seqs]
        if ints != ref_i:
            return False
    ref_s = [
        int(np.random.SeedSequence(5, spawn_key=(int(k), 0)).generate_state(1)[0]) >> 1
        for k in keys
    ]
    return run_seeds(5, keys).tolist() == ref_s
