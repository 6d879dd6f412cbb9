"""Metrics accumulated at every step inside the compiled run (never from decimated records).

A :class:`Metric` names a recorded signal, how to reduce it over its non-time axes (Euclidean norm
over the vector axis, then over spacecraft) and over time (max, min, final, mean, integral, value at a
time, settle time), and a time window. :func:`init_accumulators` / :func:`update_accumulators` /
:func:`finalize` are pure JAX functions the closed loop calls at every step (k = 0 .. n-1, with the
signals at t_k) and once more with the final sample (k = n, the run's last record), so a peak between
two records is never missed. A run that leaves its admissible set never reaches the horizon: its metrics
are those accumulated up to the start of the failing record block (the state the engine returns), with
no horizon sample (``last`` is then NaN).

A long run with many metrics folds them a block of steps at a time instead (:func:`fold_block`; the
closed loop chooses, see ``ClosedLoop.metric_block``): each step only writes the signals the metrics
read (:func:`pack_sample`), and the values and reductions of the whole block are computed at once --
the same selections, and the same sums added in another order (they may differ in the last bits).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any, NoReturn

import jax
import jax.numpy as jnp
import numpy as np

from formation_ftc.sim.components import component, static

__all__ = [
    "Metric",
    "init_accumulators",
    "update_accumulators",
    "finalize",
    "metric_names",
    "REDUCTIONS",
    "BLOCK_REDUCTIONS",
    "SPACECRAFT_REDUCTIONS",
    "STAGE_REDUCTIONS",
    "stage_values",
    "update_stage_accumulators",
    "block_signals",
    "sample_values",
    "fold_block",
    "pack_sample",
    "unpack_samples",
    "reads_steps",
]

# the names of the reductions (JAX-free: scenario sections validate them without JAX)
from formation_ftc.sim.contract import (  # noqa: E402
    BLOCK_REDUCTIONS,
    REDUCTIONS,
    SPACECRAFT_REDUCTIONS,
    STAGE_REDUCTIONS,
)

_TOL = 1e-9  # window edges are inclusive to this many seconds (times are k*dt in float64)
#: reduction -> (pairwise extreme, extreme over an axis: names in jax.numpy, starting value); names, so
#: that importing this module uses no JAX (``check``: :mod:`formation_ftc._lazy_jax`)
_EXTREMES = {"max": ("maximum", "max", -math.inf), "min": ("minimum", "min", math.inf)}
#: reduction -> starting value of each part of its accumulator tuple (``False``: a boolean part)
_START: dict[str, tuple] = {
    # (extreme so far, seen)
    "max": (-math.inf, False),
    "min": (math.inf, False),
    # (value, seen); first: (time of the first sample at or above the threshold, found)
    **dict.fromkeys(("final", "at", "last", "first"), (math.nan, False)),
    # (sum -- of squares for rms, number of samples; stage-integrated: of steps counted)
    **dict.fromkeys(("mean", "integral", "rms", *STAGE_REDUCTIONS), (0.0, 0.0)),
    # (time of the first sample after the last one at or above the threshold, seen, last above)
    **dict.fromkeys(("settle", "settle_delay"), (math.nan, False, False)),
    # block_rms: (sum over the open block, its samples, sum of the squared means of the closed blocks,
    # closed blocks); block_dev_rms: (shift = first value of the open block, sum and sum of squares of
    # value - shift over the open block, its samples, sum of squared deviations from the mean over the
    # closed blocks, their samples)
    "block_rms": (0.0,) * 4,
    "block_dev_rms": (0.0,) * 6,
}
#: spacecraft reduction -> how it combines the spacecraft axis (axis 0)
_SPACECRAFT = {
    "max": lambda v: jnp.max(v, axis=0),
    "mean": lambda v: jnp.mean(v, axis=0),
    "sum": lambda v: jnp.sum(v, axis=0),
    "range": lambda v: jnp.max(v, axis=0) - jnp.min(v, axis=0),
}


@component
class Metric:
    """One scalar metric (or one per spacecraft with ``spacecraft = "each"``).

    Attributes
    ----------
    name : metric name (``"each"`` appends ``_sc1``, ``_sc2``, ...).
    signal : name of a recorded signal of the closed loop.
    reduce : time reduction, one of :data:`REDUCTIONS`.
    norm : take a norm over the signal's last axis first (``norm_ord``).
    norm_ord : ``"2"`` Euclidean norm (default) or ``"inf"`` largest absolute component.
    spacecraft : combine the spacecraft axis (axis 0 after the norm) with one of
        :data:`SPACECRAFT_REDUCTIONS`; ``"none"`` for signals without a spacecraft axis.
    units : units of the metric (UDUNITS).
    start, end : window [s] (inclusive); ``end = inf`` for "until the end".
    threshold : threshold of ``"settle"`` and ``"first"`` [signal units].
    gate : name of a signal; when given, only the samples at which it is > 0 (true) count, so the
        window may open on an event (e.g. a mode switch). Not for the stage-integrated reductions.
    block : number of steps of a block of :data:`BLOCK_REDUCTIONS` (>= 1; a static structure choice).
    formula : the signal temporal logic formula of ``reduce = "stl"`` (:mod:`formation_ftc.sim.stl`),
        evaluated on the run's records by :meth:`~formation_ftc.sim.loop.ClosedLoop.run` (``signal``
        unused).
    """

    name: str = static()
    signal: str = static()
    reduce: str = static(default="max")
    norm: bool = static(default=False)
    spacecraft: str = static(default="none")
    units: str = static(default="1")
    start: Any = 0.0
    end: Any = float("inf")
    threshold: Any = 0.0
    norm_ord: str = static(default="2")
    square: bool = static(default=False)
    component: int | None = static(default=None)
    gate: str | None = static(default=None)
    block: int = static(default=0)
    formula: str | None = static(default=None)

    def __post_init__(self) -> None:
        def fail(problem: str) -> NoReturn:
            raise ValueError(f"metric {self.name!r}: {problem}")

        if (self.reduce == "stl") != (self.formula is not None):
            fail(
                f"reduce 'stl' and a formula go together (reduce {self.reduce!r}, formula "
                f"{self.formula!r})"
            )
        if self.formula is not None:
            from formation_ftc.sim.stl import parse

            parse(self.formula)  # StlError naming the position
        if self.norm_ord not in ("2", "inf"):
            fail(f"norm_ord must be '2' or 'inf', got {self.norm_ord!r}")
        if self.reduce not in REDUCTIONS:
            fail(f"reduce must be one of {sorted(REDUCTIONS)}, got {self.reduce!r}")
        if self.spacecraft not in SPACECRAFT_REDUCTIONS:
            fail(f"spacecraft must be one of {SPACECRAFT_REDUCTIONS}, got {self.spacecraft!r}")
        if self.gate is not None and self.reduce in STAGE_REDUCTIONS:
            fail(f"a gate is not supported by the stage-integrated reduction {self.reduce!r}")
        if self.reduce in BLOCK_REDUCTIONS and not (
            isinstance(self.block, int) and self.block >= 1
        ):
            fail(f"reduce {self.reduce!r} needs block >= 1 steps, got {self.block!r}")

    def value(self, signals: Mapping[str, jax.Array]) -> jax.Array:
        """The instantaneous value (scalar, or (N,) for ``"each"``)."""
        v = jnp.asarray(signals[self.signal])
        if self.component is not None:  # one component of the last axis; its norm is |v|
            v = v[..., self.component]
            if self.norm:
                v = jnp.abs(v)
            if self.square:
                v = v * v
        elif self.norm and self.square and self.norm_ord == "2":
            v = jnp.sum(v * v, axis=-1)
        elif self.square and not self.norm:
            v = v * v
        elif self.norm and self.norm_ord == "inf":
            v = jnp.max(jnp.abs(v), axis=-1)
        elif self.norm:  # Euclidean, not squared (the squared norm is the sum above)
            v = jnp.sqrt(jnp.sum(v * v, axis=-1))
        if self.spacecraft in _SPACECRAFT:
            v = _SPACECRAFT[self.spacecraft](v)
        each = self.spacecraft == "each"
        if v.ndim != int(each):
            expected = "(spacecraft,)" if each else "a scalar (set norm / spacecraft)"
            raise ValueError(
                f"metric {self.name!r}: signal {self.signal!r} reduces to shape {v.shape}, "
                f"expected {expected}"
            )
        return v


def metric_names(metrics: Sequence[Metric], count: int) -> list[str]:
    """Flat metric names (per-spacecraft metrics expanded).

    Parameters
    ----------
    metrics : sequence of Metric
        The metrics.
    count : int
        Number of spacecraft N.

    Returns
    -------
    list of str
        One name per scalar value.

    Examples
    --------
    >>> from formation_ftc.sim.metrics import Metric, metric_names
    >>> ms = (Metric("peak", "position_error", norm=True, spacecraft="each", units="m"),
    ...       Metric("t_settle", "mu1", reduce="settle", threshold=0.1, units="s"))
    >>> metric_names(ms, count=2)
    ['peak_sc1', 'peak_sc2', 't_settle']
    """
    each = [f"_sc{i + 1}" for i in range(count)]  # the suffixes of a per-spacecraft metric
    return [m.name + sfx for m in metrics for sfx in (each if m.spacecraft == "each" else [""])]


class _Stack:
    """Metrics of one time reduction, spacecraft mode and gate evaluated together: their values,
    windows and thresholds stacked along a leading axis, so that one step's accumulator update is one
    vector operation per group instead of one small kernel per metric (XLA runs every fused kernel of
    a scan body as a separate call; with tens of metrics these calls dominated a 6-state step).
    The arithmetic per metric is unchanged (elementwise), so results are identical."""

    def __init__(self, metrics: Sequence[Metric]):
        m0 = metrics[0]
        self.metrics = tuple(metrics)
        self.reduce, self.gate, self.block = m0.reduce, m0.gate, m0.block
        trail = (1,) if m0.spacecraft == "each" else ()

        def stacked(name):
            return jnp.reshape(
                jnp.stack([jnp.asarray(getattr(m, name), dtype=jnp.float64) for m in metrics]),
                (len(metrics),) + trail,
            )

        self.start, self.end, self.threshold = map(stacked, ("start", "end", "threshold"))

    def value(self, signals: Mapping[str, jax.Array]) -> jax.Array:
        return jnp.stack([m.value(signals) for m in self.metrics])


def _classes(metrics: Sequence[Metric]) -> list[tuple[int, list[tuple[list[int], Any]]]]:
    """(carry slot, its groups): the metrics of one time reduction, spacecraft mode, gate and block are
    accumulated together (a :class:`_Stack`, in order of their first member), and the groups of one
    value shape (scalar, or one value per spacecraft) share one float64 array in the scan carry -- the
    accumulator blocks of the groups side by side along axis 1 -- written by one fused kernel per step;
    a stage-integrated metric stays alone, with its own entry. A group is ``(member indices, the
    _Stack or stage-integrated metric that accumulates them)``."""
    members: dict[Any, list[int]] = {}
    for i, m in enumerate(metrics):
        alone = i if m.reduce in STAGE_REDUCTIONS else None  # a stage-integrated metric: its own
        members.setdefault((m.reduce, m.spacecraft == "each", m.gate, m.block, alone), []).append(i)
    out: list[tuple[int, list[tuple[list[int], Any]]]] = []
    shared: dict[bool, int] = {}
    for idx in members.values():
        m = metrics[idx[0]]
        if m.reduce in STAGE_REDUCTIONS:
            out.append((idx[0], [(idx, m)]))
            continue
        each = m.spacecraft == "each"
        if each not in shared:
            shared[each] = len(out)
            out.append((idx[0], []))
        out[shared[each]][1].append((idx, _Stack([metrics[i] for i in idx])))
    return out


def _pack(parts: tuple, rows: int) -> jax.Array:
    """A group's accumulator tuple as one float64 array of ``rows`` rows (booleans as 0/1, zero padding)."""
    arrs = [jnp.asarray(x).astype(jnp.float64) for x in parts]
    arrs += [jnp.zeros_like(arrs[0])] * (rows - len(arrs))
    return jnp.stack(arrs)


def _packed(groups, parts: Iterable[tuple]) -> jax.Array:
    """The accumulator tuples ``parts`` of a class's groups as its one shared array (see :func:`_classes`);
    each part is packed as it comes (``parts`` may be a generator: each group's operations stay
    together in the traced program)."""
    rows = max(len(_START[g.reduce]) for _, g in groups)
    return jnp.concatenate([_pack(p, rows) for p in parts], axis=1)


def _blocks(groups, packed: jax.Array) -> list[tuple]:
    """The accumulator tuple of each group from the shared array."""
    out, col = [], 0
    for idx, g in groups:
        start = _START[g.reduce]  # False marks a boolean part
        rows = packed[: len(start), col : col + len(idx)]
        out.append(tuple(rows[j] != 0 if x is False else rows[j] for j, x in enumerate(start)))
        col += len(idx)
    return out


def _initial(m: Any, signals: Mapping[str, jax.Array]) -> tuple:
    """The accumulator tuple of a group (or stage-integrated metric) before any sample (of its value's
    shape, taken from the signals at t0)."""
    shape = jnp.shape(m.value(signals))
    return tuple(jnp.full(shape, x, dtype=type(x)) for x in _START[m.reduce])


def init_accumulators(metrics: Sequence[Metric], signals: Mapping[str, jax.Array]) -> tuple:
    """Initial accumulator of each metric (shapes taken from the signals at t0). Metrics accumulated
    together keep their common accumulator (one array, see :func:`_classes`) in the first member's
    entry (the others hold ``()``).

    Parameters
    ----------
    metrics : sequence of Metric
        The metrics.
    signals : mapping of str to array
        One sample of every signal the metrics read (SI units).

    Returns
    -------
    tuple
        One entry per metric (``()`` for the members after the first of a group).

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from formation_ftc.sim.metrics import Metric
    >>> from formation_ftc.sim.metrics import finalize, init_accumulators
    >>> ms = (Metric("peak", "e", reduce="max", units="m"), Metric("avg", "e", reduce="mean", units="m"))
    >>> accs = init_accumulators(ms, {"e": jnp.asarray(0.0)})
    >>> accs[1]  # the group's accumulator is held in the first entry
    ()
    >>> [float(v) for v in finalize(ms, accs)]  # no sample yet
    [nan, nan]
    """
    accs: list[Any] = [()] * len(metrics)
    for slot, groups in _classes(metrics):
        inits = (_initial(g, signals) for _, g in groups)
        accs[slot] = _packed(groups, inits) if isinstance(groups[0][1], _Stack) else next(inits)
    return tuple(accs)


def update_accumulators(
    metrics: Sequence[Metric],
    accs: tuple,
    t: jax.Array | float,
    dt: float,
    signals: Mapping[str, jax.Array],
    is_final: bool = False,
) -> tuple:
    """Fold the sample at time ``t`` into every accumulator (``is_final``: the sample at the horizon,
    which the rectangle-rule integral does not count).

    Parameters
    ----------
    metrics : sequence of Metric
        The metrics.
    accs : tuple
        Accumulators from :func:`init_accumulators` or an earlier update.
    t : float or jax.Array
        Time of the sample [s].
    dt : float
        Step [s] (weight of the rectangle-rule integral).
    signals : mapping of str to array
        The sample's signals (SI units).
    is_final : bool, optional
        The horizon sample.

    Returns
    -------
    tuple
        The updated accumulators.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from formation_ftc.sim.metrics import Metric
    >>> from formation_ftc.sim.metrics import finalize, init_accumulators, update_accumulators
    >>> ms = (Metric("peak", "e", reduce="max", units="m"), Metric("avg", "e", reduce="mean", units="m"),
    ...       Metric("area", "e", reduce="integral", units="m s"))
    >>> accs = init_accumulators(ms, {"e": jnp.asarray(0.0)})
    >>> for k, v in enumerate([1.0, 3.0, 2.0]):
    ...     accs = update_accumulators(ms, accs, t=0.1 * k, dt=0.1, signals={"e": jnp.asarray(v)})
    >>> [round(float(v), 6) for v in finalize(ms, accs)]
    [3.0, 2.0, 0.6]
    """

    def update(g, acc, v):
        return _update_group(g, acc, t, dt, v, is_final)

    return _each_group(metrics, accs, sample_values(metrics, signals, is_final), update)


def reads_steps(m: Metric) -> bool:
    """Whether ``m`` is accumulated from every step's sample (stage-integrated metrics are folded from
    the integrator's stages, ``last`` reads the horizon sample only).

    Parameters
    ----------
    m : Metric
        The metric.

    Returns
    -------
    bool
        True when the metric reads every step's sample.

    Examples
    --------
    >>> from formation_ftc.sim.metrics import Metric, reads_steps
    >>> reads_steps(Metric("peak", "e")), reads_steps(Metric("end", "e", reduce="last"))
    (True, False)
    """
    return m.reduce not in STAGE_REDUCTIONS and m.reduce != "last"


def block_signals(metrics: Sequence[Metric]) -> tuple[str, ...]:
    """Names of the signals :func:`fold_block` reads (the signals and gates of every metric that
    :func:`reads_steps`).

    Parameters
    ----------
    metrics : sequence of Metric
        The metrics.

    Returns
    -------
    tuple of str
        Signal names, in order of first use, each once.

    Examples
    --------
    >>> from formation_ftc.sim.metrics import Metric, block_signals
    >>> ms = (Metric("a", "e"), Metric("b", "f", gate="mode"), Metric("c", "e", reduce="mean"),
    ...       Metric("d", "g", reduce="last"))
    >>> block_signals(ms)
    ('e', 'f', 'mode')
    """
    names = (n for m in metrics if reads_steps(m) for n in (m.signal, m.gate) if n is not None)
    return tuple(dict.fromkeys(names))  # in order of first use, each once


def pack_sample(metrics: Sequence[Metric], signals: Mapping[str, jax.Array]) -> jax.Array:
    """The signals of :func:`block_signals` of one sample as one flat float64 vector (a scan then
    stacks one array per step instead of one per signal: each is a separate copy per step).

    Parameters
    ----------
    metrics : sequence of Metric
        The metrics.
    signals : mapping of str to array
        One sample's signals (SI units).

    Returns
    -------
    jax.Array, shape (F,)
        The signals of :func:`block_signals`, raveled and concatenated, as float64.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from formation_ftc.sim.metrics import Metric
    >>> import numpy as np
    >>> from formation_ftc.sim.metrics import pack_sample
    >>> ms = (Metric("a", "e", norm=True), Metric("b", "f"))
    >>> np.asarray(pack_sample(ms, {"e": jnp.array([3.0, 4.0]), "f": jnp.asarray(1.5)}))
    array([3. , 4. , 1.5])
    """
    return jnp.concatenate(
        [jnp.ravel(jnp.asarray(signals[n])).astype(jnp.float64) for n in block_signals(metrics)]
    )


def unpack_samples(
    metrics: Sequence[Metric], shapes: Mapping[str, Any], packed: jax.Array
) -> dict[str, jax.Array]:
    """Inverse of :func:`pack_sample` over a block: ``packed`` (L, F) -> ``{signal: (L, *shape)}`` in the
    signals' dtypes (``shapes``: each signal's shape and dtype, e.g. from ``jax.eval_shape``).

    Parameters
    ----------
    metrics : sequence of Metric
        The metrics.
    shapes : mapping of str to shape-and-dtype
        Each signal of :func:`block_signals` with ``.shape`` and ``.dtype`` (e.g. ``jax.ShapeDtypeStruct``).
    packed : jax.Array, shape (L, F)
        L packed samples.

    Returns
    -------
    dict of str to jax.Array
        ``{signal: (L, *shape)}``.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from formation_ftc.sim.metrics import Metric
    >>> import jax
    >>> import numpy as np
    >>> from formation_ftc.sim.metrics import pack_sample, unpack_samples
    >>> ms = (Metric("a", "e", norm=True), Metric("b", "f"))
    >>> samples = [{"e": jnp.array([3.0, 4.0]), "f": jnp.asarray(1.5)}, {"e": jnp.array([0.0, 1.0]), "f": jnp.asarray(2.5)}]
    >>> packed = jnp.stack([pack_sample(ms, s) for s in samples])
    >>> shapes = {"e": jax.ShapeDtypeStruct((2,), jnp.float64), "f": jax.ShapeDtypeStruct((), jnp.float64)}
    >>> out = unpack_samples(ms, shapes, packed)
    >>> np.asarray(out["e"]), np.asarray(out["f"])
    (array([[3., 4.],
           [0., 1.]]), array([1.5, 2.5]))
    """
    out, col = {}, 0
    for n in block_signals(metrics):
        shape, dtype = tuple(shapes[n].shape), shapes[n].dtype
        size = int(np.prod(shape, dtype=int))
        out[n] = jnp.reshape(packed[:, col : col + size], packed.shape[:1] + shape).astype(dtype)
        col += size
    return out


def sample_values(
    metrics: Sequence[Metric], signals: Mapping[str, jax.Array], is_final: bool = False
) -> tuple:
    """What one sample contributes to the accumulators, per carry slot of :func:`_classes`: a group's
    stacked values and gate (``(value, gate)``; ``gate`` None without one); ``None`` for the
    stage-integrated metrics (folded by :func:`update_stage_accumulators`) and, except at the horizon
    sample, for ``last``. The values are taken apart from the accumulator update so that a block of
    samples can be evaluated in one vectorised operation (:func:`fold_block`).

    Parameters
    ----------
    metrics : sequence of Metric
        The metrics.
    signals : mapping of str to array
        One sample's signals (SI units).
    is_final : bool, optional
        The horizon sample.

    Returns
    -------
    tuple
        One entry per carry slot: a tuple of ``(values, gate)`` per group, or None.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from formation_ftc.sim.metrics import Metric
    >>> import numpy as np
    >>> from formation_ftc.sim.metrics import sample_values
    >>> ms = (Metric("peak", "e"), Metric("avg", "e", reduce="mean"))
    >>> (slot,) = sample_values(ms, {"e": jnp.asarray(2.0)})  # both scalar: one carry slot
    >>> [(np.asarray(v), gate) for v, gate in slot]  # one (values, gate) per group
    [(array([2.]), None), (array([2.]), None)]
    """
    return tuple(
        tuple(_group_sample(g, signals, is_final) for _, g in groups)
        if isinstance(groups[0][1], _Stack)
        else None
        for _, groups in _classes(metrics)
    )


def _group_sample(g: _Stack, signals: Mapping[str, jax.Array], is_final: bool) -> Any:
    """A group's ``(values, gate)`` of one sample (None for ``last`` before the horizon)."""
    if g.reduce == "last" and not is_final:
        return None
    gate = None if g.gate is None else jnp.asarray(signals[g.gate]) > 0
    return g.value(signals), gate


def _each_group(metrics: Sequence[Metric], accs: tuple, values: tuple, update) -> tuple:
    """The accumulators with ``update(group, its accumulator tuple, its values)`` applied to every
    stacked group (unpacked from and packed back into its class's shared array); the stage-integrated
    entries are left to :func:`update_stage_accumulators`."""
    out = list(accs)
    for (slot, groups), vals in zip(_classes(metrics), values, strict=True):
        if isinstance(groups[0][1], _Stack):
            parts = zip(groups, _blocks(groups, accs[slot]), vals, strict=True)
            out[slot] = _packed(groups, (update(g, acc, v) for (_, g), acc, v in parts))
    return tuple(out)


def fold_block(
    metrics: Sequence[Metric],
    accs: tuple,
    k0: jax.Array,
    t0: float,
    dt: float,
    samples: Mapping[str, jax.Array],
) -> tuple:
    """Fold a block of consecutive samples (steps ``k0 .. k0 + L - 1``, every signal of
    :func:`block_signals` with a leading axis of length L) into the accumulators: the result of
    :func:`update_accumulators` applied to the samples one by one.

    Everything is computed for the whole block at once -- the metric values, then each group's
    reduction over the block's samples (:func:`_fold_group`) -- instead of one small kernel per metric
    and step. The selections (extremes, first / last / settling samples) are the same values bit for
    bit; the sums (``mean``, ``integral``, ``rms``, the block reductions) add the block's samples first
    and then to the running sum, so they may differ from the sample-by-sample order in the last bits.

    Parameters
    ----------
    metrics : sequence of Metric
        The metrics.
    accs : tuple
        Accumulators before the block.
    k0 : int or jax.Array
        Step index of the block's first sample.
    t0 : float
        Start time of the run [s] (sample j is at ``t0 + (k0 + j) dt``).
    dt : float
        Step [s].
    samples : mapping of str to array
        Every signal of :func:`block_signals` with a leading axis of length L.

    Returns
    -------
    tuple
        The accumulators after the block.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from formation_ftc.sim.metrics import Metric
    >>> from formation_ftc.sim.metrics import finalize, fold_block, init_accumulators
    >>> ms = (Metric("peak", "e"), Metric("avg", "e", reduce="mean"), Metric("t_hit", "e", reduce="first",
    ...                                                                      threshold=2.5, units="s"))
    >>> accs = init_accumulators(ms, {"e": jnp.asarray(0.0)})
    >>> accs = fold_block(ms, accs, k0=0, t0=0.0, dt=0.1, samples={"e": jnp.array([1.0, 3.0, 2.0])})
    >>> [round(float(v), 6) for v in finalize(ms, accs)]
    [3.0, 2.0, 0.1]
    """
    n = jax.tree_util.tree_leaves(samples)[0].shape[0]
    values = jax.vmap(lambda s: sample_values(metrics, s))(samples)
    times = t0 + (k0 + jnp.arange(n, dtype=jnp.int64)) * dt

    def fold(g, acc, v):
        return acc if g.reduce == "last" else _fold_group(g, acc, times, dt, v)

    return _each_group(metrics, accs, values, fold)


def _fold_group(m: Any, acc: tuple, times: jax.Array, dt: float, value: tuple) -> tuple:
    """:func:`_update_group` over a block of samples (leading axis ``j``), computed at once."""
    v, gate = value
    t = jnp.reshape(times, times.shape + (1,) * (v.ndim - 1))
    inw = _in_window(m, t)
    if gate is not None:  # a gate of one sample broadcasts against its values from the right
        gs = gate.shape[1:]
        inw = jnp.logical_and(
            inw, jnp.reshape(gate, gate.shape[:1] + (1,) * (v.ndim - 1 - len(gs)) + gs)
        )
    inw = jnp.broadcast_to(inw, v.shape)
    t = jnp.broadcast_to(t, v.shape)
    n = v.shape[0]
    idx = jnp.reshape(jnp.arange(n), (n,) + (1,) * (v.ndim - 1))
    anyw = jnp.any(inw, axis=0)
    count = jnp.sum(inw, axis=0).astype(jnp.float64)

    def first_of(mask):  # index of the first true sample (n when none)
        return jnp.min(jnp.where(mask, idx, n), axis=0)

    def last_of(mask):  # index of the last true sample (-1 when none)
        return jnp.max(jnp.where(mask, idx, -1), axis=0)

    if m.reduce in _EXTREMES:
        (a, seen), (pair, over, start) = acc, _EXTREMES[m.reduce]
        extreme = getattr(jnp, over)(jnp.where(inw, v, start), axis=0)
        return (getattr(jnp, pair)(a, extreme), seen | anyw)
    if m.reduce == "final":
        a, seen = acc
        return (jnp.where(anyw, _at(v, last_of(inw)), a), seen | anyw)
    if m.reduce == "at":
        a, seen = acc
        return (jnp.where(anyw & jnp.logical_not(seen), _at(v, first_of(inw)), a), seen | anyw)
    if m.reduce in ("mean", "integral", "rms"):
        s, c = acc
        return (s + jnp.sum(jnp.where(inw, _summand(m.reduce, v, dt), 0.0), axis=0), c + count)
    if m.reduce in BLOCK_REDUCTIONS:
        return _fold_blocks(m, acc, v, inw)
    above = jnp.logical_not(v < m.threshold)
    if m.reduce == "first":
        ts, found = acc
        hits = inw & above
        hit = jnp.any(hits, axis=0) & jnp.logical_not(found)
        return (jnp.where(hit, _at(t, first_of(hits)), ts), found | hit)
    # settle / settle_delay: after the block, the settle time is the time of the first in-window sample
    # following the last one at or above the threshold (NaN when that is the block's last in-window
    # sample); without one in the block, the first in-window sample's time when the run was above
    # before (or had no sample yet), else unchanged
    ts, seen, last_above = acc
    j_above = last_of(inw & above)
    after = first_of(inw & (idx > j_above))
    ts_above = jnp.where(after < n, _at(t, after), jnp.nan)
    ts_below = jnp.where(last_above | jnp.logical_not(seen), _at(t, first_of(inw)), ts)
    ts_new = jnp.where(j_above >= 0, ts_above, ts_below)
    return (
        jnp.where(anyw, ts_new, ts),
        seen | anyw,
        jnp.where(anyw, _at(above, last_of(inw)), last_above),
    )


def _fold_blocks(m: Any, acc: tuple, v: jax.Array, inw: jax.Array) -> tuple:
    """``block_rms`` / ``block_dev_rms`` over a block of L samples at once. The in-window samples
    continue the open boxcar block (``n`` samples so far); sample j joins block
    ``(n + its rank among the in-window samples) // block`` (0: the open one), and every block whose
    ``block`` samples are complete is closed. At most ``(L + block - 1) // block + 1`` blocks are
    touched; their sums are one-hot sums over the samples."""
    size = m.block
    n_open = acc[3] if m.reduce == "block_dev_rms" else acc[1]
    rank = jnp.cumsum(inw.astype(jnp.int64), axis=0)  # in-window samples up to and including j
    total = rank[-1]
    filled = n_open.astype(jnp.int64) + total
    closed = filled // size  # blocks completed by this fold (the open one counts as 0)
    seg = (n_open.astype(jnp.int64) + rank - 1) // size  # block of sample j (when in window)
    nseg = (v.shape[0] + size - 1) // size + 1
    b = jnp.reshape(jnp.arange(nseg), (nseg,) + (1,) * v.ndim)
    member = jnp.logical_and(inw[None], seg[None] == b)  # (segment, j, ...)
    done = b[:, 0] < closed[None]  # segment closed by this fold
    rem = (filled - closed * size).astype(jnp.float64)  # samples of the new open block

    if m.reduce == "block_rms":
        s, _, q, nb = acc
        sums = jnp.sum(jnp.where(member, v[None], 0.0), axis=1)
        sums = sums.at[0].add(s)
        mean = sums / size
        q = q + jnp.sum(jnp.where(done, mean * mean, 0.0), axis=0)
        return (_at(sums, closed), rem, q, nb + closed.astype(jnp.float64))
    # block_dev_rms: each block's values shifted by its first value (the open block keeps its shift)
    shift0, s1, s2, _, q, nq = acc
    first_j = jnp.argmax(member, axis=1)  # first sample of each segment (0 when it has none)
    shifts = jnp.take_along_axis(v[None], first_j[:, None], axis=1)[:, 0]
    shifts = jnp.where((b[:, 0] == 0) & (n_open > 0)[None], shift0[None], shifts)
    d = jnp.where(member, v[None] - shifts[:, None], 0.0)
    sum1 = jnp.sum(d, axis=1).at[0].add(s1)
    sum2 = jnp.sum(d * d, axis=1).at[0].add(s2)
    dev = sum2 - sum1 * sum1 / size
    q = q + jnp.sum(jnp.where(done, dev, 0.0), axis=0)
    shift = jnp.where(
        rem > 0, _at(shifts, closed), jnp.where(total > 0, _at(shifts, closed - 1), shift0)
    )
    open_sums = [_at(x, closed) for x in (sum1, sum2)]  # of the new open block
    return (shift, *open_sums, rem, q, nq + (closed * size).astype(jnp.float64))


def _at(x: jax.Array, i: jax.Array) -> jax.Array:
    """``x[i]`` along axis 0 (``i`` clipped to its length), per element of the other axes."""
    return jnp.take_along_axis(x, jnp.clip(i, 0, x.shape[0] - 1)[None], axis=0)[0]


def _summand(reduce: str, v: jax.Array, dt: float) -> jax.Array:
    """What a sample adds to the sum of ``mean`` (its value), ``integral`` (a rectangle) or ``rms``."""
    return v if reduce == "mean" else v * dt if reduce == "integral" else v * v


def _in_window(m: Any, t: Any) -> jax.Array:
    """Whether time(s) ``t`` lie in the metric's window (edges inclusive to :data:`_TOL`)."""
    return jnp.logical_and(t >= m.start - _TOL, t <= m.end + _TOL)


def _update_group(
    m: Any, acc: tuple, t: jax.Array | float, dt: float, value: Any, is_final: bool
) -> tuple:
    """One group's (or metric's) accumulator after the sample ``value = (v, gate)`` at time ``t``."""
    if m.reduce == "last":  # only the horizon sample (a static branch: nothing at the steps)
        return (value[0], jnp.ones_like(acc[1])) if is_final else acc
    v, gate = value
    inw = _in_window(m, t)
    if gate is not None:
        inw = jnp.logical_and(inw, gate)
    if m.reduce in _EXTREMES:
        a, seen = acc
        return (jnp.where(inw, getattr(jnp, _EXTREMES[m.reduce][0])(a, v), a), seen | inw)
    if m.reduce == "final":
        a, seen = acc
        return (jnp.where(inw, v, a), seen | inw)
    if m.reduce == "at":
        a, seen = acc
        take = jnp.logical_and(inw, jnp.logical_not(seen))
        return (jnp.where(take, v, a), seen | inw)
    if m.reduce in ("mean", "integral", "rms"):  # the horizon sample: no rectangle, not in the rms
        s, n = acc
        take = jnp.logical_and(inw, not is_final) if m.reduce == "rms" else inw
        x = _summand(m.reduce, v, 0.0 if is_final else dt)
        return (s + jnp.where(take, x, 0.0), n + jnp.where(take, 1.0, 0.0))
    if m.reduce in ("settle", "settle_delay"):
        ts, seen, last_above = acc
        above = jnp.logical_not(v < m.threshold)
        first = jnp.logical_and(inw, jnp.logical_not(seen))
        # settle time = time of the first in-window sample below the threshold following a sample
        # at or above it (the window start when it never was above); NaN while it is above
        ts_new = jnp.where(above, jnp.nan, jnp.where(first | last_above, t, ts))
        return (jnp.where(inw, ts_new, ts), seen | inw, jnp.where(inw, above, last_above))
    if m.reduce == "first":
        ts, found = acc
        hit = inw & jnp.logical_not(v < m.threshold) & jnp.logical_not(found)
        return (jnp.where(hit, t, ts), found | hit)
    if m.reduce == "block_rms":
        s, n, q, nb = acc
        take = jnp.logical_and(inw, not is_final)
        s, n = s + jnp.where(take, v, 0.0), n + jnp.where(take, 1.0, 0.0)
        full = n >= m.block  # the block closes: fold its mean in, open the next one
        mean = s / m.block
        cleared = [jnp.where(full, 0.0, a) for a in (s, n)]  # a closed block's sums start again
        return (*cleared, q + jnp.where(full, mean * mean, 0.0), nb + jnp.where(full, 1.0, 0.0))
    if m.reduce == "block_dev_rms":
        # shifted sums (shift = the block's first value): no cancellation when the mean is large
        shift, s1, s2, n, q, nq = acc
        take = jnp.logical_and(inw, not is_final)
        shift = jnp.where(take & (n == 0), v, shift)
        d = jnp.where(take, v - shift, 0.0)
        s1, s2, n = s1 + d, s2 + d * d, n + jnp.where(take, 1.0, 0.0)
        full = n >= m.block
        dev = s2 - s1 * s1 / m.block  # sum over the block of (v - block mean)^2
        cleared = [jnp.where(full, 0.0, a) for a in (s1, s2, n)]  # as block_rms
        return (shift, *cleared, q + jnp.where(full, dev, 0.0), nq + jnp.where(full, n, 0.0))
    raise AssertionError(f"unhandled reduction {m.reduce!r}")  # pragma: no cover - checked


def finalize(metrics: Sequence[Metric], accs: tuple) -> tuple:
    """Accumulators -> metric values (NaN where the window held no sample).

    Parameters
    ----------
    metrics : sequence of Metric
        The metrics.
    accs : tuple
        Their accumulators.

    Returns
    -------
    tuple of jax.Array
        One value per metric (scalar, or (N,) for ``spacecraft = "each"``), in the metric's units.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from formation_ftc.sim.metrics import Metric
    >>> from formation_ftc.sim.metrics import finalize, init_accumulators, update_accumulators
    >>> ms = (Metric("low", "e", reduce="min", start=0.15, units="m"), Metric("rms", "e", reduce="rms", units="m"))
    >>> accs = init_accumulators(ms, {"e": jnp.asarray(0.0)})
    >>> for k, v in enumerate([3.0, 4.0, 1.0]):
    ...     accs = update_accumulators(ms, accs, t=0.1 * k, dt=0.1, signals={"e": jnp.asarray(v)})
    >>> [round(float(v), 6) for v in finalize(ms, accs)]
    [1.0, 2.94392]
    """
    out: list[Any] = [None] * len(metrics)
    for slot, groups in _classes(metrics):
        if not isinstance(groups[0][1], _Stack):
            out[slot] = _final_value(groups[0][1], accs[slot])
            continue
        for (idx, g), acc in zip(groups, _blocks(groups, accs[slot]), strict=True):
            values = _final_value(g, acc)
            for j, i in enumerate(idx):
                out[i] = values[j]
    return tuple(out)


def _final_value(m: Any, acc: tuple) -> jax.Array:
    """The value of a group (or stage-integrated metric) from its accumulator tuple."""
    if m.reduce in ("max", "min", "final", "at", "last"):
        a, seen = acc
        return jnp.where(seen, a, jnp.nan)
    if m.reduce in ("mean", "rms"):
        s, n = acc
        seen, mean = n > 0, s / jnp.maximum(n, 1.0)
        return jnp.where(seen, mean if m.reduce == "mean" else jnp.sqrt(mean), jnp.nan)
    if m.reduce in ("integral", "stage_integral"):
        s, n = acc
        return jnp.where(n > 0, s, jnp.nan)
    if m.reduce in ("settle", "first"):
        return acc[0]
    if m.reduce == "settle_delay":
        return acc[0] - m.start
    if m.reduce == "stage_root_mean":
        s, n = acc
        return jnp.where(n > 0, jnp.sqrt(s / (m.end - m.start)), jnp.nan)
    # the block reductions: (..., sum of squares, closed blocks or their samples)
    *_, q, n = acc
    if m.reduce == "block_dev_rms":  # a sum of squared deviations (rounding may go below 0)
        q = jnp.maximum(q, 0.0)
    return jnp.where(n > 0, jnp.sqrt(q / jnp.maximum(n, 1.0)), jnp.nan)


def stage_values(metrics: Sequence[Metric], signals: Mapping[str, jax.Array]) -> tuple:
    """Values of the stage-integrated metrics at one integrator stage (None for the others).

    Parameters
    ----------
    metrics : sequence of Metric
        The metrics.
    signals : mapping of str to array
        The signals at one integrator stage (SI units).

    Returns
    -------
    tuple
        The value of each stage-integrated metric, None for the others.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from formation_ftc.sim.metrics import Metric
    >>> from formation_ftc.sim.metrics import stage_values
    >>> ms = (Metric("effort", "command", reduce="stage_integral", norm=True, square=True, spacecraft="sum",
    ...              units="N2 s"), Metric("peak", "command", norm=True, spacecraft="max", units="N"))
    >>> values = stage_values(ms, {"command": jnp.array([[1.0, 2.0, 2.0]])})
    >>> float(values[0]), values[1]
    (9.0, None)
    """
    return tuple(m.value(signals) if m.reduce in STAGE_REDUCTIONS else None for m in metrics)


def update_stage_accumulators(
    metrics: Sequence[Metric], accs: tuple, t_k: jax.Array, dt: float, increments: Sequence[Any]
) -> tuple:
    """Add the integral over the step [t_k, t_k + dt] (``increments``, from the integrator's stages) to
    every stage-integrated metric whose window contains the whole step.

    Parameters
    ----------
    metrics : sequence of Metric
        The metrics.
    accs : tuple
        Their accumulators.
    t_k : jax.Array or float
        Start of the step [s].
    dt : float
        Step [s].
    increments : sequence
        Integral over the step of each stage-integrated metric's value (None for the others) [signal
        unit x s].

    Returns
    -------
    tuple
        The updated accumulators.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from formation_ftc.sim.metrics import Metric
    >>> from formation_ftc.sim.metrics import finalize, init_accumulators, update_stage_accumulators
    >>> ms = (Metric("effort", "command", reduce="stage_integral", norm=True, square=True, spacecraft="sum",
    ...              units="N2 s"),)
    >>> accs = init_accumulators(ms, {"command": jnp.zeros((1, 3))})
    >>> for k in range(2):
    ...     accs = update_stage_accumulators(ms, accs, t_k=0.1 * k, dt=0.1, increments=(jnp.asarray(0.9),))
    >>> round(float(finalize(ms, accs)[0]), 6)
    1.8
    """

    def update(m, acc, inc):
        if m.reduce not in STAGE_REDUCTIONS:
            return acc
        s, n = acc
        inw = jnp.logical_and(t_k >= m.start - _TOL, t_k + dt <= m.end + _TOL)
        return jnp.where(inw, s + inc, s), n + jnp.where(inw, 1.0, 0.0)

    return tuple(update(*args) for args in zip(metrics, accs, increments, strict=True))


def metrics_dict(metrics: Sequence[Metric], values: Sequence[Any]) -> dict[str, float]:
    """Numpy metric values -> flat ``{name: float}``.

    Parameters
    ----------
    metrics : sequence of Metric
        The metrics.
    values : sequence of array_like
        Their values (from :func:`finalize`), in the metrics' units.

    Returns
    -------
    dict of str to float
        Names as :func:`metric_names` gives them.

    Examples
    --------
    >>> from formation_ftc.sim.metrics import Metric, metrics_dict
    >>> ms = (Metric("peak", "e", spacecraft="each", units="m"), Metric("t_end", "e", reduce="last", units="m"))
    >>> metrics_dict(ms, ([1.0, 2.0], 0.5))
    {'peak_sc1': 1.0, 'peak_sc2': 2.0, 't_end': 0.5}
    """
    res: dict[str, float] = {}
    for m, v in zip(metrics, values, strict=True):
        arr = np.asarray(v, dtype=float)
        each = arr.reshape(-1) if m.spacecraft == "each" else [arr]
        res.update(zip(metric_names([m], len(each)), map(float, each), strict=True))
    return res
