"""Verified enclosures of expression-language functions of ``t`` by interval arithmetic.

A scenario's time functions (delays, disturbances, ...) are texts of the safe expression language of
:mod:`formation_ftc.core.expressions`. A condition such as "the delay rate stays below 1 over the
horizon" sampled on a grid says nothing between the samples; this module *proves* such bounds:

* :func:`enclose` returns ``[lo, hi]`` that contains every value ``f(t)`` for ``t`` in
  ``[t_lo, t_hi]``; :func:`enclose_derivative` does the same for ``df/dt`` (forward mode with interval
  dual numbers); :func:`enclose_norm` bounds the Euclidean norm of a vector of expressions.
* ``[t_lo, t_hi]`` is split into ``n_sub`` sub-intervals that are evaluated at once (numpy arrays of
  lower and upper ends, no Python loop over sub-intervals). Given a threshold (``upper`` / ``lower``),
  the sub-intervals whose enclosure does not decide it are bisected, a bounded number of rounds.

Rules (every result is rounded outward, so the enclosure holds in floating point):

* ``+ - * /`` and ``sqrt`` are correctly rounded in IEEE arithmetic: their ends move one ulp outward
  (``np.nextafter``); the library functions (``sin``, ``exp``, ``**``, ...) move :data:`LIB_ULPS` ulps
  outward, which covers the documented accuracy of numpy's and XLA's float64 implementations;
* monotone functions by their values at the ends; ``sin``/``cos`` also take 1 / -1 when an extremum
  ``pi/2 + k pi`` lies in the argument interval; ``tan`` and a division by an interval containing 0
  give ``(-inf, inf)``; ``cosh`` its minimum 1 when 0 is inside; ``atan2`` by its four corners off the
  branch cut (``[-pi, pi]`` across it); ``a ** b`` by integer/real exponent cases;
* comparisons, ``and``/``or``/``not`` are three-valued (true, false, undecided); ``where``,
  ``a if c else b``, ``piecewise``, ``step`` and ``window`` take the union of the branches where the
  condition is undecided; ``floor``, ``ceil``, ``sign``, ``abs``, ``min``, ``max``, ``clip`` and ``%``
  by their monotonicity / periods;
* an argument outside a function's domain (``sqrt`` or ``log`` of an interval reaching below 0,
  ``asin`` beyond [-1, 1], ...) gives ``(-inf, inf)``: nothing is proved there.

Derivatives: the chain rule on (value, derivative) interval pairs. Where a piecewise-constant or
branching construct (``floor``, ``step``, ``where``, ``%``, ...) may switch inside a sub-interval the
function may jump, so the derivative enclosure there is ``(-inf, inf)``; at a kink (``abs``, ``min``,
``max``, ``clip``) it is the union of both one-sided derivatives.

A construct the module cannot enclose raises :class:`IntervalError`; callers then fall back to
sampling and say so (basis "sampled" of :class:`formation_ftc.registry.Condition`).
"""

from __future__ import annotations

import ast
import functools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache, reduce
from typing import Any, cast

import numpy as np

from formation_ftc.core.expressions import CONSTANTS, FUNCTIONS, _first_true, compile_expression

__all__ = [
    "IntervalError",
    "Boxes",
    "LIB_ULPS",
    "evaluate",
    "enclose",
    "enclose_derivative",
    "enclose_norm",
]

#: ulps by which a library function's (sin, exp, pow, ...) result is widened on each side [-]
LIB_ULPS = 8
_INF = math.inf
_EPS = float(np.finfo(float).eps)
_PI = math.pi
#: most sub-intervals the bisection of :func:`_boxes` may create [-]
_MAX_BOXES = 1 << 20


class IntervalError(ValueError):
    """An expression (or a construct in it) that the interval evaluator cannot enclose."""


# --------------------------------------------------------------------------------------------------
# interval arrays and outward rounding


@dataclass(frozen=True)
class _I:
    """Interval arrays: every value of the quantity on sub-interval k lies in [lo[k], hi[k]].

    ``boolean`` marks a truth value (0/1) as JAX and numpy type it: ``+`` of two booleans is a logical
    or there, ``-`` of a boolean an error.
    """

    lo: np.ndarray
    hi: np.ndarray
    boolean: bool = False


def _clean(lo, hi) -> _I:
    """NaN ends (inf - inf, 0 * inf, ...) become the whole line: nothing is known there."""
    return _I(np.where(np.isnan(lo), -_INF, lo), np.where(np.isnan(hi), _INF, hi))


def _down(x, ulps: int = 1):
    """At least ``ulps`` ulps below x (an overflowed +inf becomes the largest float)."""
    x = np.asarray(x, dtype=float)
    if ulps == 1:
        return np.nextafter(x, -_INF)
    step = np.abs(np.spacing(x))
    return np.where(np.isfinite(x), np.nextafter(x - ulps * step, -_INF), np.nextafter(x, -_INF))


def _up(x, ulps: int = 1):
    """At least ``ulps`` ulps above x (an overflowed -inf becomes the most negative float)."""
    return -_down(-np.asarray(x, dtype=float), ulps)  # IEEE rounding is symmetric


def _out(lo, hi, ulps: int = 1) -> _I:
    return _clean(_down(lo, ulps), _up(hi, ulps))


def _const(v: float, n: int) -> _I:
    a = np.full(n, float(v))
    return _I(a, a.copy())


def _hull(a: _I, b: _I) -> _I:
    return _I(np.minimum(a.lo, b.lo), np.maximum(a.hi, b.hi))


def _select(c: _I, a: _I, b: _I) -> _I:
    """where(c, a, b) with c three-valued (see :func:`_truth`)."""
    t, f = _truth(c)
    lo = np.where(t, a.lo, np.where(f, b.lo, np.minimum(a.lo, b.lo)))
    hi = np.where(t, a.hi, np.where(f, b.hi, np.maximum(a.hi, b.hi)))
    return _I(lo, hi, a.boolean and b.boolean)


def _truth(c: _I) -> tuple[np.ndarray, np.ndarray]:
    """(certainly true, certainly false) of a value used as a condition (nonzero is true)."""
    return (c.lo > 0) | (c.hi < 0), (c.lo == 0) & (c.hi == 0)


def _bool(true, false) -> _I:
    """Three-valued boolean as a 0/1 interval: [1, 1] true, [0, 0] false, [0, 1] undecided."""
    return _I(np.where(true, 1.0, 0.0), np.where(false, 0.0, 1.0), True)


# --------------------------------------------------------------------------------------------------
# arithmetic


def _add(a: _I, b: _I) -> _I:
    if a.boolean and b.boolean:  # bool + bool is a logical or in numpy and JAX
        return _I(np.maximum(a.lo, b.lo), np.maximum(a.hi, b.hi), True)
    return _out(a.lo + b.lo, a.hi + b.hi)


def _sub(a: _I, b: _I) -> _I:
    if a.boolean or b.boolean:
        raise IntervalError("subtraction of a truth value (JAX refuses it)")
    return _out(a.lo - b.hi, a.hi - b.lo)


def _neg(a: _I) -> _I:
    if a.boolean:
        raise IntervalError("negation of a truth value (JAX refuses it)")
    return _I(-a.hi, -a.lo)


def _corners(f: Callable, a: _I, b: _I) -> tuple[np.ndarray, np.ndarray]:
    c = np.stack([f(a.lo, b.lo), f(a.lo, b.hi), f(a.hi, b.lo), f(a.hi, b.hi)])
    return c.min(axis=0), c.max(axis=0)


def _mul(a: _I, b: _I) -> _I:
    def prod(x, y):
        p = x * y
        return np.where(np.isnan(p), 0.0, p)  # 0 * inf: the factors are finite reals, so 0

    lo, hi = _corners(prod, a, b)
    if a.boolean and b.boolean:  # a logical and: exact 0/1
        return _I(lo, hi, True)
    return _out(lo, hi)


def _sqr(a: _I) -> _I:
    m = _abs(a)
    return _out(m.lo * m.lo, m.hi * m.hi)


def _div(a: _I, b: _I) -> _I:
    zero = (b.lo <= 0) & (b.hi >= 0)
    return _in_domain(_out(*_corners(np.true_divide, a, b)), ~zero)


def _monotone(f: Callable, a: _I, increasing: bool = True, ulps: int = LIB_ULPS) -> _I:
    fl, fh = f(a.lo), f(a.hi)
    return _out(fl, fh, ulps) if increasing else _out(fh, fl, ulps)


def _in_domain(r: _I, ok) -> _I:
    return _I(np.where(ok, r.lo, -_INF), np.where(ok, r.hi, _INF))


def _contains_point(a: _I, offset: float, period: float) -> np.ndarray:
    """True where some offset + k period may lie in [lo, hi] (generous: rounding only adds points)."""
    big = np.maximum(np.maximum(np.abs(a.lo), np.abs(a.hi)), 1.0)
    slack = 64 * _EPS * big
    lo, hi = a.lo - slack, a.hi + slack
    k = np.ceil((lo - offset) / period)
    hit = np.zeros(lo.shape, dtype=bool)
    for dk in (-1.0, 0.0, 1.0):
        p = offset + (k + dk) * period
        hit |= (p >= lo) & (p <= hi)
    wide = ~np.isfinite(lo) | ~np.isfinite(hi) | (hi - lo >= period) | (big > 1e15)
    return hit | wide


def _sinusoid(f: Callable, a: _I, top: float, bottom: float) -> _I:
    """sin or cos: the values at the ends, and 1 / -1 where a maximum ``top`` / minimum ``bottom``
    (+ k 2 pi) may lie inside."""
    f_lo, f_hi = f(a.lo), f(a.hi)
    r = _out(np.minimum(f_lo, f_hi), np.maximum(f_lo, f_hi), LIB_ULPS)
    hi = np.where(_contains_point(a, top, 2 * _PI), 1.0, r.hi)
    lo = np.where(_contains_point(a, bottom, 2 * _PI), -1.0, r.lo)
    return _I(np.maximum(lo, -1.0), np.minimum(hi, 1.0))


def _sin(a: _I) -> _I:
    return _sinusoid(np.sin, a, _PI / 2, -_PI / 2)


def _cos(a: _I) -> _I:
    return _sinusoid(np.cos, a, 0.0, _PI)


def _tan(a: _I) -> _I:
    return _in_domain(_monotone(np.tan, a), ~_contains_point(a, _PI / 2, _PI))  # poles


def _clip_range(r: _I, lo: float, hi: float) -> _I:
    return _I(np.clip(r.lo, lo, hi), np.clip(r.hi, lo, hi))


def _arc(f: Callable, lo: float, hi: float, increasing: bool) -> Callable[[_I], _I]:
    """asin / acos: monotone on [-1, 1] with values in [lo, hi]; nothing known beyond [-1, 1]."""

    def g(a: _I) -> _I:
        r = _monotone(f, _clip_range(a, -1.0, 1.0), increasing)
        return _in_domain(_clip_range(r, lo, hi), (a.lo >= -1) & (a.hi <= 1))

    return g


_asin = _arc(np.arcsin, -_up(_PI / 2, 2), _up(_PI / 2, 2), increasing=True)
_acos = _arc(np.arccos, 0.0, _up(_PI, 2), increasing=False)


def _atan(a: _I) -> _I:
    return _clip_range(_monotone(np.arctan, a), -_up(_PI / 2, 2), _up(_PI / 2, 2))


def _atan2(y: _I, x: _I) -> _I:
    # atan2 is continuous off the cut {x <= 0, y = 0}; there it is monotone in each argument for a fixed
    # other one, so its extremes over a box lie at the corners
    off_cut = (x.lo > 0) | (y.lo > 0) | (y.hi < 0)
    r = _out(*_corners(np.arctan2, y, x), LIB_ULPS)
    bound = float(_up(_PI, 2))
    lo = np.where(off_cut, np.maximum(r.lo, -bound), -bound)
    hi = np.where(off_cut, np.minimum(r.hi, bound), bound)
    return _I(lo, hi)


def _cosh(a: _I) -> _I:
    r = _monotone(np.cosh, _abs(a))  # cosh is increasing in |a|
    return _I(np.maximum(r.lo, 1.0), r.hi)


def _log(f: Callable) -> Callable[[_I], _I]:
    def g(a: _I) -> _I:
        ok = a.lo >= 0
        return _in_domain(_monotone(f, _I(np.maximum(a.lo, 0.0), np.maximum(a.hi, 0.0))), ok)

    return g


def _sqrt(a: _I) -> _I:
    ok = a.lo >= 0
    lo, hi = np.sqrt(np.maximum(a.lo, 0.0)), np.sqrt(np.maximum(a.hi, 0.0))
    r = _out(lo, hi)
    return _in_domain(_I(np.maximum(r.lo, 0.0), r.hi), ok)


def _abs(a: _I) -> _I:
    straddle = (a.lo <= 0) & (a.hi >= 0)
    lo = np.where(straddle, 0.0, np.minimum(np.abs(a.lo), np.abs(a.hi)))
    return _I(lo, np.maximum(np.abs(a.lo), np.abs(a.hi)))


def _exact_monotone(f: Callable) -> Callable[[_I], _I]:
    """sign, floor, ceil: non-decreasing and exact in floating point."""
    return lambda a: _I(f(a.lo), f(a.hi))


def _is_integer(x) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    return np.isfinite(x) & (x == np.round(x)) & (np.abs(x) < 2.0**53)


def _pow(a: _I, b: _I) -> _I:
    fixed = b.lo == b.hi
    p = np.where(fixed, b.lo, 0.0)
    integer = fixed & _is_integer(p)
    even = integer & (np.remainder(p, 2.0) == 0)
    straddle = (a.lo <= 0) & (a.hi >= 0)
    m = _abs(a)
    amin, amax = m.lo, m.hi
    # integer exponent p (even or odd), defined unless a negative power of an interval with 0
    pos = p > 0
    lo_even = np.where(pos, amin**p, amax**p)
    hi_even = np.where(pos, amax**p, amin**p)
    lo_odd = np.where(pos, np.power(a.lo, p), np.power(a.hi, p))
    hi_odd = np.where(pos, np.power(a.hi, p), np.power(a.lo, p))
    ok_integer = pos | ~straddle
    zero = integer & (p == 0)
    # real exponent p (base must be >= 0)
    base_ok = a.lo >= 0
    lo_real = np.where(pos, np.power(np.maximum(a.lo, 0), p), np.power(np.maximum(a.hi, 0), p))
    hi_real = np.where(pos, np.power(np.maximum(a.hi, 0), p), np.power(np.maximum(a.lo, 0), p))
    # general exponent interval: base > 0, corners of exp(b log a)
    glo, ghi = _corners(np.power, a, b)
    general_ok = a.lo > 0
    lo = np.where(even, lo_even, np.where(integer, lo_odd, np.where(fixed, lo_real, glo)))
    hi = np.where(even, hi_even, np.where(integer, hi_odd, np.where(fixed, hi_real, ghi)))
    ok = np.where(integer, ok_integer, np.where(fixed, base_ok, general_ok))
    r = _out(lo, hi, LIB_ULPS)
    lo = np.where(zero, 1.0, np.where(ok, r.lo, -_INF))  # nothing known outside the domain
    hi = np.where(zero, 1.0, np.where(ok, r.hi, _INF))
    lo = np.where(even & ok, np.maximum(lo, 0.0), lo)
    return _clean(lo, hi)


def _mod(a: _I, b: _I) -> tuple[_I, np.ndarray]:
    """numpy's remainder (sign of the divisor); also returns where a wrap (jump) may occur."""
    fixed = b.lo == b.hi
    d = b.lo
    k_lo, k_hi = np.floor(a.lo / d), np.floor(a.hi / d)
    big = np.maximum(np.maximum(np.abs(a.lo), np.abs(a.hi)), np.abs(d))
    slack = 8 * _EPS * big
    r_lo, r_hi = a.lo - k_lo * d, a.hi - k_lo * d
    # one period, and the remainders clear of both ends by the rounding slack (d > 0 or d < 0)
    lo_end, hi_end = np.minimum(0.0, d), np.maximum(0.0, d)
    r_min, r_max = np.minimum(r_lo, r_hi), np.maximum(r_lo, r_hi)
    clear = (r_min > lo_end + slack) & (r_max < hi_end - slack)
    same = fixed & (d != 0) & (k_lo == k_hi) & np.isfinite(k_lo) & clear
    tight = _I(r_min - slack, r_max + slack)
    pos, neg = b.lo > 0, b.hi < 0
    lo = np.where(same, tight.lo, np.where(pos, 0.0, np.where(neg, b.lo, -_INF)))
    hi = np.where(same, tight.hi, np.where(pos, b.hi, np.where(neg, 0.0, _INF)))
    return _clean(lo, hi), ~same


def _cmp(op: type, a: _I, b: _I) -> _I:
    if op in (ast.Gt, ast.GtE):  # a > b is b < a
        return _cmp(ast.Lt if op is ast.Gt else ast.LtE, b, a)
    if op is ast.Lt:
        return _bool(a.hi < b.lo, a.lo >= b.hi)
    if op is ast.LtE:
        return _bool(a.hi <= b.lo, a.lo > b.hi)
    point = (a.lo == a.hi) & (b.lo == b.hi) & (a.lo == b.lo)
    apart = (a.hi < b.lo) | (b.hi < a.lo)
    if op is ast.Eq:
        return _bool(point, apart)
    if op is ast.NotEq:
        return _bool(apart, point)
    raise IntervalError(f"comparison {op.__name__} cannot be enclosed")


def _and(a: _I, b: _I) -> _I:
    (ta, fa), (tb, fb) = _truth(a), _truth(b)
    return _bool(ta & tb, fa | fb)


def _or(a: _I, b: _I) -> _I:
    return _not(_and(_not(a), _not(b)))  # De Morgan: exact on three-valued truth


def _not(a: _I) -> _I:
    true, false = _truth(a)
    return _bool(false, true)


def _dpow(a: _I, da: _I, b: _I, db: _I, v: _I) -> _I:
    """Derivative of ``v = a ** b``."""
    fixed = b.lo == b.hi
    if np.all(fixed) and np.all(db.lo == 0) and np.all(db.hi == 0):
        # d(a^p) = p a^(p-1) a'
        p = b.lo
        pm1 = _pow(a, _I(p - 1.0, p - 1.0))
        dd = _mul(_mul(_I(p, p), pm1), da)
        zero = p == 0
        return _I(np.where(zero, 0.0, dd.lo), np.where(zero, 0.0, dd.hi))
    # d(a^b) = a^b (b' log a + b a'/a), a > 0
    la = _log(np.log)(a)
    return _mul(v, _add(_mul(db, la), _mul(b, _div(da, a))))


#: arithmetic operators but ``%`` (which also reports its wraps, :func:`_mod`): enclosure of
#: ``a op b`` and of its derivative given ``(a, a', b, b', v = a op b)``
_BINARY: dict[type, tuple[Callable[[_I, _I], _I], Callable[..., _I]]] = {
    ast.Add: (_add, lambda a, da, b, db, v: _add(da, db)),
    ast.Sub: (_sub, lambda a, da, b, db, v: _sub(da, db)),
    ast.Mult: (_mul, lambda a, da, b, db, v: _add(_mul(da, b), _mul(a, db))),
    ast.Div: (_div, lambda a, da, b, db, v: _div(_sub(da, _mul(v, db)), b)),  # (a' - (a/b) b') / b
    ast.Pow: (_pow, _dpow),
}


# --------------------------------------------------------------------------------------------------
# the evaluator: (value, derivative) pairs over the parsed tree


#: (value, derivative): the derivative is an _I, or None when no derivative is taken
_Pair = tuple[_I, Any]


@dataclass(frozen=True)
class _Evaluator:
    """Walk the (already validated) syntax tree with interval (and optionally dual) arithmetic."""

    text: str
    env: Mapping[str, _I]
    time: str | None
    n: int
    der: bool  # derivatives too (forward mode)
    variables: Sequence[str] = ()

    def zero(self) -> _I | None:
        """Derivative of a constant (None when no derivative is taken)."""
        return _const(0.0, self.n) if self.der else None

    def jump(self, possible: np.ndarray, d: _I | None) -> _I | None:
        """Derivative where a discontinuity may occur: unbounded there."""
        if d is None:
            return None
        return _I(np.where(possible, -_INF, d.lo), np.where(possible, _INF, d.hi))

    def pair(self, v: _I, derivative: Callable[[], _I | None]) -> _Pair:
        """``(v, derivative())``, the derivative computed only when derivatives are taken."""
        return v, (derivative() if self.der else None)

    def switching(self, v: _I) -> _Pair:
        """A piecewise-constant value (a truth value, ``floor``, ...): derivative 0, unbounded where
        the value may switch inside a sub-interval."""
        return v, self.jump(~_decided(v), self.zero())

    def visit(self, node: ast.AST) -> _Pair:
        method = getattr(self, f"visit_{type(node).__name__}", None)
        if method is None:
            raise IntervalError(f"{type(node).__name__} in {self.text!r} cannot be enclosed")
        return method(node)

    def visit_Constant(self, node: ast.Constant) -> _Pair:
        return _const(float(cast(float, node.value)), self.n), self.zero()

    def visit_Name(self, node: ast.Name) -> _Pair:
        if node.id in self.env:  # derivative 1 for the time, 0 for a fixed variable
            return self.pair(self.env[node.id], lambda: _const(float(node.id == self.time), self.n))
        if node.id in self.variables:
            raise TypeError(f"expression {self.text!r} needs a value for {node.id!r}")
        if node.id in CONSTANTS:
            return _const(CONSTANTS[node.id], self.n), self.zero()
        raise IntervalError(f"unknown name {node.id!r} in {self.text!r}")

    def visit_UnaryOp(self, node: ast.UnaryOp) -> _Pair:
        v, d = self.visit(node.operand)
        if isinstance(node.op, ast.USub):
            return _neg(v), (_neg(d) if d is not None else None)
        if isinstance(node.op, ast.UAdd):
            return v, d
        if isinstance(node.op, ast.Not):
            return self.switching(_not(v))
        raise IntervalError(f"operator {type(node.op).__name__} cannot be enclosed")

    def visit_BinOp(self, node: ast.BinOp) -> _Pair:
        (a, da), (b, db) = self.visit(node.left), self.visit(node.right)
        op = type(node.op)
        if op is ast.Mod:
            v, wrap = _mod(a, b)
            # d(a % b) = a' - floor(a/b) b' away from a wrap (a jump); b' = 0 for a constant period
            k = np.floor(a.lo / np.where(b.lo != 0, b.lo, 1.0))
            return self.pair(v, lambda: self.jump(wrap, _sub(da, _mul(_I(k, k), db))))
        if op not in _BINARY:
            raise IntervalError(f"operator {op.__name__} cannot be enclosed")
        value, derivative = _BINARY[op]
        v = value(a, b)
        return self.pair(v, lambda: derivative(a, da, b, db, v))

    def visit_BoolOp(self, node: ast.BoolOp) -> _Pair:
        vals = [self.visit(v)[0] for v in node.values]
        return self.switching(reduce(_and if isinstance(node.op, ast.And) else _or, vals))

    def visit_Compare(self, node: ast.Compare) -> _Pair:
        vals = [self.visit(v)[0] for v in (node.left, *node.comparators)]
        tests = [
            _cmp(type(op), a, b) for op, a, b in zip(node.ops, vals[:-1], vals[1:], strict=True)
        ]
        return self.switching(reduce(_and, tests))  # a < b < c is a < b and b < c

    def visit_IfExp(self, node: ast.IfExp) -> _Pair:
        (c, _), a, b = self.visit(node.test), self.visit(node.body), self.visit(node.orelse)
        return self._where(c, a, b)

    def _where(self, c: _I, a: _Pair, b: _Pair) -> _Pair:
        t, f = _truth(c)  # the branch is known where the condition is
        return self.pair(
            _select(c, a[0], b[0]), lambda: self.jump(~(t | f), _select(c, a[1], b[1]))
        )

    def visit_Call(self, node: ast.Call) -> _Pair:
        name = node.func.id if isinstance(node.func, ast.Name) else ""
        if name not in FUNCTIONS:
            raise IntervalError(f"function {name!r} in {self.text!r} cannot be enclosed")
        args = [self.visit(a) for a in node.args]
        if name in _SMOOTH:
            return self._smooth(args[0], *_SMOOTH[name])
        if name in _PIECEWISE_CONSTANT:
            return self.switching(_PIECEWISE_CONSTANT[name](args[0][0]))
        handler = getattr(self, f"call_{name}", None)
        if handler is None:  # pragma: no cover - every whitelisted function has a handler (tested)
            raise IntervalError(f"function {name!r} in {self.text!r} cannot be enclosed")
        return handler(*args)

    # smooth unary functions (:data:`_SMOOTH`): value and derivative factor f'(a)
    def _smooth(self, arg: _Pair, f: Callable[[_I], _I], fprime: Callable[[_I, _I], _I]) -> _Pair:
        a, da = arg
        v = f(a)
        return self.pair(v, lambda: _mul(fprime(a, v), da))

    def call_atan2(self, y, x):
        (yv, dy), (xv, dx) = y, x
        if not self.der:
            return _atan2(yv, xv), None
        # d atan2(y, x) = (x y' - y x') / (x^2 + y^2); the branch cut is a jump
        d = _div(_sub(_mul(xv, dy), _mul(yv, dx)), _add(_sqr(xv), _sqr(yv)))
        on_cut = ~((xv.lo > 0) | (yv.lo > 0) | (yv.hi < 0))
        return _atan2(yv, xv), self.jump(on_cut, d)

    def call_abs(self, x):
        a, da = x
        if not self.der:
            return _abs(a), None
        pos, neg = a.lo > 0, a.hi < 0
        both = _hull(da, _neg(da))  # at the kink: either one-sided derivative
        lo = np.where(pos, da.lo, np.where(neg, -da.hi, both.lo))
        hi = np.where(pos, da.hi, np.where(neg, -da.lo, both.hi))
        return _abs(a), _I(lo, hi)

    def _extreme(self, *args, lower: bool) -> _Pair:
        out = args[0]
        pick: Callable[..., np.ndarray] = np.minimum if lower else np.maximum
        for b in args[1:]:
            (av, ad), (bv, bd) = out, b
            if lower:  # where the min is certainly a / b
                first, second = av.hi <= bv.lo, bv.hi <= av.lo
            else:
                first, second = av.lo >= bv.hi, bv.lo >= av.hi
            v = _I(pick(av.lo, bv.lo), pick(av.hi, bv.hi), av.boolean and bv.boolean)
            # the derivative of the one that is certainly the extreme, else both
            out = (v, _select(_bool(first, second), ad, bd) if self.der else None)
        return out

    call_min = functools.partialmethod(_extreme, lower=True)
    call_max = functools.partialmethod(_extreme, lower=False)

    def call_clip(self, x, lo, hi):
        # numpy / jax: minimum(maximum(x, lo), hi)
        return self._extreme(self._extreme(x, lo, lower=False), hi, lower=True)

    def call_where(self, c, a, b):
        return self._where(c[0], a, b)

    def call_window(self, x, lo, hi):
        c = _and(_cmp(ast.GtE, x[0], lo[0]), _cmp(ast.LtE, x[0], hi[0]))
        # a float 0/1 (jnp.where(..., 1.0, 0.0)), not a truth value
        return self.switching(_I(c.lo, c.hi))

    def call_piecewise(self, *args):
        return _first_true(self.call_where, args)


def _one(a: _I) -> _I:
    """The constant 1 on every sub-interval of ``a``."""
    return _const(1.0, a.lo.size)


def _ln10(a: _I) -> _I:
    """log(10) rounded outward, on every sub-interval of ``a``."""
    c = _const(math.log(10.0), a.lo.size)
    return _out(c.lo, c.hi, 2)


#: smooth unary functions: name -> (enclosure of f(a), enclosure of f'(a) given a and v = f(a))
_SMOOTH: dict[str, tuple[Callable[[_I], _I], Callable[[_I, _I], _I]]] = {
    "sin": (_sin, lambda a, v: _cos(a)),
    "cos": (_cos, lambda a, v: _neg(_sin(a))),
    "tan": (_tan, lambda a, v: _add(_one(a), _sqr(v))),
    "asin": (_asin, lambda a, v: _div(_one(a), _sqrt(_sub(_one(a), _sqr(a))))),
    "acos": (_acos, lambda a, v: _neg(_div(_one(a), _sqrt(_sub(_one(a), _sqr(a)))))),
    "atan": (_atan, lambda a, v: _div(_one(a), _add(_one(a), _sqr(a)))),
    "sinh": (lambda a: _monotone(np.sinh, a), lambda a, v: _cosh(a)),
    "cosh": (_cosh, lambda a, v: _monotone(np.sinh, a)),
    "tanh": (
        lambda a: _clip_range(_monotone(np.tanh, a), -1.0, 1.0),
        lambda a, v: _sub(_one(a), _sqr(v)),
    ),
    "exp": (lambda a: _clip_range(_monotone(np.exp, a), 0.0, _INF), lambda a, v: v),
    "log": (_log(np.log), lambda a, v: _div(_one(a), a)),
    "log10": (_log(np.log10), lambda a, v: _div(_one(a), _mul(a, _ln10(a)))),
    "sqrt": (_sqrt, lambda a, v: _div(_const(0.5, a.lo.size), v)),
}

#: piecewise-constant functions (a jump wherever the value may change): name -> enclosure
_PIECEWISE_CONSTANT: dict[str, Callable[[_I], _I]] = {
    "sign": _exact_monotone(np.sign),
    "floor": _exact_monotone(np.floor),
    "ceil": _exact_monotone(np.ceil),
    "step": lambda a: _I(np.where(a.lo >= 0, 1.0, 0.0), np.where(a.hi >= 0, 1.0, 0.0)),
}


def _decided(b: _I) -> np.ndarray:
    """A 0/1 interval whose value is known (not [0, 1])."""
    return b.lo == b.hi


# --------------------------------------------------------------------------------------------------
# public API


@lru_cache(maxsize=1024)
def _parse(text: str | float | int, variables: tuple[str, ...]) -> ast.AST:
    compile_expression(text, variables)  # the whitelist, the size limits and constant folding
    if isinstance(text, int | float):
        return ast.Constant(value=float(text))
    return ast.parse(text.strip(), mode="eval").body


def evaluate(
    text: str | float | int,
    variables: Sequence[str],
    t_lo,
    t_hi,
    *,
    derivative: bool = False,
    time: str = "t",
    **fixed: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Enclosures of ``f`` (or ``df/dt``) on each sub-interval ``[t_lo[k], t_hi[k]]`` (arrays).

    Parameters
    ----------
    text : an expression of :mod:`formation_ftc.core.expressions` (validated like a scenario field).
    variables : the names the expression may use; ``time`` (default ``t`` [s]) is the interval
        variable, every other one needs a value in ``fixed``.
    t_lo, t_hi : arrays of the sub-interval ends (``t_lo <= t_hi``).
    derivative : enclose ``d f / d time`` instead of ``f``.

    Returns
    -------
    (lo, hi) : arrays with ``lo[k] <= f(t) <= hi[k]`` for every t in sub-interval k (``-inf``/``inf``
        where nothing is known).
    """
    tree = _parse(text, tuple(variables))
    a, b = np.broadcast_arrays(*(np.atleast_1d(np.asarray(x, dtype=float)) for x in (t_lo, t_hi)))
    if np.any(a > b) or not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise ValueError("sub-intervals need finite ends with t_lo <= t_hi")
    n = a.size
    env = {name: _const(float(v), n) for name, v in fixed.items() if name in variables}
    if time in variables:  # the interval variable (also when ``fixed`` names it)
        env[time] = _I(a.ravel().copy(), b.ravel().copy())
    with np.errstate(all="ignore"):  # the whole walk: inf / NaN ends are handled, not warned about
        val, der = _Evaluator(str(text), env, time, n, derivative, variables).visit(tree)
    r = der if derivative else val
    return r.lo.reshape(a.shape), r.hi.reshape(a.shape)


@dataclass(frozen=True)
class Boxes:
    """Sub-intervals ``[a[k], b[k]]`` of the time range and the enclosures ``lo[m, k] <= f_m <= hi[m, k]``
    of each expression m on them; ``rounds`` is the number of bisection rounds performed."""

    a: np.ndarray
    b: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    rounds: int


def _stacked(texts: Sequence[str | float], variables: Sequence[str], a, b, **options):
    """The enclosures (lo, hi) of every expression on the sub-intervals [a, b], one row per expression
    (``options``: those of :func:`evaluate`)."""
    out = [evaluate(tx, variables, a, b, **options) for tx in texts]
    return np.stack([o[0] for o in out]), np.stack([o[1] for o in out])


def _boxes(ev: Callable, t_lo: float, t_hi: float, n_sub: int, refine, max_rounds: int) -> Boxes:
    """``n_sub`` sub-intervals of [t_lo, t_hi] and the enclosures ``ev(a, b)`` on them; those that
    ``refine(lo, hi)`` (None: none) marks are bisected, at most ``max_rounds`` times."""
    if not (math.isfinite(t_lo) and math.isfinite(t_hi)) or t_hi < t_lo:
        raise ValueError(f"need a finite range t_lo <= t_hi, got [{t_lo}, {t_hi}]")
    if n_sub < 1:
        raise ValueError("n_sub must be >= 1")
    edges = np.linspace(float(t_lo), float(t_hi), int(n_sub) + 1)  # ends exactly t_lo and t_hi
    a, b = edges[:-1].copy(), edges[1:].copy()
    lo, hi = ev(a, b)
    rounds = 0
    while refine is not None and rounds < max_rounds:
        bad = np.asarray(refine(lo, hi), dtype=bool) & (b > a)
        nbad = int(bad.sum())
        if nbad == 0 or a.size + nbad > _MAX_BOXES:
            break
        mid = 0.5 * (a[bad] + b[bad])
        na = np.concatenate([a[bad], mid])
        nb = np.concatenate([mid, b[bad]])
        nlo, nhi = ev(na, nb)
        keep = ~bad
        a = np.concatenate([a[keep], na])
        b = np.concatenate([b[keep], nb])
        lo = np.concatenate([lo[:, keep], nlo], axis=1)
        hi = np.concatenate([hi[:, keep], nhi], axis=1)
        rounds += 1
    order = np.argsort(a, kind="stable")
    return Boxes(a[order], b[order], lo[:, order], hi[:, order], rounds)


def _threshold_refiner(upper: float | None, lower: float | None):
    if upper is None and lower is None:
        return None

    def refine(lo, hi):
        bad = np.zeros(lo.shape[1], dtype=bool)
        if upper is not None:  # not yet below, and not certainly above (a certain violation)
            bad |= np.any((hi >= upper) & (lo < upper), axis=0)
        if lower is not None:
            bad |= np.any((lo <= lower) & (hi > lower), axis=0)
        return bad

    return refine


def enclose(
    text: str | float,
    variables: Sequence[str],
    t_lo: float,
    t_hi: float,
    n_sub: int = 4096,
    *,
    upper: float | None = None,
    lower: float | None = None,
    max_rounds: int = 8,
    time: str = "t",
    derivative: bool = False,
    **fixed: float,
) -> tuple[float, float]:
    """``(lo, hi)`` with ``lo <= f(t) <= hi`` for every ``t`` in ``[t_lo, t_hi]`` (with ``derivative``:
    enclosing ``df/dt``, :func:`enclose_derivative`).

    With ``upper`` (``lower``) the sub-intervals whose enclosure reaches the threshold without
    certainly exceeding it are bisected (at most ``max_rounds`` times), so that ``hi < upper``
    (``lo > lower``) is proved whenever a few bisections suffice. Other variables of the expression
    (e.g. the spacecraft number ``i``) are given as keywords.
    """
    refine = _threshold_refiner(upper, lower)
    ev = functools.partial(_stacked, [text], variables, derivative=derivative, time=time, **fixed)
    bx = _boxes(ev, t_lo, t_hi, n_sub, refine, max_rounds)
    return float(bx.lo.min()), float(bx.hi.max())


def enclose_derivative(
    text: str | float,
    variables: Sequence[str],
    t_lo: float,
    t_hi: float,
    n_sub: int = 4096,
    **options,
) -> tuple[float, float]:
    """``(lo, hi)`` enclosing ``df/dt`` over ``[t_lo, t_hi]`` (the options of :func:`enclose`);
    ``(-inf, inf)`` when the expression may jump inside the range."""
    return enclose(text, variables, t_lo, t_hi, n_sub, derivative=True, **options)


def _norm_upper(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Upper bound of sqrt(sum_m x_m^2) for x_m in [lo_m, hi_m] (per column), rounded up."""
    m = np.maximum(np.abs(lo), np.abs(hi))
    total = np.zeros(m.shape[1])
    for row in m:
        total = np.nextafter(total + np.nextafter(row * row, _INF), _INF)
    return np.nextafter(np.sqrt(total), _INF)


def enclose_norm(
    texts: Sequence[str | float],
    variables: Sequence[str],
    t_lo: float,
    t_hi: float,
    n_sub: int = 4096,
    *,
    upper: float | None = None,
    max_rounds: int = 8,
    time: str = "t",
    **fixed: float,
) -> float:
    """Upper bound of the Euclidean norm ``|(f_1(t), ..., f_m(t))|`` over ``[t_lo, t_hi]``.

    Per sub-interval the norm is bounded from the component enclosures (``sqrt(sum max|f_m|^2)``,
    rounded up); with ``upper`` the sub-intervals whose bound reaches it are bisected.
    """
    refine = None if upper is None else (lambda lo, hi: _norm_upper(lo, hi) >= upper)
    ev = functools.partial(_stacked, texts, variables, time=time, **fixed)
    bx = _boxes(ev, t_lo, t_hi, n_sub, refine, max_rounds)
    return float(_norm_upper(bx.lo, bx.hi).max())
