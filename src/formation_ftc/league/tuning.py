"""``formation-ftc tune``: choose a league method's ``[tune]`` gains at one actuator level on training
replicates, then report them next to the paper gains on held-out replicates (docs/tuning.md: the
objective, the seeds, the optimisers and what tuning can rescue).

A tunable field must be a numeric leaf of the built loop, as a campaign binds a sampled field
(:mod:`formation_ftc.campaign.binding`): the runs of one method are then batches of one compiled
program, and each evaluation only writes the gains into their leaves.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import math
import os
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict

from formation_ftc.atomic import atomic_write
from formation_ftc.errors import InputError
from formation_ftc.exitcodes import jsonable
from formation_ftc.league.tuning_options import DEFAULT_OPTIMISER, OPTIMISERS, TRAIN_START
from formation_ftc.limits import Budgets
from formation_ftc.runout import TMP_RE, oserror_as

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
    "TuneJournal",
    "evaluate",
    "journal_path",
    "check_tune_budgets",
    "check_tune_out",
]

_NM_STEP = 0.15  # initial simplex of Nelder-Mead, as a fraction of each field's (scaled) range


_UNBUILT = "tuning: a run cannot be built"


class TuneError(InputError):
    """A tuning that cannot run (exit code 2); the message names the field or option."""


@dataclass(frozen=True)
class TuneField:
    """A tunable field ``slot.name`` and its bounds ``low < high`` [field units]; ``log``: searched in
    ``log(value)`` (``low > 0``); ``rebuild``: the field is an input of its builder (a derived
    gain), so the runs are built again at each evaluation instead of writing a leaf. The optimisers
    see it scaled to [0, 1]."""

    path: str
    low: float
    high: float
    log: bool = False
    rebuild: bool = False

    def __post_init__(self) -> None:
        lo, hi = self.low, self.high
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise TuneError(f"tune field {self.path!r}: bounds [{lo:g}, {hi:g}] need low < high")
        if self.log and lo <= 0:
            raise TuneError(f"tune field {self.path!r}: log scale needs low > 0, got {lo:g}")

    def _ends(self) -> tuple[float, float]:
        scale = math.log if self.log else float
        return scale(self.low), scale(self.high)

    def to_unit(self, value: float) -> float:
        """The field value mapped to [0, 1]."""
        lo, hi = self._ends()
        return ((math.log(value) if self.log else value) - lo) / (hi - lo)

    def from_unit(self, z):
        """A point of [0, 1] mapped back to the field (numpy or JAX)."""
        lo, hi = self._ends()
        if self.log:
            import jax.numpy as jnp

            return jnp.exp(lo + z * (hi - lo))
        return lo + z * (hi - lo)


@dataclass
class GainProblem:
    """Runs of one structure, in batches of ``size`` runs of one compiled program, with the gains
    ``fields`` (paper values ``initial``) written into their parameter leaves."""

    fields: tuple[TuneField, ...]
    initial: np.ndarray
    metric_names: tuple[str, ...]
    size: int
    _loop: Any
    _chunks: list[tuple[Any, Any, int]]  # (batch, in_axes, real runs)
    _slots: list[tuple[int, np.ndarray] | None]  # (leaf position, flat indices); None: rebuilt
    _raws: list[list[Mapping[str, Any]]] | None = None  # each chunk's scenarios (rebuilt fields)

    @property
    def batch(self) -> Any:
        """The parameters of the first (for a training set: the only) batch."""
        return self._chunks[0][0]

    def _write(self, batch, theta, traced: bool = False):
        import jax
        import jax.numpy as jnp

        leaves, treedef = jax.tree_util.tree_flatten(batch)
        for slot, v in zip(self._slots, theta, strict=True):
            if slot is None:  # a rebuilt field: already in the batch
                continue
            n, index = slot
            if traced:
                leaf = jnp.asarray(leaves[n])
                leaves[n] = leaf.reshape(-1).at[index].set(v).reshape(leaf.shape)
            else:
                leaves[n] = np.array(leaves[n], dtype=np.float64, copy=True)
                leaves[n].reshape(-1)[index] = float(v)
        return jax.tree_util.tree_unflatten(treedef, leaves)

    def outputs(self, theta, batch=None):
        """JAX, traceable: ``(metrics, diverged)`` of the first batch at gains ``theta`` (a jitted
        caller passes ``batch`` as an argument, so that it is not compiled in as constants)."""
        import jax

        if self._raws is not None:
            rebuilt = [f.path for f in self.fields if f.rebuild]
            raise TuneError(
                f"{rebuilt} are rebuilt at each evaluation (rebuild = true): no traced form, so no "
                "gradient; use evaluate() (optimisers nelder-mead, powell)"
            )
        run = jax.vmap(type(self._loop).run, in_axes=(self._chunks[0][1],), axis_size=self.size)
        out = run(self._write(self.batch if batch is None else batch, theta, traced=True))
        return dict(zip(self.metric_names, out["metrics"], strict=True)), out["diverged_step"] >= 0

    def evaluate(
        self, theta: Sequence[float] | np.ndarray
    ) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """Every run at gains ``theta`` [field units] through the package's cached batch program:
        ``(metrics {name: (runs, ...)}, diverged (runs,))``."""
        import jax

        from formation_ftc.sim.batch import batched_run

        parts, bads = [], []
        for k, (batch, in_axes, n) in enumerate(self._chunks):
            if self._raws is not None:
                batch = self._rebuilt(self._raws[k], theta, in_axes)
            fn = batched_run(self._loop, in_axes, self.size)
            out = jax.device_get(fn(self._write(batch, theta)))
            parts.append([np.asarray(v)[:n] for v in out["metrics"]])
            bads.append(np.asarray(out["diverged_step"])[:n] >= 0)
        metrics = {k: np.concatenate(vs) for k, *vs in zip(self.metric_names, *parts, strict=True)}
        return metrics, np.concatenate(bads)

    def _rebuilt(self, raws, theta, in_axes) -> Any:
        """The batch of ``raws`` built with the rebuilt fields at ``theta``, laid out as ``in_axes``."""
        values = {f.path: float(v) for f, v in zip(self.fields, theta, strict=True) if f.rebuild}
        built = _build_runs(raws, values)
        if built[0].static_key != self._loop.static_key:
            raise TuneError(
                f"tune fields {sorted(values)} at {values}: the loop's structure changes (another "
                "compiled program); only numeric inputs can be tuned"
            )
        batch, axes = _stack_like(built, in_axes, self.size)
        if axes is not in_axes:
            raise TuneError(f"tune fields {sorted(values)}: the rebuilt runs differ in layout")
        return batch


def _build_runs(raws: Sequence[Mapping[str, Any]], values: Mapping[str, float] = {}) -> list[Any]:
    """The loops of ``raws`` (with the dotted ``values`` set), which must share one structure; a run
    that does not build is a TuneError."""
    from formation_ftc import api
    from formation_ftc.config.loader import apply_overrides

    try:
        scenarios = [api.load_scenario(apply_overrides(dict(r), dict(values))) for r in raws]
        loops = [api.build_loop(s) for s in scenarios]
    except InputError:
        raise
    except (ValueError, TypeError) as exc:
        raise TuneError(f"{_UNBUILT}: {exc}") from None
    if any(c.static_key != loops[0].static_key for c in loops[1:]):
        raise TuneError("tuning: the runs do not share one structure (one compiled program)")
    return loops


def _stack_like(params: Sequence[Any], in_axes: Any, size: int) -> tuple[Any, Any]:
    """``params`` stacked with the batched leaves of ``in_axes`` (so that its program serves them), or
    in their own layout where a leaf that ``in_axes`` shares differs between them."""
    import jax

    from formation_ftc.sim.batch import stack_params

    batch, axes = stack_params(params, size)
    leaves, treedef = jax.tree_util.tree_flatten(batch)
    want = treedef.flatten_up_to(in_axes)  # type: ignore[attr-defined]  # PyTreeDef in jax stubs
    have = treedef.flatten_up_to(axes)  # type: ignore[attr-defined]
    if any(w is None and h is not None for w, h in zip(want, have, strict=True)):
        return batch, axes
    leaves = [
        np.repeat(np.asarray(x)[None], size, axis=0) if h is None and w is not None else x
        for x, w, h in zip(leaves, want, have, strict=True)
    ]
    return jax.tree_util.tree_unflatten(treedef, leaves), in_axes


def build_problem(
    raws: Sequence[Mapping[str, Any]],
    fields: Sequence[TuneField],
    like: GainProblem | None = None,
) -> GainProblem:
    """The full scenarios ``raws`` (one structure) as batches with ``fields`` bound to their leaves.

    Every field must be one finite number, the same in every run and inside its bounds, and a numeric
    leaf of the built loop holding exactly it: the first run is built again with another value and its
    whole parameter tree compared with the bound one (a derived, structural or coupled field fails,
    named). ``like``: lay the runs out as that problem's batches (size and batched leaves, the last
    batch padded), so that its compiled program serves them too (held-out runs); default: one batch.
    """
    import jax

    from formation_ftc.campaign.binding import bind_fields
    from formation_ftc.config.loader import get_dotted
    from formation_ftc.sim.batch import stack_params

    fields = tuple(fields)
    if not raws:
        raise TuneError("tuning: no runs")
    if not fields:
        raise TuneError("tuning: no tunable fields (give a [tune] fields table)")
    if len({f.path for f in fields}) != len(fields):
        raise TuneError(f"tuning: a field is listed twice ({[f.path for f in fields]})")
    initial = []
    for f in fields:
        try:
            v0, *vals = [get_dotted(raw, f.path) for raw in raws]
        except KeyError:
            raise TuneError(
                f"tune field {f.path!r}: the scenario has no such field (give the law's paper "
                "value in the method file)"
            ) from None
        if isinstance(v0, bool) or not isinstance(v0, int | float) or not math.isfinite(v0):
            raise TuneError(
                f"tune field {f.path!r}: {v0!r} is not one finite number (a tunable field is one "
                "scalar gain)"
            )
        if any(v != v0 for v in vals):
            raise TuneError(f"tune field {f.path!r}: differs between the runs")
        if not f.low <= v0 <= f.high:
            raise TuneError(
                f"tune field {f.path!r}: the paper value {v0:g} lies outside the bounds "
                f"[{f.low:g}, {f.high:g}]"
            )
        initial.append(float(v0))
    if like is not None and [f.rebuild for f in fields] != [f.rebuild for f in like.fields]:
        raise TuneError("tuning: the held-out fields are not the training ones")
    loops = _build_runs(raws)
    template = loops[0]
    key = template.static_key
    if not getattr(template, "metrics", ()):
        raise TuneError("tuning: the scenario computes no metrics (nothing to minimise)")
    bindings = {}
    for f, v0 in zip(fields, initial, strict=True):
        if f.rebuild:
            continue
        bound = bind_fields(template, {f.path: v0})
        if not bound:
            raise TuneError(
                f"tune field {f.path!r}: not a numeric leaf of the built loop (its builder derives "
                "the parameters from it, or it names no component attribute); declare it with "
                "rebuild = true to build the runs again at each evaluation"
            )
        bindings[f.path] = bound[f.path]
    if like is None:
        _check_bindings(raws[0], fields, initial, template, key, bindings)
        size = len(raws)
        chunks = [(*stack_params(loops), size)]
    else:
        if like._loop.static_key != key:
            raise TuneError("tuning: these runs do not have the structure of the training runs")
        size, in_axes = like.size, like._chunks[0][1]
        parts = [loops[s : s + size] for s in range(0, len(loops), size)]
        chunks = [(*_stack_like(p, in_axes, size), len(p)) for p in parts]
    chunked_raws = [list(raws[s : s + size]) for s in range(0, len(raws), size)]
    treedef = jax.tree_util.tree_structure(template)
    for path, b in bindings.items():
        if any(treedef.flatten_up_to(ax)[b.leaf] is not None for _, ax, _ in chunks):  # type: ignore[attr-defined]
            raise TuneError(
                f"tune field {path!r}: its leaf differs between the runs (another field or a "
                "sampled value shares it)"
            )
    return GainProblem(
        fields=fields,
        initial=np.asarray(initial, dtype=np.float64),
        metric_names=tuple(m.name for m in template.metrics),
        size=size,
        _loop=template,
        _chunks=chunks,
        _slots=[
            None if f.rebuild else (bindings[f.path].leaf, np.asarray(bindings[f.path].index))
            for f in fields
        ],
        _raws=chunked_raws if any(f.rebuild for f in fields) else None,
    )


def _check_bindings(raw, fields, initial, template, key, bindings) -> None:
    """Build ``raw`` again with each field moved and compare the whole parameter tree with the
    template's with the bound leaf written: a derived or structural field fails, named."""
    from formation_ftc import api
    from formation_ftc.campaign.binding import apply_bindings, params_close, take_run
    from formation_ftc.config.loader import apply_overrides

    for f, v0 in zip(fields, initial, strict=True):
        z0 = f.to_unit(v0)
        v1 = float(f.from_unit(0.5 * z0 + 0.37 if abs(z0 - 0.74) > 1e-3 else 0.3))  # inside
        try:
            c = api.build_loop(api.load_scenario(apply_overrides(dict(raw), {f.path: v1})))
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
        if f.rebuild:
            if params_close(template, c):
                raise TuneError(
                    f"tune field {f.path!r}: another value changes nothing in the built loop (the "
                    "builder does not use it in this scenario)"
                )
            continue
        one = {f.path: bindings[f.path]}
        batch, axes = apply_bindings(template, one, {f.path: np.asarray([v1])}, 1)
        if not params_close(take_run(batch, axes, 0), c):
            raise TuneError(
                f"tune field {f.path!r}: not a numeric leaf of the built loop -- another value also "
                "moves parameters derived from it (the builder scales or converts it); tune the "
                "field the loop holds as it is"
            )


def _check_penalty_options(margin: float, penalty: float, violation_cap: float) -> None:
    """The requirement penalty's options of :func:`penalised_objective`, each named when out of range."""
    for name, value, ok, allowed in (
        ("margin", margin, 0 <= margin < 1, "in [0, 1)"),
        ("penalty", penalty, penalty >= 0, ">= 0"),
        ("violation_cap", violation_cap, violation_cap > 0, "> 0 (inf: no cap)"),
    ):
        if not ok:
            raise TuneError(f"{name} = {value}: {allowed}")


def penalised_objective(
    objective: str | Callable[[Mapping[str, Any]], Any],
    *,
    statistic: str = "mean",
    requirement: tuple[str, float] | None = None,
    margin: float = 0.1,
    penalty: float = 100.0,
    violation_cap: float = 1.0,
    bad_run_penalty: float = 10.0,
    scale: float = 1.0,
) -> Callable[[Mapping[str, Any], Any], Any]:
    """``J(metrics, bad) -> (value, terms)`` of docs/tuning.md, a JAX function of one batch's metrics.

    ``objective``: a metric name or ``metrics -> (runs,)`` cost; ``requirement``: (metric, maximum),
    tightened by ``margin``, each run's relative violation capped at ``violation_cap`` (a run that
    fails by more counts as one failure, whatever its error) and weighted by ``penalty`` (None:
    unconstrained); a diverged or non-finite run counts as ``f = scale`` with a violation of
    ``bad_run_penalty``. ``terms``: the statistic of the objective (unscaled), the mean violation and
    the fraction of failing runs.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> J = penalised_objective("dv", requirement=("err", 1.0), margin=0.0, penalty=10.0, scale=2.0)
    >>> value, terms = J({"dv": jnp.array([1.0, 3.0]), "err": jnp.array([0.5, 1.5])}, jnp.array([False, False]))
    >>> float(value), float(terms["objective"]), float(terms["fail_fraction"])
    (3.5, 2.0, 0.5)
    >>> value, _ = J({"dv": jnp.array([1.0, 3.0]), "err": jnp.array([0.5, 9.0])}, jnp.array([False, False]))
    >>> float(value)  # 9 m counts as a violation of 1 (the cap), as 2 m would
    6.0
    """
    import jax.numpy as jnp

    if statistic not in ("mean", "median"):
        raise TuneError(f"statistic = {statistic!r}: 'mean' or 'median'")
    _check_penalty_options(margin, penalty, violation_cap)
    stat = jnp.mean if statistic == "mean" else jnp.median

    def J(metrics, bad):
        f = jnp.asarray(metrics[objective] if isinstance(objective, str) else objective(metrics))
        bad_f = bad | ~jnp.isfinite(f)
        f_ok = jnp.where(bad_f, scale, f)
        fail = bad_f
        viol = jnp.zeros_like(f_ok)
        if requirement is not None:
            m = jnp.asarray(metrics[requirement[0]])
            bad_m = bad | ~jnp.isfinite(m)
            m_ok = jnp.where(bad_m, 0.0, m)
            excess = jnp.clip(m_ok / ((1.0 - margin) * requirement[1]) - 1.0, 0.0, violation_cap)
            viol = jnp.where(bad_m, bad_run_penalty, excess)
            fail = bad_f | bad_m | (m_ok > requirement[1])
        viol = jnp.where(bad_f, bad_run_penalty, viol)
        obj = stat(f_ok)
        return obj / scale + penalty * jnp.mean(viol), {
            "objective": obj,
            "violation": jnp.mean(viol),
            "fail_fraction": jnp.mean(fail.astype(f_ok.dtype)),
        }

    return J


@dataclass
class TuneOutcome:
    """What :func:`minimise` found: the best gains evaluated [field units], J and its terms there and
    at the start, the batch evaluations (a gradient one costs about 1 + fields forward runs), the wall
    time and that of the first evaluation (compilation) [s], every evaluation's gains and J, and the
    optimiser's own message."""

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
    journal: TuneJournal | None = None,
    on_evaluation: Callable[[], None] | None = None,
) -> TuneOutcome:
    """Minimise ``J`` (:func:`penalised_objective`) over the problem's gains within their bounds, from
    ``start`` (default: the scenario's gains), in at most ``max_evaluations`` batch evaluations.

    ``optimiser``: scipy's bounded ``"nelder-mead"`` (from a simplex of 15 % of each scaled range) or
    ``"powell"``, or ``"gradient"``: L-BFGS-B with :func:`jax.jacfwd` through the vmapped loop.
    ``tolerance`` is on the scaled gains (and on J, derivative-free). ``journal``: each evaluation is
    looked up there first and recorded there once computed (:class:`TuneJournal`: a resumed tuning
    replays its evaluations, so the optimiser takes the same path); ``on_evaluation`` is called after
    each one (progress). The LQR oracle in tests/league/test_tuning.py is the example.
    """
    import jax
    import jax.numpy as jnp
    from scipy import optimize

    if optimiser not in OPTIMISERS:
        raise TuneError(f"optimiser = {optimiser!r}: one of {', '.join(OPTIMISERS)}")
    if max_evaluations < 2:
        raise TuneError(f"max_evaluations = {max_evaluations}: at least 2")
    fields = problem.fields
    x_start = problem.initial if start is None else start
    z0 = np.clip([f.to_unit(v) for f, v in zip(fields, x_start, strict=True)], 0.0, 1.0)
    bounds = [(0.0, 1.0)] * len(fields)
    history: list[tuple[list[float], float]] = []
    seen: dict[bytes, tuple[float, dict[str, float]]] = {}  # scaled gains -> (J, terms)
    compile_s: list[float] = []

    def gains(z) -> list[float]:
        return [float(f.from_unit(float(zi))) for f, zi in zip(fields, z, strict=True)]

    def record(z, v, terms, since: float) -> float:
        v = float(v) if math.isfinite(float(v)) else 1e6
        if not compile_s:
            compile_s.append(time.perf_counter() - since)
        history.append((gains(z), v))
        key = np.asarray(z, dtype=np.float64).tobytes()
        seen[key] = (v, {k: float(t) for k, t in terms.items()})
        if on_evaluation is not None:
            on_evaluation()
        return v

    options: dict[str, Any]  # scipy's, of the optimiser's method
    t0 = time.perf_counter()
    if optimiser == "gradient":
        if len(problem._chunks) != 1:
            raise TuneError("optimiser 'gradient': the training runs must be one batch")

        def value(z, batch):
            theta = jnp.stack([f.from_unit(z[i]) for i, f in enumerate(fields)])
            v, terms = J(*problem.outputs(theta, batch))
            return v, (v, terms)

        vg = jax.jit(jax.jacfwd(value, has_aux=True))

        def gradient(z) -> dict[str, Any]:
            grad, (v, terms) = vg(jnp.asarray(z), problem.batch)
            return {
                "value": float(v),
                "terms": {k: float(t) for k, t in terms.items()},
                "grad": np.asarray(grad, dtype=np.float64).tolist(),
            }

        def fun(z):
            ts = time.perf_counter()
            hit = _journalled(journal, TuneJournal.key("gradient", z), lambda: gradient(z))
            g = np.asarray(hit["grad"], dtype=np.float64)
            return record(z, hit["value"], hit["terms"], ts), np.where(np.isfinite(g), g, 0.0)

        method = "L-BFGS-B"
        options = dict(maxfun=max_evaluations, maxiter=max_evaluations, gtol=tolerance)
    else:

        def fun(z):
            z = np.clip(np.asarray(z, dtype=np.float64), 0.0, 1.0)
            if z.tobytes() in seen:
                return seen[z.tobytes()][0]
            ts = time.perf_counter()
            return record(z, *J(*evaluate(problem, gains(z), journal)), ts)

        method = "Nelder-Mead" if optimiser == "nelder-mead" else "Powell"
        options = {"maxfev": max_evaluations, "xtol": tolerance, "ftol": tolerance}
        if optimiser == "nelder-mead":  # the same tolerances under scipy's names, and the simplex
            step = np.where(z0 + _NM_STEP <= 1.0, _NM_STEP, -_NM_STEP)  # inward at the top end
            options = {"maxfev": max_evaluations, "xatol": tolerance, "fatol": tolerance}
            options["initial_simplex"] = np.vstack([z0, z0 + np.diag(step)])
    jac = optimiser == "gradient"  # L-BFGS-B: fun returns J and its gradient
    res = optimize.minimize(fun, z0, jac=jac, method=method, bounds=bounds, options=options)
    seconds = time.perf_counter() - t0
    if z0.tobytes() not in seen:
        fun(z0)
    z_best, (v_best, terms_best) = min(seen.items(), key=lambda kv: kv[1][0])  # an optimiser may
    v_start, terms_start = seen[z0.tobytes()]  # stop elsewhere than its best point
    return TuneOutcome(
        gains=np.asarray(gains(np.frombuffer(z_best, dtype=np.float64))),
        value=v_best,
        initial_value=v_start,
        terms=dict(terms_best),
        initial_terms=dict(terms_start),
        optimiser=optimiser,
        evaluations=len(history),
        seconds=seconds,
        compile_seconds=compile_s[0] if compile_s else 0.0,
        history=history,
        message=str(getattr(res, "message", "")),
    )


def replicate_raws(spec, method: str, cells, replicates: Sequence[int]):
    """The full scenarios of ``cells`` (a method's league cells) for league replicates ``replicates``,
    cell-major, drawn exactly as ``league run`` draws them (paired across cells), and the labels
    ``{"case", "level", "replicate"}`` of each: ``(raws, labels)``."""
    from formation_ftc.campaign.sampling import draw_value, run_seed
    from formation_ftc.campaign.spec import parse_sampler
    from formation_ftc.config.loader import apply_overrides
    from formation_ftc.league.runner import _campaign

    camp = _campaign(spec, method, [], 1, [])
    seed = int(spec.league.seed)
    samplers = [parse_sampler(p, s) for p, s in camp["sample"].items()]
    draws = {
        j: {
            "simulation.seed": run_seed(seed, j),
            **{s.path: draw_value(s, seed, j) for s in samplers},
        }
        for j in replicates
    }
    runs = [(c, j) for c in cells for j in replicates]
    raws = [apply_overrides(c.raw, {**camp["overrides"], **draws[j]}) for c, j in runs]
    return raws, [{"case": c.case, "level": c.level, "replicate": int(j)} for c, j in runs]


def _pass_stats(metrics, bad, requirement, objective: str, idx=slice(None)) -> dict[str, Any]:
    m = np.asarray(metrics[requirement[0]], dtype=float)[idx]
    f = np.asarray(metrics[objective], dtype=float)[idx]
    bad = np.asarray(bad)[idx]
    ok = ~bad & np.isfinite(m)
    fin = ok & np.isfinite(f)
    return {
        "runs": int(m.size),
        "pass_rate": float(np.mean(ok & (m <= requirement[1]))),
        "diverged": int(np.sum(bad)),
        f"{objective}_mean": float(np.mean(f[fin])) if fin.any() else None,
        f"{objective}_median": float(np.median(f[fin])) if fin.any() else None,
        f"{requirement[0]}_median": float(np.median(m[ok])) if ok.any() else None,
        # what the mean and the medians cover: the finished runs (a diverged run has no score)
        "finished": int(np.sum(fin)),
        "left_out": int(m.size - np.sum(fin)),
    }


# -------------------------------------------------------------------------------------- journal
JOURNAL_KIND = "formation-ftc tuning journal"


class TuneJournal:
    """The completed evaluations of one tuning problem, so that a killed ``tune`` resumes instead of
    starting again: ``path`` (``OUT/METHOD--LEVEL.journal.jsonl``) holds one JSON line per completed
    evaluation (its gains -> every run's scores, or J and its gradient), after a header naming the
    problem (``problem``: league and its hash, method, level, cases, seeds, optimiser, options) and
    its sha256 fingerprint. Each line is appended and synced once its evaluation is complete; a kill
    while a line is written leaves it unfinished at the end, and it is dropped on the next start (the
    journal is rewritten without it, atomically). A journal of another problem, or a damaged one, is
    refused (TuneError, exit code 2) unless ``force``, which discards it.

    Examples
    --------
    >>> import tempfile
    >>> path = Path(tempfile.mkdtemp()) / "m--l.journal.jsonl"
    >>> j = TuneJournal(path, {"method": "m"})
    >>> j.put(TuneJournal.key("train", [0.5]), {"x": 1})
    >>> TuneJournal(path, {"method": "m"}).get("train 0x1.0000000000000p-1")
    {'key': 'train 0x1.0000000000000p-1', 'x': 1}
    >>> TuneJournal(path, {"method": "n"})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    formation_ftc.league.tuning.TuneError: ... the journal of another tuning problem (method: 'm' there, 'n' here); ...
    """

    def __init__(self, path: str | Path, problem: Mapping[str, Any], *, force: bool = False):
        self.path = Path(path)
        self.problem = json.loads(json.dumps(dict(problem), sort_keys=True))
        text = json.dumps(self.problem, sort_keys=True)
        self.fingerprint = hashlib.sha256(text.encode()).hexdigest()
        self.entries: dict[str, dict[str, Any]] = {}
        if self.path.exists() or self.path.is_symlink():
            try:
                self._load()
            except TuneError:
                if not force:
                    raise
                self.entries = {}
        self.resumed = len(self.entries)
        header = {"kind": JOURNAL_KIND, "fingerprint": self.fingerprint, "problem": self.problem}
        lines = [json.dumps(header), *(json.dumps(e) for e in self.entries.values())]
        with self._io():
            atomic_write(self.path, "\n".join(lines) + "\n")

    @staticmethod
    def key(name: str, values: Sequence[float] | np.ndarray) -> str:
        """The key of an evaluation: its kind and its numbers, exactly (hexadecimal floats)."""
        return " ".join([name, *map(float.hex, np.ravel(np.asarray(values, dtype=float)))])

    def get(self, key: str) -> dict[str, Any] | None:
        return self.entries.get(key)

    def put(self, key: str, record: Mapping[str, Any]) -> None:
        """Record a completed evaluation (appended and synced before this returns)."""
        entry = {"key": key, **record}
        with self._io(), open(self.path, "a", encoding="utf-8") as f:
            f.write(json.dumps(entry) + "\n")
            f.flush()
            os.fsync(f.fileno())
        self.entries[key] = entry

    @contextlib.contextmanager
    def _io(self) -> Iterator[None]:
        """Writing the journal: its directory made, an OSError a TuneError naming it."""
        where = f"--out {self.path.parent}: cannot write the tuning journal {self.path.name} there"
        with oserror_as(TuneError, where):
            self.path.parent.mkdir(parents=True, exist_ok=True)
            yield

    def _load(self) -> None:
        advice = "give another --out, or --force to discard the journal and start again"
        try:
            text = self.path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise TuneError(
                f"{self.path}: unreadable tuning journal ({getattr(exc, 'strerror', None) or exc}); "
                f"{advice}"
            ) from None
        *lines, tail = text.split("\n")
        if tail:  # no newline yet: written when the process was killed; kept only when it is whole
            with contextlib.suppress(ValueError):
                json.loads(tail)
                lines.append(tail)
        header = None
        with contextlib.suppress(ValueError):
            header = json.loads(lines[0]) if lines else None
        if not isinstance(header, dict) or header.get("kind") != JOURNAL_KIND:
            raise TuneError(
                f"{self.path}: not a tuning journal (damaged, or another file); {advice}"
            )
        if header.get("fingerprint") != self.fingerprint:
            theirs = header["problem"] if isinstance(header.get("problem"), dict) else {}
            diff = [
                f"{k}: {theirs.get(k)!r} there, {self.problem.get(k)!r} here"
                for k in sorted(set(theirs) | set(self.problem))
                if theirs.get(k) != self.problem.get(k)
            ]
            raise TuneError(
                f"--out {self.path.parent}: {self.path.name} is the journal of another tuning "
                f"problem ({'; '.join(diff[:4]) or 'another fingerprint'}); give the options it was "
                f"started with to resume it, or {advice}"
            )
        for n, line in enumerate(lines[1:], start=2):
            entry = None
            with contextlib.suppress(ValueError):
                entry = json.loads(line)
            if not isinstance(entry, dict) or not isinstance(entry.get("key"), str):
                raise TuneError(f"{self.path}: line {n} is damaged; {advice}")
            self.entries[entry["key"]] = entry


def evaluate(
    problem: GainProblem,
    theta: Sequence[float] | np.ndarray,
    journal: TuneJournal | None = None,
    name: str = "train",
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """:meth:`GainProblem.evaluate` through ``journal``: an evaluation it holds (the set ``name`` at the
    same gains) is read back, exactly (dtype and shape kept); another one is computed and recorded."""

    def compute() -> dict[str, Any]:
        metrics, bad = problem.evaluate(theta)
        return {
            "metrics": {k: np.asarray(v).tolist() for k, v in metrics.items()},
            "dtypes": {k: np.asarray(v).dtype.str for k, v in metrics.items()},
            "shapes": {k: list(np.shape(v)) for k, v in metrics.items()},
            "diverged": np.asarray(bad, dtype=bool).tolist(),
        }

    # computed or read back, the runs' numbers come from the record (a float's list form is exact)
    hit = _journalled(journal, TuneJournal.key(name, theta), compute)
    metrics = {
        k: np.asarray(v, dtype=hit["dtypes"][k]).reshape(hit["shapes"][k])
        for k, v in hit["metrics"].items()
    }
    return metrics, np.asarray(hit["diverged"], dtype=bool)


def _journalled(
    journal: TuneJournal | None, key: str, compute: Callable[[], dict[str, Any]]
) -> dict[str, Any]:
    """The record ``key`` of ``journal``; where it holds none (or there is no journal), the record
    ``compute()`` returns, journalled."""
    hit = journal.get(key) if journal is not None else None
    if hit is None:
        hit = compute()
        if journal is not None:
            journal.put(key, hit)
    return hit


def journal_path(out_dir: str | Path, method: str, level: str) -> Path:
    """Where ``tune`` journals the evaluations of ``method`` at ``level`` (next to its result)."""
    return Path(out_dir) / f"{method}--{level}.journal.jsonl"


# -------------------------------------------------------------------------------------- budgets
def check_tune_budgets(
    cells: Sequence[Any],
    *,
    n_fields: int,
    train_seeds: int,
    holdout_seeds: int,
    max_evaluations: int,
    optimiser: str,
    budgets: Budgets,
    where: str,
    run_bytes: int | None = None,
) -> None:
    """Refuse, before anything runs, a tuning over the budgets campaigns have
    (:mod:`formation_ftc.limits`): at most :data:`~formation_ftc.campaign.spec.MAX_RUNS` training and
    held-out seeds per cell, the integration steps of every cell's run, the run-steps of the whole
    tuning (training runs x evaluations, a gradient evaluation counting 1 + fields forward runs, plus
    the held-out runs at the paper and the tuned gains) within ``budgets.max_campaign_steps``, and
    (``run_bytes``: one run's memory) the training batch within ``budgets.max_memory``. The message
    names the option to lower and the range it allows.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> cells = [SimpleNamespace(n_steps=1000, key="none--limited")]
    >>> check_tune_budgets(cells, n_fields=2, train_seeds=10**9, holdout_seeds=1, max_evaluations=9,
    ...     optimiser="nelder-mead", budgets=Budgets(), where="tune m @ limited")
    Traceback (most recent call last):
    ...
    formation_ftc.league.tuning.TuneError: --train-seeds 1,000,000,000: allowed: --train-seeds 1 to 10,000,000 (the runs per cell a campaign allows)
    """
    from formation_ftc.campaign.spec import MAX_RUNS
    from formation_ftc.limits import check_run_steps, format_bytes

    T, H, E, n = int(train_seeds), int(holdout_seeds), int(max_evaluations), int(n_fields)
    for opt, v in (("--train-seeds", T), ("--holdout-seeds", H)):
        if not 1 <= v <= MAX_RUNS:
            raise TuneError(
                f"{opt} {v:,}: allowed: {opt} 1 to {MAX_RUNS:,} (the runs per cell a campaign allows)"
            )
    if E < 2:
        raise TuneError(f"--max-evaluations {E:,}: allowed: --max-evaluations 2 or more")
    for c in cells:
        check_run_steps(c.n_steps, budgets, f"{where}, cell {c.key}")
    sps = sum(int(c.n_steps) for c in cells)  # one seed of every cell
    k = 1 + n if optimiser == "gradient" else 1  # forward runs per evaluation

    # per training seed: the optimiser's evaluations (scipy may pass its budget by one simplex), then
    # the paper, the start and the tuned gains; held out: the paper and tuned gains, in batches padded
    # to the training one
    per_train = k * (E + n + 1) + 3
    held = 2 * (H + T - 1)
    total = sps * (T * per_train + held)
    budget = budgets.max_campaign_steps
    if budget is not None and sps and total > budget:
        size = (
            f"{where} would simulate up to {total:,} run-steps ({len(cells)} cell(s); "
            f"{T:,} training seed(s) x {per_train:,} evaluations, {H:,} held-out seed(s) x 2)"
        )
        limit = (
            f"the budget of {budget:,} run-steps (raise it with --max-campaign-steps / "
            "FORMATION_FTC_MAX_CAMPAIGN_STEPS)"
        )
        room = budget // sps  # seed-runs of every cell
        e_max = ((room - held) // T - 3) // k - n - 1
        t_max = (room - 2 * H + 2) // (per_train + 2)
        h_max = (room - per_train * T) // 2 - T + 1
        # the first option that alone can bring the tuning within the budget
        for opt, value, low, high, others in (
            ("--max-evaluations", E, 2, e_max, f"--train-seeds {T:,} and --holdout-seeds {H:,}"),
            ("--train-seeds", T, 1, t_max, f"--max-evaluations {E:,} and --holdout-seeds {H:,}"),
            ("--holdout-seeds", H, 1, h_max, f"--train-seeds {T:,} and --max-evaluations {E:,}"),
        ):
            if high >= low:
                raise TuneError(
                    f"{opt} {value:,}: {size}, over {limit}; allowed: {opt} {low} to {high:,} "
                    f"with {others}"
                )
        raise TuneError(
            f"{size}, over {limit}; lower --train-seeds, --holdout-seeds and --max-evaluations, "
            "or tune on fewer --cases"
        )
    if run_bytes is not None and budgets.max_memory is not None and cells:
        per_seed = int(run_bytes) * len(cells) * k
        if per_seed * T > budgets.max_memory:
            t_max = budgets.max_memory // per_seed
            allowed = f"allowed: --train-seeds 1 to {t_max:,}"
            if t_max < 1:
                allowed = "even 1 seed per cell is over it: tune on fewer --cases"
            raise TuneError(
                f"--train-seeds {T:,}: {where}: a training batch of {len(cells) * T:,} runs needs "
                f"about {format_bytes(per_seed * T)} of memory, over the budget of "
                f"{format_bytes(budgets.max_memory)}; {allowed}, or raise the budget with "
                "--max-memory / FORMATION_FTC_MAX_MEMORY"
            )


# ------------------------------------------------------------------------------------------ --out
def check_tune_out(out_dir: str | Path, method: str, level: str, *, force: bool = False) -> None:
    """Refuse, before anything is computed, an ``--out`` the result of ``method`` at ``level`` may not
    go to: a file or a device (or a path under one), an unwritable directory, a campaign directory
    (or a path inside one), a league directory (its ``tuned/`` subdirectory is the place), a
    directory holding anything but tuning results and journals, or one that holds this result
    already (unless ``force``). A file of the result's name that is not a tuning result is never
    replaced."""
    from formation_ftc.league.runner import LEAGUE_FILE, _check_target

    out = Path(out_dir)
    what = f"--out {out}"
    result = f"{method}--{level}.json"
    with oserror_as(TuneError, f"{what}: unusable path"):
        if not _check_target(
            out,
            what,
            TuneError,
            "give a directory of its own for tuning results (new, empty or holding tuning results)",
            "give a directory for tuning results",
        ):
            parent = next(p for p in out.absolute().parents if p.exists() or p.is_symlink())
            if not parent.is_dir():
                raise TuneError(f"{what}: {parent} is not a directory; give a directory")
            if not os.access(parent, os.W_OK | os.X_OK):
                raise TuneError(f"{what}: cannot create it ({parent} is not writable)")
            return
        if not os.access(out, os.W_OK | os.X_OK):
            raise TuneError(f"{what}: not writable")
        entries = sorted(e.name for e in out.iterdir())
        if LEAGUE_FILE in entries:
            raise TuneError(
                f"{what}: is a league directory; give its tuned/ subdirectory (--out "
                f"{out / 'tuned'}), which `league report` reads"
            )
        own = journal_path(out, method, level).name  # judged (resumed or refused) by TuneJournal
        foreign = [
            e for e in entries if not (e == own or TMP_RE.match(e) or _is_tuning_file(out / e))
        ]
        if foreign:
            raise TuneError(
                f"{what}: holds files that are not tuning results (e.g. {foreign[:3]}); refusing to "
                "write there: give a new or empty directory, or one of tuning results"
            )
        if result in entries and not force:
            raise TuneError(
                f"{what}: holds a tuning result of {method} at {level} already ({result}); "
                "--force replaces it, or give another --out"
            )


def _is_tuning_file(path: Path) -> bool:
    """A tuning result (``kind`` "formation-ftc tuning") or journal, judged by its content."""
    if not path.is_file() or path.is_symlink():
        return False
    try:
        with open(path, encoding="utf-8") as f:
            if path.name.endswith(".journal.jsonl"):
                return json.loads(f.readline()).get("kind") == JOURNAL_KIND
            return path.suffix == ".json" and json.load(f).get("kind") == "formation-ftc tuning"
    except (OSError, ValueError, AttributeError):
        return False


# ------------------------------------------------------------------------------------------- tune
def tune_league_method(
    league,
    method: str,
    level: str,
    *,
    cases: Sequence[str] | None = None,
    train_seeds: int = 8,
    holdout_seeds: int = 16,
    fresh_seeds: int | None = None,
    train_start: int = TRAIN_START,
    gains: Mapping[str, float] | None = None,
    optimiser: str = DEFAULT_OPTIMISER,
    max_evaluations: int = 60,
    margin: float = 0.1,
    penalty: float = 100.0,
    violation_cap: float = 1.0,
    step_checks: Mapping[str, Any] | None = None,
    log: Callable[[str], None] | None = None,
    budgets: Budgets | None = None,
    journal: str | Path | None = None,
    force: bool = False,
    progress: bool = False,
) -> dict[str, Any]:
    """Tune ``method``'s ``[tune]`` fields at actuator ``level`` of ``league`` (a name, file or
    :class:`~formation_ftc.league.definition.LeagueSpec`); the result as a JSON-able dict (the fields
    of docs/tuning.md). The options are those of ``formation-ftc tune``; ``log`` receives progress
    lines, ``progress``: progress lines with ETA on a terminal's stderr (step check, evaluations).

    The runs fly at the step the league's step check chooses for the method (as ``league run``
    does): the check runs here unless ``step_checks`` (a league's ``league.json`` record
    ``step_check``, ``{method: record}``) holds it. ``budgets`` (default :meth:`Budgets.resolve`)
    bound the tuning before anything runs (:func:`check_tune_budgets`). ``journal``: a file where
    the step check and every evaluation are recorded as they complete (:class:`TuneJournal`); a
    tuning of the same problem started again replays them and continues, to the same result;
    ``force`` discards a journal of another problem instead of refusing it. Raises TuneError or
    LeagueError (exit code 2) naming a bad league, method, level, case, field or option.

    Held out are the league's replicates 0 .. ``holdout_seeds`` - 1 (the leaderboard's own first
    seeds); ``fresh_seeds`` (default: as many) more are replicates neither the league nor the training
    uses (from ``max(league seeds, train_start + train_seeds)``): the result's ``fresh`` block.
    ``gains`` (field path -> value; fields not given keep the paper's): evaluate those gains against
    the paper's on the held-out and fresh replicates, with no training and no optimiser."""
    from formation_ftc import __version__
    from formation_ftc.league import runner
    from formation_ftc.league.definition import LeagueSpec, league_hash, load_league, method_tune

    say = log or (lambda _line: None)
    spec = league if isinstance(league, LeagueSpec) else load_league(league)
    entry = spec.method(method)
    tune = method_tune(spec, entry)  # validated: fields, bounds, paper values, objective
    if tune is None:
        raise TuneError(
            f"method {method}: its file ({entry.scenario}) has no [tune] table: declare the tunable "
            'fields and bounds, e.g. [tune] fields = {"controller.k" = [0.05, 1.0]}'
        )
    levels = [lv.name for lv in spec.levels]
    if level not in levels:
        raise TuneError(f"--level {level!r}: not a level of league {spec.league.name} ({levels})")
    if optimiser not in OPTIMISERS:
        raise TuneError(f"--optimiser {optimiser!r}: one of {', '.join(OPTIMISERS)}")
    # the requirement penalty's options (in the order of the result's objective block)
    penalty_options = {"penalty": penalty, "violation_cap": violation_cap, "margin": margin}
    _check_penalty_options(**penalty_options)  # before any run is built
    fresh_seeds = holdout_seeds if fresh_seeds is None else fresh_seeds
    if fresh_seeds < 0:
        raise TuneError(f"--fresh-seeds {fresh_seeds}: 0 (none) or more")
    if train_start < holdout_seeds:
        raise TuneError(
            f"--train-start {train_start}: the training replicates would overlap the held-out ones "
            f"(0 .. {holdout_seeds - 1}); allowed: --train-start {holdout_seeds} or more"
        )
    objective, statistic = tune.objective, tune.statistic
    req = spec.league.requirement
    requirement = (req.metric, float(req.max))
    fields = [TuneField(p, b.low, b.high, b.log, b.rebuild) for p, b in tune.fields.items()]  # type: ignore[union-attr]  # TuneBounds once validated
    unknown_gains = sorted(set(gains or {}) - {f.path for f in fields})
    if unknown_gains:
        raise TuneError(
            f"--gains: {unknown_gains} not among the [tune] fields of {method} "
            f"({', '.join(f.path for f in fields)})"
        )
    budgets = budgets if budgets is not None else Budgets.resolve()
    planned = runner.plan_cells(spec, [method])

    def chosen() -> list[Any]:
        return [c for c in planned[method] if c.level == level and (not cases or c.case in cases)]

    def check_budgets(cells: list[Any]) -> None:
        check_tune_budgets(
            cells,
            n_fields=len(fields),
            train_seeds=train_seeds,
            holdout_seeds=holdout_seeds,
            max_evaluations=max_evaluations,
            optimiser=optimiser,
            budgets=budgets,
            where=f"tune {method} @ {level}",
            run_bytes=runner.run_bytes(cells[0].raw, TuneError, _UNBUILT) if cells else None,
        )

    known = [c.case for c in planned[method] if c.level == level]
    unknown = [c for c in cases or () if c not in known]
    if unknown:
        raise TuneError(f"--cases: {unknown} not among the cases of {method} ({', '.join(known)})")
    first = chosen()
    check_budgets(first)  # at the method's own step, before anything runs (the step check included)
    book = None
    if journal is not None:
        problem_key = {
            "league": spec.league.name,
            "league_hash": league_hash(spec),
            "battery_sha256": runner._battery(spec).sha256,
            "method": method,
            "level": level,
            "cases": [c.case for c in first],
            "train_seeds": train_seeds,
            "holdout_seeds": holdout_seeds,
            "train_start": train_start,
            "fresh_seeds": fresh_seeds,
            "gains": {k: repr(float(v)) for k, v in (gains or {}).items()} or None,
            "optimiser": optimiser,
            "max_evaluations": max_evaluations,
            **penalty_options,
            "violation_cap": repr(float(violation_cap)),
            "step_check_from": jsonable((step_checks or {}).get(method)),
            "version": __version__,
        }
        book = TuneJournal(journal, problem_key, force=force)
        if book.resumed:
            say(f"{method} @ {level}: resuming, {book.resumed} completed step(s) in {book.path}")
    # the step the league flies this method at: its step check (run here, journalled, or reused)
    done = dict(step_checks or {})
    journalled = book.get("step_check") if book is not None else None
    if journalled is not None and method not in done:
        done[method] = journalled["record"]
    step_check = runner._step_checks(spec, planned, {"step_check": done}, log, progress).get(method)
    if step_check is not None:
        if book is not None and journalled is None:
            book.put("step_check", {"record": step_check})
        say(f"{method}: flying at dt = {step_check['chosen_dt']:g} s (the league's step check)")
    cells = chosen()
    if [c.n_steps for c in cells] != [c.n_steps for c in first]:  # again, at the chosen step
        check_budgets(cells)
    t0 = time.perf_counter()
    train = list(range(train_start, train_start + train_seeds))
    held = list(range(holdout_seeds))
    fresh_start = max(spec.league.seeds, train_start + train_seeds)
    fresh = list(range(fresh_start, fresh_start + fresh_seeds))
    # the training runs; with given gains, the first held-out ones (they set the batch layout)
    raws, _ = replicate_raws(spec, method, cells, train if gains is None else held[:train_seeds])
    if gains is None:
        say(
            f"{method} @ {level}: {len(raws)} training runs ({len(cells)} cells x {train_seeds} "
            f"seeds), fields {', '.join(f.path for f in fields)}"
        )
    else:
        say(f"{method} @ {level}: evaluating the given gains (no training)")
    problem = build_problem(raws, fields)
    paper = problem.initial.copy()
    if gains is None:
        m0, bad0 = evaluate(problem, paper, book)
        f0 = np.asarray(m0[objective], dtype=float)[~bad0]
        f0 = f0[np.isfinite(f0)]
        scale = float(np.mean(f0) if statistic == "mean" else np.median(f0)) if f0.size else 1.0
        scale = scale if math.isfinite(scale) and scale > 0 else 1.0
        J = penalised_objective(
            objective, statistic=statistic, requirement=requirement, scale=scale, **penalty_options
        )
        with runner.Counter(
            f"tune {method} @ {level}", max_evaluations, "evaluations", enabled=progress
        ) as bar:
            outcome = minimise(
                problem,
                J,
                optimiser=optimiser,
                max_evaluations=max_evaluations,
                journal=book,
                on_evaluation=bar.advance,
            )
        say(
            f"{method}: {optimiser}, {outcome.evaluations} evaluations in {outcome.seconds:.1f} s: "
            f"J {outcome.initial_value:.4g} -> {outcome.value:.4g}"
        )
        tuned = np.asarray(outcome.gains, dtype=float)
        m_tr, bad_tr = evaluate(problem, tuned, book)
    else:
        scale = math.nan
        tuned = np.array([float(gains.get(f.path, v)) for f, v in zip(fields, paper, strict=True)])

    def block(seeds: list[int], name: str, what: str) -> dict[str, Any]:
        """Pass statistics of the paper and tuned gains on ``seeds`` (batches laid out as the training
        batch), over all and per case."""
        h_raws, labels = [], []
        for k in range(0, len(seeds), train_seeds):
            r, lb = replicate_raws(spec, method, cells, seeds[k : k + train_seeds])
            h_raws += r
            labels += lb
        hold = build_problem(h_raws, fields, like=problem)
        runs = {k: evaluate(hold, g, book, name) for k, g in (("paper", paper), ("tuned", tuned))}
        cases = {c.case: np.flatnonzero([lb["case"] == c.case for lb in labels]) for c in cells}
        return {
            "replicates": [seeds[0], seeds[-1]],
            "seeds_per_cell": len(seeds),
            "what": what,
            **{k: _pass_stats(m, bad, requirement, objective) for k, (m, bad) in runs.items()},
            "per_case": {
                k: {c: _pass_stats(m, bad, requirement, objective, i) for c, i in cases.items()}
                for k, (m, bad) in runs.items()
            },
        }

    given = gains is not None
    return {
        "kind": "formation-ftc tuning",
        "league": spec.league.name,
        "league_version": spec.league.version,
        "method": method,
        "level": level,
        "cases": [c.case for c in cells],
        "dt": float(cells[0].raw["simulation"]["dt"]) if cells else None,
        "step_check": step_check,
        "fields": [dataclasses.asdict(f) for f in fields],  # path, low, high, log, rebuild
        "paper_gains": {f.path: float(v) for f, v in zip(fields, paper, strict=True)},
        "tuned_gains": {f.path: float(v) for f, v in zip(fields, tuned, strict=True)},
        "given_gains": given,
        "objective": {
            "metric": objective,
            "statistic": statistic,
            "units": next(
                (str(m.get("units", "1")) for m in spec.metrics if m.get("name") == objective), "1"
            ),
            "scale": scale,
            **penalty_options,
            "form": (
                "J = S(f)/f0 + penalty * mean(min(max(0, m / ((1 - margin) max) - 1), violation_cap))"
            ),
        },
        "requirement": {"metric": requirement[0], "max": requirement[1], "units": req.units},
        "J": None if given else {"paper": outcome.initial_value, "tuned": outcome.value},
        "train": None
        if given
        else {
            "replicates": [train[0], train[-1]],
            "seeds_per_cell": train_seeds,
            "paper": _pass_stats(m0, bad0, requirement, objective),
            "tuned": _pass_stats(m_tr, bad_tr, requirement, objective),
        },
        "holdout": block(held, "holdout", "the league's own first replicates"),
        "fresh": block(fresh, "fresh", "replicates neither the league nor the training uses")
        if fresh
        else None,
        "optimiser": {"name": "none (given gains)", "evaluations": 0}
        if given
        else {
            "name": optimiser,
            "evaluations": outcome.evaluations,
            "max_evaluations": max_evaluations,
            "seconds": outcome.seconds,
            "compile_seconds": outcome.compile_seconds,
            "message": outcome.message,
            "history": [{"gains": g, "J": v} for g, v in outcome.history],
        },
        "seconds": time.perf_counter() - t0,
        "provenance": runner._provenance(),
    }


def write_tuning(result: Mapping[str, Any], out_dir: str | Path) -> Path:
    """Write ``result`` (JSON-safe) to ``out_dir/<method>--<level>.json`` atomically; returns the path.

    Examples
    --------
    >>> import tempfile
    >>> p = write_tuning({"method": "m", "level": "limited", "x": float("nan")}, tempfile.mkdtemp())
    >>> p.name, json.loads(p.read_text())["x"]
    ('m--limited.json', None)
    """
    out = Path(out_dir)
    path = out / f"{result['method']}--{result['level']}.json"
    with oserror_as(TuneError, f"--out {out}: cannot write there"):
        out.mkdir(parents=True, exist_ok=True)
        atomic_write(path, json.dumps(jsonable(dict(result)), indent=1, allow_nan=False))
    return path


def load_tunings(directory: str | Path) -> dict[tuple[str, str], dict[str, Any]]:
    """The tuning results in ``directory`` (from :func:`write_tuning`) by ``(method, level)``; other
    files are skipped, a missing directory gives ``{}``. A result whose fields the leaderboard reads
    have the wrong type (:class:`_TuningRecord`) is a TuneError (exit code 2) naming the file and
    the field.

    Examples
    --------
    >>> load_tunings("/nonexistent")
    {}
    """
    from pydantic import ValidationError

    from formation_ftc.league.runner import record_error

    out: dict[tuple[str, str], dict[str, Any]] = {}
    for p in sorted(Path(directory).glob("*.json")):
        try:
            r = json.loads(p.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        if isinstance(r, dict) and r.get("kind") == "formation-ftc tuning":
            try:
                _TuningRecord.model_validate(r)
            except ValidationError as exc:
                raise TuneError(f"tuning result {record_error(p, exc)}") from None
            out[(r["method"], r["level"])] = r
    return out


class _Record(BaseModel):
    model_config = ConfigDict(strict=True, extra="allow")


class _Objective(_Record):
    metric: str
    units: str = ""
    statistic: str = "mean"


class _Optimiser(_Record):
    name: str


class _Holdout(_Record):
    paper: dict[str, float | int | None]
    tuned: dict[str, float | int | None]
    seeds_per_cell: int | None = None


class _TuningRecord(_Record):
    """The fields of a tuning result the leaderboard's tuned column reads (``league report``)."""

    method: str
    level: str
    tuned_gains: dict[str, float]
    paper_gains: dict[str, float]
    objective: _Objective
    holdout: _Holdout
    fresh: _Holdout | None = None
    optimiser: _Optimiser
