"""The error-state sensors (``tracking-error``): the measured layout against the error state, and the
sensors refused, naming what they need and who provides it, on a plant without an error state."""

import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.sensors.tracking_error import TrackingErrorSensors
from formation_ftc.config import loader


def test_measurement_is_the_error_state_split_for_the_laws():
    X = np.arange(2 * 13, dtype=float).reshape(2, 13)
    y = TrackingErrorSensors(count=2).measure(0.0, {"x": jnp.asarray(X)}, None)
    np.testing.assert_array_equal(y["translation"], -X[:, 0:6])  # actual minus desired
    np.testing.assert_array_equal(y["omega"], X[:, 6:9])
    np.testing.assert_array_equal(y["q"], X[:, 9:13])


def test_refused_on_a_plant_without_an_error_state():
    raw = loader.read_raw("cw-pd-fault")[0]
    raw["sensors"] = {"type": "tracking-error"}
    with pytest.raises(loader.ScenarioError) as err:
        ftc.load_scenario(raw)
    msg = str(err.value)
    assert "sensors tracking-error needs a plant whose state is the error state" in msg, msg
    assert 'plant type = "switched-formation"' in msg, msg
