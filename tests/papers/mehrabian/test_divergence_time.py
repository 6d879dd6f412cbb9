"""The reproduction's batched path dates a run that leaves its admissible set exactly.

The reproduction records once per run (``record_every = n_steps``), so the engine's block check alone
would date every exit at the block's first step, t = 0 (the report once said seed 10 of Case C reached
the singularity "at t = 0.00 s"). :func:`run_batch` replays such a run alone; its exit step must equal
the one of the same run recorded at every step, and the metrics of the windows that end before the
exit must be those of that run.

A run that leaves the set mid-block in 60 s: Case C, seed 5 with the fault on [10, 40] s, the metric
windows [10, 30] s and [15, 30] s and the admissible pitch lowered to 45 deg (its largest |theta|
starts at 42.2 deg, falls to ~33 deg and climbs past 45 deg at 38.27 s).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.papers.mehrabian.seed_study import run_batch
from formation_ftc.papers.programs import simulate

DT = 0.01  # [s]
HORIZON = 60.0  # [s]
OVERRIDES = {
    "simulation.horizon": HORIZON,
    "actuator.faults.0.start": 10.0,
    "actuator.faults.0.end": 40.0,
    "evaluations.0.fault_window": [10.0, 30.0],
    "evaluations.0.assessment_window": [15.0, 30.0],
    "simulation.max_pitch": math.radians(45.0),
}
CASE, SEED = "mehrabian-isolation", 5


def test_batched_divergence_step_is_exact():
    M, div = run_batch([CASE], [SEED], OVERRIDES)
    with pytest.raises(ftc.SimulationDiverged) as err:
        simulate(
            ftc.load_scenario(
                CASE, {**OVERRIDES, "simulation.seed": SEED, "simulation.record_every": 1}
            )
        )
    info = err.value.info
    assert info.variable.startswith("plant.pitch")
    step = int(div[0, 0])
    n_steps = round(HORIZON / DT)
    assert 0 < step < n_steps and step == info.step  # mid-block, exact
    assert step * DT > 31.0  # after the metric windows (measured: 38.27 s)
    # the windows closed before the exit are complete and equal to the every-step run's
    partial = json.loads(err.value.partial.attrs["metrics_json"])
    fault_window = [k for k in M if k.endswith("_fault_window")]
    assert len(fault_window) == 12
    for k in fault_window:
        assert np.isfinite(M[k][0, 0]), k
        assert M[k][0, 0] == pytest.approx(partial[k], rel=1e-12), k
