"""Synthetic FDI with configurable imperfections as an estimator (Mehrabian Sec. IV, Assumption 4).

The FDI unit runs beside the controller and reports, per spacecraft and channel, a fault flag and an
estimate ``u*`` of the additive actuator fault (:mod:`formation_ftc.blocks.fdi`: detection latency,
missed detection, isolation routing, identification scale / bias / noise). It is a *scripted* report:
the scenario compiles the same fault description into the truth-side actuator
(:class:`~formation_ftc.components.actuators.additive_faults.HeldAdditiveFaultActuator`) and into this
component's own time profile, so the estimator reads no truth at run time -- only its own profile and
its own noise stream (the fourth stream of the run seed, ``fold_in(key, k)`` per step).
"""

from __future__ import annotations

from typing import Any

import jax

from formation_ftc.blocks.fdi import FDIModel, fdi_output
from formation_ftc.core.disturbances import run_key, step_key
from formation_ftc.core.fault_profiles import windowed_additive_faults
from formation_ftc.sim.components import Estimator, FlightInputs, Signal, component, static

__all__ = ["ScriptedFdi", "fdi_noise_key"]

VEC = ("spacecraft", "axis")


def fdi_noise_key(seed):
    """Root key of the FDI noise: the fourth of the run's four streams (see
    :func:`formation_ftc.components.plants.euler_angle_attitude.seed_streams`).

    Parameters
    ----------
    seed : int or array_like
        The run's seed (uint32) [-].

    Returns
    -------
    jax.Array
        The FDI stream's root key.

    Examples
    --------
    >>> import numpy as np
    >>> from formation_ftc.components.estimators.fdi_imperfections import fdi_noise_key
    >>> from formation_ftc.components.plants.euler_angle_attitude import seed_streams
    >>> bool(np.array_equal(fdi_noise_key(7), seed_streams(7)[3]))
    True
    """
    return jax.random.split(run_key(seed), 4)[3]


@component
class ScriptedFdi(Estimator):
    """FDI report (flag, u*) at every step from the scripted fault profile.

    Leaves: ``seed`` (uint32), ``windows`` (n_faults, 2) fault windows [s], ``params`` (the
    :func:`formation_ftc.blocks.fdi.fdi_params` pytree: onset, delay, detected, scale, bias, noise_std,
    routing, fault mask). Static: the fault expressions, 0-based spacecraft / channels, and the number
    of channels; the step index and the step come with the flight inputs. The estimate is an :class:`~formation_ftc.blocks.fdi.FDIOutput`.
    """

    count: int = static()
    seed: Any = 0
    windows: Any = None
    params: Any = None
    torques: tuple[str, ...] = static(default=())
    spacecraft: tuple[int, ...] = static(default=())
    channels: tuple[int, ...] = static(default=())
    n_channels: int = static(default=3)

    def _model(self, dt: float) -> FDIModel:
        def fault_fn(k):
            return windowed_additive_faults(
                k,
                dt,
                self.windows,
                self.torques,
                self.spacecraft,
                self.channels,
                self.count,
                self.n_channels,
            )

        return FDIModel(self.count, self.n_channels, fault_fn, dt)

    def update(self, t, state, inputs: FlightInputs):
        k = inputs.step.k
        return state, fdi_output(
            self._model(inputs.step.dt), self.params, k, step_key(fdi_noise_key(self.seed), k)
        )

    def signals(self):
        return (
            Signal("fdi_flag", VEC, "1", "channel reported faulty by the FDI (reconfigure)"),
            Signal("fdi_estimate", VEC, "N m", "fault estimate u* reported by the FDI"),
        )

    def outputs(self, t, state, estimate):
        return {"fdi_flag": estimate.flag, "fdi_estimate": estimate.estimate}
