"""Monte Carlo campaigns: sampled/swept scenarios run as vmapped chunks, stored resumably.

* :mod:`~formation_ftc.campaign.spec` -- the campaign file (TOML, pydantic) and its samplers
* :mod:`~formation_ftc.campaign.sampling` -- run ids, per-run seeds and samples, chunks (deterministic)
* :mod:`~formation_ftc.campaign.runner` -- one chunk = one ``jax.vmap`` batch; :func:`run_campaign`
* :mod:`~formation_ftc.campaign.executors` -- in-process, process pool (spawn) or Dask
* :mod:`~formation_ftc.campaign.storage` -- manifest + one Parquet file per finished chunk (atomic)
* :mod:`~formation_ftc.campaign.report` -- summary statistics and sensitivity plots
* :mod:`~formation_ftc.campaign.cli` -- ``formation-ftc campaign list | run | report``

>>> from formation_ftc.campaign import run_campaign
>>> outcome = run_campaign("cw-pd-gains", "out/cw-pd-gains")     # doctest: +SKIP
>>> outcome.results[["run_id", "status", "metric:max_position_error"]]  # doctest: +SKIP
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING

# loaded on first use, so that ``formation-ftc --help`` does not import SciPy, pandas or JAX
_LAZY = {
    name: sub
    for sub, names in {
        "executors": ("DaskExecutor", "LocalExecutor", "make_executor"),
        "report": ("summarize", "write_report"),
        "runner": ("CampaignOutcome", "make_plan", "run_campaign", "run_chunk"),
        "sampling": ("CampaignPlan", "Chunk", "RunInputs"),
        "spec": ("CampaignError", "CampaignSpec", "builtin_campaigns", "load_campaign"),
        "storage": ("CampaignStore",),
    }.items()
    for name in names
}

if TYPE_CHECKING:  # pragma: no cover
    from formation_ftc.campaign.executors import DaskExecutor, LocalExecutor, make_executor
    from formation_ftc.campaign.report import summarize, write_report
    from formation_ftc.campaign.runner import CampaignOutcome, make_plan, run_campaign, run_chunk
    from formation_ftc.campaign.sampling import CampaignPlan, Chunk, RunInputs
    from formation_ftc.campaign.spec import (
        CampaignError,
        CampaignSpec,
        builtin_campaigns,
        load_campaign,
    )
    from formation_ftc.campaign.storage import CampaignStore


def __getattr__(name: str):
    sub = _LAZY.get(name)
    if sub is None:
        raise AttributeError(f"module 'formation_ftc.campaign' has no attribute {name!r}")
    value = getattr(import_module(f"formation_ftc.campaign.{sub}"), name)
    globals()[name] = value
    return value


__all__ = [
    "CampaignError",
    "CampaignSpec",
    "CampaignPlan",
    "CampaignStore",
    "CampaignOutcome",
    "Chunk",
    "RunInputs",
    "DaskExecutor",
    "LocalExecutor",
    "builtin_campaigns",
    "load_campaign",
    "make_executor",
    "make_plan",
    "run_campaign",
    "run_chunk",
    "summarize",
    "write_report",
]
