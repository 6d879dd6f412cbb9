"""Field types and conversions the component sections share (TOML side, numpy only)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Annotated, Any

import numpy as np
from pydantic import AfterValidator, Field

from formation_ftc.config.base import ExprText, StrictModel
from formation_ftc.sim.contract import CompositionError

__all__ = [
    "Vec3",
    "Vec3Expr",
    "Quat",
    "UnitQuaternions",
    "positive_values",
    "Masses",
    "Inertia",
    "per_axis",
    "per_spacecraft",
    "section_floats",
    "expression_text",
    "check_unit_quaternions",
    "quaternion_rows",
    "onboard_mean_motion",
    "nominal_masses",
    "check_rows",
    "initial_states",
    "grid_steps",
    "STATE_DIM",
    "ErrorState",
]

#: three numbers, one per LVLH or body axis
Vec3 = tuple[float, float, float]
#: three expressions in t [s] and the 1-based spacecraft number i, one per axis
Vec3Expr = tuple[ExprText, ExprText, ExprText]
#: a unit quaternion, vector part first
Quat = tuple[float, float, float, float]


def positive_values(what: str = "value", unit: str = "", zero: bool = False) -> AfterValidator:
    """A field check: every number of the value (one, a list or a tuple of them; None passes) is finite
    and > 0 (``zero``: >= 0), else ``every <what> must be finite and > 0<unit>`` (the section error
    names the field).

    Parameters
    ----------
    what : str
        What one number is, for the error.
    unit : str
        Its unit, for the error (with a leading space).
    zero : bool
        Accept 0 as well.

    Returns
    -------
    pydantic.AfterValidator
        For ``Annotated[<type>, positive_values(...)]``.

    Examples
    --------
    >>> from typing import Annotated
    >>> from pydantic import TypeAdapter
    >>> masses = TypeAdapter(Annotated[float | list[float], positive_values("mass", " kg")])
    >>> masses.validate_python([100.0, 120.0])
    [100.0, 120.0]
    >>> masses.validate_python([100.0, 0.0])
    Traceback (most recent call last):
    ...
    pydantic_core._pydantic_core.ValidationError: 1 validation error for ...
    """

    bound = ">= 0" if zero else "> 0"

    def check(value: Any) -> Any:
        if value is None:
            return value
        listed = isinstance(value, list | tuple)
        bad = [
            f"[{i}] = {v!r}" if listed else repr(v)
            for i, v in enumerate(value if listed else [value])
            if not (math.isfinite(v) and (v > 0 or zero and v == 0))
        ]
        if bad:
            raise ValueError(
                f"every {what} must be finite and {bound}{unit} (got {', '.join(bad)})"
            )
        return value

    return AfterValidator(check)


#: stated (on-board) masses [kg]: one for every spacecraft or one per spacecraft, each finite and > 0
Masses = Annotated[float | list[float], positive_values("mass", " kg")]
#: principal inertias [kg m^2], each finite and > 0
Inertia = Annotated[Vec3, positive_values("principal inertia", " kg m^2")]


def section_floats(section: Any, *names: str) -> dict[str, Any]:
    """The fields ``names`` of ``section`` as float64 arrays, keyed by name: the keyword arguments of a
    component whose leaves of those names are the section's numbers unchanged.

    Parameters
    ----------
    section : pydantic.BaseModel
        The validated section.
    *names : str
        Its numeric fields.

    Returns
    -------
    dict of str to numpy.ndarray
        ``{name: float64 array of section.name}``.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> section_floats(SimpleNamespace(kp=2, kd=[1, 3]), "kp", "kd")
    {'kp': array(2.), 'kd': array([1., 3.])}
    """
    return {name: np.asarray(getattr(section, name), dtype=np.float64) for name in names}


def per_spacecraft(value: Any, n: int, field: str) -> np.ndarray:
    """One number or ``n`` numbers -> (n,) float64 (errors name ``field``).

    Parameters
    ----------
    value : float or sequence of float
        One value for every spacecraft, or one per spacecraft.
    n : int
        Number of spacecraft.
    field : str
        The field's dotted name, for the error.

    Returns
    -------
    numpy.ndarray
        Shape (n,).

    Examples
    --------
    >>> per_spacecraft(2.0, 3, "controller.kp")
    array([2., 2., 2.])
    """
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        return np.full(n, float(arr))
    if arr.shape != (n,):
        raise ValueError(f"{field}: {arr.size} values for {n} spacecraft (give one number or {n})")
    return arr


def per_axis(value: Any, n: int, field: str) -> np.ndarray:
    """A number, 3 values (per axis, every spacecraft) or N x 3 values -> (N, 3) float64 (errors name
    ``field``).

    Parameters
    ----------
    value : float or array_like
        A number, 3 values or N x 3 values.
    n : int
        Number of spacecraft N.
    field : str
        The field's dotted name, for the error.

    Returns
    -------
    numpy.ndarray
        Shape (N, 3), float64.

    Examples
    --------
    >>> per_axis([1.0, 2.0, 3.0], 2, "plant.disturbance").tolist()
    [[1.0, 2.0, 3.0], [1.0, 2.0, 3.0]]
    """
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        return np.full((n, 3), float(arr))
    if arr.shape == (3,):
        return np.broadcast_to(arr, (n, 3)).copy()
    if arr.shape != (n, 3):
        raise ValueError(f"{field}: shape {arr.shape}, expected a number, 3 values or {n} x 3")
    return arr


def expression_text(v: Vec3Expr) -> tuple[str, str, str]:
    """Three expressions of a section as the plain strings a component keeps (static fields).

    Parameters
    ----------
    v : Vec3Expr
        Three expressions in t [s] and i.

    Returns
    -------
    tuple of str
        The expressions' text.

    Examples
    --------
    >>> expression_text(("0", "0.1*t", "i"))
    ('0', '0.1*t', 'i')
    """
    a, b, c = v
    return str(a), str(b), str(c)


def check_unit_quaternions(value: Quat | list[Quat] | None) -> Quat | list[Quat] | None:
    """``value`` (one quaternion, a list of them, or None) if every quaternion has unit norm
    (to 1e-6); a ValueError naming the first that has not (a section validator's check).

    Parameters
    ----------
    value : Quat or list of Quat or None
        Quaternions [q1, q2, q3, q4], vector first [-].

    Returns
    -------
    Quat or list of Quat or None
        ``value`` unchanged.

    Examples
    --------
    >>> check_unit_quaternions([(0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.6, 0.8)])
    [(0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.6, 0.8)]
    >>> check_unit_quaternions((0.0, 0.0, 0.0, 2.0))
    Traceback (most recent call last):
    ...
    ValueError: quaternion 0: norm 2, a unit quaternion [q1, q2, q3, q4] is needed
    """
    if value is None:
        return value
    rows = [value] if isinstance(value, tuple) else value
    for k, p in enumerate(rows):
        norm = float(np.linalg.norm(p))
        if not abs(norm - 1.0) <= 1e-6:
            raise ValueError(
                f"quaternion {k}: norm {norm:.9g}, a unit quaternion [q1, q2, q3, q4] is needed"
            )
    return value


#: one unit quaternion (vector first), one per spacecraft, or None
UnitQuaternions = Annotated[Quat | list[Quat] | None, AfterValidator(check_unit_quaternions)]


def quaternion_rows(rows: Quat | list[Quat] | None, n: int, field: str) -> np.ndarray:
    """One quaternion for every spacecraft, or ``n`` of them, -> (n, 4) float64 (None: the
    identity, vector first); errors name ``field``.

    Parameters
    ----------
    rows : Quat or list of Quat or None
        Quaternions [q1, q2, q3, q4] [-].
    n : int
        Number of spacecraft.
    field : str
        The field's dotted name, for the error.

    Returns
    -------
    numpy.ndarray
        Shape (n, 4).

    Examples
    --------
    >>> quaternion_rows(None, 2, "controller.desired_quaternion").tolist()
    [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0]]
    """
    if rows is None:
        return np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    arr = np.asarray(rows, dtype=float)
    arr = np.tile(arr, (n, 1)) if arr.ndim == 1 else arr
    if arr.shape != (n, 4):
        raise ValueError(
            f"{field}: {arr.shape[0]} quaternions for {n} spacecraft (give one or {n})"
        )
    return arr


def onboard_mean_motion(given: float | None, reference: Any) -> float | None:
    """The mean motion of an on-board circular-orbit (CW) model [rad/s]: ``given``, else
    sqrt(mu / a^3) of the ``[reference]`` section ``reference`` (an orbit known on board); None
    without either (never the plant's orbit: that is truth).

    Parameters
    ----------
    given : float or None
        The section's stated mean motion [rad/s].
    reference : pydantic model or None
        The scenario's ``[reference]`` section (its ``semi_major_axis`` [m] and ``mu`` [m^3/s^2]).

    Returns
    -------
    float or None
        The mean motion [rad/s].

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> round(onboard_mean_motion(None, SimpleNamespace(semi_major_axis=7000e3, mu=3.986004418e14)), 9)
    0.001078008
    >>> onboard_mean_motion(None, None) is None
    True
    """
    if given is not None:
        return float(given)
    if reference is not None and hasattr(reference, "semi_major_axis"):
        return math.sqrt(reference.mu / reference.semi_major_axis**3)
    return None


def nominal_masses(value: Any, default: float, n: int, field: str) -> np.ndarray:
    """Stated on-board masses [kg] (one or ``n``; None: ``default`` each) -> (n,), each finite and
    > 0 (errors name ``field``).

    Parameters
    ----------
    value : float, sequence of float or None
        The stated masses [kg].
    default : float
        The documented nominal mass when none is stated [kg].
    n : int
        Number of spacecraft.
    field : str
        The field's dotted name, for the error.

    Returns
    -------
    numpy.ndarray
        Shape (n,) [kg].

    Examples
    --------
    >>> nominal_masses(None, 100.0, 2, "controller.nominal_mass").tolist()
    [100.0, 100.0]
    """
    arr = per_spacecraft(default if value is None else value, n, field)
    if not np.all(np.isfinite(arr) & (arr > 0)):
        raise ValueError(f"{field}: every mass must be finite and > 0 kg")
    return arr


def check_nominal_masses(
    mass: np.ndarray, n: int | None, wrapper: str, part: str, need: str
) -> None:
    """A CompositionError unless ``mass`` holds one finite mass > 0 [kg] per spacecraft of ``part``
    (the check of a wrapper that converts between a force and an acceleration with the nominal masses).

    Parameters
    ----------
    mass : numpy.ndarray
        The nominal masses [kg].
    n : int or None
        Number of spacecraft of the wrapped part (None: any one-dimensional array).
    wrapper, part, need : str
        The wrapper's class name, the wrapped part (``"controller Name"``) and what is needed, for the
        error.

    Examples
    --------
    >>> check_nominal_masses(np.array([100.0, 120.0]), 2, "W", "controller C", "need 2, each > 0")
    >>> check_nominal_masses(np.array([100.0]), 2, "W", "controller C", "need 2, each > 0")
    Traceback (most recent call last):
    ...
    formation_ftc.sim.components.CompositionError: W: nominal masses [100.0] kg for controller C of 2 spacecraft (need 2, each > 0)
    """
    shape_ok = mass.ndim == 1 and (n is None or mass.shape == (n,))
    if not shape_ok or not np.all(np.isfinite(mass) & (mass > 0)):
        raise CompositionError(
            f"{wrapper}: nominal masses {mass.tolist()} kg for {part} of {n} spacecraft ({need})"
        )


def check_rows(section: Any, names: Sequence[str], n: int) -> None:
    """A ValueError naming the first of the fields ``names`` of ``section`` that is given (not None)
    without one row per spacecraft (a section validator's check).

    Parameters
    ----------
    section : pydantic.BaseModel
        The section.
    names : sequence of str
        Its per-spacecraft fields.
    n : int
        Number of spacecraft.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> check_rows(SimpleNamespace(initial_velocity=None), ["initial_velocity"], 2)
    >>> check_rows(SimpleNamespace(initial_position=[(0.0, 0.0, 0.0)]), ["initial_position"], 2)
    Traceback (most recent call last):
    ...
    ValueError: initial_position: 1 rows for 2 spacecraft
    """
    for name in names:
        rows = getattr(section, name)
        if rows is not None and len(rows) != n:
            raise ValueError(f"{name}: {len(rows)} rows for {n} spacecraft")


def grid_steps(time: float, dt: float, field: str) -> int:
    """The step count of ``time`` [s], a multiple of the step ``dt`` [s] (to 1e-9 relative); a
    ValueError naming ``field`` otherwise.

    Parameters
    ----------
    time : float
        A time on the step grid [s].
    dt : float
        The step [s].
    field : str
        The field's dotted name, for the error.

    Returns
    -------
    int
        ``time / dt``.

    Examples
    --------
    >>> grid_steps(10.0, 0.5, "supervisor.modes[1].start")
    20
    >>> grid_steps(10.2, 0.5, "supervisor.modes[1].start")
    Traceback (most recent call last):
    ...
    ValueError: supervisor.modes[1].start = 10.2 s is not a multiple of simulation.dt = 0.5 s
    """
    k = time / dt
    if abs(k - round(k)) > 1e-9 * max(1.0, k):
        raise ValueError(f"{field} = {time} s is not a multiple of simulation.dt = {dt} s")
    return round(k)


def initial_states(position: Any, velocity: Any) -> np.ndarray:
    """Initial states ``[r, v]`` (N, 6) from one position row per spacecraft and as many velocity rows
    (None: at rest).

    Parameters
    ----------
    position : array_like, shape (N, 3)
        Initial positions [m].
    velocity : array_like, shape (N, 3), or None
        Initial velocities [m/s].

    Returns
    -------
    numpy.ndarray
        Shape (N, 6), float64 [m, m/s].

    Examples
    --------
    >>> initial_states([(1.0, 2.0, 3.0)], None).tolist()
    [[1.0, 2.0, 3.0, 0.0, 0.0, 0.0]]
    """
    r = np.asarray(position, dtype=float)
    v = np.zeros_like(r) if velocity is None else np.asarray(velocity, dtype=float)
    return np.hstack([r, v])


#: length of Yang2013's error state x_i = [e_R, e_V, e_w, e_q, e_q4] (7) of one spacecraft
STATE_DIM = 13


class ErrorState(StrictModel):
    """Error state x_i of one spacecraft (7): desired minus actual, in the body frame F_i."""

    spacecraft: int = Field(ge=1, description="Spacecraft number (1 = main spacecraft) [-].")
    e_R: Vec3 = Field((0.0, 0.0, 0.0), description="Relative position error e_R [m].")
    e_V: Vec3 = Field((0.0, 0.0, 0.0), description="Relative velocity error e_V [m/s].")
    e_omega: Vec3 = Field((0.0, 0.0, 0.0), description="Angular velocity error e_omega [rad/s].")
    e_q: Vec3 = Field((0.0, 0.0, 0.0), description="Quaternion vector error e_q [-].")
    e_q4: float = Field(0.0, description="Quaternion scalar error e_q4 [-] (E001-03: start at 0).")

    def vector(self) -> np.ndarray:
        """The 13-vector x_i."""
        return np.array([*self.e_R, *self.e_V, *self.e_omega, *self.e_q, self.e_q4], dtype=float)
