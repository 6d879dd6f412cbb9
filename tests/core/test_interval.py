"""Verified enclosures of the expression language (formation_ftc.core.interval).

Truth: the compiled JAX expression (what a simulation evaluates) and numpy, at 10,000 random points of
random sub-intervals per function / operator; closed-form ranges; finite differences for derivatives.
An enclosure must contain every finite value; NaN values (outside a function's domain) are skipped.
"""

import math

import jax
import numpy as np
import pytest

from formation_ftc.core import interval as iv
from formation_ftc.core.expressions import FUNCTIONS, ExpressionError, compile_expression

#: name -> (expression in t, t range). Every whitelisted function and operator appears.
CASES = {
    "sin": ("sin(3*t - 1)", (-10, 10)),
    "cos": ("cos(2*t + 0.5)", (-10, 10)),
    "tan": ("tan(t)", (-4, 4)),
    "asin": ("asin(t/10)", (-10, 10)),
    "acos": ("acos(0.1*t)", (-10, 10)),
    "atan": ("atan(t**3 - t)", (-3, 3)),
    "atan2": ("atan2(sin(t), cos(2*t) - 0.3)", (-10, 10)),
    "sinh": ("sinh(t/2)", (-10, 10)),
    "cosh": ("cosh(t - 1)", (-6, 6)),
    "tanh": ("tanh(2*t)", (-3, 3)),
    "exp": ("exp(-t**2) + exp(t/4)", (-10, 10)),
    "log": ("log(t**2 + 0.5)", (-10, 10)),
    "log10": ("log10(abs(t) + 1e-3)", (-10, 10)),
    "sqrt": ("sqrt(abs(t))", (-10, 10)),
    "abs": ("abs(sin(t))*t", (-10, 10)),
    "sign": ("sign(t - 1.5)", (-10, 10)),
    "floor": ("floor(1.7*t)", (-10, 10)),
    "ceil": ("ceil(t/3)", (-10, 10)),
    "min": ("min(t, 2 - t, sin(t))", (-10, 10)),
    "max": ("max(t**2, 4 - t, cos(t))", (-10, 10)),
    "clip": ("clip(t, -1, 2 + sin(t))", (-10, 10)),
    "where": ("where(sin(t) > 0, t, -t**2)", (-10, 10)),
    "step": ("step(t - 2)", (-10, 10)),
    "window": ("window(t, -1, 3)*t", (-10, 10)),
    "piecewise": ("piecewise(t < -2, 1, t < 2, t**2, 5 - t)", (-10, 10)),
    "op +": ("t + 1/3", (-10, 10)),
    "op -": ("2 - t", (-10, 10)),
    "op unary": ("-t + (+t)*0.5", (-10, 10)),
    "op *": ("t*t*sin(t)", (-10, 10)),
    "op /": ("1/(t - 0.3) + t/7", (-10, 10)),
    "op **": ("abs(t)**1.5 + t**3 + (t**2 + 1)**(-2) + 2**t + (t + 11)**(0.1*t)", (-10, 10)),
    "op %": ("t % 2.5 + (t*t) % 1.5 + t % (-2)", (-10, 10)),
    "op compare": (
        "(t < 1)*1 + (t <= 2)*2 + (t > 0)*3 + (t >= -1)*4 + (t == 0.5)*5 + (t != 0.5)*6",
        (-10, 10),
    ),
    "op chain": ("(0 <= t < 3)*t", (-10, 10)),
    "op bool add": (
        "(t > 0) + (t > 1) + 2*(step(t) + window(t, -1, 3) + window(t, 0, 5))",
        (-10, 10),
    ),
    "op and/or/not": ("(t > 1 and t < 4) + 2*(t < -5 or t > 8) + 4*(not t > 0)", (-10, 10)),
    "op ifexp": ("t**2 if t > 1 else -t", (-10, 10)),
    "constants": ("pi*e*t", (-10, 10)),
}
N_BOX, N_PTS = 500, 20  # 10,000 points per case


def test_every_whitelisted_function_has_a_case():
    assert set(FUNCTIONS) <= set(CASES)


@pytest.mark.parametrize("name", sorted(CASES))
def test_enclosure_contains_the_values(name):
    text, (t0, t1) = CASES[name]
    rng = np.random.default_rng(20260115 + sorted(CASES).index(name))
    a = rng.uniform(t0, t1, N_BOX)
    w = rng.choice([1e-6, 1e-3, 0.1, 1.0, 5.0], N_BOX)
    b = np.minimum(a + w, t1)
    lo, hi = iv.evaluate(text, ("t",), a, b)
    u = rng.uniform(0, 1, (N_BOX, N_PTS))
    t = a[:, None] + u * (b - a)[:, None]
    t[:, 0], t[:, 1] = a, b  # the ends too
    f = compile_expression(text, ("t",))
    with np.errstate(all="ignore"):
        got = np.asarray(f(t=t))
    finite = np.isfinite(got)
    assert finite.mean() > 0.5, name
    inside = (got >= lo[:, None]) & (got <= hi[:, None])
    bad = finite & ~inside
    assert not bad.any(), (
        name,
        t[bad][:5],
        got[bad][:5],
        np.broadcast_to(lo[:, None], t.shape)[bad][:5],
        np.broadcast_to(hi[:, None], t.shape)[bad][:5],
    )


@pytest.mark.parametrize("name", sorted(CASES))
def test_derivative_enclosure_contains_the_autodiff_derivative(name):
    text, (t0, t1) = CASES[name]
    rng = np.random.default_rng(7 + sorted(CASES).index(name))
    a = rng.uniform(t0, t1, 200)
    b = np.minimum(a + rng.choice([1e-3, 0.1, 1.0], 200), t1)
    lo, hi = iv.evaluate(text, ("t",), a, b, derivative=True)
    t = a[:, None] + rng.uniform(0, 1, (200, 10)) * (b - a)[:, None]
    f = compile_expression(text, ("t",))
    try:
        d = np.asarray(jax.vmap(jax.grad(lambda s: f(t=s)))(t.ravel())).reshape(t.shape)
    except TypeError:  # boolean-valued expressions: no JAX derivative
        pytest.skip("boolean result")
    finite = np.isfinite(d)
    bad = finite & ~((d >= lo[:, None]) & (d <= hi[:, None]))
    assert not bad.any(), (name, t[bad][:5], d[bad][:5])


def test_known_ranges():
    lo, hi = iv.enclose("sin(t)", ("t",), 0.0, math.pi, n_sub=64)
    assert -1e-15 <= lo <= 0.0 and hi == 1.0
    lo, hi = iv.enclose("cos(t)", ("t",), 0.0, 2 * math.pi, n_sub=3)
    assert lo == -1.0 and hi == 1.0
    lo, hi = iv.enclose("exp(t)", ("t",), 0.0, 1.0, n_sub=1)  # monotone: the ends, a few ulps out
    assert lo <= 1.0 <= lo + 1e-14 and hi >= math.e and hi <= math.e * (1 + 1e-14)
    assert iv.enclose("1/(t - 1)", ("t",), 0.0, 2.0) == (-math.inf, math.inf)
    lo, hi = iv.enclose("t**2", ("t",), -1.0, 2.0, n_sub=1)
    assert lo == 0.0 and 4.0 <= hi <= 4.0 * (1 + 1e-14)
    lo, hi = iv.enclose("sqrt(t - 1)", ("t",), 0.0, 2.0, n_sub=2)  # half outside the domain
    assert (lo, hi) == (-math.inf, math.inf)
    lo, hi = iv.enclose("step(t - 1)", ("t",), 0.0, 0.5, n_sub=8)
    assert (lo, hi) == (0.0, 0.0)
    lo, hi = iv.enclose("(t > 0) + (t > 1)", ("t",), 2.0, 3.0, n_sub=1)  # a logical or in JAX
    assert (lo, hi) == (1.0, 1.0)


def test_a_fixed_variable_and_a_threshold():
    lo, hi = iv.enclose("i*sin(t)", ("t", "i"), 0.0, 10.0, i=3.0)
    assert -3.0 - 1e-12 <= lo <= -3.0 and 3.0 <= hi <= 3.0 + 1e-12
    with pytest.raises(TypeError, match="needs a value for 'i'"):
        iv.enclose("i*sin(t)", ("t", "i"), 0.0, 1.0)


def test_derivative_enclosure_against_closed_form():
    # d/dt [2 - exp(-0.2 t) cos(0.6 t)] = exp(-0.2 t) (0.2 cos(0.6 t) + 0.6 sin(0.6 t)), max ~0.44 (t ~ 1.55 s)
    t = np.linspace(0, 3000, 3_000_001)
    exact = np.exp(-0.2 * t) * (0.2 * np.cos(0.6 * t) + 0.6 * np.sin(0.6 * t))
    lo, hi = iv.enclose_derivative("2 - exp(-0.2*t)*cos(0.6*t)", ("t",), 0.0, 3000.0, upper=0.45)
    assert lo <= exact.min() and exact.max() <= hi < 0.45


def test_derivative_of_a_jump_is_unbounded():
    assert iv.enclose_derivative("step(t - 1)", ("t",), 0.0, 2.0) == (-math.inf, math.inf)
    assert iv.enclose_derivative("floor(t)", ("t",), 0.2, 0.8) == (0.0, 0.0)
    lo, hi = iv.enclose_derivative("abs(t)", ("t",), -1.0, 1.0)  # kink: both one-sided slopes
    assert lo <= -1.0 and hi >= 1.0


def test_width_shrinks_as_n_sub_grows():
    text = "exp(-0.1*t)*sin(t) + 0.3*cos(3*t)"
    t = np.linspace(0, 20, 2_000_001)
    f = np.exp(-0.1 * t) * np.sin(t) + 0.3 * np.cos(3 * t)
    widths = []
    for n in (16, 256, 4096):
        lo, hi = iv.enclose(text, ("t",), 0.0, 20.0, n_sub=n)
        assert lo <= f.min() and hi >= f.max()
        widths.append((hi - lo) - (f.max() - f.min()))
    assert widths[0] > widths[1] > widths[2] >= 0 and widths[2] < 1e-2


def test_refinement_proves_a_bound_the_coarse_grid_cannot():
    text = "sin(t) + sin(1.1*t)"  # max 1.99610 over [0, 50] (the peaks never coincide there)
    _, coarse = iv.enclose(text, ("t",), 0.0, 50.0, n_sub=8)
    assert coarse >= 1.999
    _, fine = iv.enclose(text, ("t",), 0.0, 50.0, n_sub=8, upper=1.999, max_rounds=20)
    t = np.linspace(0, 50, 1_000_001)
    assert np.max(np.sin(t) + np.sin(1.1 * t)) <= fine < 1.999
    _, capped = iv.enclose(
        text, ("t",), 0.0, 50.0, n_sub=8, upper=1.999, max_rounds=2
    )  # bounded work
    assert capped >= 1.999


def test_norm_bound_of_a_vector():
    texts = ["0.06/sqrt(3)*sin(t + i)", "0.06/sqrt(3)*cos(t + 2*i)", "0.06/sqrt(3)*sin(t + 3*i)"]
    t = np.linspace(0, 200, 400_001)
    norm = np.linalg.norm(
        [
            0.06 / np.sqrt(3) * np.sin(t + 1),
            0.06 / np.sqrt(3) * np.cos(t + 2),
            0.06 / np.sqrt(3) * np.sin(t + 3),
        ],
        axis=0,
    )
    b = iv.enclose_norm(texts, ("t", "i"), 0.0, 200.0, upper=0.06, i=1.0)
    assert norm.max() <= b < 0.06


def test_bad_input():
    with pytest.raises(ValueError):
        iv.enclose("t", ("t",), 1.0, 0.0)
    with pytest.raises(ExpressionError):
        iv.enclose("__import__('os')", ("t",), 0.0, 1.0)
    with pytest.raises(iv.IntervalError):
        iv.enclose("-(t > 1)", ("t",), 0.0, 2.0)
