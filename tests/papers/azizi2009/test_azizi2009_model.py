"""The azizi2009 closed loop (composed scenarios) against SPEC P4.6 acceptance checks (reduced horizons: the error is
periodic after a ~5 s transient, so 60-100 s windows contain the 300 s maximum).

Truths: the reduced model (7) integrated independently (design.flfr, RK4 at the same step) for the
continuous-time loop, to the SPEC's 1e-6 m; the SPEC reference numbers of the reviewer's script
(max errors 5.4e-5 / 0.0636 m, efforts at 100 s, printed to 3-4 digits -> 1 % tolerance); first-order
convergence of the ZOH discretisation error in dt; relations of Theorem 2 (monotonicity).
"""

import numpy as np
import pytest

from formation_ftc.api import load_scenario as load
from formation_ftc.core.polygon_formation import relative_acceleration_fn, rotating_polygon
from formation_ftc.design.allocation import perturbation_coefficients
from formation_ftc.design.flfr import reduced_model, simulate_reduced_model
from formation_ftc.methods.composed import make_loop
from formation_ftc.papers.azizi2009.alpha2_study import run_batch
from formation_ftc.papers.azizi2009.conditions import d_norms
from formation_ftc.papers.programs import simulate
from formation_ftc.registry import get_method

ALPHAS = [1.0, 3.0, 4.0, 5.0, 6.0, 10.0]


@pytest.fixture(scope="module")
def sweep():
    sc = load(
        "azizi2009-llfr",
        {"simulation.horizon": 100.0, "plant.axes": 1, "simulation.record_every": 1000},
    )
    A = np.ones((len(ALPHAS), 4))
    A[:, 1] = ALPHAS
    return run_batch(sc, {"alpha": A})


def test_fault_free_error_is_discretisation_level():  # SPEC P4.6-3
    _, m = simulate(load("azizi2009-fault-free", {"simulation.horizon": 60.0}))
    assert 1e-6 < m["max_err"] <= 2e-4
    assert m["max_err"] == pytest.approx(5.4e-5, rel=0.02)
    assert m["n_events"] == 0.0


def test_zoh_error_converges_first_order_in_dt():
    errs = []
    for dt in (2e-3, 1e-3):
        _, m = simulate(
            load(
                "azizi2009-fault-free",
                {
                    "simulation.horizon": 20.0,
                    "simulation.dt": dt,
                    "plant.axes": 1,
                    "simulation.record_every": 100,
                    "plant.disturbance_acceleration": "0",
                },
            )
        )
        errs.append(m["max_err"])
    assert errs[0] / errs[1] == pytest.approx(2.0, rel=0.05)


def test_reduced_model_7_matches_full_simulation():  # SPEC P4.6-2
    over = {
        "simulation.horizon": 20.0,
        "plant.axes": 1,
        "plant.integration": "rk4",
        "controller.sampling": "continuous",
        "plant.disturbance_acceleration": "0",
        "simulation.record_every": 100,
    }
    sc = load("azizi2009-llfr", over)
    ds, _ = simulate(sc)
    pc = perturbation_coefficients([1.0, 1.0, 1.0, 1.0], [1.0, 0.88, 1.0, 1.0], 1)
    eps = 0.88 - 0.8  # b_hat = b + eps
    d = pc.d(eps, 1.0)
    _, _, A_clp = reduced_model(2.0, 3.0, (d[0], d[1]))
    w_fn = relative_acceleration_fn(4, 200.0, 0.1, 0)
    X, _ = simulate_reduced_model(A_clp, w_fn, 20.0, 1e-3, weights=d[:3], record_every=100)
    e = ds["tracking_error"].sel(axis="x").values
    assert np.max(np.abs(X[:, 0] - e[:, 0])) < 1e-6  # e12
    assert np.max(np.abs(X[:, 2] - e[:, 1])) < 1e-6  # e23
    assert np.max(np.abs(e[:, 2])) < 1e-6  # e34 unperturbed
    assert np.max(np.abs(e[:, 0])) > 0.03  # a non-trivial comparison
    # the sampled-data (ZOH) loop differs from (7) only at the discretisation level
    ds_z, _ = simulate(
        load("azizi2009-llfr", {**over, "plant.integration": "exact", "controller.sampling": "zoh"})
    )
    dz = np.max(np.abs(ds_z["tracking_error"].sel(axis="x").values[:, 0] - X[:, 0]))
    assert dz < 2e-4


def test_llfr_error_band_and_monotone_in_alpha2(sweep):  # SPEC P4.6-4
    me = np.array([r["max_err"] for r in sweep])
    assert 0.05 <= me[0] <= 0.09 and me[0] > 0.03
    assert me[0] == pytest.approx(0.0636, rel=0.01)
    assert np.all(np.diff(me) < 0)
    a_cross = np.interp(0.03, me[::-1], np.array(ALPHAS)[::-1])
    assert 3.5 <= a_cross <= 6.5
    d = np.array([r["D_norm_llfr"] for r in sweep])
    assert np.all(np.diff(d) < 0)


def test_effort_redistribution_matches_spec(sweep):  # SPEC P4.6-7 and P4.4 efforts
    E = {
        a: [r[f"effort_x_100s_sc{j}"] for j in range(1, 5)]
        for a, r in zip(ALPHAS, sweep, strict=True)
    }
    ref = {
        1.0: [98.8, 131.8, 97.1, 123.5],
        6.0: [146.9, 19.4, 135.0, 281.3],
        10.0: [164.7, 8.7, 150.7, 321.7],
    }
    for a, vals in ref.items():
        np.testing.assert_allclose(E[a], vals, rtol=0.01)
    assert E[1.0][1] > E[6.0][1] > E[10.0][1]
    for j in (0, 2, 3):
        assert E[1.0][j] < E[6.0][j] < E[10.0][j]


def test_batched_member_equals_single_run(sweep):
    _, m = simulate(
        load(
            "azizi2009-llfr",
            {
                "simulation.horizon": 100.0,
                "plant.axes": 1,
                "simulation.record_every": 1000,
                "controller.alpha": [1.0, 6.0, 1.0, 1.0],
            },
        )
    )
    assert m["max_err"] == pytest.approx(sweep[ALPHAS.index(6.0)]["max_err"], rel=1e-12)


def test_supervisor_switches_to_flfr_and_meets_e_s(tmp_path):
    sc = load("azizi2009-flfr", {"simulation.horizon": 60.0})
    ds, m = simulate(sc)
    assert m["n_events"] == 2.0 and 0.5 < m["t_flfr"] < 5.0
    # the recorded mode is the one in force over [t_k, t_k+1): LLFR from step 0 (the supervisor leaves
    # Nominal at step 0, its first decision), then FLFR
    mode = ds["mode"].values
    t = ds["time"].values
    assert set(mode[t < m["t_flfr"] - 1e-9]) == {1}
    assert set(mode[t > m["t_flfr"]]) == {2}
    loop = make_loop(sc)
    alpha_flfr = float(loop.controller.alpha_flfr)
    assert alpha_flfr == pytest.approx(4.723, abs=2e-3)  # eq. (9), H from A_clp
    assert m["max_err"] > 0.03  # the violation that triggers FLFR
    assert m["max_err_after_flfr"] <= 0.03
    d_llfr, d_flfr = d_norms(sc, loop, loop.controller.alpha, alpha_flfr)
    assert d_flfr < d_llfr
    # the faulty x axis does not disturb y, z (decoupled axes)
    assert np.max(np.abs(ds["tracking_error"].sel(axis=["y", "z"]).values)) <= 2e-4
    (png,) = get_method("composed").plot(ds, sc, tmp_path)  # the paper's run figure
    assert png.name == "azizi2009-flfr.png" and png.stat().st_size > 10_000


def test_noise_is_seeded():
    over = {
        "simulation.horizon": 5.0,
        "plant.axes": 1,
        "sensors.position_noise_std": 1e-3,
        "sensors.velocity_noise_std": 1e-3,
        "simulation.record_every": 100,
    }
    sc = load("azizi2009-llfr", over)
    A = np.ones((3, 4))
    r = run_batch(sc, {"alpha": A, "seed": np.array([0, 0, 1])})
    assert r[0]["max_err"] == r[1]["max_err"]
    assert r[0]["max_err"] != r[2]["max_err"]


def test_exact_estimate_recovers_fault_free_errors_general_n():
    """With b_hat = b the allocation cancels the fault exactly (eq. (4)): the errors equal the fault-free
    run's (ZOH discretisation level) -- here for N = 5 and a fault on satellite 3 (general N)."""
    r0, v0, _ = rotating_polygon(0.0, 5, 3, 200.0, 0.1)  # on the pentagon at t = 0
    base = {
        "simulation.horizon": 10.0,
        "plant.initial_position": np.asarray(r0).tolist(),
        "plant.initial_velocity": np.asarray(v0).tolist(),
        "plant.axes": 2,
        "controller.b": [1.0] * 5,
        "controller.alpha": [1.0, 2.0, 1.0, 0.5, 1.0],
        "actuator.gain": [1.0] * 5,
        "simulation.record_every": 100,
    }
    fault = {**base, "controller.faulty_spacecraft": 3, "actuator.spacecraft": 3}
    _, m_ff = simulate(load("azizi2009-fault-free", base))
    _, m_ex = simulate(
        load("azizi2009-llfr", {**fault, "actuator.effectiveness": 0.6, "controller.b_hat": 0.6})
    )
    _, m_bad = simulate(
        load("azizi2009-llfr", {**fault, "actuator.effectiveness": 0.6, "controller.b_hat": 0.66})
    )
    assert m_ff["max_err"] < 2e-4
    # the applied relative accelerations J(b) u = p are identical, so the errors agree to round-off
    assert m_ex["max_err"] == pytest.approx(m_ff["max_err"], rel=1e-6)
    assert m_bad["max_err"] > 100 * m_ff["max_err"]


def test_seed_by_weight_grid_equals_the_flat_batch():
    """The reproduction's seed study runs seeds x weights as a grid (each seed's noise drawn once for
    its row): the metrics of every run equal those of the same runs in one flat batch, in the same
    order. Tolerance 1e-10 relative: the two programs are compiled separately and may sum in another
    order; the switching of the FLFR loop carries such a last-bit difference further (measured: 11 of
    the 12 runs bit for bit, one max_err 1.7e-12 apart; the flat batch and the runs alone agree bit for
    bit)."""
    sc = load(
        "azizi2009-llfr",
        {
            "simulation.horizon": 10.0,
            "plant.axes": 1,
            "simulation.record_every": 1000,
            "sensors.position_noise_std": 1e-5,
            "sensors.velocity_noise_std": 1e-5,
        },
    )
    seeds, weights = 3, [1.0, 4.0, 6.0, 10.0]
    A = np.ones((seeds * len(weights), 4))
    A[:, 1] = np.tile(weights, seeds)
    S = np.repeat(np.arange(seeds), len(weights))
    flat = run_batch(sc, {"alpha": A, "seed": S})
    grid = run_batch(sc, {"alpha": A, "seed": S}, grid=(seeds, len(weights)))
    assert len({m["max_err"] for m in flat}) == len(
        flat
    )  # every run differs: seeds and weights matter
    for b, (f, g) in enumerate(zip(flat, grid, strict=True)):
        assert f.keys() == g.keys()
        for k in f:  # (NaN where a metric's window never opened, e.g. no FLFR event: NaN in both)
            assert g[k] == pytest.approx(f[k], rel=1e-10, abs=1e-300, nan_ok=True), (b, k)
    with pytest.raises(ValueError, match=r"rows x columns must equal the batch size 12"):
        run_batch(sc, {"alpha": A, "seed": S}, grid=(5, 2))
