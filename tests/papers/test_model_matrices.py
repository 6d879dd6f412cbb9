"""Direct tests of the model matrices and vector fields that paper packages keep beside ``core/``.

Truths are derived by hand in the comments (not computed with the package):

* yang2013: the slot variation maps P[j] of the built-in mode sequence (S_ij of the scenario placed on
  the spacecraft slots, kept in components/supervisors/switching.py), the leave flags, and the translational error
  dynamics (2) at a hand-picked state (now in core);
* azizi2009: the rotating-square desired state, now in core (positions on the circumscribed circle,
  v = omega x r, a = -omega^2 r) and the desired relative accelerations of the chain pairs.
"""

import jax.numpy as jnp
import numpy as np

from formation_ftc import api
from formation_ftc.components.supervisors.switching import switched_structure
from formation_ftc.core.dynamics.attitude_quaternion import rigid_body_quaternion_rates
from formation_ftc.core.dynamics.tracking_error import translational_error_rates
from formation_ftc.core.polygon_formation import relative_acceleration_fn
from formation_ftc.core.polygon_formation import rotating_polygon as desired_state


def test_yang2013_slot_variation_maps_of_the_builtin_sequence():
    sc = api.load_scenario("yang2013-healthy")
    st = switched_structure(sc.section("supervisor"), 6, sc.simulation.dt)
    # modes: {1,2,3} -> {1..5} (S_12: rows 4 and 5 copy spacecraft 1) -> {1..5} (I) -> {1..5} (I)
    #        -> {1, -, 3, 6} (S_45 keeps 1 and 3; 6 enters with X*)
    P1 = np.zeros((6, 6))
    P1[0, 0] = P1[1, 1] = P1[2, 2] = 1.0
    P1[3, 0] = P1[4, 0] = 1.0
    P_id5 = np.diag([1.0, 1, 1, 1, 1, 0])
    P4 = np.diag([1.0, 0, 1, 0, 0, 0])
    np.testing.assert_array_equal(st.P[0], np.eye(6))
    np.testing.assert_array_equal(st.P[1], P1)
    np.testing.assert_array_equal(st.P[2], P_id5)
    np.testing.assert_array_equal(st.P[3], P_id5)
    np.testing.assert_array_equal(st.P[4], P4)
    np.testing.assert_array_equal(
        st.active.astype(int),
        [[1, 1, 1, 0, 0, 0]] + [[1, 1, 1, 1, 1, 0]] * 3 + [[1, 0, 1, 0, 0, 1]],
    )
    leaves = np.zeros((5, 6), dtype=bool)
    leaves[3, [1, 3, 4]] = True  # spacecraft 2, 4 and 5 have zero columns in S_45
    np.testing.assert_array_equal(st.leaves, leaves)
    np.testing.assert_array_equal(st.switch_steps * 0.05, [0.0, 1000.0, 2000.0, 3000.0, 4000.0])
    assert st.xstar[4, 5, 0] == 0.2 and not np.any(st.xstar[4, 5, 1:3])


def test_yang2013_translational_error_dynamics_by_hand():
    # e_R = (1, 2, 3), e_V = (0.1, -0.2, 0.3); eq. (2): e_R' = e_V - w x e_R, e_V' = Phi - (f + d)/M - w x e_V
    e_R, e_V = jnp.array([1.0, 2, 3]), jnp.array([0.1, -0.2, 0.3])
    Phi, f, d = jnp.array([0.5, 0, -1.0]), jnp.array([10.0, 20.0, 0.0]), jnp.array([0.0, 0.0, 4.0])
    dR, dV = (np.asarray(a) for a in translational_error_rates(e_R, e_V, Phi, f, d, 10.0))
    np.testing.assert_allclose(dR, [0.1, -0.2, 0.3], rtol=0, atol=1e-15)
    np.testing.assert_allclose(dV, [0.5 - 1.0, -2.0, -1.0 - 0.4], rtol=0, atol=1e-15)
    w = jnp.array([0.0, 0.0, 0.5])  # w x e_R = (-1, 0.5, 0), w x e_V = (0.1, 0.05, 0)
    dR, dV = (np.asarray(a) for a in translational_error_rates(e_R, e_V, Phi, f, d, 10.0, w))
    np.testing.assert_allclose(dR, [0.1 + 1.0, -0.2 - 0.5, 0.3], rtol=0, atol=1e-15)
    np.testing.assert_allclose(dV, [-0.5 - 0.1, -2.0 - 0.05, -1.4], rtol=0, atol=1e-15)


def test_yang2013_attitude_error_dynamics_by_hand():
    # eq. (5) at the error level: J e_w' = Upsilon + tau + iota (no gyroscopic term), q' = 1/2 (q4 w - w x q, -w.q)
    J = np.diag([2.0, 4.0, 5.0])
    torque = jnp.array([2.0, 1.0, -3.0])  # Upsilon + tau + iota
    w = jnp.array([0.01, 0.0, 0.0])
    dw, dq = (
        np.asarray(a)
        for a in rigid_body_quaternion_rates(w, jnp.array([0.0, 0, 0, 1]), torque, J, False)
    )
    np.testing.assert_allclose(dw, [2.0 / 2, 1.0 / 4, -3.0 / 5], rtol=0, atol=1e-15)
    np.testing.assert_allclose(dq, [0.005, 0, 0, 0], rtol=0, atol=1e-15)
    q = jnp.array([0.0, 0.6, 0.0, 0.8])  # w x q_v = (0, 0, 0.006), w . q_v = 0
    _, dq = (np.asarray(a) for a in rigid_body_quaternion_rates(w, q, torque, J, False))
    np.testing.assert_allclose(dq, [0.5 * 0.8 * 0.01, 0, -0.5 * 0.006, 0], rtol=0, atol=1e-15)


def test_azizi_rotating_square_by_hand():
    side, omega = 200.0, 0.1
    r = 100.0 * np.sqrt(2.0)  # circumradius of a 200 m square
    pos, vel, acc = (np.asarray(a) for a in desired_state(0.0, 4, 3, side, omega))
    np.testing.assert_allclose(
        pos, [[100, 100, 0], [-100, 100, 0], [-100, -100, 0], [100, -100, 0]], rtol=0, atol=1e-12
    )
    np.testing.assert_allclose(
        vel,
        0.1 * np.array([[-100, 100, 0], [-100, -100, 0], [100, -100, 0], [100, 100, 0]]),
        rtol=0,
        atol=1e-12,
    )
    np.testing.assert_allclose(acc, -0.01 * pos, rtol=0, atol=1e-12)
    t = 7.0  # rotated by 0.7 rad: satellite 1 at angle pi/4 + 0.7 on the circle
    pos, _, acc = (np.asarray(a) for a in desired_state(t, 4, 2, side, omega))
    np.testing.assert_allclose(
        pos[0], r * np.array([np.cos(np.pi / 4 + 0.7), np.sin(np.pi / 4 + 0.7)]), rtol=1e-14
    )
    np.testing.assert_allclose(np.linalg.norm(pos, axis=1), r, rtol=1e-14)
    rel = np.asarray(relative_acceleration_fn(4, side, omega, 0)(t))
    np.testing.assert_allclose(
        rel, [acc[1, 0] - acc[0, 0], acc[2, 0] - acc[1, 0], acc[3, 0] - acc[2, 0]], rtol=1e-14
    )
