"""Sensors ``relative-state``: exact (no noise drawn) when both noise levels are 0, otherwise the noise
levels are the sensors' leaves; the noise drawn has the stated standard deviations."""

from __future__ import annotations

import jax
import numpy as np

from formation_ftc.components.sensors.relative_state import (
    ExactRelativeStateSensors,
    RelativeStateSensors,
)
from formation_ftc.config import loader
from formation_ftc.methods.composed import make_loop


def _sensors(**fields):
    raw, _ = loader.read_raw("compose-li2020-on-cw")
    raw["sensors"] = {"type": "relative-state", **fields}
    return make_loop(loader.validate(raw, "x")).sensors


def test_zero_noise_is_the_exact_state():
    exact = _sensors()
    assert isinstance(exact, ExactRelativeStateSensors)
    assert (exact.position_noise_std, exact.velocity_noise_std) == (0.0, 0.0)
    noisy = _sensors(position_noise_std=0.5, velocity_noise_std=0.002)
    assert isinstance(noisy, RelativeStateSensors)
    assert (float(noisy.position_noise_std), float(noisy.velocity_noise_std)) == (0.5, 0.002)


def test_noise_has_the_stated_standard_deviations():
    sensors = RelativeStateSensors(
        count=20_000, position_noise_std=np.float64(0.5), velocity_noise_std=np.float64(0.002)
    )
    noise = np.asarray(sensors.noise(jax.random.PRNGKey(7)))
    # 60,000 samples per part: the sample std is within 2 % of the stated one (about 7 sigma)
    np.testing.assert_allclose(noise[:, :3].std(), 0.5, rtol=0.02)
    np.testing.assert_allclose(noise[:, 3:].std(), 0.002, rtol=0.02)
    assert abs(noise[:, :3].mean()) < 0.02
