"""``formation-ftc tune``: choose a law's gains for a league, and report them on held-out seeds.

A league method file may declare which of its numbers are gains worth tuning, with bounds::

    [tune]
    objective = "delta_v_total"        # a league metric, minimised (default delta_v_total)
    statistic = "mean"                 # over the training runs: "mean" (default) or "median"
    fields = {"controller.K1" = [1e-3, 5e-2], "controller.K2" = {low = 1e-3, high = 0.1, log = true}}

:func:`tune_league_method` minimises the objective over a **training set** -- the method's cells of one
actuator level (every battery case that applies, or a chosen few) times ``train_seeds`` replicates --
subject to the league requirement on every training run, then runs the tuned and the paper gains on
**held-out** replicates and reports both. :func:`build_problem` and :func:`minimise` are the same
machinery for any set of scenarios of one structure (the LQR oracle test uses them directly).

Gains are parameters, not scenarios
-----------------------------------
A tunable field ``slot.name`` must be a numeric leaf of the built loop, as a campaign binds a sampled
field (:mod:`formation_ftc.campaign.binding`): the attribute ``name`` of the slot's component (or one
level down, or the attribute its section declares in ``leaf_paths``) holding exactly the field's value.
:func:`build_problem` checks it by building the scenario again with another value of the field and
comparing the whole parameter tree with the bound one: a field whose leaf is derived from it (LQR's
Bryson maxima turned into a Riccati gain, a gain scaled by a mass), a field that also moves other
leaves, or a structural field, is rejected with a message naming it. The runs are then one batch
(``jax.vmap`` over cells and seeds, every cell of a method has one structure) and every evaluation of
the objective only writes the gains into their leaves: no rebuild, one compiled program.

Objective and requirement (a penalty)
-------------------------------------
With ``f_r`` the objective metric of training run r, ``m_r`` its requirement metric and ``M`` the
requirement's maximum, the optimiser minimises over the gains (scaled to the unit cube, logarithmically
for ``log`` fields)::

    J = S_r(f_r) / f_0 + rho * mean_r(max(0, m_r / ((1 - margin) M) - 1))

S the statistic (mean or median), f_0 the statistic at the paper gains (so J = 1 there when they meet
the requirement), ``rho`` (default 10) the penalty weight and ``margin`` (default 10 %) a tightening of
the requirement on the training runs, so that the held-out runs, with other initial errors, onsets and
noise, keep a margin. The requirement is a **penalty**, not a hard constraint: an L1 (exact) penalty,
which reaches the constrained optimum once rho exceeds the constraint's Lagrange multiplier (about the
relative objective saved per relative relaxation of the requirement: small here), and which gives the
optimiser a slope back into the feasible set when the paper gains fail it. A diverged run, or one whose
scores are not finite, counts as ``f_r = f_0`` and a violation of ``bad_run_penalty`` (default 10).

Gradients, or derivative-free
-----------------------------
``optimiser = "gradient"`` differentiates J through the compiled, vmapped closed loop
(:func:`jax.jacfwd`: forward mode, one tangent per gain, so memory does not grow with the horizon as
reverse mode's stored residuals would; the gains are few) and runs L-BFGS-B on the bounds. The loop is
differentiated **as it is**: saturation (``clip``), switching (``where``: fault onsets, supervisors) and
the metrics' windows give the exact derivative almost everywhere, zero where a command is saturated, and
nothing across a switch. No smooth surrogate replaces them here -- saturation and switching live in the
actuator and law components, which this module does not rewrite -- so the gradient is that of a
piecewise-smooth function and a kink can stop L-BFGS-B early. ``"nelder-mead"`` (the default) and
``"powell"`` are scipy's bounded derivative-free optimisers on the same J (Nelder-Mead from a simplex of
15 % of each bound range around the paper gains). docs/tuning.md gives the measured comparison and
what tuning can and cannot rescue.

Seeds
-----
Replicate ``j`` of a league is drawn as the league draws it (:func:`formation_ftc.campaign.sampling`:
``simulation.seed``, the initial-error seed and the fault onset from the league seed and key ``j``,
paired across cells). Training uses replicates ``train_start .. train_start + train_seeds - 1``
(default from 10 000, beyond any league's seeds); held-out uses ``0 .. holdout_seeds - 1``, the league's
own first replicates, so the held-out paper-gain runs are exactly those of ``league run`` and the tuned
ones are paired with them.
"""

from __future__ import annotations

import copy
import json
import math
import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from formation_ftc.errors import InputError
from formation_ftc.exitcodes import jsonable
from formation_ftc.league.tune_cli import DEFAULT_OPTIMISER, OPTIMISERS, TRAIN_START

__all__ = [
    "TuneError",
    "TuneField",
    "GainProblem",
    "TuneOutcome",
    "OPTIMISERS",
    "build_problem",
    "penalised_objective",
    "minimise",
    "replicate_raws",
    "tune_league_method",
    "write_tuning",
    "load_tunings",
]


_NM_STEP = 0.15  # initial simplex of Nelder-Mead, as a fraction of each field's (scaled) range


class TuneError(InputError):
    """A tuning that cannot run (exit code 2); the message names the field or option."""


# ---------------------------------------------------------------------------------------- fields
@dataclass(frozen=True)
class TuneField:
    """One tunable field: dotted scenario path and bounds [field units].

    Attributes
    ----------
    path : str
        ``slot.name`` of the scenario (e.g. ``"controller.kp"``).
    low, high : float
        Bounds, ``low < high`` (``low > 0`` when ``log``).
    log : bool
        Search in ``log(value)`` (gains spanning decades).
    """

    path: str
    low: float
    high: float
    log: bool = False

    def __post_init__(self) -> None:
        lo, hi = float(self.low), float(self.high)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise TuneError(f"tune field {self.path!r}: bounds [{lo:g}, {hi:g}] need low < high")
        if self.log and lo <= 0:
            raise TuneError(f"tune field {self.path!r}: log scale needs low > 0, got {lo:g}")

    def to_unit(self, value: float) -> float:
        """The field value mapped to [0, 1] (logarithmically for ``log``)."""
        if self.log:
            return (math.log(value) - math.log(self.low)) / (
                math.log(self.high) - math.log(self.low)
            )
        return (value - self.low) / (self.high - self.low)

    def from_unit(self, z):
        """A point of [0, 1] mapped back to the field (works on numpy and JAX arrays)."""
        if self.log:
            import jax.numpy as jnp

            lo, hi = math.log(self.low), math.log(self.high)
            return jnp.exp(lo + z * (hi - lo))
        return self.low + z * (self.high - self.low)


def fields_from_table(fields: Mapping[str, Any]) -> list[TuneField]:
    """``{path: [low, high] | {low, high, log}}`` (a ``[tune] fields`` table) -> :class:`TuneField` s.

    Parameters
    ----------
    fields : Mapping[str, Any]
        The table (already validated by :func:`formation_ftc.league.definition.method_tune`, or given
        by hand).

    Returns
    -------
    list of TuneField
        In table order.

    Examples
    --------
    >>> fields_from_table({"controller.kp": [0.1, 10.0], "controller.kd": {"low": 1, "high": 100, "log": True}})
    [TuneField(path='controller.kp', low=0.1, high=10.0, log=False), TuneField(path='controller.kd', low=1.0, high=100.0, log=True)]
    """
    out = []
    for path, b in fields.items():
        if isinstance(b, Mapping):
            out.append(
                TuneField(path, float(b["low"]), float(b["high"]), bool(b.get("log", False)))
            )
        elif hasattr(b, "low"):  # a validated TuneBounds
            out.append(TuneField(path, float(b.low), float(b.high), bool(b.log)))
        else:
            lo, hi = b
            out.append(TuneField(path, float(lo), float(hi)))
    return out


def _get_path(raw: Mapping[str, Any], path: str) -> Any:
    node: Any = raw
    for part in path.split("."):
        if isinstance(node, Mapping) and part in node:
            node = node[part]
        elif isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]
        else:
            raise KeyError(path)
    return node


def _set_path(raw: dict[str, Any], path: str, value: Any) -> None:
    *head, last = path.split(".")
    node: Any = raw
    for part in head:
        node = node[int(part)] if isinstance(node, list) else node.setdefault(part, {})
    if isinstance(node, list):
        node[int(last)] = value
    else:
        node[last] = value


def _is_number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(float(v))


# --------------------------------------------------------------------------------------- problem
@dataclass
class GainProblem:
    """Runs of one structure, in batches of one compiled program, whose gains are written into their
    parameter leaves.

    Attributes
    ----------
    fields : tuple of TuneField
        The tuned fields.
    initial : numpy.ndarray
        Their values in the scenarios (the paper gains) [field units].
    metric_names : tuple of str
        The loop's metrics, in order (the keys of :meth:`evaluate`'s result).
    labels : list of dict
        One per run (e.g. ``{"case": ..., "replicate": ...}``), in run order.
    size : int
        Runs per batch (the program's batch size); :attr:`n_runs` runs in all.
    """

    fields: tuple[TuneField, ...]
    initial: np.ndarray
    metric_names: tuple[str, ...]
    labels: list[dict[str, Any]]
    size: int
    _compiled: Any
    _chunks: list[tuple[Any, Any, int]]  # (batch, in_axes, real runs)
    _slots: list[tuple[int, np.ndarray]]  # (leaf position, flat element indices) per field
    _fns: dict[Any, Callable] = field(default_factory=dict)

    @property
    def n_runs(self) -> int:
        """Number of runs."""
        return sum(n for _, _, n in self._chunks)

    @property
    def batch(self) -> Any:
        """The parameters of the first (for a training set: the only) batch."""
        return self._chunks[0][0]

    def _write_np(self, batch, theta):
        import jax

        leaves, treedef = jax.tree_util.tree_flatten(batch)
        for (n, index), v in zip(self._slots, theta, strict=True):
            leaf = np.array(leaves[n], dtype=np.float64, copy=True)
            leaf.reshape(-1)[index] = float(v)
            leaves[n] = leaf
        return jax.tree_util.tree_unflatten(treedef, leaves)

    def outputs(self, theta, batch=None):
        """JAX: ``(metrics {name: (runs, ...)}, diverged (runs,))`` of the first batch at gains
        ``theta`` [field units] (traceable; a jitted caller passes ``batch``, :attr:`batch`, as an
        argument so that it is not compiled in as constants)."""
        import jax
        import jax.numpy as jnp

        batch = self.batch if batch is None else batch
        in_axes = self._chunks[0][1]
        leaves, treedef = jax.tree_util.tree_flatten(batch)
        for i, (n, index) in enumerate(self._slots):
            leaf = jnp.asarray(leaves[n])
            leaves[n] = leaf.reshape(-1).at[index].set(theta[i]).reshape(leaf.shape)
        params = jax.tree_util.tree_unflatten(treedef, leaves)
        out = jax.vmap(self._compiled.run, in_axes=(in_axes,), axis_size=self.size)(params)
        return dict(zip(self.metric_names, out["metrics"], strict=True)), out["diverged_step"] >= 0

    def evaluate(
        self, theta: Sequence[float] | np.ndarray
    ) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """Run every run at gains ``theta`` [field units] through the package's cached batch program
        (:func:`formation_ftc.sim.batch.batched_run`: one compilation for every batch of the layout).

        Parameters
        ----------
        theta : sequence of float or numpy.ndarray
            One value per field [field units].

        Returns
        -------
        metrics : dict of str to numpy.ndarray
            Every metric of every run (leading axis: runs, in :attr:`labels` order).
        diverged : numpy.ndarray of bool
            Runs that left their admissible set.
        """
        import jax

        from formation_ftc.sim.batch import batched_run

        parts: list[dict[str, np.ndarray]] = []
        bads = []
        for batch, in_axes, n in self._chunks:
            fn = batched_run(self._compiled, in_axes, self.size)
            out = jax.device_get(fn(self._write_np(batch, theta)))
            parts.append(
                {
                    k: np.asarray(v)[:n]
                    for k, v in zip(self.metric_names, out["metrics"], strict=True)
                }
            )
            bads.append(np.asarray(out["diverged_step"])[:n] >= 0)
        metrics = {k: np.concatenate([p[k] for p in parts]) for k in self.metric_names}
        return metrics, np.concatenate(bads)


def _stack_like(params: Sequence[Any], in_axes: Any, size: int) -> Any | None:
    """``params`` stacked as ``in_axes`` says (a batched leaf stacked and padded with the last run even
    where the runs agree), or None when a leaf ``in_axes`` shares differs between the runs."""
    import jax

    flat = [jax.tree_util.tree_flatten(p) for p in params]
    treedef = flat[0][1]
    if any(td != treedef for _, td in flat[1:]):  # type: ignore[operator]  # PyTreeDef unresolved in jax stubs
        return None
    axes = treedef.flatten_up_to(in_axes)  # type: ignore[attr-defined]
    leaves = []
    for vals, ax in zip(zip(*(f[0] for f in flat), strict=True), axes, strict=True):
        arrs = [np.asarray(v) for v in vals]
        if ax is None:
            kind = arrs[0].dtype.kind in "fc"
            if not all(
                a.shape == arrs[0].shape and np.array_equal(a, arrs[0], equal_nan=kind)
                for a in arrs[1:]
            ):
                return None
            leaves.append(arrs[0])
        else:
            arrs += [arrs[-1]] * (size - len(arrs))
            leaves.append(np.stack(arrs))
    return jax.tree_util.tree_unflatten(treedef, leaves)


def build_problem(
    raws: Sequence[Mapping[str, Any]],
    fields: Sequence[TuneField],
    labels: Sequence[dict[str, Any]] | None = None,
    like: GainProblem | None = None,
) -> GainProblem:
    """The scenarios ``raws`` (one structure) with ``fields`` bound to their leaves, as batches.

    Every field must be a number, the same in every scenario and within its bounds, and a numeric leaf
    of the built loop holding exactly that number: checked by building the first scenario again with
    another value and comparing every parameter with the bound ones (see the module docstring).

    Parameters
    ----------
    raws : sequence of mapping
        Full scenarios (dicts as :func:`formation_ftc.api.load_scenario` takes them), one per run.
    fields : sequence of TuneField
        The gains to tune.
    labels : sequence of dict, optional
        One label per run (kept in the result).
    like : GainProblem, optional
        Lay the runs out as this problem's batch (its size and batched leaves; consecutive runs of
        ``raws``, the last batch padded), so that its compiled program serves these runs too (the
        held-out runs of a training set). Default: all runs in one batch.

    Returns
    -------
    GainProblem
        The batches, ready to :meth:`~GainProblem.evaluate` at any gains.

    Raises
    ------
    TuneError
        A field that is missing, not a number, differs between runs, lies outside its bounds, is
        structural, or is not a leaf of the built loop; runs of different structures.

    Examples
    --------
    >>> from formation_ftc.league.tuning import TuneField, build_problem
    >>> raw = {"scenario": {"name": "doc", "method": "composed"},
    ...        "simulation": {"horizon": 1.0, "dt": 0.5},
    ...        "plant": {"type": "clohessy-wiltshire", "semi_major_axis": 7e6, "mass": [10.0],
    ...                  "initial_position": [[1.0, 0.0, 0.0]]},
    ...        "controller": {"type": "pd", "kp": 1.0, "kd": 5.0, "nominal_mass": 10.0},
    ...        "metrics": [{"name": "e", "signal": "position_error", "reduce": "final", "norm": True,
    ...                     "spacecraft": "max", "units": "m"}]}
    >>> p = build_problem([raw], [TuneField("controller.kp", 0.1, 10.0)])
    >>> p.initial, p.n_runs, p.metric_names
    (array([1.]), 1, ('e',))
    """
    from formation_ftc import api
    from formation_ftc.campaign.binding import bind_fields
    from formation_ftc.sim.batch import stack_params

    if not raws:
        raise TuneError("tuning: no runs")
    fields = tuple(fields)
    if not fields:
        raise TuneError("tuning: no tunable fields (give a [tune] fields table)")
    if len({f.path for f in fields}) != len(fields):
        raise TuneError(f"tuning: a field is listed twice ({[f.path for f in fields]})")
    initial = []
    for f in fields:
        vals = []
        for raw in raws:
            try:
                vals.append(_get_path(raw, f.path))
            except KeyError:
                raise TuneError(
                    f"tune field {f.path!r}: the scenario has no such field (give the law's paper "
                    "value in the method file)"
                ) from None
        v0 = vals[0]
        if not _is_number(v0):
            raise TuneError(
                f"tune field {f.path!r}: {v0!r} is not one finite number (a tunable field is one "
                "scalar gain)"
            )
        if any(v != v0 for v in vals[1:]):
            raise TuneError(f"tune field {f.path!r}: differs between the runs")
        if not f.low <= float(v0) <= f.high:
            raise TuneError(
                f"tune field {f.path!r}: the paper value {v0:g} lies outside the bounds "
                f"[{f.low:g}, {f.high:g}]"
            )
        initial.append(float(v0))
    try:
        scenarios = [api.load_scenario(dict(r)) for r in raws]
        compiled = [api.compile_scenario(s) for s in scenarios]
    except InputError:
        raise
    except (ValueError, TypeError) as exc:
        raise TuneError(f"tuning: a run cannot be built: {exc}") from None
    key = compiled[0].static_key
    if any(c.static_key != key for c in compiled[1:]):
        raise TuneError("tuning: the runs do not share one structure (one compiled program)")
    template = compiled[0].params
    bindings = {}
    for f, v0 in zip(fields, initial, strict=True):
        bound = bind_fields(template, scenarios[0], {f.path: v0})
        if not bound:
            raise TuneError(
                f"tune field {f.path!r}: not a numeric leaf of the built loop (its builder derives "
                "the parameters from it, or it names no component attribute); only gains the loop "
                "holds as they are can be tuned"
            )
        bindings[f.path] = bound[f.path]
    if like is None:
        _check_bindings(raws[0], fields, initial, template, key, bindings)
        size = len(raws)
        batch, in_axes = stack_params([c.params for c in compiled])
        chunks = [(batch, in_axes, size)]
    else:
        if like._compiled.static_key != key:
            raise TuneError("tuning: these runs do not have the structure of the training runs")
        size, in_axes = like.size, like._chunks[0][1]
        chunks = []
        for s in range(0, len(compiled), size):
            part = [c.params for c in compiled[s : s + size]]
            batch = _stack_like(part, in_axes, size)
            if batch is None:  # another layout: its own program
                chunks.append((*stack_params(part, size), len(part)))
            else:
                chunks.append((batch, in_axes, len(part)))
    slots = []
    for f in fields:
        b = bindings[f.path]
        for _, axes, _ in chunks:
            import jax

            treedef = jax.tree_util.tree_structure(template)
            if treedef.flatten_up_to(axes)[b.leaf] is not None:  # type: ignore[attr-defined]
                raise TuneError(
                    f"tune field {f.path!r}: its leaf differs between the runs (another field or a "
                    "sampled value shares it)"
                )
        slots.append((b.leaf, np.asarray(b.index)))
    return GainProblem(
        fields=fields,
        initial=np.asarray(initial, dtype=np.float64),
        metric_names=tuple(_metric_names(template)),
        labels=list(labels) if labels is not None else [{} for _ in raws],
        size=size,
        _compiled=compiled[0],
        _chunks=chunks,
        _slots=slots,
    )


def _metric_names(loop) -> list[str]:
    names = [m.name for m in getattr(loop, "metrics", ())]
    if not names:
        raise TuneError("tuning: the scenario computes no metrics (nothing to minimise)")
    return names


def _check_bindings(raw, fields, initial, template, key, bindings) -> None:
    """Build ``raw`` again with every field moved and compare the whole parameter tree with the
    template's with the bound leaves written: a derived or structural field fails, named."""
    from formation_ftc import api
    from formation_ftc.campaign.binding import apply_bindings, params_close, take_run

    for f, v0 in zip(fields, initial, strict=True):
        z0 = f.to_unit(v0)
        z1 = 0.5 * z0 + 0.37 if abs(z0 - 0.74) > 1e-3 else 0.3  # another value inside the bounds
        v1 = float(f.from_unit(z1))
        moved = copy.deepcopy(dict(raw))
        _set_path(moved, f.path, v1)
        try:
            c = api.compile_scenario(api.load_scenario(moved))
        except (InputError, ValueError, TypeError) as exc:
            raise TuneError(
                f"tune field {f.path!r}: the scenario does not build with {f.path} = {v1:g}, "
                f"inside the bounds [{f.low:g}, {f.high:g}]: {exc}"
            ) from None
        if c.static_key != key:
            raise TuneError(
                f"tune field {f.path!r}: structural (another value changes the compiled program); "
                "only numeric gains can be tuned"
            )
        batch, axes = apply_bindings(
            template, {f.path: bindings[f.path]}, {f.path: np.asarray([v1], dtype=float)}, 1
        )
        if not params_close(take_run(batch, axes, 0), c.params):
            raise TuneError(
                f"tune field {f.path!r}: not a numeric leaf of the built loop -- another value also "
                "moves parameters derived from it (the builder scales or converts it); tune the "
                "field the loop holds as it is"
            )


# ------------------------------------------------------------------------------------- objective
Objective = Callable[[Mapping[str, Any]], Any]


def penalised_objective(
    objective: str | Objective,
    *,
    statistic: str = "mean",
    requirement: tuple[str, float] | None = None,
    margin: float = 0.1,
    penalty: float = 10.0,
    bad_run_penalty: float = 10.0,
    scale: float = 1.0,
) -> Callable[[Mapping[str, Any], Any], Any]:
    """J(metrics, bad) of the module docstring, a JAX function of one batch's metrics.

    Parameters
    ----------
    objective : str or callable
        A metric name, or ``metrics -> (runs,)`` cost per run (JAX).
    statistic : {"mean", "median"}
        Statistic of the per-run objective.
    requirement : (str, float), optional
        Metric and maximum of the requirement (None: unconstrained).
    margin : float
        Fraction the requirement is tightened by on the training runs [-].
    penalty : float
        Weight rho of the mean relative violation [-].
    bad_run_penalty : float
        Violation counted for a diverged or non-finite run [-].
    scale : float
        f_0: the objective statistic is divided by it.

    Returns
    -------
    callable
        ``(metrics, bad) -> (J, terms)``, terms a dict of the objective statistic (unscaled), the mean
        violation and the fraction of failing runs.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> J = penalised_objective("dv", requirement=("err", 1.0), margin=0.0, penalty=10.0, scale=2.0)
    >>> value, terms = J({"dv": jnp.array([1.0, 3.0]), "err": jnp.array([0.5, 1.5])}, jnp.array([False, False]))
    >>> float(value), float(terms["objective"]), float(terms["fail_fraction"])
    (3.5, 2.0, 0.5)
    """
    import jax.numpy as jnp

    if statistic not in ("mean", "median"):
        raise TuneError(f"statistic = {statistic!r}: 'mean' or 'median'")
    if not 0 <= margin < 1:
        raise TuneError(f"margin = {margin}: in [0, 1)")
    stat = jnp.mean if statistic == "mean" else jnp.median

    def J(metrics, bad):
        f = metrics[objective] if isinstance(objective, str) else objective(metrics)
        f = jnp.asarray(f)
        bad_f = bad | ~jnp.isfinite(f)
        f_ok = jnp.where(bad_f, scale, f)
        fail = bad_f
        viol = jnp.zeros_like(f_ok)
        if requirement is not None:
            m = jnp.asarray(metrics[requirement[0]])
            bad_m = bad | ~jnp.isfinite(m)
            m_ok = jnp.where(bad_m, 0.0, m)
            limit = (1.0 - margin) * requirement[1]
            viol = jnp.where(bad_m, bad_run_penalty, jnp.maximum(m_ok / limit - 1.0, 0.0))
            fail = bad_f | bad_m | (m_ok > requirement[1])
        viol = jnp.where(bad_f, bad_run_penalty, viol)
        obj = stat(f_ok)
        value = obj / scale + penalty * jnp.mean(viol)
        return value, {
            "objective": obj,
            "violation": jnp.mean(viol),
            "fail_fraction": jnp.mean(fail.astype(f_ok.dtype)),
        }

    return J


# -------------------------------------------------------------------------------------- optimise
@dataclass
class TuneOutcome:
    """What :func:`minimise` found.

    Attributes
    ----------
    gains : numpy.ndarray
        The best gains [field units].
    value : float
        J there.
    initial_value : float
        J at the starting gains.
    terms, initial_terms : dict
        J's terms there and at the start.
    optimiser : str
        The optimiser used.
    evaluations : int
        Batch evaluations (a gradient evaluation counts once; it costs about 1 + fields forward runs).
    seconds : float
        Wall time, compilation included [s].
    compile_seconds : float
        Of which the first evaluation (compilation) [s].
    history : list of (list of float, float)
        Gains and J of every evaluation, in order.
    message : str
        The optimiser's own final message.
    """

    gains: np.ndarray
    value: float
    initial_value: float
    terms: dict[str, float]
    initial_terms: dict[str, float]
    optimiser: str
    evaluations: int
    seconds: float
    compile_seconds: float
    history: list[tuple[list[float], float]]
    message: str


def minimise(
    problem: GainProblem,
    J: Callable[[Mapping[str, Any], Any], Any],
    *,
    optimiser: str = DEFAULT_OPTIMISER,
    max_evaluations: int = 60,
    start: Sequence[float] | None = None,
    tolerance: float = 1e-4,
) -> TuneOutcome:
    """Minimise ``J`` (from :func:`penalised_objective`) over the problem's gains, within their bounds.

    Parameters
    ----------
    problem : GainProblem
        The runs and their gains.
    J : callable
        ``(metrics, bad) -> (value, terms)`` (JAX).
    optimiser : {"nelder-mead", "powell", "gradient"}
        Derivative-free (scipy, bounded) or L-BFGS-B with forward-mode gradients through the loop.
    max_evaluations : int
        Largest number of batch evaluations.
    start : sequence of float, optional
        Starting gains [field units] (default: the scenario's).
    tolerance : float
        Convergence tolerance on the scaled gains (and on J for the derivative-free optimisers).

    Returns
    -------
    TuneOutcome
        The best gains found, J and its terms there and at the start, evaluations and time.

    Raises
    ------
    TuneError
        Unknown optimiser, or ``max_evaluations < 2``.

    Examples
    --------
    See ``tests/league/test_tuning.py`` (the LQR oracle).
    """
    import jax
    import jax.numpy as jnp
    from scipy import optimize

    if optimiser not in OPTIMISERS:
        raise TuneError(f"optimiser = {optimiser!r}: one of {', '.join(OPTIMISERS)}")
    if max_evaluations < 2:
        raise TuneError(f"max_evaluations = {max_evaluations}: at least 2")
    fields = problem.fields
    x_start = np.asarray(problem.initial if start is None else start, dtype=np.float64)
    z0 = np.clip([f.to_unit(v) for f, v in zip(fields, x_start, strict=True)], 0.0, 1.0)

    def theta_of(z):
        return jnp.stack([f.from_unit(z[i]) for i, f in enumerate(fields)])

    def value_terms(z, batch):
        v, terms = J(*problem.outputs(theta_of(z), batch))
        return v, terms

    t0 = time.perf_counter()
    history: list[tuple[list[float], float]] = []
    cache: dict[bytes, tuple[float, dict[str, float], np.ndarray | None]] = {}
    compile_s: list[float] = []

    def record(z, v, terms, grad=None):
        th = [float(f.from_unit(float(zi))) for f, zi in zip(fields, z, strict=True)]
        history.append((th, v))
        cache[np.asarray(z, dtype=np.float64).tobytes()] = (v, terms, grad)

    def finite(v: float) -> float:
        return v if math.isfinite(v) else 1e6

    if optimiser == "gradient":
        if len(problem._chunks) != 1:
            raise TuneError("optimiser 'gradient': the training runs must be one batch")

        def v_aux(z, batch):
            v, terms = value_terms(z, batch)
            return v, (v, terms)

        vg = jax.jit(jax.jacfwd(v_aux, has_aux=True))

        def fun(z):
            key = np.asarray(z, dtype=np.float64).tobytes()
            if key in cache and cache[key][2] is not None:
                v, _, g = cache[key]
                return v, g
            ts = time.perf_counter()
            grad, (v, terms) = vg(jnp.asarray(z), problem.batch)
            v = finite(float(v))
            g = np.nan_to_num(np.asarray(grad, dtype=np.float64), nan=0.0, posinf=0.0, neginf=0.0)
            if not compile_s:
                compile_s.append(time.perf_counter() - ts)
            record(z, v, {k: float(t) for k, t in terms.items()}, g)
            return v, g

        res = optimize.minimize(
            fun,
            z0,
            jac=True,
            method="L-BFGS-B",
            bounds=[(0.0, 1.0)] * len(fields),
            options={"maxfun": max_evaluations, "maxiter": max_evaluations, "gtol": tolerance},
        )
    else:

        def fun(z):
            z = np.clip(np.asarray(z, dtype=np.float64), 0.0, 1.0)
            key = z.tobytes()
            if key in cache:
                return cache[key][0]
            ts = time.perf_counter()
            theta = [float(f.from_unit(float(zi))) for f, zi in zip(fields, z, strict=True)]
            v, terms = J(*problem.evaluate(theta))  # the cached batch program; J on its numbers
            v = finite(float(v))
            if not compile_s:
                compile_s.append(time.perf_counter() - ts)
            record(z, v, {k: float(t) for k, t in terms.items()})
            return v

        bounds = [(0.0, 1.0)] * len(fields)
        if optimiser == "nelder-mead":
            simplex = [z0]
            for i in range(len(fields)):
                z = z0.copy()
                z[i] = z[i] + _NM_STEP if z[i] + _NM_STEP <= 1.0 else z[i] - _NM_STEP
                simplex.append(z)
            res = optimize.minimize(
                fun,
                z0,
                method="Nelder-Mead",
                bounds=bounds,
                options={
                    "maxfev": max_evaluations,
                    "initial_simplex": np.asarray(simplex),
                    "xatol": tolerance,
                    "fatol": tolerance,
                },
            )
        else:
            res = optimize.minimize(
                fun,
                z0,
                method="Powell",
                bounds=bounds,
                options={"maxfev": max_evaluations, "xtol": tolerance, "ftol": tolerance},
            )
    seconds = time.perf_counter() - t0
    # the best point evaluated (an optimiser may stop elsewhere)
    z_start = np.asarray(z0, dtype=np.float64)
    if z_start.tobytes() not in cache:
        fun(z_start)
    v_start, terms_start, _ = cache[z_start.tobytes()]
    best = min(cache.items(), key=lambda kv: kv[1][0])
    z_best = np.frombuffer(best[0], dtype=np.float64)
    gains = np.asarray([float(f.from_unit(float(z))) for f, z in zip(fields, z_best, strict=True)])
    return TuneOutcome(
        gains=gains,
        value=float(best[1][0]),
        initial_value=float(v_start),
        terms=dict(best[1][1]),
        initial_terms=dict(terms_start),
        optimiser=optimiser,
        evaluations=len(history),
        seconds=seconds,
        compile_seconds=compile_s[0] if compile_s else 0.0,
        history=history,
        message=str(getattr(res, "message", "")),
    )


# --------------------------------------------------------------------------------------- league
def replicate_raws(spec, method: str, cells, replicates: Sequence[int]):
    """The runs of ``cells`` (a method's :class:`~formation_ftc.league.runner.Cell` s) for league
    replicates ``replicates``, drawn exactly as ``league run`` draws them (paired across cells).

    Parameters
    ----------
    spec : LeagueSpec
        The league.
    method : str
        The method's name.
    cells : sequence of Cell
        The cells.
    replicates : sequence of int
        Replicate keys (the league's seeds are 0 .. seeds - 1).

    Returns
    -------
    raws : list of dict
        One full scenario per (cell, replicate), cell-major.
    labels : list of dict
        ``{"case", "level", "replicate"}`` of each.
    """
    from formation_ftc.campaign.sampling import draw_value, run_seed
    from formation_ftc.campaign.spec import parse_sampler
    from formation_ftc.league.runner import _campaign, _network_kind

    networked = _network_kind(spec, spec.method(method))[0]
    camp = _campaign(spec, method, [], 1, [], networked)
    seed = int(spec.league.seed)
    samplers = [parse_sampler(p, s) for p, s in camp["sample"].items()]
    draws = {
        j: {
            "simulation.seed": run_seed(seed, j),
            **{s.path: draw_value(s, seed, j) for s in samplers},
        }
        for j in replicates
    }
    raws, labels = [], []
    for c in cells:
        for j in replicates:
            raw = copy.deepcopy(c.raw)
            for path, v in {**camp["overrides"], **draws[j]}.items():
                _set_path(raw, path, v)
            raws.append(raw)
            labels.append({"case": c.case, "level": c.level, "replicate": int(j)})
    return raws, labels


def _pass_stats(metrics, bad, requirement, objective: str) -> dict[str, Any]:
    m = np.asarray(metrics[requirement[0]], dtype=float)
    f = np.asarray(metrics[objective], dtype=float)
    ok = ~np.asarray(bad) & np.isfinite(m)
    passed = ok & (m <= requirement[1])
    fin = ok & np.isfinite(f)
    return {
        "runs": int(m.size),
        "pass_rate": float(np.mean(passed)),
        "diverged": int(np.sum(np.asarray(bad))),
        f"{objective}_mean": float(np.mean(f[fin])) if fin.any() else None,
        f"{objective}_median": float(np.median(f[fin])) if fin.any() else None,
        f"{requirement[0]}_median": float(np.median(m[ok])) if ok.any() else None,
    }


def _per_case(labels, metrics, bad, requirement, objective) -> dict[str, dict[str, Any]]:
    cases = list(dict.fromkeys(lb["case"] for lb in labels))
    out = {}
    for case in cases:
        idx = np.asarray([i for i, lb in enumerate(labels) if lb["case"] == case])
        sub = {k: np.asarray(v)[idx] for k, v in metrics.items()}
        out[case] = _pass_stats(sub, np.asarray(bad)[idx], requirement, objective)
    return out


def tune_league_method(
    league,
    method: str,
    level: str,
    *,
    cases: Sequence[str] | None = None,
    train_seeds: int = 8,
    holdout_seeds: int = 16,
    train_start: int = TRAIN_START,
    optimiser: str = DEFAULT_OPTIMISER,
    max_evaluations: int = 60,
    objective: str | None = None,
    statistic: str | None = None,
    margin: float = 0.1,
    penalty: float = 10.0,
    log: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """Tune a league method's ``[tune]`` fields at one actuator level; the result as a JSON-able dict.

    Parameters
    ----------
    league : str, Path or LeagueSpec
        Built-in league name, league file, or a loaded league.
    method : str
        The method (its file needs a ``[tune]`` table).
    level : str
        Actuator level (e.g. ``"limited"``).
    cases : sequence of str, optional
        Fault cases of the training and held-out sets (default: every case that applies).
    train_seeds, holdout_seeds : int
        Replicates per cell of each set.
    train_start : int
        First training replicate (held-out: 0 .. holdout_seeds - 1; the two must not overlap).
    optimiser : str
        One of :data:`OPTIMISERS`.
    max_evaluations : int
        Largest number of batch evaluations of the training set.
    objective : str, optional
        League metric minimised (default: the ``[tune]`` table's, else ``delta_v_total``).
    statistic : str, optional
        ``"mean"`` or ``"median"`` (default: the table's, else mean).
    margin, penalty : float
        See :func:`penalised_objective`.
    log : callable, optional
        Receives progress lines.

    Returns
    -------
    dict
        Method, level, fields and bounds, paper and tuned gains, objective and pass rates on the
        training and held-out sets (per case too), optimiser, evaluations, times, provenance.

    Raises
    ------
    TuneError, LeagueError
        A bad league, method, level, case, field or option (exit code 2).
    """
    from formation_ftc.league.definition import LeagueSpec, load_league, method_tune
    from formation_ftc.league.runner import plan_cells

    say = log or (lambda _line: None)
    spec = league if isinstance(league, LeagueSpec) else load_league(league)
    entry = spec.method(method)
    tune = method_tune(spec, entry)
    if tune is None:
        raise TuneError(
            f"method {method}: its file ({entry.scenario}) has no [tune] table: declare the tunable "
            'fields and bounds, e.g. [tune] fields = {"controller.k" = [0.05, 1.0]}'
        )
    levels = [lv.name for lv in spec.levels]
    if level not in levels:
        raise TuneError(f"--level {level!r}: not a level of league {spec.league.name} ({levels})")
    if train_seeds < 1 or holdout_seeds < 1:
        raise TuneError("--train-seeds and --holdout-seeds: at least 1 each")
    if train_start < holdout_seeds:
        raise TuneError(
            f"--train-start {train_start}: the training replicates would overlap the held-out ones "
            f"(0 .. {holdout_seeds - 1})"
        )
    objective = objective or tune.objective
    statistic = statistic or tune.statistic
    metric_names = [str(m.get("name")) for m in spec.metrics]
    if objective not in metric_names:
        raise TuneError(f"objective {objective!r}: not a league metric ({', '.join(metric_names)})")
    req = spec.league.requirement
    requirement = (req.metric, float(req.max))
    all_cells = [c for c in plan_cells(spec, [method])[method] if c.level == level]
    applying = [c.case for c in all_cells]
    if cases:
        unknown = [c for c in cases if c not in applying]
        if unknown:
            raise TuneError(
                f"--cases: {unknown} not among the cases of {method} ({', '.join(applying)})"
            )
        all_cells = [c for c in all_cells if c.case in cases]
    fields = fields_from_table(tune.fields)
    t0 = time.perf_counter()
    train = list(range(train_start, train_start + train_seeds))
    held = list(range(holdout_seeds))
    raws, labels = replicate_raws(spec, method, all_cells, train)
    say(
        f"{method} @ {level}: {len(raws)} training runs ({len(all_cells)} cells x {train_seeds} "
        f"seeds), fields {', '.join(f.path for f in fields)}"
    )
    problem = build_problem(raws, fields, labels)
    paper = problem.initial.copy()
    m0, bad0 = problem.evaluate(paper)
    f0 = np.asarray(m0[objective], dtype=float)[~bad0]
    f0 = f0[np.isfinite(f0)]
    scale = float(np.mean(f0) if statistic == "mean" else np.median(f0)) if f0.size else 1.0
    if not (math.isfinite(scale) and scale > 0):
        scale = 1.0
    J = penalised_objective(
        objective,
        statistic=statistic,
        requirement=requirement,
        margin=margin,
        penalty=penalty,
        scale=scale,
    )
    outcome = minimise(problem, J, optimiser=optimiser, max_evaluations=max_evaluations)
    say(
        f"{method}: {optimiser}, {outcome.evaluations} evaluations in {outcome.seconds:.1f} s: "
        f"J {outcome.initial_value:.4g} -> {outcome.value:.4g}"
    )
    m_tr, bad_tr = problem.evaluate(outcome.gains)
    train_paper = _pass_stats(m0, bad0, requirement, objective)
    train_tuned = _pass_stats(m_tr, bad_tr, requirement, objective)
    # held-out: the league's own first replicates, paper and tuned gains
    h_raws, h_labels = [], []
    for k in range(
        0, len(held), train_seeds
    ):  # batches laid out as the training batch: one program
        r, lb = replicate_raws(spec, method, all_cells, held[k : k + train_seeds])
        h_raws += r
        h_labels += lb
    hold = build_problem(h_raws, fields, h_labels, like=problem)
    mh0, badh0 = hold.evaluate(paper)
    mh1, badh1 = hold.evaluate(outcome.gains)
    result = {
        "kind": "formation-ftc tuning",
        "league": spec.league.name,
        "league_version": spec.league.version,
        "method": method,
        "level": level,
        "cases": [c.case for c in all_cells],
        "fields": [
            {"path": f.path, "low": f.low, "high": f.high, "log": f.log} for f in problem.fields
        ],
        "paper_gains": {f.path: float(v) for f, v in zip(fields, paper, strict=True)},
        "tuned_gains": {f.path: float(v) for f, v in zip(fields, outcome.gains, strict=True)},
        "objective": {
            "metric": objective,
            "statistic": statistic,
            "units": _metric_units(spec, objective),
            "scale": scale,
            "penalty": penalty,
            "margin": margin,
            "form": "J = S(f)/f0 + penalty * mean(max(0, m / ((1 - margin) max) - 1))",
        },
        "requirement": {
            "metric": requirement[0],
            "max": requirement[1],
            "units": spec.league.requirement.units,
        },
        "J": {"paper": outcome.initial_value, "tuned": outcome.value},
        "train": {
            "replicates": [train[0], train[-1]],
            "seeds_per_cell": train_seeds,
            "paper": train_paper,
            "tuned": train_tuned,
        },
        "holdout": {
            "replicates": [held[0], held[-1]],
            "seeds_per_cell": holdout_seeds,
            "paper": _pass_stats(mh0, badh0, requirement, objective),
            "tuned": _pass_stats(mh1, badh1, requirement, objective),
            "per_case": {
                "paper": _per_case(h_labels, mh0, badh0, requirement, objective),
                "tuned": _per_case(h_labels, mh1, badh1, requirement, objective),
            },
        },
        "optimiser": {
            "name": optimiser,
            "evaluations": outcome.evaluations,
            "max_evaluations": max_evaluations,
            "seconds": outcome.seconds,
            "compile_seconds": outcome.compile_seconds,
            "message": outcome.message,
            "history": [{"gains": g, "J": v} for g, v in outcome.history],
        },
        "seconds": time.perf_counter() - t0,
        "provenance": _provenance(),
    }
    return result


def _metric_units(spec, name: str) -> str:
    for m in spec.metrics:
        if m.get("name") == name:
            return str(m.get("units", "1"))
    return "1"


def _provenance() -> dict[str, Any]:
    from formation_ftc.provenance import provenance

    try:
        return dict(provenance())
    except Exception:  # noqa: BLE001 - provenance is best effort
        return {}


def result_name(method: str, level: str) -> str:
    """File name of a tuning result: ``<method>--<level>.json``."""
    return f"{method}--{level}.json"


def write_tuning(result: Mapping[str, Any], out_dir: str | Path) -> Path:
    """Write ``result`` to ``out_dir/<method>--<level>.json`` (atomically); returns the path.

    Parameters
    ----------
    result : Mapping
        From :func:`tune_league_method`.
    out_dir : str or Path
        Directory (created).

    Returns
    -------
    Path
        The file written.

    Examples
    --------
    >>> import tempfile
    >>> p = write_tuning({"method": "m", "level": "limited", "x": float("nan")}, tempfile.mkdtemp())
    >>> p.name, json.loads(p.read_text())["x"]
    ('m--limited.json', None)
    """
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
        path = out / result_name(str(result["method"]), str(result["level"]))
        tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
        tmp.write_text(
            json.dumps(jsonable(dict(result)), indent=1, allow_nan=False), encoding="utf-8"
        )
        os.replace(tmp, path)
    except OSError as exc:
        raise TuneError(f"--out {out}: cannot write there ({exc.strerror or exc})") from None
    return path


def load_tunings(directory: str | Path) -> dict[tuple[str, str], dict[str, Any]]:
    """The tuning results in ``directory`` (``*.json`` written by :func:`write_tuning`), by
    ``(method, level)``; files of other kinds are skipped, a missing directory gives ``{}``.

    Parameters
    ----------
    directory : str or Path
        E.g. ``LEAGUE_DIR/tuned``.

    Returns
    -------
    dict
        ``(method, level) -> result``.

    Examples
    --------
    >>> load_tunings("/nonexistent")
    {}
    """
    d = Path(directory)
    out: dict[tuple[str, str], dict[str, Any]] = {}
    if not d.is_dir():
        return out
    for p in sorted(d.glob("*.json")):
        try:
            r = json.loads(p.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        if isinstance(r, dict) and r.get("kind") == "formation-ftc tuning":
            out[(str(r.get("method")), str(r.get("level")))] = r
    return out
