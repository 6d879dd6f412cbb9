"""Individual (per-spacecraft) controllers of Yang et al. 2013, eqs. (12)-(13): the equations, their
components and their builders, shared by the controller homes ``yang2013-translational``,
``yang2013-relative``, ``yang2013-force-torque`` and ``yang2013-attitude``.

Each spacecraft i tracks the main spacecraft 1 only (leader-following: its error state
``x_i = [e_R, e_V, e_omega, e_q, e_q4]`` in R^13 (7) is formed from its own measurements and the main
spacecraft's broadcast state). The controllers are feedback-linearising::

    f_i   = M_i (Phi_i + (K1 + 1) e_R + K2 e_V)                                          # eq. (12)
    tau_i = -Upsilon_i - J_i (K3 e_w + e_q + e_w (K4 |e_q|^2 + K5 e_q4^2) / (2(|e_w|^2 + kappa)))  # eq. (13)

where Phi_i, Upsilon_i are the *known drift* (feed-forward) terms of the error dynamics (2), (5) --
without f, d, tau, iota (E001-02). The gains must be **positive** (E001-01; the paper's "negative
constants" would destabilise the loop). With the drift cancelled, the translational closed loop is
``e_V_dot = -(K1+1) e_R - K2 e_V - d/M`` and ``e_R_dot = e_V`` (omega x terms norm-preserving), whose
amplitude decays as ``exp(-K2 t / 2)`` when underdamped -- gains with K2 = eta realise exactly the
paper's decay rate eta (see :func:`formation_ftc.design.dwell_time.gains_for_decay_rate`).

Units: e_R [m], e_V [m/s], e_w [rad/s], e_q, e_q4 [-], M [kg], J [kg m^2], f [N], tau [N m]. Each
component reads only :class:`~formation_ftc.sim.components.FlightInputs`; its on-board mass and
inertia are stated (``nominal_mass``, ``nominal_inertia``), never the plant's.
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np

from formation_ftc.components._registry import BuildContext, per_spacecraft
from formation_ftc.components._sections import expression_text, section_floats
from formation_ftc.components.controllers._desired_position import desired_motion
from formation_ftc.core.dynamics.two_body import gravity_acceleration
from formation_ftc.core.orbit import MU_EARTH
from formation_ftc.sim.components import Controller, FlightInputs, component, static
from formation_ftc.sim.contract import as_float

__all__ = [
    "translational_control",
    "attitude_control",
    "translational_drift",
    "Yang2013TranslationalController",
    "Yang2013AttitudeController",
    "translational_law",
    "attitude_law",
]


# ------------------------------------------------------------------------------------- equations
def translational_control(e_R, e_V, Phi, mass, K1, K2):
    """Control force f of eq. (12) [N].

    Parameters
    ----------
    e_R, e_V : array_like, shape (..., 3)
        Position error [m] and velocity error [m/s], desired minus actual.
    Phi : array_like, shape (..., 3)
        Known drift of (2) [m/s^2] (E001-02).
    mass : array_like
        M_i [kg], broadcastable to (..., 1).
    K1 : float or array_like
        Position gain offset [1/s^2] (the e_R gain is K1 + 1), scalar or per spacecraft.
    K2 : float or array_like
        Velocity gain [1/s], scalar or per spacecraft.

    Returns
    -------
    jax.Array
        f = M (Phi + (K1 + 1) e_R + K2 e_V), shape (..., 3) [N].

    Examples
    --------
    >>> import numpy as np
    >>> f = translational_control(np.ones(3), np.zeros(3), np.zeros(3), 150.0, 0.005, 0.01)
    >>> np.round(np.asarray(f), 6).tolist()
    [150.75, 150.75, 150.75]
    """
    K1 = jnp.asarray(K1)[..., None] if jnp.ndim(K1) else K1
    K2 = jnp.asarray(K2)[..., None] if jnp.ndim(K2) else K2
    return mass * (Phi + (K1 + 1.0) * e_R + K2 * e_V)  # Yang2013 eq. (12)


def attitude_control(e_w, e_q, e_q4, Upsilon, J, K3, K4, K5, kappa):
    """Control torque tau of eq. (13) [N m].

    Parameters
    ----------
    e_w : array_like, shape (..., 3)
        Angular velocity error [rad/s].
    e_q, e_q4 : array_like, shapes (..., 3) and (...,)
        Quaternion vector and scalar errors [-].
    Upsilon : array_like, shape (..., 3)
        Known drift of (5) [N m] (E001-02).
    J : array_like, shape (3, 3)
        Inertia of the law's model [kg m^2].
    K3, K4, K5 : float
        Gains [1/s].
    kappa : float
        Smoothing constant [rad^2/s^2].

    Returns
    -------
    jax.Array
        tau, shape (..., 3) [N m].

    Examples
    --------
    >>> import numpy as np
    >>> tau = attitude_control(np.zeros(3), np.array([0.1, 0.0, 0.0]), 0.0, np.zeros(3),
    ...                        25.0 * np.eye(3), 0.2, 1.0, 1.0, 1e-3)
    >>> float(tau[0])  # -J e_q at rest
    -2.5
    """
    e_q4 = jnp.asarray(e_q4)
    shaping = (K4 * jnp.sum(e_q * e_q, axis=-1) + K5 * e_q4**2) / (
        2.0 * (jnp.sum(e_w * e_w, axis=-1) + kappa)
    )
    inner = K3 * e_w + e_q + e_w * shaping[..., None]
    return -Upsilon - jnp.einsum("ij,...j->...i", jnp.asarray(J), inner)  # Yang2013 eq. (13)


def translational_drift(R_i, R_main, a_main, a_desired, mu: float = MU_EARTH):
    """Known drift Phi_i of (2) for a follower whose frame F_i is parallel to F0 (omega_i = 0) [m/s^2].

    With e_R = R~^d - (R_i - R_1) and e_V = V~^d - (V_i - V_1),
    ``e_V_dot = a^d - g(R_i) + a_1 - f/M - d/M``, so ``Phi_i = a^d - g(R_i) + a_1`` where g is the
    inverse-square gravity and a_1 the main spacecraft's (measured) acceleration; it contains no f, d
    (E001-02). (12) then makes the error dynamics exactly the error-level closed loop of method
    ``yang2013``.

    Parameters
    ----------
    R_i : array_like, shape (..., 3)
        Follower's position from the Earth's centre [m].
    R_main : array_like, shape (..., 3)
        Main spacecraft's position [m] (the frames are parallel: not used beyond the error's
        definition).
    a_main : array_like, shape (..., 3)
        Main spacecraft's measured acceleration [m/s^2].
    a_desired : array_like, shape (..., 3)
        Desired relative acceleration [m/s^2].
    mu : float, optional
        Gravitational parameter [m^3/s^2].

    Returns
    -------
    jax.Array
        Phi_i, shape (..., 3) [m/s^2].

    Examples
    --------
    >>> import numpy as np
    >>> R = np.array([7000e3, 0.0, 0.0])
    >>> phi = translational_drift(R, R, np.zeros(3), np.zeros(3))
    >>> bool(np.isclose(float(phi[0]), 3.986004418e14 / 7000e3**2))  # -g(R_i): outwards
    True
    """
    return a_desired - gravity_acceleration(R_i, mu) + a_main


# ------------------------------------------------------------------------------------ components
@component
class Yang2013TranslationalController(Controller):
    """Feedback-linearising formation law (12) on the measured (N, 6) relative state y = [p, v] [m, m/s]::

        e_R = p^d(t) - p,  e_V = v^d(t) - v                     (errors desired minus actual, (7))
        f_i = M_i (Phi_i + (K1 + 1) e_R + K2 e_V),  Phi_i = a_i^d(t)     # Yang2013 eq. (12)

    ``p^d(t)`` is an expression per axis (in t [s] and the 1-based spacecraft number i; default 0); v^d
    and a^d are its exact time derivatives. The feed-forward Phi_i is the desired acceleration: the
    plant's own drift is taken as cancelled (exact at the error level of Yang2013, where the desired
    trajectory is zero and y is the deviation from it). ``nominal_mass`` (N,) M_i [kg] (stated on
    board), ``K1`` [1/s^2] (e_R gain K1 + 1), ``K2`` [1/s], positive (E001-01).
    """

    count: int = static()
    nominal_mass: Any = 1.0
    K1: Any = 0.005
    K2: Any = 0.01
    desired_position: tuple[str, str, str] = static(default=("0", "0", "0"))

    def exogenous(self, t):
        return desired_motion(self.desired_position, self.count, t)

    def desired_position_at(self, exogenous):
        return exogenous["p"]

    def output(self, t, state, inputs: FlightInputs):
        y, d = inputs.measurement, inputs.exogenous
        e_R = d["p"] - y[:, 0:3]
        e_V = d["v"] - y[:, 3:6]
        # eq. (12)
        f = translational_control(e_R, e_V, d["a"], self.nominal_mass[:, None], self.K1, self.K2)
        return f, None, {}


@component
class Yang2013AttitudeController(Controller):
    """Attitude law (13) on the measured attitude error ``{"omega": (N, 3), "q": (N, 4)}`` (e_omega
    [rad/s], (e_q, e_q4) [-])::

        tau_i = -Upsilon_i - J (K3 e_w + e_q + e_w (K4 |e_q|^2 + K5 e_q4^2) / (2 (|e_w|^2 + kappa)))

    with the drift Upsilon_i taken as cancelled (zero). ``nominal_inertia`` J (3, 3) [kg m^2] (the
    law's model, stated on board); K3, K4, K5 [1/s] and kappa [rad^2/s^2] positive (E001-01).
    """

    quantity = "torque"

    count: int = static()
    nominal_inertia: Any = None
    K3: Any = 0.2
    K4: Any = 1.0
    K5: Any = 1.0
    kappa: Any = 1e-3

    def output(self, t, state, inputs: FlightInputs):
        w, q = inputs.measurement["omega"], inputs.measurement["q"]
        drift = jnp.zeros_like(w)  # Upsilon_i taken as cancelled
        # Yang2013 eq. (13)
        tau = attitude_control(
            w,
            q[:, 0:3],
            q[:, 3],
            drift,
            self.nominal_inertia,
            self.K3,
            self.K4,
            self.K5,
            self.kappa,
        )
        return tau, None, {}


# -------------------------------------------------------------------------------------- builders
def translational_law(ctx: BuildContext, sec: Any) -> Yang2013TranslationalController:
    """Yang2013's law (12) of a section's ``nominal_mass``, ``K1``, ``K2`` and (if it has one)
    ``desired_position`` (the one builder of the law).

    Parameters
    ----------
    ctx : BuildContext
        The build's context (the spacecraft count).
    sec : pydantic.BaseModel
        The section: ``nominal_mass`` (float or list of float: the law's stated masses M_i [kg], one
        or per spacecraft, never the plant's), ``K1`` (position gain offset [1/s^2]; the e_R gain is
        K1 + 1), ``K2`` (velocity gain [1/s]) and optionally ``desired_position`` (desired position
        p^d per axis, expressions in t [s] and i [m]; default 0).

    Returns
    -------
    Yang2013TranslationalController
        The law.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> sec = SimpleNamespace(nominal_mass=150.0, K1=0.005, K2=0.01)
    >>> law = translational_law(SimpleNamespace(count=2), sec)
    >>> law.nominal_mass.tolist(), law.count
    ([150.0, 150.0], 2)
    """
    n = ctx.count
    return Yang2013TranslationalController(
        count=n,
        nominal_mass=as_float(per_spacecraft(sec.nominal_mass, n, "controller.nominal_mass")),
        **section_floats(sec, "K1", "K2"),
        desired_position=expression_text(getattr(sec, "desired_position", ("0", "0", "0"))),
    )


def attitude_law(ctx: BuildContext, sec: Any) -> Yang2013AttitudeController:
    """Yang2013's law (13) of a section's ``nominal_inertia``, ``K3``, ``K4``, ``K5`` and ``kappa`` (the
    one builder of the law: ``yang2013-attitude`` and ``yang2013-force-torque`` use it).

    Parameters
    ----------
    ctx : BuildContext
        The build's context (the spacecraft count).
    sec : pydantic.BaseModel
        The section: ``nominal_inertia`` (Vec3: the law's stated principal inertia [kg m^2], never the
        plant's), the gains ``K3``, ``K4``, ``K5`` [1/s] and the smoothing constant ``kappa``
        [rad^2/s^2].

    Returns
    -------
    Yang2013AttitudeController
        The law.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> sec = SimpleNamespace(nominal_inertia=(20.0, 25.0, 30.0), K3=0.2, K4=1.0, K5=1.0, kappa=1e-3)
    >>> law = attitude_law(SimpleNamespace(count=2), sec)
    >>> law.nominal_inertia.diagonal().tolist(), law.count
    ([20.0, 25.0, 30.0], 2)
    """
    return Yang2013AttitudeController(
        count=ctx.count,
        nominal_inertia=as_float(np.diag(np.asarray(sec.nominal_inertia, dtype=float))),
        **section_floats(sec, "K3", "K4", "K5", "kappa"),
    )
