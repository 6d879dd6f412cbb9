"""Field types and conversions the component sections share (TOML side, numpy only)."""

from __future__ import annotations

from typing import Any

import numpy as np

from formation_ftc.config.base import ExprText

__all__ = ["Vec3", "Vec3Expr", "Quat", "per_axis"]

#: three numbers, one per LVLH or body axis
Vec3 = tuple[float, float, float]
#: three expressions in t [s] and the 1-based spacecraft number i, one per axis
Vec3Expr = tuple[ExprText, ExprText, ExprText]
#: a unit quaternion, vector part first
Quat = tuple[float, float, float, float]


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
