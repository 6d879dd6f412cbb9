"""Controller ``networked-el-hinf``: the distributed H-infinity law with adaptive recovery.

Truths: the exact-model closed-loop identity D s_dot + C s = tau (modified computed torque (6), E003-04),
the algebraic rewriting of the literal law given in SPEC P3.3, the modal decomposition of the coupling
(eigenvectors of the row-normalised adjacency), and the definitions of (18)-(19).
"""

from __future__ import annotations

import dataclasses
import inspect
import typing

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.actuators.euler_torque_allocation import HeldAdditiveFaultActuator
from formation_ftc.components.controllers import networked_el_hinf as ctl
from formation_ftc.components.controllers.networked_el_hinf import NetworkedElHinfController
from formation_ftc.components.estimators.scripted_fdi import ScriptedFdi
from formation_ftc.core import graph as graphs
from formation_ftc.core.dynamics import euler_lagrange as el
from formation_ftc.methods.composed import make_loop
from formation_ftc.sim.components import FlightInputs

M = 8
#: the Mehrabian scenarios' graph: ring 1-2-...-8-1 plus chords 1-5 and 3-7 (E003-10)
DEFAULT_EDGES = [(1, 2), (2, 3), (3, 4), (4, 5), (5, 6), (6, 7), (7, 8), (8, 1), (1, 5), (3, 7)]
A = graphs.adjacency(M, [(a - 1, b - 1) for a, b in DEFAULT_EDGES], directed=False)
AVG = graphs.row_normalized(A)


def gains(alpha=0.86):
    one = np.ones((M, 3))
    return dict(
        K=jnp.asarray(20 * one),
        K_P=jnp.asarray(0.16 * one),
        K_I=jnp.asarray(0.001 * one),
        sigma=jnp.asarray(0.5 * one),
        e_gain=jnp.asarray(one),
        alpha=jnp.asarray(alpha * np.ones(M)),
        gamma=jnp.asarray(0.6 * np.ones(M)),
        phi_b=jnp.asarray(0.01),
        avg=jnp.asarray(AVG),
    )


@pytest.mark.parametrize("law", ["literal", "diffusive"])
@pytest.mark.parametrize("comp", ["sat", "sign", "certainty_equivalence"])
def test_exact_model_gives_s_dynamics(law, comp):
    """With the true inertia in (6), the plant obeys D s_dot + C s = tau (residual < 1e-10 N m relative to
    terms of order 10 N m: float64 round-off of 3x3 solves)."""
    rng = np.random.default_rng(0)
    q = jnp.asarray(rng.uniform(-1.0, 1.0, (M, 3)))
    qd = jnp.asarray(rng.normal(0, 0.2, (M, 3)))
    z = jnp.asarray(rng.normal(0, 1.0, (M, 3)))
    u_hat = jnp.asarray(rng.normal(0, 0.5, (M, 3)))
    flag = jnp.asarray((rng.uniform(size=(M, 3)) > 0.5).astype(float))
    J = jnp.asarray(np.stack([np.diag(rng.uniform(10, 25, 3)) for _ in range(M)]))
    t = 1.3
    e = jnp.asarray(0.1 * np.sin(t) * np.ones((M, 3)))
    ed = jnp.asarray(0.1 * np.cos(t) * np.ones((M, 3)))
    edd = -e
    p = gains()
    out = ctl.control(q, qd, z, u_hat, flag, e, ed, edd, J, p, ctl.ELHinfConfig(law, comp))
    qdd = el.el_rhs(q, qd, out.u, J)
    err = ctl.tracking_errors(q, qd, z, e, ed, edd, p["K_P"], p["K_I"])
    s_dot = qdd - err.r_dot  # d/dt(q_dot - r)
    lhs = el.el_forces(q, qd, s_dot, err.s, J)
    np.testing.assert_allclose(
        np.asarray(lhs), np.asarray(out.tau_sync + out.gamma_comp), atol=1e-10
    )
    np.testing.assert_allclose(
        np.asarray(err.s), np.asarray(qd - ed + 0.16 * (q - e) + 0.001 * z), atol=1e-15
    )


def test_literal_law_rewriting():
    """SPEC P3.3: literal law = -1/2 (1-alpha) K s_j - 1/2 alpha K avg(s_j - s_n) + s_j / (2 gamma^2)."""
    rng = np.random.default_rng(1)
    s = jnp.asarray(rng.normal(size=(M, 3)))
    p = gains()
    got = ctl.synchronisation_torque(s, p["avg"], p["K"], p["alpha"], p["gamma"], "literal")
    a, K, g = 0.86, 20.0, 0.6
    want = -0.5 * (1 - a) * K * s - 0.5 * a * K * (s - AVG @ s) + s / (2 * g**2)
    np.testing.assert_allclose(np.asarray(got), np.asarray(want), atol=1e-12)


@pytest.mark.parametrize("law", ["literal", "diffusive"])
def test_modal_damping_matches_eigenvectors(law):
    """Along a right eigenvector v of avg (eigenvalue mu), tau_sync = -modal_damping(mu) v; the consensus
    direction (mu = 1) gives 0.0111 N m s for the literal law and 8.611 for the diffusive one (SPEC P3.3)."""
    p = gains()
    mu, V = np.linalg.eig(AVG)
    for k in range(M):
        v = np.real(V[:, k])
        s = jnp.asarray(np.repeat(v[:, None], 3, axis=1))
        tau = ctl.synchronisation_torque(s, p["avg"], p["K"], p["alpha"], p["gamma"], law)
        np.testing.assert_allclose(
            np.asarray(tau),
            -ctl.modal_damping(20.0, 0.86, 0.6, np.real(mu[k]), law) * np.asarray(s),
            atol=1e-11,
        )
    want = 0.5 * ((1 - 0.86) * 20 - 1 / 0.36) if law == "literal" else 0.5 * (20 - 1 / 0.36)
    assert ctl.modal_damping(20.0, 0.86, 0.6, 1.0, law) == pytest.approx(want, rel=1e-12)


def test_compensation_and_adaptation():
    s = jnp.asarray([[-1.0, -0.005, 0.0], [0.002, 0.5, 3.0]])
    u_hat = jnp.asarray([[0.6, 0.6, 0.6], [-0.2, 0.4, 0.0]])
    flag = jnp.asarray([[1.0, 1.0, 1.0], [1.0, 0.0, 1.0]])
    sat = np.asarray(ctl.compensation_torque(s, u_hat, flag, 0.01, "sat"))
    np.testing.assert_allclose(sat, [[0.6, 0.3, 0.0], [0.2 * 0.2, 0.0, 0.0]], atol=1e-15)
    sgn = np.asarray(ctl.compensation_torque(s, u_hat, flag, 0.01, "sign"))
    np.testing.assert_allclose(sgn, [[0.6, 0.6, 0.0], [0.2, 0.0, 0.0]], atol=1e-15)
    ce = np.asarray(ctl.compensation_torque(s, u_hat, flag, 0.01, "certainty_equivalence"))
    np.testing.assert_allclose(ce, [[-0.6, -0.6, -0.6], [0.2, 0.0, 0.0]], atol=1e-15)
    u_star = jnp.asarray([[0.5, 0.0, 0.0], [0.0, 1.0, 0.0]])
    rate = np.asarray(ctl.adaptation_rate(s, u_hat, u_star, flag, 0.5, 1.0))
    np.testing.assert_allclose(rate, np.asarray(flag * (0.5 * s - (u_hat - u_star))), atol=1e-15)
    assert rate[1, 1] == 0.0  # unflagged channel: estimate frozen
    with pytest.raises(ValueError, match="controller.law"):
        ctl.ELHinfConfig(law="other")


TRUTH_FIELDS = {"state", "true_state", "fault", "faults", "disturbance", "force", "process_noise"}


def _loop(name="mehrabian-identification", **ov):
    return make_loop(
        ftc.load_scenario(name, {"simulation.horizon": 1.0, "simulation.record_every": 1, **ov})
    )


def _hints(cls, meth):
    mod = vars(inspect.getmodule(cls)) | {"FlightInputs": FlightInputs}
    return typing.get_type_hints(getattr(cls, meth), globalns=mod)


def test_controller_and_fdi_cannot_see_the_truth():
    """Controller and FDI read FlightInputs only (no truth field); with the same flight inputs the
    command and the FDI report are unchanged when the true fault, the disturbance and the true inertia
    change, while the applied torque changes."""
    assert _hints(NetworkedElHinfController, "output")["inputs"] is FlightInputs
    assert _hints(ScriptedFdi, "update")["inputs"] is FlightInputs
    assert not TRUTH_FIELDS & set(FlightInputs._fields)
    # fault active from t = 0 and the FDI reporting from 0 s (no latency)
    loop = _loop(**{"actuator.faults.0.start": 0.0, "estimator.delay": 0.0})
    assert isinstance(loop.controller, NetworkedElHinfController) and isinstance(
        loop.estimator, ScriptedFdi
    )
    assert isinstance(loop.actuator, HeldAdditiveFaultActuator)
    act = dataclasses.replace(
        loop.actuator, torques=("3*sin(t) - 2",), windows=loop.actuator.windows + 0.0
    )
    plant = dataclasses.replace(
        loop.plant,
        disturbance_std=loop.plant.disturbance_std * 50.0,
        inertia_uncertainty=loop.plant.inertia_uncertainty * 0.1,
    )
    other = dataclasses.replace(loop, actuator=act, plant=plant)
    k = jnp.asarray(3, dtype=jnp.int64)
    state = loop.initial_state()  # same true state (same seed), hence the same measurement
    step = jax.jit(lambda lp, st: lp.prepared().step(k, st)[1])
    a, b = step(loop, state), step(other, state)
    for name in ("command", "fdi_flag", "fdi_estimate", "sliding_variable"):
        np.testing.assert_array_equal(np.asarray(a[name]), np.asarray(b[name]))
    assert np.max(np.abs(np.asarray(a["applied"]) - np.asarray(b["applied"]))) > 1.0
    assert np.asarray(a["fdi_flag"])[0, 2] == 1.0
