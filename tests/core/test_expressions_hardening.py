"""Expression validation is total: bounded tree size and depth (own messages, no RecursionError),
float64 literals, and constant sub-expressions folded with float64 errors raised -- without changing
the value of any valid expression."""

from __future__ import annotations

import numpy as np
import pytest

from formation_ftc.core import expressions as ex
from formation_ftc.core.expressions import ExpressionError, compile_expression


@pytest.mark.parametrize(
    "text,fragment",
    [
        ("+".join(["1"] * 999), "nested too deeply (more than 200 levels"),
        ("-" * 999 + "t", "nested too deeply"),
        ("not " * 300 + "t", "nested too deeply"),
        ("(" * 250 + "t" + ")" * 250, "too many nested parentheses"),
        ("1" + "0" * 400, "outside the float64 range"),
        ("1e400", "outside the float64 range"),
        ("1/0", "division by a constant zero"),
        ("t/(2-2)", "division by a constant zero"),
        ("1%0", "modulo by a constant zero"),
        ("9**9**9**9", "overflow in power"),
        ("10**400", "overflow in power"),
        ("t + exp(1000)", "not a finite float64 (overflow in exp)"),
        ("where(t > 0, 1, log(0))", "divide by zero in log"),
        ("sqrt(-1) * t", "invalid value in sqrt"),
        ("acos(2)", "invalid value in arccos"),
        ("t\x00", "NUL character"),
    ],
)
def test_rejected_at_validation(text, fragment):
    with pytest.raises(ExpressionError) as info:
        compile_expression(text, field="faults.bias[0]")
    msg = str(info.value)
    assert fragment in msg and msg.startswith("faults.bias[0]: ")
    assert len(msg) < 600  # a 2,000-character expression is abbreviated in the message


def test_non_finite_numbers_are_not_expressions():
    for v in (float("inf"), float("nan"), 10**400):
        with pytest.raises(ExpressionError, match="must be finite"):
            compile_expression(v)


def test_node_limit_has_its_own_message(monkeypatch):
    monkeypatch.setattr(ex, "MAX_LENGTH", 100_000)
    text = "max(" + ",".join(["t"] * 6000) + ")"  # shallow but 6,001 names
    with pytest.raises(ExpressionError, match="more than 5000 syntax nodes"):
        compile_expression(text)


@pytest.mark.parametrize(
    "text,ref",
    [
        ("2*pi*t + 1/3", lambda t: 2 * np.pi * t + 1 / 3),
        ("t*0 + 10**300", lambda t: t * 0 + 1e300),
        ("where(t >= 1, exp(-(t-1)), 1/(1+1))", lambda t: np.where(t >= 1, np.exp(-(t - 1)), 0.5)),
        (
            "1/(t - 5)",
            lambda t: 1 / (t - 5),
        ),  # a singularity in t is the run's business, not a constant's
        ("(1 if 2 > 1 else 0) * t % 3", lambda t: (1.0 * t) % 3),
        ("max(t, 0, 2**0.5) + min(1, 2)", lambda t: max(t, 0, 2**0.5) + 1),
    ],
)
def test_valid_expressions_keep_their_values(text, ref):
    f = compile_expression(text)
    for t in (0.0, 0.5, 2.0, 7.25):
        with np.errstate(all="ignore"):
            assert float(f(t=t, i=1.0)) == pytest.approx(float(ref(t)), rel=1e-14)
