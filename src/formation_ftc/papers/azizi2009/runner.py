"""Run helpers of the azizi2009 package: load a scenario with this paper's schema, simulate one run,
and run a batch of parameter variations as **one** vmapped, jitted program (the alpha_2 sweep and the
seed spread of the reproduction).

Loading validates directly with :class:`Azizi2009Scenario` (same TOML reader and ``--set`` override
syntax as :func:`formation_ftc.api.load_scenario`), so the paper's code does not depend on other paper
packages importing cleanly.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from formation_ftc.config import loader
from formation_ftc.papers.azizi2009.model import build
from formation_ftc.papers.azizi2009.schema import Azizi2009Scenario

__all__ = ["load", "simulate", "run_batch"]


def load(name_or_path: str | Path, overrides: Mapping[str, Any] | Iterable[str] | None = None) -> Azizi2009Scenario:
    """Built-in scenario name or TOML path (+ overrides) -> validated :class:`Azizi2009Scenario`."""
    from formation_ftc.api import load_scenario

    sc = load_scenario(name_or_path, overrides)
    if not isinstance(sc, Azizi2009Scenario):
        raise loader.ScenarioError(f"{name_or_path}: scenario.method must be 'azizi2009', got {sc.scenario.method!r}")
    return sc


def simulate(sc: Azizi2009Scenario):
    """One run -> (xarray.Dataset with provenance, metrics dict); raises SimulationDiverged."""
    from formation_ftc.api import simulate_with_metrics

    return simulate_with_metrics(sc)


def run_batch(sc: Azizi2009Scenario, variations: Mapping[str, np.ndarray]) -> list[dict[str, float]]:
    """Metrics of len(batch) runs that differ only in the given ``params`` entries.

    ``variations`` maps a params key to an array with a leading batch axis (e.g. ``alpha`` of shape
    (B, N), ``seed`` of shape (B,)); all other params are shared (unbatched). One ``jax.jit(jax.vmap(run))``.
    """
    compiled = build(sc)
    sizes = {np.asarray(v).shape[0] for v in variations.values()}
    if len(sizes) != 1:
        raise ValueError(f"all variations need the same batch size, got {sizes}")
    (bsz,) = sizes
    unknown = set(variations) - set(compiled.params)
    if unknown:
        raise KeyError(f"unknown params {sorted(unknown)}; valid: {sorted(compiled.params)}")
    # only the varied entries are batched; the others are passed once (in_axes None), so work that
    # depends only on them is done once per step for the whole batch (see formation_ftc.sim.batch)
    batched = {key: jnp.asarray(variations[key], dtype=val.dtype) if key in variations else val
               for key, val in compiled.params.items()}
    in_axes = {key: 0 if key in variations else None for key in compiled.params}

    def run_final(p):
        out = compiled.run(p)
        # keep only what metrics need from the records (effort at the record times) to save memory
        return {"final": out["final"], "records": {"effort": out["records"]["effort"]},
                "diverged_step": out["diverged_step"]}

    outs = jax.jit(jax.vmap(run_final, in_axes=(in_axes,)))(batched)
    outs = jax.tree_util.tree_map(np.asarray, outs)
    res = []
    for b in range(bsz):
        one = jax.tree_util.tree_map(lambda a, b=b: a[b], outs)
        if int(one["diverged_step"]) >= 0:
            raise RuntimeError(f"batch member {b} diverged at step {int(one['diverged_step'])}")
        res.append(compiled.metrics(one))
    return res
