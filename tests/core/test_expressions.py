"""Safe expression compiler: values against numpy, and rejection of everything off the whitelist."""

import jax
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from formation_ftc.core.expressions import ExpressionError, compile_expression


def ev(text, **kw):
    return np.asarray(compile_expression(text)(**{"t": 0.0, "i": 1.0, **kw}))


def test_li2020_effectiveness_expression():
    f = compile_expression("where(t >= 10, 1 - 0.1*(i+1)*exp(-(t-10)), 1)")
    t = np.array([0.0, 9.99, 10.0, 12.0])
    for i in (1, 4):
        ref = np.where(t >= 10, 1 - 0.1 * (i + 1) * np.exp(-(t - 10)), 1)
        np.testing.assert_allclose(f(t=t, i=i), ref, rtol=1e-15)


@given(st.floats(-50, 50), st.floats(-5, 5))
@settings(max_examples=60, deadline=None)
def test_matches_numpy(t, a):
    text = (
        f"{a!r}*sin(0.2*t) + sqrt(abs(t)) - t**2/(1 + cos(t)**2) + atan2(t, 3) + max(t, 0, {a!r})"
    )
    ref = (
        a * np.sin(0.2 * t)
        + np.sqrt(abs(t))
        - t**2 / (1 + np.cos(t) ** 2)
        + np.arctan2(t, 3)
        + max(t, 0, a)
    )
    np.testing.assert_allclose(ev(text, t=t), ref, rtol=1e-12, atol=1e-12)


def test_piecewise_step_window_ifexp_comparisons():
    f = "piecewise(t < 1, 10, t < 2, 20, 30)"
    assert [float(ev(f, t=x)) for x in (0.5, 1.5, 2.5)] == [10, 20, 30]
    assert float(ev("step(t - 3)", t=3.0)) == 1.0 and float(ev("step(t - 3)", t=2.9)) == 0.0
    assert float(ev("window(t, 40, 240)", t=240.0)) == 1.0
    assert float(ev("1 if 0 < t <= 2 and not t == 1 else -1", t=2.0)) == 1.0
    assert float(ev("1 if 0 < t <= 2 and not t == 1 else -1", t=1.0)) == -1.0
    assert float(ev("pi - e")) == pytest.approx(np.pi - np.e)


def test_differentiable_in_t():
    f = compile_expression("3 + 0.6*sin(0.2*t)")
    dfdt = jax.grad(lambda t: f(t=t, i=1.0))
    assert float(dfdt(2.0)) == pytest.approx(0.12 * np.cos(0.4), rel=1e-12)


def test_numbers_are_expressions():
    assert float(compile_expression(2.5)(t=0, i=0)) == 2.5


@pytest.mark.parametrize(
    "text,fragment",
    [
        ("__import__('os')", "unknown function '__import__'"),
        ("t.real", "attribute"),
        ("os.system('x')", "call of 'os.system'"),
        ("x + 1", "unknown name 'x'"),
        ("sin", "functions must be called"),
        ("[1, 2]", "list"),
        ("lambda: 1", "lambda"),
        ("'abc'", "not a number"),
        ("sin(1, 2)", "takes 1 argument"),
        ("piecewise(t<1, 2)", "piecewise"),
        ("t +", "syntax error"),
        ("t @ t", "MatMult"),
        ("sin(x=1)", "keyword"),
        ("t[0]", "subscript"),
    ],
)
def test_rejected(text, fragment):
    with pytest.raises(ExpressionError) as info:
        compile_expression(text, field="faults.bias")
    msg = str(info.value)
    assert fragment in msg and "faults.bias" in msg


def test_error_has_caret_column():
    with pytest.raises(ExpressionError) as info:
        compile_expression("1 + foo*t", field="f")
    assert info.value.col == 4


def test_vector_expression_per_spacecraft():
    from formation_ftc.core.expressions import compile_vector_expression

    f = compile_vector_expression(
        ["0.1*i*t", "1", "where(t >= 10, 1 - 0.05*(i+2), 1)"], field="faults.x"
    )
    idx = np.arange(1, 5, dtype=float)
    out = np.asarray(f(12.0, idx))
    assert out.shape == (4, 3)
    np.testing.assert_allclose(out[:, 0], 1.2 * idx)
    np.testing.assert_allclose(out[:, 1], 1.0)
    np.testing.assert_allclose(out[:, 2], 1 - 0.05 * (idx + 2))
    with pytest.raises(ExpressionError, match=r"faults.x\[1\]"):
        compile_vector_expression(["t", "bad_name"], field="faults.x")
