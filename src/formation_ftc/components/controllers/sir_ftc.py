"""Controller ``sir-ftc``: the SIR-FTC baseline used for comparison in Li et al. 2020, Sec. IV-D (their
ref. [21]), on the measured relative state; no communication.

Per spacecraft, on the same composite error s_i = e_i2 + k_i e_i1 (eq. (6))::

    f_i      = -(k0 + k_i(t)) s_i
    k_i(t)   = b_hat_i Phi / (||s_i|| + eps)
    b_hat_dot_i = -sigma1 b_hat_i + sigma2 ||s_i||^2 Phi / (||s_i|| + eps)
    eps      = mu_S / (1 + Phi)

Symbols renamed to avoid clashes (E000-16): the paper's mu -> ``mu_s``, k_i(t) -> ``k_adaptive``.
Paper values: k0 = 20, Phi = 1, sigma1 = 1, sigma2 = 10, mu_S = 1, b_hat(0) = 10.
"""

from __future__ import annotations

from typing import Any, ClassVar

import jax.numpy as jnp
import numpy as np
from pydantic import Field

from formation_ftc.components._registry import BuildContext, per_spacecraft, register
from formation_ftc.components._sections import section_floats
from formation_ftc.components.controllers._formation import FormationSection, RotatingFormation
from formation_ftc.components.controllers.li2020_adaptive import VELOCITY_ERROR, composite_error
from formation_ftc.config.base import StrictModel
from formation_ftc.sim.components import Controller, FlightInputs, Signal, component, static
from formation_ftc.sim.contract import as_float

__all__ = [
    "SirFtcController",
    "SirFtcSection",
    "ADAPTIVE_PARAMETERS",
    "sir_epsilon",
    "sir_ftc_control",
    "sir_ftc_rate",
]

#: the adaptive parameters of the law (recorded signals) -> their units
ADAPTIVE_PARAMETERS = {"b_hat": "N"}


def sir_epsilon(mu_s, phi):
    """The boundary-layer offset eps = mu_S / (1 + Phi).

    Parameters
    ----------
    mu_s : float
        Smoothing mu_S [m/s].
    phi : float
        Boundary-layer width Phi [-].

    Returns
    -------
    float
        eps [m/s].

    Examples
    --------
    >>> sir_epsilon(1.0, 1.0)
    0.5
    """
    return mu_s / (1.0 + phi)


def sir_ftc_control(s, b_hat, k0, phi, eps):
    """Commanded force f_i = -(k0 + k_i(t)) s_i with k_i(t) = b_hat_i Phi / (||s_i|| + eps).

    Parameters
    ----------
    s : array_like, shape (N, 3)
        Composite error [m/s].
    b_hat : array_like, shape (N,)
        Adaptive bound [N].
    k0 : float
        Feedback gain [kg/s].
    phi : float
        Boundary-layer width Phi [-].
    eps : float
        :func:`sir_epsilon` [m/s].

    Returns
    -------
    jax.Array, shape (N, 3)
        Commanded force [N].

    Examples
    --------
    >>> import numpy as np
    >>> np.asarray(sir_ftc_control(np.array([[3.0, 4.0, 0.0]]), np.array([5.5]), 1.0, 1.0, 0.5))[0, :2]
    array([-6., -8.])
    """
    ns = jnp.linalg.norm(s, axis=-1)
    k_adaptive = b_hat * phi / (ns + eps)
    return -(k0 + k_adaptive)[:, None] * s


def sir_ftc_rate(s, b_hat, phi, eps, sigma1, sigma2):
    """Rate of the adaptive bound, b_hat_dot_i = -sigma1 b_hat_i + sigma2 ||s_i||^2 Phi / (||s_i|| + eps).

    Parameters
    ----------
    s : array_like, shape (N, 3)
        Composite error [m/s].
    b_hat : array_like, shape (N,)
        Adaptive bound [N].
    phi : float
        Boundary-layer width Phi [-].
    eps : float
        :func:`sir_epsilon` [m/s].
    sigma1 : float
        Leakage [1/s].
    sigma2 : float
        Adaptation gain [kg/m].

    Returns
    -------
    jax.Array, shape (N,)
        b_hat_dot [N/s].

    Examples
    --------
    >>> import numpy as np
    >>> rate = sir_ftc_rate(np.array([[3.0, 4.0, 0.0]]), np.array([2.0]), 1.0, 0.5, 1.0, 1.1)
    >>> round(float(rate[0]), 12)  # -2 + 1.1 * 25 / 5.5
    3.0
    """
    ns = jnp.linalg.norm(s, axis=-1)
    return -sigma1 * b_hat + sigma2 * ns**2 * phi / (ns + eps)


@component
class SirFtcController(Controller):
    """f_i = -(k0 + b_hat_i Phi / (||s_i|| + eps)) s_i [N] with the adaptive gain b_hat_i [N]
    (:func:`sir_ftc_control`, :func:`sir_ftc_rate`) on s_i = e_i2 + k_i e_i1 (eq. (6)) of the measured
    (N, 6) relative state; no communication. Continuous-time (b_hat integrated with the plant)."""

    count: int = static()
    formation: RotatingFormation
    k: Any  # (N,) [1/s]
    k0: Any  # [kg/s]
    phi: Any  # Phi [-]
    sigma1: Any  # [1/s]
    sigma2: Any  # [kg/m]
    mu_s: Any  # [m/s]
    b_hat0: Any  # (N,) [N]

    def initial_state(self):
        return {"b_hat": self.b_hat0}

    def exogenous(self, t):
        return self.formation.at(t)

    def desired_position_at(self, exogenous):
        return exogenous["rho_d"]

    def output(self, t, state, inputs: FlightInputs):
        s, _, e2 = composite_error(inputs.measurement, inputs.exogenous, self.k)
        eps = sir_epsilon(self.mu_s, self.phi)
        f = sir_ftc_control(s, state["b_hat"], self.k0, self.phi, eps)
        rate = sir_ftc_rate(s, state["b_hat"], self.phi, eps, self.sigma1, self.sigma2)
        return f, {"b_hat": rate}, {"velocity_error": e2, "b_hat": state["b_hat"]}

    def signals(self):
        return (
            VELOCITY_ERROR,
            Signal("b_hat", ("spacecraft",), ADAPTIVE_PARAMETERS["b_hat"], "adaptive gain b_hat_i"),
        )


class SirFtcSection(StrictModel):
    """SIR-FTC on the composite error of the desired formation (Li2020 Sec. IV-D)."""

    #: the law's adaptive parameters (recorded signals) and their units, reported by the
    #: ``li2020-formation-errors`` evaluation (final values and values at 0.9 T)
    adaptive_parameters: ClassVar[dict[str, str]] = ADAPTIVE_PARAMETERS
    formation: FormationSection
    k: float | list[float] = Field(0.2, description="Sliding gain k_i [1/s].")
    k0: float = Field(20.0, gt=0, description="Feedback gain [kg/s].")
    phi: float = Field(1.0, gt=0, description="Boundary-layer width Phi [-].")
    sigma1: float = Field(0.01, ge=0, description="Leakage sigma_1 [1/s].")
    sigma2: float = Field(1.0, gt=0, description="Adaptation gain sigma_2 [kg/m].")
    mu_s: float = Field(0.01, gt=0, description="Smoothing mu_s [m/s].")
    b_hat0: float = Field(0.0, ge=0, description="Initial bound estimate [N].")


def _build(sec: SirFtcSection, ctx: BuildContext) -> SirFtcController:
    """The controller of a validated ``[controller] type = "sir-ftc"`` section."""
    n = ctx.count
    return SirFtcController(
        count=n,
        formation=sec.formation.component(n),
        k=as_float(per_spacecraft(sec.k, n, "controller.k")),
        **section_floats(sec, "k0", "phi", "sigma1", "sigma2", "mu_s"),
        b_hat0=as_float(np.full(n, sec.b_hat0)),
    )


register(
    "controller",
    "sir-ftc",
    SirFtcSection,
    _build,
    "SIR-FTC baseline (sliding mode with an adaptive bound, no communication)",
)
