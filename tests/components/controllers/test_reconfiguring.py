"""The reconfiguring allocation (components/controllers/_reconfiguring.py): the command of the channel
the FDI isolated and identified divided by its effectiveness, up to the rating (the oracle: that
formula on a hand-made estimate), and in closed loop a 50 % loss compensated (the oracle: the same run
without the fault)."""

from __future__ import annotations

import numpy as np
import pytest

from formation_ftc.api import load_scenario, simulate_with_metrics
from formation_ftc.components.controllers._acceleration_to_force import force_from_acceleration
from formation_ftc.components.controllers._reconfiguring import reconfigured
from formation_ftc.sim.components import CompositionError, Controller, FlightInputs, component


@component
class _Constant(Controller):
    """A force law commanding ``u`` (N, 3) [N]."""

    u: object
    quantity = "force"

    @property
    def count(self) -> int:
        return int(np.shape(self.u)[0])

    def output(self, t, state, inputs):
        return self.u, state, {}


U = np.array([[0.1, -0.1, 0.05], [0.08, -0.15, 0.0]])


def _estimate(detected, effectiveness, identified=True):
    iso = np.zeros((2, 3), dtype=bool)
    iso[1, 1] = True
    eff = np.ones((2, 3))
    eff[1, 1] = effectiveness
    return {
        "detected": np.asarray(detected),
        "isolated": iso,
        "identified": np.full((2, 3), identified),
        "effectiveness": eff,
    }


@pytest.mark.parametrize(
    ("detected", "effectiveness", "identified", "expected"),
    [
        (True, 0.5, True, -0.2),  # -0.15 / 0.5 = -0.3, clipped at the 0.2 N rating
        (True, 0.9, True, -0.15 / 0.9),
        (True, 0.0, True, -0.2),  # an outage: the floor 0.05, then the rating
        (True, 1.2, True, -0.15),  # identified above 1: unchanged
        (True, 0.5, False, -0.15),  # not identified: unchanged
        (False, 0.5, True, -0.15),  # no alarm: unchanged
    ],
)
def test_the_isolated_identified_channel_is_divided_by_its_effectiveness(
    detected, effectiveness, identified, expected
):
    ctrl = reconfigured(_Constant(u=U), 0.2)
    inputs = FlightInputs(
        None, None, _estimate(detected, effectiveness, identified), None, None, None, None
    )
    force, _, out = ctrl.output(0.0, None, inputs)
    force = np.asarray(force)
    assert force[1, 1] == pytest.approx(expected)
    np.testing.assert_array_equal(np.delete(force.ravel(), 4), np.delete(U.ravel(), 4))
    np.testing.assert_array_equal(np.asarray(out["law_command"]), U)
    assert "fault-identification" in ctrl.needs()


def test_only_a_force_law_can_be_reallocated():
    from formation_ftc.components.controllers.none import FreeDrift

    with pytest.raises(CompositionError, match="reallocates a force"):
        reconfigured(FreeDrift(count=2), 0.2)
    assert (
        reconfigured(force_from_acceleration(FreeDrift(count=2), np.ones(2)), 0.2).quantity
        == "force"
    )


def test_a_loss_of_effectiveness_is_compensated_in_closed_loop():
    """cw-fdi-identification (the LQR acquiring under a 50 % along-track loss from the start): with the
    reallocation the formation's position error at the end is within 10 % of the healthy run's, and the
    faulty thruster delivers what the law asked (applied = law_command on that channel, to 2 %)."""
    base = {"controller.mode": "sampled", "simulation.horizon": 400.0}
    healthy, _ = simulate_with_metrics(
        load_scenario("cw-fdi-identification", {**base, "actuator.kind": "none"})
    )
    active, _ = simulate_with_metrics(
        load_scenario("cw-fdi-identification", {**base, "controller.fault_estimate": "estimator"})
    )
    plain, _ = simulate_with_metrics(load_scenario("cw-fdi-identification", base))
    err = {k: np.linalg.norm(d["position_error"].values[-1]) for k, d in
           (("healthy", healthy), ("active", active), ("plain", plain))}  # fmt: skip
    assert err["active"] == pytest.approx(err["healthy"], rel=0.1)
    late = active.time.values > 100.0
    np.testing.assert_allclose(
        active["applied"].values[late, 1, 1],
        active["law_command"].values[late, 1, 1],
        rtol=0.02,
        atol=1e-6,
    )
    assert not np.allclose(
        plain["position_error"].values, healthy["position_error"].values, atol=1e-3
    )
