"""A reproduction's runs: one compiled program per structure, and batches of one structure.

:func:`simulate` runs one scenario through the process's shared program of its structure
(:func:`formation_ftc.sim.programs.jitted_run`, re-exported here with :func:`executable` and
:func:`clear`): the second scenario of a structure calls the program the first one compiled.
:func:`simulate_batched` runs scenarios of one structure as one ``jax.vmap`` batch;
:func:`run_loops` runs closed loops of one structure as one batch or grid and returns their outputs.
"""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

import jax
import numpy as np

from formation_ftc.sim.batch import batched_grid_run, batched_run, stack_params, stack_params_grid
from formation_ftc.sim.programs import clear, executable, jitted_run

__all__ = ["simulate", "simulate_batched", "run_loops", "jitted_run", "executable", "clear"]


def simulate(scenario, raise_on_divergence: bool = True) -> tuple[Any, dict[str, float]]:
    """Run one validated scenario: :func:`formation_ftc.api.simulate_with_metrics`, which runs the
    process's shared program of its structure (:func:`jitted_run`)."""
    from formation_ftc.api import simulate_with_metrics

    return simulate_with_metrics(scenario, raise_on_divergence=raise_on_divergence)


def simulate_batched(
    scenarios: list, timings: list | None = None
) -> list[tuple[Any, dict[str, float]]]:
    """Run scenarios as one ``jax.vmap`` batch per compiled structure (same ``static_key``: only numbers
    differ; :func:`formation_ftc.sim.batch.batched_run`) and return ``[(xarray.Dataset, {metric: float})]``
    in order, as :func:`simulate` returns them one by one (a divergence raises, as there).

    ``timings``: a list that receives ``(compile_s, run_s)`` of each run's batch [s], in order."""
    import time

    from formation_ftc.api import build_loop, finish_run

    loops = [build_loop(s) for s in scenarios]
    groups: dict[Hashable, list[int]] = {}
    for i, c in enumerate(loops):
        groups.setdefault(c.static_key, []).append(i)
    results: list[Any] = [None] * len(loops)
    times: list[Any] = [None] * len(loops)
    for idx in groups.values():
        batch, in_axes = stack_params([loops[i] for i in idx])
        fn = batched_run(loops[idx[0]], in_axes, len(idx))
        t0 = time.perf_counter()
        exe = fn.lower(batch).compile()
        t1 = time.perf_counter()
        out = jax.tree_util.tree_map(np.asarray, jax.block_until_ready(exe(batch)))
        t2 = time.perf_counter()
        for j, i in enumerate(idx):
            results[i] = finish_run(
                scenarios[i], loops[i], jax.tree_util.tree_map(lambda a, j=j: a[j], out)
            )
            times[i] = (t1 - t0, t2 - t1)
    if timings is not None:
        timings.extend(times)
    return results


def run_loops(loops: list, columns: int | None = None) -> Any:
    """The outputs of closed loops of one structure run as one compiled, vmapped program
    (:mod:`formation_ftc.sim.batch`; leaves shared by every run stay unbatched), as NumPy arrays with
    the run axis first.

    ``columns``: the loops, row by row, are the cells of a grid ``columns`` wide, batched by two nested
    maps (:func:`formation_ftc.sim.batch.stack_params_grid`): a leaf that changes only from row to row
    -- a seed per row -- is batched once per row, and so is the work that depends on it alone; the
    outputs then have the axes ``(rows, columns)`` first."""
    if columns is None:
        batch, axes = stack_params(loops)
        run = batched_run(loops[0], axes, len(loops))
    else:
        rows = [loops[i : i + columns] for i in range(0, len(loops), columns)]
        batch, row_axes, col_axes = stack_params_grid(rows)
        run = batched_grid_run(loops[0], row_axes, col_axes, len(rows), columns)
    return jax.tree_util.tree_map(np.asarray, run(batch))
