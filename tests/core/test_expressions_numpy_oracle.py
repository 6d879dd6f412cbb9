"""Every whitelisted function and operator of the expression language against numpy on random inputs.

Truth: numpy (written here independently of ``core.expressions``' tables), evaluated on 300 random
points per function in its domain. Both code paths are covered: the compiled JAX closures (variables
x, y, z, w) and the numpy constant folder (all arguments literal numbers). A swapped table entry (e.g.
``min`` implemented as ``max``) fails here.
"""

import re

import numpy as np
import pytest

from formation_ftc.core import expressions as ex
from formation_ftc.core.expressions import FUNCTIONS, compile_expression

RNG = np.random.default_rng(20260101)
N = 300


def _u(lo, hi):
    return lambda: RNG.uniform(lo, hi, N)


def _piecewise_oracle(c1, v1, c2, v2, d):
    return np.select([c1 != 0, c2 != 0], [v1, v2], default=d)


#: name -> (text with x, y, z, w, u as arguments, numpy oracle, samplers for the arguments)
ORACLES = {
    "sin": ("sin(x)", np.sin, [_u(-10, 10)]),
    "cos": ("cos(x)", np.cos, [_u(-10, 10)]),
    "tan": ("tan(x)", np.tan, [_u(-1.4, 1.4)]),
    "asin": ("asin(x)", np.arcsin, [_u(-1, 1)]),
    "acos": ("acos(x)", np.arccos, [_u(-1, 1)]),
    "atan": ("atan(x)", np.arctan, [_u(-20, 20)]),
    "atan2": ("atan2(x, y)", np.arctan2, [_u(-5, 5), _u(-5, 5)]),
    "sinh": ("sinh(x)", np.sinh, [_u(-5, 5)]),
    "cosh": ("cosh(x)", np.cosh, [_u(-5, 5)]),
    "tanh": ("tanh(x)", np.tanh, [_u(-5, 5)]),
    "exp": ("exp(x)", np.exp, [_u(-20, 20)]),
    "log": ("log(x)", np.log, [_u(1e-3, 1e3)]),
    "log10": ("log10(x)", np.log10, [_u(1e-3, 1e3)]),
    "sqrt": ("sqrt(x)", np.sqrt, [_u(0, 100)]),
    "abs": ("abs(x)", np.abs, [_u(-10, 10)]),
    "sign": ("sign(x)", np.sign, [_u(-10, 10)]),
    "floor": ("floor(x)", np.floor, [_u(-10, 10)]),
    "ceil": ("ceil(x)", np.ceil, [_u(-10, 10)]),
    "min": ("min(x, y, z)", lambda a, b, c: np.min(np.stack([a, b, c]), axis=0), [_u(-5, 5)] * 3),
    "max": ("max(x, y, z)", lambda a, b, c: np.max(np.stack([a, b, c]), axis=0), [_u(-5, 5)] * 3),
    "clip": (
        "clip(x, y, z)",
        lambda a, lo, hi: np.minimum(np.maximum(a, lo), hi),
        [_u(-5, 5), _u(-3, -1), _u(1, 3)],
    ),
    "where": ("where(x > y, z, w)", lambda a, b, c, d: np.where(a > b, c, d), [_u(-1, 1)] * 4),
    "step": ("step(x)", lambda a: (a >= 0).astype(float), [_u(-1, 1)]),
    "window": (
        "window(x, y, z)",
        lambda a, lo, hi: ((a >= lo) & (a <= hi)).astype(float),
        [_u(-2, 2), _u(-1, 0), _u(0, 1)],
    ),
    "piecewise": (
        "piecewise(x > 0.5, y, x < -0.5, z, w)",
        lambda a, b, c, d: _piecewise_oracle(a > 0.5, b, a < -0.5, c, d),
        [_u(-1, 1)] * 4,
    ),
}
VARS = ("x", "y", "z", "w")


def _substitute(text, values):
    """Replace the variable names (whole words only) by parenthesised literals."""
    return re.sub(
        r"\b([xyzw])\b",
        lambda m: f"({float(values[m.group(1)])!r})" if m.group(1) in values else m.group(1),
        text,
    )


def test_every_whitelisted_function_has_an_oracle():
    assert set(ORACLES) == set(FUNCTIONS)


@pytest.mark.parametrize("name", sorted(ORACLES))
def test_function_matches_numpy(name):
    text, oracle, samplers = ORACLES[name]
    args = [s() for s in samplers]
    f = compile_expression(text, VARS)
    env = dict(zip(VARS, args + [np.zeros(N)] * (4 - len(args)), strict=True))
    got = np.asarray(f(**env))
    np.testing.assert_allclose(got, oracle(*args), rtol=1e-13, atol=1e-15)


@pytest.mark.parametrize("name", sorted(ORACLES))
def test_constant_folder_matches_numpy(name):
    """All-literal calls go through the numpy folder at validation; its table must agree too."""
    text, oracle, samplers = ORACLES[name]
    for k in range(20):
        vals = [float(s()[k]) for s in samplers]
        lit = _substitute(text, dict(zip(VARS, vals, strict=False)))
        assert float(compile_expression(lit, ())()) == pytest.approx(
            float(oracle(*[np.float64(v) for v in vals])), rel=1e-13, abs=1e-15
        )
        folded = (
            ex._NP_FUNCTIONS[name](*[np.float64(v) for v in vals])
            if name not in ("where", "piecewise")
            else None
        )
        if folded is not None:
            assert float(folded) == pytest.approx(
                float(oracle(*[np.float64(v) for v in vals])), rel=1e-13, abs=1e-15
            )


BINARY = {
    "x + y": np.add,
    "x - y": np.subtract,
    "x * y": np.multiply,
    "x / y": np.divide,
    "x ** y": np.power,
    "x % y": np.mod,
    "x < y": np.less,
    "x <= y": np.less_equal,
    "x > y": np.greater,
    "x >= y": np.greater_equal,
    "x == y": np.equal,
    "x != y": np.not_equal,
    "(x > 0) and (y > 0)": lambda a, b: (a > 0) & (b > 0),
    "(x > 0) or (y > 0)": lambda a, b: (a > 0) | (b > 0),
    "not (x > y)": lambda a, b: ~(a > b),
    "-x + y": lambda a, b: -a + b,
    "+x - y": lambda a, b: a - b,
    "x if x > y else y": np.maximum,
    "x < y <= 0.5": lambda a, b: (a < b) & (b <= 0.5),
}


@pytest.mark.parametrize("text", sorted(BINARY))
def test_operator_matches_numpy(text):
    a = RNG.uniform(0.1, 3.0, N) * RNG.choice([-1.0, 1.0], N)
    b = RNG.uniform(0.1, 3.0, N) * RNG.choice([-1.0, 1.0], N)
    if "**" in text:
        a = np.abs(a)
    if "==" in text or "!=" in text:
        b = np.where(RNG.random(N) < 0.3, a, b)  # some exact equalities
    f = compile_expression(text, ("x", "y"))
    np.testing.assert_allclose(
        np.asarray(f(x=a, y=b), dtype=float),
        np.asarray(BINARY[text](a, b), dtype=float),
        rtol=1e-13,
        atol=1e-15,
    )
    for k in range(10):  # constant folder
        lit = _substitute(text, {"x": a[k], "y": b[k]})
        assert float(compile_expression(lit, ())()) == pytest.approx(
            float(BINARY[text](a[k], b[k])), rel=1e-13
        )
