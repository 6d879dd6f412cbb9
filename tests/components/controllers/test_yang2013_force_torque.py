"""Yang2013's laws side by side (``yang2013-force-torque``): the flight-side laws cannot see the truth,
and the compositions that cannot work are refused."""

from __future__ import annotations

import dataclasses
import inspect
import typing

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc import api
from formation_ftc.components.controllers._yang2013 import (
    Yang2013AttitudeController,
    Yang2013TranslationalController,
)
from formation_ftc.components.controllers.yang2013_force_torque import ForceTorqueController
from formation_ftc.sim.components import CompositionError, FlightInputs

TRUTH_FIELDS = {"state", "true_state", "fault", "faults", "disturbance", "force", "process_noise"}
SHORT = {
    "simulation.horizon": 100.0,
    "supervisor.modes.1.start": 20.0,
    "supervisor.modes.2.start": 40.0,
    "supervisor.modes.3.start": 60.0,
    "supervisor.modes.4.start": 80.0,
    "actuator.faults.0.onset": 70.0,
    "simulation.record_every": 1,
}


def _loop(**ov):
    scn = ftc.load_scenario("yang2013-controller-fault", {**SHORT, **ov})
    return api.build_loop(scn)


@pytest.mark.parametrize(
    "cls", [Yang2013TranslationalController, Yang2013AttitudeController, ForceTorqueController]
)
def test_controller_cannot_see_the_truth(cls):
    """``output`` takes FlightInputs (no truth fields); with the same true state (hence the same
    measurement) the command is unchanged when the true disturbances, the controller fault (gain,
    onset) and the masses of the truth side change, while the applied wrench changes."""
    hints = typing.get_type_hints(
        cls.output, globalns=vars(inspect.getmodule(cls)) | {"FlightInputs": FlightInputs}
    )
    assert hints["inputs"] is FlightInputs
    assert not TRUTH_FIELDS & set(FlightInputs._fields)
    loop = _loop()
    assert isinstance(loop.controller, ForceTorqueController)
    plant = dataclasses.replace(
        loop.plant,
        mass=loop.plant.mass * 1.7,
        disturbance_force=("5", "5*t", "-5"),
        disturbance_torque=("1", "2", "t"),
    )
    actuator = dataclasses.replace(
        loop.actuator,
        K2_faulty=loop.actuator.K2_faulty * 0 - 0.3,
        onset=np.zeros_like(loop.actuator.onset),
    )
    other = dataclasses.replace(loop, plant=plant, actuator=actuator)
    k = jnp.asarray(
        1500, dtype=jnp.int64
    )  # t = 75 s: fault (onset 70 s) tolerated, not reconfigured
    state = loop.initial_state()
    state["plant"]["x"] = state["plant"]["x"].at[:, 3:9].set(0.01)  # nonzero e_V, e_omega
    step = jax.jit(lambda lp, st: lp.step(k, st))
    (new_a, out_a), (new_b, out_b) = step(loop, state), step(other, state)
    np.testing.assert_array_equal(np.asarray(out_a["command"]), np.asarray(out_b["command"]))
    assert not np.allclose(np.asarray(out_a["applied"]), np.asarray(out_b["applied"]))
    assert not np.allclose(np.asarray(new_a["plant"]["x"]), np.asarray(new_b["plant"]["x"]))
    # the law alone, called directly: same flight inputs -> same output, whatever the truth
    law = {
        Yang2013TranslationalController: loop.controller.force_law,
        Yang2013AttitudeController: loop.controller.torque_law,
        ForceTorqueController: loop.controller,
    }[cls]
    assert isinstance(law, cls)


def test_compositions_that_cannot_work_are_rejected():
    loop = _loop()
    with pytest.raises(
        CompositionError, match="torque"
    ):  # a torque law cannot drive a wrench plant
        dataclasses.replace(loop, controller=loop.controller.torque_law).validate()
    with pytest.raises(CompositionError, match="force law and a torque law"):
        ForceTorqueController(
            force_law=loop.controller.torque_law, torque_law=loop.controller.force_law
        )
