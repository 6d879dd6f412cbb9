"""formation-ftc: fault-tolerant control of spacecraft formations in JAX (float64).

Public entry points::

    import formation_ftc as ftc
    scenario = ftc.load_scenario("li2020-thm1", overrides={"simulation.horizon": 100.0})
    result = ftc.simulate(scenario)        # xarray.Dataset with provenance attributes
    table = ftc.check(scenario)            # theorem / design conditions

The package enables ``jax_enable_x64`` on import (see :mod:`formation_ftc._jax`).
"""

from __future__ import annotations

from formation_ftc import _jax  # noqa: F401  (x64 before anything else)

try:  # single source: the version in pyproject.toml, read from the installed package's metadata
    from importlib.metadata import PackageNotFoundError as _NotFound
    from importlib.metadata import version as _version

    __version__ = _version("formation-ftc")
except _NotFound:  # pragma: no cover - running from a source tree that was never installed
    __version__ = "0+unknown"

from formation_ftc.api import (  # noqa: E402
    check,
    list_scenarios,
    load_scenario,
    save_result,
    simulate,
    simulate_with_metrics,
)
from formation_ftc.sim.engine import SimulationDiverged  # noqa: E402

__all__ = [
    "__version__", "check", "list_scenarios", "load_scenario", "save_result", "simulate",
    "simulate_with_metrics", "SimulationDiverged",
]
