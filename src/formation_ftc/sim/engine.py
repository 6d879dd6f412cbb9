"""The fixed-step ``lax.scan`` driver shared by every method.

One control step (the order every method follows; docs/architecture.md "One control step")::

    k -> (1) measure -> (2) network: push/read delayed messages -> (3) FDI, observers
      -> (4) supervisor -> (5) controller -> (6) actuator chain (faults act here)
      -> (7) integrate the plant over [t_k, t_k + dt] (RK4; continuous-time laws evaluated per stage)
      -> (8) push histories, accumulate metrics

A method supplies ``step(k, state) -> state`` (everything above; ``t_k = t0 + k*dt`` is computed from
the integer step index, so event times are exact step boundaries) and ``observe(k, state) -> dict``
(what to record). :func:`run_fixed_step` runs ``n_steps`` steps as a scan over records of
``record_every`` inner steps each (output decimation: a 3-million-step run keeps only
``n_steps/record_every + 1`` samples; metrics that need every step live in the state and are
accumulated by ``step``).

Divergence: at the end of every record block the state (or the part ``check_of`` selects) is checked
for non-finite values. The first non-finite block records its first step index; a snapshot of the
state at that block's start (the last finite state) is kept and returned, and the records after it
(non-finite) are masked out by :func:`trim_records`. :func:`diagnose_divergence` then replays the block
(one compiled loop) to name the time, variable and spacecraft. The snapshot is a separate carry (one
select per block), never a select on the running state: under ``jax.vmap`` a per-run select would make
every state leaf batched, even those that depend only on parameters shared by all runs (the reference
orbit of Li2020), and multiply their cost by the batch size.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from formation_ftc.sim.runtime import xla

__all__ = [
    "RunOutput",
    "run_fixed_step",
    "trim_records",
    "SimulationDiverged",
    "DivergenceInfo",
    "diagnose_divergence",
    "steps_from_horizon",
]

PyTree = Any


#: A run's output: a plain dict (a JAX pytree) with keys ``records`` (pytree, leading axis = record
#: index), ``final`` (final state), ``diverged_step`` (int, -1 when the run stayed finite) and
#: ``last_finite`` (the last finite state, equal to ``final``; kept as a separate name for clarity).
RunOutput = dict


def steps_from_horizon(
    horizon: float, dt: float, record_every: int = 1, field: str = "simulation"
) -> int:
    """Number of steps for ``horizon``; the step must divide the horizon (to 1e-9 relative).

    Parameters
    ----------
    horizon : float
        Simulated time (> 0) [s].
    dt : float
        Step (> 0) [s].
    record_every : int, optional
        Steps between records; must divide the step count.
    field : str, optional
        Section name used in the error messages.

    Returns
    -------
    int
        ``horizon / dt``.

    Raises
    ------
    ValueError
        Non-positive ``dt`` or ``horizon``, ``dt`` not dividing ``horizon``, or ``record_every`` not
        dividing the step count.

    Examples
    --------
    >>> from formation_ftc.sim.engine import steps_from_horizon
    >>> steps_from_horizon(600.0, 0.1, record_every=10)
    6000
    >>> steps_from_horizon(10.0, 0.3)
    Traceback (most recent call last):
    ...
    ValueError: simulation.dt = 0.3 s does not divide simulation.horizon = 10.0 s
    """
    if dt <= 0:
        raise ValueError(f"{field}.dt must be > 0 s, got {dt}")
    if horizon <= 0:
        raise ValueError(f"{field}.horizon must be > 0 s, got {horizon}")
    n = round(horizon / dt)
    if abs(n * dt - horizon) > 1e-9 * max(horizon, 1.0):
        raise ValueError(f"{field}.dt = {dt} s does not divide {field}.horizon = {horizon} s")
    if n % record_every:
        raise ValueError(
            f"{field}.record_every = {record_every} must divide the number of steps {n} (horizon/dt)"
        )
    return n


def _all_finite(tree) -> jax.Array:
    leaves = [
        jnp.all(jnp.isfinite(x))
        for x in jax.tree_util.tree_leaves(tree)
        if jnp.issubdtype(jnp.asarray(x).dtype, jnp.inexact)
    ]
    return jnp.all(jnp.stack(leaves)) if leaves else jnp.asarray(True)


def run_fixed_step(
    step: Callable[[jax.Array, PyTree], PyTree],
    observe: Callable[[jax.Array, PyTree], PyTree],
    state0: PyTree,
    n_steps: int,
    record_every: int = 1,
    unroll: int = 1,
    check_finite: bool = True,
    check_of: Callable[[PyTree], PyTree] | None = None,
    admissible: Callable[[PyTree], jax.Array] | None = None,
    fold: Callable[[jax.Array, PyTree, PyTree], PyTree] | None = None,
    fold_every: int = 1,
) -> RunOutput:
    """Run ``n_steps`` steps; record ``observe`` at k = 0, record_every, 2*record_every, ..., n_steps.

    Pure and jittable (``n_steps`` and ``record_every`` are static). Finiteness is tested once per
    record block (every ``record_every`` steps, so the check costs nothing per step); ``check_of(state)``
    selects the part of the state tested (default: all of it); ``admissible(state) -> bool`` narrows the
    admissible set further (e.g. positions within a bound). When a block ends outside it, the state
    at that block's start -- the last finite state -- is returned as ``final``/``last_finite`` and
    ``diverged_step`` is the block's first step (the run itself goes on to the horizon; its later
    records are not finite and :func:`trim_records` drops them); :func:`diagnose_divergence` replays the block to find
    the exact step and variable. ``observe`` is traced once (one scan over ``n_records + 1`` record
    points, the last of which only records). Returns a :data:`RunOutput`.

    ``fold``: with it, ``step(k, state)`` returns ``(state, sample)`` and every ``fold_every`` steps
    (a divisor of ``record_every``) ``fold(k_first, state, samples)`` receives the samples of those
    steps stacked along a leading axis (k_first: the first one's step index) and returns the state --
    per-step bookkeeping (metric accumulators) done once per block of steps, in vectorised form.

    Parameters
    ----------
    step : callable
        ``step(k, state) -> state`` (``(state, sample)`` with ``fold``); k is the int64 step index
        (``t_k = t0 + k dt`` [s]).
    observe : callable
        ``observe(k, state) -> pytree`` recorded every ``record_every`` steps.
    state0 : pytree
        Initial state (SI units).
    n_steps : int
        Number of steps (static).
    record_every : int, optional
        Steps between records (a divisor of ``n_steps``; static).
    unroll : int, optional
        ``lax.scan`` unroll of the inner loop.
    check_finite : bool, optional
        Test the state for non-finite values at the end of every record block.
    check_of : callable, optional
        ``check_of(state)``: the part of the state tested.
    admissible : callable, optional
        ``admissible(state) -> bool``: further bounds of the admissible set.
    fold : callable, optional
        ``fold(k_first, state, samples) -> state``: per-step bookkeeping folded a block at a time.
    fold_every : int, optional
        Steps per fold (a divisor of ``record_every``).

    Returns
    -------
    RunOutput
        ``{"records", "final", "diverged_step", "last_finite"}``: the records (leading axis
        ``n_steps / record_every + 1``), the final (or last finite) state, the first step of the first
        failing block (-1 when none) and the last finite state.

    Raises
    ------
    ValueError
        ``record_every`` does not divide ``n_steps`` or ``fold_every`` does not divide ``record_every``.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> import numpy as np
    >>> from formation_ftc.sim.engine import run_fixed_step
    >>> out = run_fixed_step(lambda k, x: 0.5 * x, lambda k, x: {"x": x}, jnp.asarray(1.0), n_steps=4,
    ...                      record_every=2)
    >>> np.asarray(out["records"]["x"]), int(out["diverged_step"])
    (array([1.    , 0.25  , 0.0625]), -1)

    A run that overflows keeps its last finite state and dates the failing block:

    >>> out = run_fixed_step(lambda k, x: 1e200 * x, lambda k, x: {"x": x}, jnp.asarray(1.0), n_steps=4)
    >>> int(out["diverged_step"]), float(out["final"])
    (1, 1e+200)
    """
    if n_steps % record_every:
        raise ValueError(f"record_every={record_every} must divide n_steps={n_steps}")
    if fold is not None and (fold_every < 1 or record_every % fold_every):
        raise ValueError(f"fold_every={fold_every} must divide record_every={record_every}")
    n_records = n_steps // record_every
    select = check_of if check_of is not None else (lambda s: s)

    def inner(carry, _):
        k, state = carry
        return (k + 1, step(k, state)), None

    # the state after a record block ([0][1]: the state of a scan's final carry (k, state))
    def block(k, state):
        if fold is None:
            return jax.lax.scan(inner, (k, state), None, length=record_every, unroll=unroll)[0][1]

        def emitting(carry, _):
            k, state = carry
            state, sample = step(k, state)
            return (k + 1, state), sample

        def folded(carry, _):
            k, state = carry
            (k_next, state), samples = jax.lax.scan(
                emitting, (k, state), None, length=fold_every, unroll=unroll
            )
            return (k_next, fold(k, state, samples)), None

        if fold_every == record_every:
            return folded((k, state), None)[0][1]
        return jax.lax.scan(folded, (k, state), None, length=record_every // fold_every)[0][1]

    def outer(carry, _):
        k, state, div, frozen = carry
        # the record at t_k (the initial one is the first iteration's: one ``observe`` in the loop, fewer
        # operations to lower and compile); of the running state, never of the snapshot (under vmap
        # that would evaluate the run-independent leaves per run)
        rec = observe(k, state)
        # taken while k < n_steps (k is never batched, so this stays a conditional under vmap); the
        # extra last iteration only records. XLA:CPU also compiles the block's inner loop faster inside
        # a conditional than inline -- measured 2.8 s vs 3.9-4.4 s for the 300,000-step li2020-thm2-delays run
        new = jax.lax.cond(k < n_steps, lambda: block(k, state), lambda: state)
        if check_finite:
            ok = _all_finite(select(new))
            if admissible is not None:
                ok = jnp.logical_and(ok, admissible(new))
            div = jnp.where(jnp.logical_and(div < 0, jnp.logical_not(ok)), k, div)
            # the last finite state is kept in a separate snapshot, updated once per block; the
            # running state itself is never selected, so under ``vmap`` leaves that do not depend on
            # the batched parameters (reference orbit, desired trajectory, ...) stay unbatched
            frozen = jax.tree_util.tree_map(lambda f, n: jnp.where(div >= 0, f, n), frozen, new)
        return (k + record_every, new, div, frozen), rec

    k0, div0 = jnp.asarray(0, dtype=jnp.int64), jnp.asarray(-1, dtype=jnp.int64)
    carry0 = (k0, state0, div0, state0 if check_finite else None)
    (_, final, div, frozen), records = jax.lax.scan(outer, carry0, None, length=n_records + 1)
    final = frozen if check_finite else final
    return dict(records=records, final=final, diverged_step=div, last_finite=final)


def trim_records(records: PyTree, diverged_step: int, record_every: int) -> tuple[PyTree, int]:
    """Keep the records computed before divergence (all of them when ``diverged_step < 0``).

    Parameters
    ----------
    records : pytree
        Records of :func:`run_fixed_step` (leading axis = record index).
    diverged_step : int
        ``RunOutput["diverged_step"]`` (-1: the run stayed finite).
    record_every : int
        Steps between records.

    Returns
    -------
    records : pytree
        The records up to the first failing block's start (numpy arrays when trimmed).
    n_records : int
        How many were kept.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.sim.engine import trim_records
    >>> records = {"x": np.array([1.0, 1e200, np.inf, np.inf, np.inf])}
    >>> trim_records(records, diverged_step=1, record_every=1)
    ({'x': array([1.e+000, 1.e+200])}, 2)
    >>> trim_records(records, diverged_step=-1, record_every=1)[1]
    5
    """
    n = jax.tree_util.tree_leaves(records)[0].shape[0]
    if diverged_step < 0:
        return records, n
    keep = int(diverged_step) // record_every + 1
    return jax.tree_util.tree_map(lambda a: np.asarray(a)[:keep], records), keep


@dataclass(frozen=True)
class DivergenceInfo:
    step: int
    time: float
    variable: str
    spacecraft: int | None  # 0-based index, None when the variable has no spacecraft axis
    index: tuple[int, ...]
    reason: str = "became non-finite"

    def __str__(self) -> str:
        who = f"spacecraft {self.spacecraft + 1}" if self.spacecraft is not None else "formation"
        return (
            f"simulation diverged at t = {self.time:.6g} s (step {self.step}): {who}, "
            f"variable '{self.variable}' index {list(self.index)} {self.reason}"
        )


class SimulationDiverged(RuntimeError):
    """A run produced a non-finite state. ``partial`` holds what was computed up to then."""

    def __init__(self, info: DivergenceInfo, partial: Any = None):
        super().__init__(str(info) + "; results up to that time were kept")
        self.info = info
        self.partial = partial


def _path_name(path) -> str:
    """'x.rho' for a pytree path of dict keys, attribute names (named tuples) and list indices."""
    return jax.tree_util.keystr(tuple(path), simple=True, separator=".")


def _nonfinite_leaves(tree) -> list[tuple[Any, np.ndarray, tuple[int, ...]]]:
    """(path, array, index of the first non-finite entry) of every inexact leaf that is not finite."""
    out = []
    for path, leaf in jax.tree_util.tree_flatten_with_path(tree)[0]:
        arr = np.asarray(leaf)
        if not np.issubdtype(arr.dtype, np.inexact):
            continue
        finite = np.isfinite(arr)
        if not finite.all():  # (a 0-d leaf has no argwhere rows: its index is ())
            idx = tuple(int(v) for v in np.argwhere(~finite)[0]) if arr.ndim else ()
            out.append((path, arr, idx))
    return out


_CALL_JAXPR_PARAMS = ("jaxpr", "call_jaxpr", "fun_jaxpr")


def _var_deps(env: dict, v) -> frozenset:
    return frozenset() if type(v).__name__ == "Literal" else env.get(v, frozenset())


def _propagate(jaxpr, in_deps: list[frozenset]) -> list[frozenset]:
    """Which inputs each output of ``jaxpr`` depends on (structural; loops are treated as mixing all
    their inputs, which can only over-state a dependency)."""
    env: dict = dict(zip(jaxpr.invars, in_deps, strict=True))
    for eqn in jaxpr.eqns:
        ins = [_var_deps(env, v) for v in eqn.invars]
        outs = None
        sub = next((eqn.params[n] for n in _CALL_JAXPR_PARAMS if n in eqn.params), None)
        if eqn.primitive.name == "cond" and "branches" in eqn.params:
            pred, ops = ins[0], ins[1:]
            per = [_propagate(b.jaxpr, ops) for b in eqn.params["branches"]]
            outs = [pred.union(*cols) for cols in zip(*per, strict=True)]
        elif sub is not None and eqn.primitive.name not in ("scan", "while"):
            inner = getattr(sub, "jaxpr", sub)
            if len(inner.invars) == len(ins) and len(inner.outvars) == len(eqn.outvars):
                outs = _propagate(inner, ins)
        if outs is None:
            outs = [frozenset().union(*ins)] * len(eqn.outvars)  # everything
        for v, d in zip(eqn.outvars, outs, strict=True):
            env[v] = d
    return [_var_deps(env, v) for v in jaxpr.outvars]


#: steps replayed past a step where only accumulators became non-finite, looking for their cause
_FOLLOW_STEPS = 20


def _info(bad: tuple, k: int, t: float, spacecraft_axis) -> DivergenceInfo:
    path, arr, idx = bad
    name = _path_name(path)
    ax = spacecraft_axis(name) if spacecraft_axis else (0 if arr.ndim >= 2 else None)
    sc = idx[ax] if ax is not None and len(idx) > ax else None
    return DivergenceInfo(int(k), float(t), name, sc, idx)


def _accumulators(step, k, state) -> set[int]:
    """Indices of the state leaves that no other leaf of ``step(k, state)`` depends on."""
    closed = jax.make_jaxpr(step)(k, state)
    n_in = len(jax.tree_util.tree_leaves((k, state)))
    deps = _propagate(closed.jaxpr, [frozenset({i}) for i in range(n_in)])
    n_state = n_in - 1  # input 0 is k
    if len(deps) != n_state:
        return set()
    return {
        i for i in range(n_state) if not any(i + 1 in deps[o] for o in range(n_state) if o != i)
    }


def _replay_loop(step, ok, state, k, n):
    """Step from ``state`` (step ``k``) until a state fails ``ok`` or ``n`` steps are done. Carry
    ``(j, last_ok, latest, bad)``: ``latest`` is the state of the last step computed -- the first
    failing state when ``bad`` -- so a diagnosis needs no separately compiled step to see it."""

    def cond(c):
        j, _, _, bad = c
        return jnp.logical_and(j < n, jnp.logical_not(bad))

    def body(c):
        j, st, _, _ = c
        new = step(jnp.asarray(k, dtype=jnp.int64) + j, st)
        bad = jnp.logical_not(ok(new))
        st = jax.tree_util.tree_map(lambda a, b: jnp.where(bad, a, b), st, new)
        return j + jnp.where(bad, 0, 1), st, new, bad

    return jax.lax.while_loop(
        cond, body, (jnp.asarray(0, jnp.int64), state, state, jnp.asarray(False))
    )


def _params_replay(params, state, k, n):
    """:func:`_replay_loop` of a closed loop given as a pytree argument: compiled once per loop
    structure (the parameters are arguments, not constants of a closure), so the diagnostics of many
    failed runs of one campaign share one program (jitted by :func:`_jitted`)."""
    return _replay_loop(params.replay_step(), params.admissible, state, k, n)


def _params_step(params, k, state):
    return params.replay_step()(k, state)


@functools.cache
def _jitted(fn: Callable[..., Any]) -> Callable[..., Any]:
    """``fn`` jitted as the run it replays is (:func:`formation_ftc.sim.runtime.xla.jit`), made on first
    use and kept (not at import: ``check`` imports this module without JAX, :mod:`formation_ftc._lazy_jax`)."""
    return xla.jit(fn)


def _replay(step, state, k: int, n: int, ok, params: Any) -> tuple[int, PyTree, PyTree | None]:
    """One compiled replay of up to ``n`` steps: ``(j, last_ok, failing)`` with ``failing`` the first
    state that fails ``ok`` (None when none does in ``n`` steps, then ``j = n``)."""
    if params is not None:
        j, st, latest, bad = _jitted(_params_replay)(
            params, state, jnp.asarray(k, jnp.int64), jnp.asarray(n, jnp.int64)
        )
    else:
        j, st, latest, bad = xla.jit(lambda s0: _replay_loop(step, ok, s0, k, n))(state)
    return int(j), st, (latest if bool(bad) else None)


def diagnose_divergence(
    step: Callable[[jax.Array, PyTree], PyTree],
    last_finite: PyTree,
    k: int,
    t: float,
    spacecraft_axis: Callable[[str], int | None] | None = None,
    *,
    max_steps: int = 1,
    dt: float = 0.0,
    admissible: Callable[[PyTree], jax.Array] | None = None,
    violations: Callable[[PyTree], list[tuple[str, tuple[int, ...], int | None]]] | None = None,
    params: Any = None,
) -> DivergenceInfo:
    """Replay up to ``max_steps`` steps from the last finite state (at step ``k``, time ``t``) and
    name the first non-finite state variable of the first non-finite step (time ``t + j*dt``).

    Accumulators -- leaves that no other leaf depends on, such as an integrated delta-v or control
    effort -- are named only when nothing else became non-finite: they merely follow the variable
    that left its admissible set. Dependencies are read from the step's jaxpr (structurally, without
    computing anything).

    ``params``: the closed loop whose ``replay_step`` and ``admissible`` ``step`` and ``admissible`` are
    (optional); given, the replays are compiled once per loop structure and reused for every
    diagnosed run of that structure (a campaign with many failed runs compiles them once).

    One compiled program does the usual diagnosis: the replay returns the first failing state along
    with the last admissible one. A one-step program is compiled only when the run must be followed
    past that state (only accumulators non-finite) or when the replay finds no failing step.

    Parameters
    ----------
    step : callable
        ``step(k, state) -> state`` of the run.
    last_finite : pytree
        The last finite state (``RunOutput["last_finite"]``).
    k : int
        Its step index.
    t : float
        Its time [s].
    spacecraft_axis : callable, optional
        ``variable name -> axis of the spacecraft dimension or None`` (default: axis 0 of leaves with
        two or more dimensions).
    max_steps : int, optional
        Steps replayed at most (a record block).
    dt : float, optional
        Step [s], to date the failing step.
    admissible : callable, optional
        ``admissible(state) -> bool``, the whole test of a state when given.
    violations : callable, optional
        ``violations(state) -> [(name, index, spacecraft), ...]`` naming a bound that was left.
    params : ClosedLoop, optional
        The loop whose ``replay_step`` and ``admissible`` are ``step`` and ``admissible``.

    Returns
    -------
    DivergenceInfo
        Step, time [s], variable, 0-based spacecraft (or None), index and reason.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from formation_ftc.sim.engine import diagnose_divergence
    >>> def step(k, state):
    ...     return {"q": 1e200 * state["q"]}
    >>> last = {"q": jnp.array([[1.0, 1.0, 1.0], [1.0, 1e200, 1.0]])}
    >>> print(diagnose_divergence(step, last, k=5, t=0.5, dt=0.1))
    simulation diverged at t = 0.5 s (step 5): spacecraft 2, variable 'q' index [1, 1] became non-finite
    """
    if not (hasattr(params, "replay_step") and hasattr(params, "admissible")):
        params = None  # no closed loop: the replays are compiled for this call

    # ``admissible`` (when given) is the whole test, finiteness of the checked state included
    ok = _all_finite if admissible is None else admissible

    # Date it exactly first: one compiled replay of the block (of one step when ``max_steps`` is 1). It
    # also returns the first failing state, so the usual diagnosis compiles nothing else; a step
    # program is compiled only to follow the run past that state (accumulators only) or when the
    # replay does not fail.
    max_steps = max(1, max_steps)
    j0, state0, failing = _replay(step, last_finite, k, max_steps, ok, params)
    if failing is not None:
        last_finite, k, t, max_steps = state0, k + j0, t + j0 * dt, max_steps - j0
    # compiled on its first call only (jit is lazy)
    jstep = xla.jit(step) if params is None else functools.partial(_jitted(_params_step), params)
    acc: set[int] | None = None
    first: DivergenceInfo | None = None
    state, n, j = last_finite, max_steps, 0
    while j < n:
        kj = jnp.asarray(k + j, dtype=jnp.int64)
        new = failing if (j == 0 and failing is not None) else jstep(kj, state)
        # inside the admissible set (when given), leaves it does not check may be NaN
        inside = admissible is not None and bool(admissible(new))
        bad = [] if inside else _nonfinite_leaves(new)
        if admissible is not None and not inside:
            checked = getattr(admissible, "checked_prefixes", None)
            if checked:
                bad = [b for b in bad if _path_name(b[0]).startswith(tuple(checked))]
            if not bad:
                found = violations(new) if violations is not None else []
                name, index, sc = found[0] if found else ("<admissible set>", (), None)
                return DivergenceInfo(
                    int(k + j), float(t + j * dt), name, sc, index, reason="left its admissible set"
                )
        if bad:
            if acc is None:
                try:
                    acc = _accumulators(step, kj, state)
                except Exception:  # noqa: BLE001 - a diagnostic must never fail; keep the first leaf
                    acc = set()
            order = [p for p, _ in jax.tree_util.tree_flatten_with_path(new)[0]]
            causes = [b for b in bad if order.index(b[0]) not in acc]
            info = _info(causes[0] if causes else bad[0], k + j, t + j * dt, spacecraft_axis)
            if causes:
                return info
            # only accumulators so far: follow the run a few steps to find the cause
            if first is None:
                first, n = info, j + 1 + _FOLLOW_STEPS
        state = new
        j += 1
    return first if first is not None else DivergenceInfo(int(k), float(t), "<unknown>", None, ())
