"""Resource budgets checked before anything is compiled or run.

A scenario (or a campaign) whose estimated size exceeds a budget is refused with
:class:`formation_ftc.errors.ResourceLimitError` (exit status 2) naming the fields to change, instead
of asking XLA for terabytes or running for days. Budgets and their defaults:

==========================  =====================  =====================================================
budget                      default                override (flag / environment variable)
==========================  =====================  =====================================================
memory of one run/batch     8 GiB, at most half    ``--max-memory 32GB`` / ``FORMATION_FTC_MAX_MEMORY``
                            the machine's memory
integration steps per run   1e9                    ``--max-run-steps`` / ``FORMATION_FTC_MAX_RUN_STEPS``
run-steps per campaign      1e11                   ``--max-campaign-steps`` /
                                                   ``FORMATION_FTC_MAX_CAMPAIGN_STEPS``
==========================  =====================  =====================================================

The memory of a run is estimated from the shapes of its outputs, found with :func:`jax.eval_shape`
(nothing is computed): twice the records (the scan's stacked records and the concatenated copy) plus
four copies of the state (running state, last finite snapshot, final state, integrator stages) plus
the parameters. A campaign batch of ``chunk_size`` runs needs ``chunk_size`` times that. ``0`` or
``none`` disables a budget.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from typing import Any

from formation_ftc.errors import InputError, ResourceLimitError

__all__ = [
    "Budgets",
    "parse_bytes",
    "parse_count",
    "format_bytes",
    "run_memory_bytes",
    "check_run_steps",
    "check_memory",
    "DEFAULT_MAX_RUN_STEPS",
    "DEFAULT_MAX_CAMPAIGN_STEPS",
    "default_max_memory",
]

DEFAULT_MAX_RUN_STEPS = 1_000_000_000
DEFAULT_MAX_CAMPAIGN_STEPS = 100_000_000_000
_DEFAULT_MAX_MEMORY = 8 * 2**30
#: what a budget option or variable may say for "no budget" (as 0 does)
_NO_BUDGET = ("none", "off", "unlimited")
#: size suffixes (lower case) -> bytes: SI prefixes (k, kb = 1000 B) and binary ones (kib = 1024 B)
_UNITS = {"": 1, "b": 1}
for _k, _p in enumerate("kmgt", start=1):
    _UNITS.update({_p: 1000**_k, f"{_p}b": 1000**_k, f"{_p}ib": 1024**_k})


def _physical_memory() -> int | None:
    try:
        return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover - not POSIX
        return None


def default_max_memory() -> int:
    """8 GiB, or half the physical memory when that is smaller [bytes]."""
    phys = _physical_memory()
    return min(_DEFAULT_MAX_MEMORY, phys // 2) if phys else _DEFAULT_MAX_MEMORY


def parse_bytes(text: str | int | float | None, what: str = "--max-memory") -> int | None:
    """``"8GB"``, ``"512MiB"``, ``"1e9"`` -> bytes; ``0``/``"none"`` -> None (no budget)."""
    if text is None or str(text).strip().lower() in _NO_BUDGET:
        return None
    if isinstance(text, int | float) and not isinstance(text, bool):
        value, unit = float(text), ""
    else:
        m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([a-zA-Z]*)\s*", str(text))
        if not m or m.group(2).lower() not in _UNITS:
            raise ResourceLimitError(
                f"{what}: expected a size such as 8GB, 512MiB or 2e9 (bytes), got {text!r}"
            )
        value, unit = float(m.group(1)), m.group(2).lower()
    if not math.isfinite(value) or value < 0:
        raise ResourceLimitError(f"{what}: expected a finite size >= 0, got {text!r}")
    return int(value * _UNITS[unit]) or None


def parse_count(text: str | int | float | None, what: str) -> int | None:
    """``"1e9"``/``"1000000"`` -> int; ``0``/``"none"`` -> None (no budget)."""
    if text is None or str(text).strip().lower() in _NO_BUDGET:
        return None
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise ResourceLimitError(f"{what}: expected a number such as 1e9, got {text!r}") from None
    if not math.isfinite(value) or value < 0:
        raise ResourceLimitError(f"{what}: expected a finite number >= 0, got {text!r}")
    return int(value) or None


def format_bytes(n: float) -> str:
    for unit, size in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{int(n)} B"


@dataclass(frozen=True)
class Budgets:
    """Resource budgets; None = unlimited. :meth:`resolve` applies flags, then environment, then defaults."""

    max_memory: int | None = _DEFAULT_MAX_MEMORY
    max_run_steps: int | None = DEFAULT_MAX_RUN_STEPS
    max_campaign_steps: int | None = DEFAULT_MAX_CAMPAIGN_STEPS

    @classmethod
    def resolve(
        cls, max_memory: Any = None, max_run_steps: Any = None, max_campaign_steps: Any = None
    ) -> Budgets:

        def pick(flag, option, parse, default):
            """``--option`` when given, else ``$FORMATION_FTC_OPTION`` when set, else ``default``."""
            var = "FORMATION_FTC_" + option.upper().replace("-", "_")
            if flag is not None:
                return parse(flag, f"--{option}")
            if os.environ.get(var, "").strip():
                return parse(os.environ[var], var)
            return default

        return cls(
            pick(max_memory, "max-memory", parse_bytes, default_max_memory()),
            pick(max_run_steps, "max-run-steps", parse_count, DEFAULT_MAX_RUN_STEPS),
            pick(max_campaign_steps, "max-campaign-steps", parse_count, DEFAULT_MAX_CAMPAIGN_STEPS),
        )


def check_run_steps(n_steps: int, budgets: Budgets, where: str = "scenario") -> None:
    """Refuse a run of more than ``budgets.max_run_steps`` integration steps (before compiling)."""
    if budgets.max_run_steps is not None and n_steps > budgets.max_run_steps:
        raise ResourceLimitError(
            f"{where}: {n_steps:.3g} integration steps per run (simulation.horizon / simulation.dt) exceed the "
            f"budget of {budgets.max_run_steps:.3g}; shorten simulation.horizon or enlarge simulation.dt, or "
            f"raise the budget with --max-run-steps / FORMATION_FTC_MAX_RUN_STEPS"
        )


def _tree_bytes(tree: Any) -> int:
    import jax
    import numpy as np

    total = 0
    for x in jax.tree_util.tree_leaves(tree):  # arrays, shape structures and Python scalars
        dtype = getattr(x, "dtype", None) or np.asarray(x).dtype
        total += int(np.prod(np.shape(x), dtype=np.float64)) * np.dtype(dtype).itemsize
    return total


def run_memory_bytes(loop: Any) -> int:
    """Estimated peak memory of one run of ``loop`` [bytes] (shapes only, nothing computed)."""
    import jax

    out = dict(jax.eval_shape(type(loop).run, loop))
    return (
        2 * _tree_bytes(out.get("records")) + 4 * _tree_bytes(out.get("final")) + _tree_bytes(loop)
    )


def check_memory(loop: Any, budgets: Budgets, where: str = "scenario", batch: int = 1) -> int:
    """Refuse when ``batch`` runs of ``loop`` need more than ``budgets.max_memory``; the estimate."""
    need = run_memory_bytes(loop) * batch
    if budgets.max_memory is not None and need > budgets.max_memory:
        what = f"a batch of {batch} runs" if batch > 1 else "one run"
        fix = "lower campaign.chunk_size (--chunk-size), " if batch > 1 else ""
        raise ResourceLimitError(
            f"{where}: {what} needs about {format_bytes(need)} of memory for its records and state, over the "
            f"budget of {format_bytes(budgets.max_memory)}; {fix}raise simulation.record_every (fewer "
            f"records), shorten simulation.horizon or use fewer spacecraft, or raise the budget with "
            f"--max-memory / FORMATION_FTC_MAX_MEMORY"
        )
    return need


def check_campaign_budgets(plan: Any, budgets: Budgets) -> dict[str, int]:
    """Refuse a campaign over budget before anything runs: run-steps per run and in total, and the
    memory of one vmapped batch of ``chunk_size`` runs (first run of each base scenario, compiled but
    not run). Returns the estimates (``run_steps``, ``campaign_steps``, ``batch_memory`` [bytes])."""
    from formation_ftc import api

    where = f"campaign {plan.name!r}"
    # the first run of each grid point
    probe = [g * plan.runs for g in range(min(plan.n_grid, 256))]
    if any(s.path.startswith("simulation.") for s in plan.samplers):
        probe += list(range(min(plan.n_runs, 16)))  # sampled horizon/step: look at a few runs too
    steps = 0
    first_of_base: dict[str, int] = {}
    for r in sorted(set(probe)):
        inputs = plan.run_inputs(r)
        n = int(plan.scenario(inputs).simulation.n_steps)
        check_run_steps(n, budgets, f"{where}, run {r}")
        steps = max(steps, n)
        first_of_base.setdefault(inputs.base, r)
    total = steps * int(plan.n_runs)
    if budgets.max_campaign_steps is not None and total > budgets.max_campaign_steps:
        raise ResourceLimitError(
            f"{where}: {int(plan.n_runs):,} runs, {total:.3g} run-steps in total exceed the budget of "
            f"{budgets.max_campaign_steps:.3g}; lower campaign.runs (--runs), the grid sizes or "
            f"simulation.horizon, or raise the budget with --max-campaign-steps / "
            f"FORMATION_FTC_MAX_CAMPAIGN_STEPS"
        )
    batch = 0
    for base, r in first_of_base.items():
        try:
            loop = api.build_loop(plan.scenario(plan.run_inputs(r)))
        except (ValueError, TypeError, ArithmeticError, RecursionError) as exc:
            if isinstance(exc, InputError):
                raise
            raise InputError(
                f"{where}: base scenario {base!r} (run {r}) cannot be compiled: {exc}"
            ) from None
        batch = max(batch, check_memory(loop, budgets, where, batch=int(plan.chunk_size)))
    return {"run_steps": steps, "campaign_steps": total, "batch_memory": batch}
