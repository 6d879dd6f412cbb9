"""Plant ``orbital-truth`` and its LVLH relative-state sensors, in composed closed loops.

Independent references: the relative-LVLH plant (Li2020's nonlinear elliptic relative dynamics, a
different formulation integrated in its own frame), the orbital elements the initial state comes from,
and the sample statistics of the sensors' noise.
"""

from __future__ import annotations

import copy

import jax
import numpy as np
import pytest

import formation_ftc as ftc
from formation_ftc.components.plants.orbital_truth import InertialFormationPlant
from formation_ftc.components.sensors.lvlh_relative_state import LvlhRelativeStateSensors
from formation_ftc.components.sensors.relative_state import RelativeStateSensors
from formation_ftc.config.loader import ScenarioError
from formation_ftc.core.dynamics.orbital_truth import eci_to_elements
from formation_ftc.sim.components import SensorInputs

A, E, NU0 = 7000e3, 0.05, 0.3
OFFSETS = [[300.0, -200.0, 100.0], [-150.0, 400.0, -250.0]]
DISTURBANCE = ["0.02*sin(0.01*t)*i", "0.01*i", "-0.015*cos(0.02*t)"]


def _loop(plant: dict, sensors: dict | None, reference: bool = True) -> dict:
    raw = {
        "scenario": {"name": "truth-vs-model", "method": "composed"},
        "simulation": {"horizon": 600.0, "dt": 1.0, "record_every": 30},
        "plant": {
            "mass": [100.0, 120.0],
            "initial_position": OFFSETS,
            "initial_velocity": [[0.05, -0.02, 0.01], [0.0, 0.03, -0.04]],
            "disturbance_force": DISTURBANCE,
            **plant,
        },
        "controller": {
            "type": "pd",
            "kp": 0.02,
            "kd": 2.0,
            "nominal_mass": 0.0,
            "desired_position": ["100", "50*i", "-20"],
        },
    }
    if reference:
        raw["reference"] = {
            "type": "keplerian",
            "semi_major_axis": A,
            "eccentricity": E,
            "true_anomaly0": NU0,
        }
    if sensors is not None:
        raw["sensors"] = sensors
    return raw


TRUTH = {
    "type": "orbital-truth",
    "semi_major_axis": A,
    "eccentricity": E,
    "inclination": 0.9,
    "raan": 0.4,
    "arg_perigee": 1.1,
    "true_anomaly": NU0,
    "j2": False,
    "drag": False,
    "srp": False,
}


def test_inertial_truth_in_a_closed_loop_equals_the_relative_lvlh_plant():
    """J2, drag and SRP off, a PD law and LVLH disturbance forces: the truth's LVLH positions equal those
    of the relative-LVLH plant (same orbit, same law, forces in the same LVLH axes) to < 1e-6 m over
    600 s (measured 3.2e-8 m: RK4 at 1 s on two formulations, float64 rounding of ECI positions),
    velocities to < 1e-8 m/s (measured 4e-10), commands to < 1e-8 N (4.4e-10); delta-v and effort
    agree to 1e-8 relative. A wrong LVLH -> ECI force rotation (e.g. R instead of
    R^T) moves the spacecraft by metres here."""
    ds_t = ftc.simulate(ftc.load_scenario(_loop(TRUTH, {"type": "lvlh-relative-state"})))
    ds_m = ftc.simulate(
        ftc.load_scenario(_loop({"type": "relative-lvlh"}, {"type": "relative-state"}))
    )
    np.testing.assert_allclose(ds_t.position.values, ds_m.position.values, rtol=0, atol=1e-6)
    np.testing.assert_allclose(ds_t.velocity.values, ds_m.velocity.values, rtol=0, atol=1e-8)
    np.testing.assert_allclose(ds_t.command.values, ds_m.command.values, rtol=0, atol=1e-8)
    np.testing.assert_allclose(ds_t.delta_v.values, ds_m.delta_v.values, rtol=1e-8)
    np.testing.assert_allclose(ds_t.control_effort.values, ds_m.control_effort.values, rtol=1e-8)
    # the law moved the formation (the comparison is not between two motionless states)
    assert np.max(np.abs(ds_t.position.values[-1] - ds_t.position.values[0])) > 10.0
    # the chief's altitude follows the conic r = p / (1 + e cos nu) - R_E at t = 0
    r0 = A * (1 - E**2) / (1 + E * np.cos(NU0))
    assert np.isclose(float(ds_t.chief_altitude.values[0]), r0 - 6378137.0, rtol=1e-12)
    assert ds_t.position.attrs["frame"] == "LVLH"


def test_initial_state_maps_elements_and_offsets():
    plant = InertialFormationPlant(
        mass=np.array([100.0, 50.0]),
        chief_elements=np.array([A, E, 0.9, 0.4, 1.1, NU0]),
        initial_state_lvlh=np.array([[300.0, -200, 100, 0.1, 0.2, 0.3], [0, 0, 0, 0, 0, 0]]),
        ballistic_coefficient=np.array([0.02, 0.02]),
        chief_ballistic_coefficient=np.array(0.02),
        srp_coefficient=np.array([0.01, 0.01]),
        chief_srp_coefficient=np.array(0.01),
    )
    x0 = plant.initial_state()
    np.testing.assert_allclose(
        [float(v) for v in eci_to_elements(x0["chief"])], [A, E, 0.9, 0.4, 1.1, NU0], rtol=1e-11
    )
    np.testing.assert_allclose(plant.position(x0), [[300.0, -200, 100], [0, 0, 0]], atol=1e-7)
    np.testing.assert_allclose(plant.velocity(x0), [[0.1, 0.2, 0.3], [0, 0, 0]], atol=1e-10)
    # a deputy at the chief's place with the chief's velocity has the chief's ECI state
    np.testing.assert_allclose(x0["deputies"][1], x0["chief"], rtol=1e-15)


def test_perturbations_act_on_the_truth_chief():
    """J2 + drag + SRP on, chief on a 400 km-perigee orbit: the chief's altitude differs from the two-body
    conic, and drag with a larger ballistic coefficient for spacecraft 2 makes it fall behind (negative
    along-track drift relative to spacecraft 1, which has the chief's coefficient)."""
    plant = {
        **TRUTH,
        "semi_major_axis": 6778137.0,
        "eccentricity": 0.0,
        "j2": True,
        "drag": True,
        "srp": True,
        "ballistic_coefficient": [0.02, 0.2],
        "chief_ballistic_coefficient": 0.02,
        "srp_coefficient": 0.015,
        "disturbance_force": ["0", "0", "0"],
    }
    raw = _loop(plant, {"type": "lvlh-relative-state"}, reference=False)
    raw["controller"] = {"type": "pd", "kp": 0.0, "kd": 0.0, "nominal_mass": 0.0}
    raw["plant"]["initial_position"] = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    raw["plant"].pop("initial_velocity")
    ds = ftc.simulate(ftc.load_scenario(raw))
    pos = ds.position.values
    np.testing.assert_allclose(
        pos[:, 0], 0.0, atol=1e-6
    )  # same B and C_R A/m as the chief: stays with it
    assert (
        pos[-1, 1, 1] < -1.0
    )  # differential drag (Delta B = 0.18 m^2/kg at 400 km): measured -2.76 m at 600 s
    alt = ds.chief_altitude.values
    assert np.ptp(alt) > 1e3  # J2 makes the 'circular' orbit's radius vary by kilometres


# -------------------------------------------------------------------------------------------- sensors
def _plant():
    return InertialFormationPlant(
        mass=np.full(3, 100.0),
        chief_elements=np.array([A, E, 0.9, 0.4, 1.1, NU0]),
        initial_state_lvlh=np.array(
            [[300.0, -200, 100, 0.1, 0.2, 0.3], [10, 20, 30, 0, 0, 0], [-500, 0, 0, 0, -0.5, 0]]
        ),
        ballistic_coefficient=np.full(3, 0.02),
        chief_ballistic_coefficient=np.array(0.02),
        srp_coefficient=np.full(3, 0.01),
        chief_srp_coefficient=np.array(0.01),
    )


def test_sensors_output_is_the_relative_state_sensors_output_plus_bias():
    plant = _plant()
    x0 = plant.initial_state()
    bias = np.arange(18.0).reshape(3, 6) * 0.1
    lv = LvlhRelativeStateSensors(
        count=3, position_noise_std=np.array(2.0), velocity_noise_std=np.array(0.01), bias=bias
    )
    rs = RelativeStateSensors(
        count=3, position_noise_std=np.array(2.0), velocity_noise_std=np.array(0.01)
    )
    key = jax.random.PRNGKey(3)
    y_lv = lv.measure(0.0, x0, SensorInputs(noise=lv.noise(key), reference=None))
    q = np.hstack([plant.position(x0), plant.velocity(x0)])
    y_rs = rs.measure(0.0, {"q": q}, SensorInputs(noise=rs.noise(key), reference=None))
    assert y_lv.shape == (3, 6)
    np.testing.assert_allclose(y_lv, np.asarray(y_rs) + bias, rtol=0, atol=1e-12)


def test_sensor_noise_and_bias_statistics():
    """20,000 draws: the sample mean of y - truth is the bias within 5 standard errors (sigma/sqrt(n))
    and the sample standard deviation is sigma within 3 % (its standard error is sigma/sqrt(2n) = 0.5 %)."""
    plant = _plant()
    x0 = plant.initial_state()
    sp, sv = 3.0, 0.02
    bias = np.tile([1.0, -2.0, 0.5, 0.01, -0.02, 0.0], (3, 1))
    lv = LvlhRelativeStateSensors(
        count=3, position_noise_std=np.array(sp), velocity_noise_std=np.array(sv), bias=bias
    )
    n = 20000
    keys = jax.random.split(jax.random.PRNGKey(11), n)
    ys = np.asarray(
        jax.jit(jax.vmap(lambda k: lv.measure(0.0, x0, SensorInputs(lv.noise(k), None))))(keys)
    )
    err = ys - np.hstack([plant.position(x0), plant.velocity(x0)])
    sig = np.array([sp] * 3 + [sv] * 3)
    assert np.all(np.abs(err.mean(axis=0) - bias) < 5 * sig / np.sqrt(n))
    np.testing.assert_allclose(err.std(axis=0), np.broadcast_to(sig, (3, 6)), rtol=0.03)


def test_biased_sensors_in_a_closed_loop_shift_the_command_by_the_pd_gain():
    """Noise-free, biased sensors: at t = 0 the PD command differs from the unbiased loop's by exactly
    -kp * position_bias - kd * velocity_bias (the law sees the bias, the truth does not); a noisy loop
    runs and stays finite."""
    bias_p, bias_v = np.array([2.0, 0.0, -1.0]), np.array([0.0, 0.01, 0.0])
    raw = _loop(
        TRUTH,
        {
            "type": "lvlh-relative-state",
            "position_bias": bias_p.tolist(),
            "velocity_bias": bias_v.tolist(),
            "position_noise_std": 0.0,
        },
    )
    raw0 = _loop(TRUTH, {"type": "lvlh-relative-state"})
    raw_noisy = _loop(
        TRUTH,
        {"type": "lvlh-relative-state", "position_noise_std": 0.5, "velocity_noise_std": 1e-3},
    )
    # the 600 s of _loop: the program of the inertial-truth closed-loop test above
    ds, ds0, ds_n = (ftc.simulate(ftc.load_scenario(r)) for r in (raw, raw0, raw_noisy))
    kp, kd = raw["controller"]["kp"], raw["controller"]["kd"]
    np.testing.assert_allclose(
        ds.command.values[0] - ds0.command.values[0],
        np.broadcast_to(-kp * bias_p - kd * bias_v, (2, 3)),
        rtol=0,
        atol=1e-10,
    )
    assert np.all(np.isfinite(ds_n.position.values))
    assert np.max(np.abs(ds_n.command.values - ds0.command.values)) > 1e-3


# ------------------------------------------------------------------------------------------- catalog
@pytest.mark.parametrize(
    "field, value, needle",
    [
        ("eccentricity", 0.95, "plant.eccentricity"),
        ("semi_major_axis", 6.0e6, "plant.semi_major_axis"),
        ("ballistic_coefficient", [0.02, -0.01], "ballistic_coefficient"),
        ("mass", [100.0, 0.0], "mass"),
        ("inclination", 4.0, "plant.inclination"),
    ],
)
def test_catalog_rejects_bad_plant_fields_naming_them(field, value, needle):
    raw = _loop({**TRUTH, field: value}, {"type": "lvlh-relative-state"})
    with pytest.raises(ScenarioError) as exc:
        ftc.load_scenario(raw)
    assert needle in str(exc.value)


def test_catalog_rejects_perigee_inside_the_earth_and_bad_sensor_bias():
    with pytest.raises(ScenarioError, match="eccentricity: perigee radius"):
        ftc.load_scenario(_loop({**TRUTH, "eccentricity": 0.1}, {"type": "lvlh-relative-state"}))
    with pytest.raises(ScenarioError, match="sensors.position_bias"):
        ftc.load_scenario(
            _loop(TRUTH, {"type": "lvlh-relative-state", "position_bias": [1.0, 2.0]})
        )
    # a relative-state plant is fine (its sensed state is the (N, 6) relative state)
    ftc.load_scenario(_loop({"type": "relative-lvlh"}, {"type": "lvlh-relative-state"}))


def test_relative_state_sensors_and_the_default_run_unchanged_on_the_truth():
    """The plant's sensed state is the LVLH relative state, so the relative-state sensors (same noise
    draws) and the default exact sensors give the loop of the lvlh-relative-state sensors exactly."""
    noise = {"position_noise_std": 0.5, "velocity_noise_std": 1e-3}
    runs = []
    for sensors in (
        {"type": "lvlh-relative-state", **noise},
        {"type": "relative-state", **noise},
        {"type": "lvlh-relative-state"},
        None,
    ):
        raw = _loop(TRUTH, sensors)
        raw["simulation"]["horizon"] = 60.0
        runs.append(ftc.simulate(ftc.load_scenario(raw)))
    np.testing.assert_array_equal(runs[0].command.values, runs[1].command.values)
    np.testing.assert_array_equal(runs[2].command.values, runs[3].command.values)
    assert (
        np.max(np.abs(runs[0].command.values - runs[2].command.values)) > 1e-3
    )  # the noise is there


def test_builtin_scenario_validates_with_the_truth_plant_and_sensors():
    """The built-in composition (a full CLI run is exercised by hand: see the docs page) names the truth
    plant with J2 and drag, the LVLH sensors and an on-board Keplerian model with the chief's a and e."""
    scn = ftc.load_scenario("compose-li2020-on-orbital-truth", {"simulation.horizon": 2.0})
    plant, ref = scn.section("plant"), scn.section("reference")
    assert (
        scn.type_of("plant") == "orbital-truth" and scn.type_of("sensors") == "lvlh-relative-state"
    )
    assert plant.j2 and plant.drag and not plant.srp
    assert (ref.semi_major_axis, ref.eccentricity) == (plant.semi_major_axis, plant.eccentricity)
    raw = copy.deepcopy(_loop(TRUTH, {"type": "lvlh-relative-state"}))
    raw["plant"]["eccentricity"] = "high"
    with pytest.raises(ScenarioError, match="plant.eccentricity"):
        ftc.load_scenario(raw)


def test_initial_condition_from_relative_orbital_elements():
    """``initial_roe`` [m] (a_c times the dimensionless ROE) replaces the LVLH offsets: the deputies'
    osculating elements give the same ROE back; giving both or neither is rejected naming the field."""
    from formation_ftc.core.dynamics.orbital_truth import elements_to_roe
    from formation_ftc.methods.composed import make_loop

    roe_m = [[0.0, 200.0, 100.0, -50.0, 80.0, 60.0], [5.0, -300.0, 0.0, 0.0, -40.0, 0.0]]
    plant = {k: v for k, v in TRUTH.items()}
    raw = _loop({**plant, "initial_roe": roe_m}, {"type": "lvlh-relative-state"})
    raw["plant"].pop("initial_position")
    raw["plant"].pop("initial_velocity")
    loop = make_loop(ftc.load_scenario(raw))
    x0 = loop.plant.initial_state()
    chief = [float(v) for v in eci_to_elements(x0["chief"])]
    roe = np.asarray(elements_to_roe(chief, eci_to_elements(x0["deputies"])))
    np.testing.assert_allclose(
        roe * A, roe_m, atol=1e-5
    )  # ~1e-12 relative rounding of the elements
    # the LVLH offsets are ~ the ROE scale (hundreds of metres), not zero
    assert 100.0 < np.max(np.abs(loop.plant.position(x0))) < 1000.0
    with pytest.raises(ScenarioError, match="plant: .*initial_position: give either"):
        ftc.load_scenario(_loop({**plant, "initial_roe": roe_m}, {"type": "lvlh-relative-state"}))
    raw["plant"]["initial_roe"] = roe_m[:1]
    with pytest.raises(ScenarioError, match="initial_roe: 1 rows for 2 spacecraft"):
        ftc.load_scenario(raw)


def test_initial_dispersion_is_seeded_gaussian_and_zero_by_default():
    """The dispersion drawn from ``dispersion_seed`` (what a league samples, one number per run): zero
    without deviations, the same for the same seed, different for another seed, and with the stated
    standard deviations (4,000 spacecraft: sample std within 5 %, mean within 5 standard errors)."""
    import numpy as np

    from formation_ftc.components.plants.orbital_truth import InertialFormationPlant

    def plant(n, std, seed):
        return InertialFormationPlant(
            mass=np.full(n, 100.0),
            chief_elements=np.array([7e6, 0.01, 1.0, 0, 0, 0]),
            initial_state_lvlh=np.zeros((n, 6)),
            ballistic_coefficient=np.zeros(n),
            chief_ballistic_coefficient=np.asarray(0.0),
            srp_coefficient=np.zeros(n),
            chief_srp_coefficient=np.asarray(0.0),
            initial_dispersion=np.asarray(std),
            dispersion_seed=np.asarray(float(seed)),
        )

    assert np.all(np.asarray(plant(4, [0.0, 0.0], 7).dispersion()) == 0.0)
    a = np.asarray(plant(4, [10.0, 0.01], 7).dispersion())
    np.testing.assert_array_equal(a, np.asarray(plant(4, [10.0, 0.01], 7).dispersion()))
    assert not np.allclose(a, np.asarray(plant(4, [10.0, 0.01], 8).dispersion()))
    big = np.asarray(plant(4000, [10.0, 0.01], 3).dispersion())
    for cols, std in ((slice(0, 3), 10.0), (slice(3, 6), 0.01)):
        v = big[:, cols].ravel()
        assert abs(v.std() / std - 1) < 0.05
        assert abs(v.mean()) < 5 * std / np.sqrt(v.size)
    # the initial state carries it: LVLH relative state at t = 0 equals offsets + dispersion
    p = plant(4, [10.0, 0.01], 7)
    np.testing.assert_allclose(np.asarray(p.relative_state(p.initial_state())), a, atol=1e-6)
