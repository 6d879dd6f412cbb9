"""Safe math expressions in ``t`` (and other whitelisted variables) compiled to JAX functions.

Scenario files describe time-varying quantities (faults, disturbances, delays, desired trajectories) as
text such as ``"1 - 0.1*(i+1)*exp(-(t-10))"``. They are *data*: the text is parsed with :mod:`ast` and
only a whitelist of node types, names and functions is accepted; the tree is then turned into nested
closures over :mod:`jax.numpy` -- nothing is ever passed to ``eval``/``exec``.

Grammar (Python syntax subset)
------------------------------
* numbers, the variables given to :func:`compile_expression` (by default ``t`` [s] and ``i``, the
  **1-based** spacecraft number as printed in the papers), constants ``pi`` and ``e``;
* ``+ - * / ** %``, unary ``-``/``+``, comparisons ``< <= > >= == !=`` (chains allowed),
  ``and``/``or``/``not`` and ``a if cond else b``;
* functions: ``sin cos tan asin acos atan atan2 sinh cosh tanh exp log log10 sqrt abs sign floor ceil
  min max clip where(cond, a, b) step(x)`` (Heaviside, 1 for x >= 0), ``window(x, lo, hi)`` (1 on
  [lo, hi]), ``piecewise(c1, v1, c2, v2, ..., default)`` (first true condition wins).

Errors raise :class:`ExpressionError` naming the field, the expression, the offending token and its
column.
"""

from __future__ import annotations

import ast
import math
from collections.abc import Callable, Sequence
from functools import lru_cache

import jax.numpy as jnp

__all__ = ["ExpressionError", "Expression", "compile_expression", "compile_vector_expression", "FUNCTIONS",
           "CONSTANTS"]


class ExpressionError(ValueError):
    """An expression that cannot be parsed or uses something outside the whitelist."""

    def __init__(self, message: str, expression: str = "", field: str = "", col: int | None = None):
        where = f"{field}: " if field else ""
        caret = ""
        if expression and col is not None:
            caret = f"\n    {expression}\n    {' ' * col}^"
        super().__init__(f"{where}{message} in expression {expression!r}{caret}")
        self.field = field
        self.expression = expression
        self.col = col


def _piecewise(*args):
    if len(args) < 3 or len(args) % 2 == 0:
        raise TypeError("piecewise needs pairs (condition, value) followed by a default value")
    out = args[-1]
    for k in range(len(args) - 3, -1, -2):
        out = jnp.where(args[k], args[k + 1], out)
    return out


FUNCTIONS: dict[str, tuple[Callable, tuple[int, int | None]]] = {
    # name: (function, (min args, max args))
    "sin": (jnp.sin, (1, 1)), "cos": (jnp.cos, (1, 1)), "tan": (jnp.tan, (1, 1)),
    "asin": (jnp.arcsin, (1, 1)), "acos": (jnp.arccos, (1, 1)), "atan": (jnp.arctan, (1, 1)),
    "atan2": (jnp.arctan2, (2, 2)), "sinh": (jnp.sinh, (1, 1)), "cosh": (jnp.cosh, (1, 1)),
    "tanh": (jnp.tanh, (1, 1)), "exp": (jnp.exp, (1, 1)), "log": (jnp.log, (1, 1)),
    "log10": (jnp.log10, (1, 1)), "sqrt": (jnp.sqrt, (1, 1)), "abs": (jnp.abs, (1, 1)),
    "sign": (jnp.sign, (1, 1)), "floor": (jnp.floor, (1, 1)), "ceil": (jnp.ceil, (1, 1)),
    "min": (lambda *a: _reduce(jnp.minimum, a), (2, None)),
    "max": (lambda *a: _reduce(jnp.maximum, a), (2, None)),
    "clip": (jnp.clip, (3, 3)),
    "where": (jnp.where, (3, 3)),
    "step": (lambda x: jnp.where(x >= 0, 1.0, 0.0), (1, 1)),
    "window": (lambda x, lo, hi: jnp.where((x >= lo) & (x <= hi), 1.0, 0.0), (3, 3)),
    "piecewise": (_piecewise, (3, None)),
}
CONSTANTS = {"pi": math.pi, "e": math.e}


def _reduce(op, args):
    out = args[0]
    for a in args[1:]:
        out = op(out, a)
    return out


_BINOPS = {
    ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b, ast.Mult: lambda a, b: a * b,
    ast.Div: lambda a, b: a / b, ast.Pow: lambda a, b: a**b, ast.Mod: lambda a, b: a % b,
}
_CMPOPS = {
    ast.Lt: jnp.less, ast.LtE: jnp.less_equal, ast.Gt: jnp.greater, ast.GtE: jnp.greater_equal,
    ast.Eq: jnp.equal, ast.NotEq: jnp.not_equal,
}

Env = dict


class Expression:
    """A compiled expression: call it with the variables as keyword arguments (arrays broadcast)."""

    def __init__(self, text: str, fn: Callable[[Env], object], variables: tuple[str, ...]):
        self.text = text
        self._fn = fn
        self.variables = variables

    def __call__(self, **values):
        missing = [v for v in self.variables if v not in values]
        if missing:
            raise TypeError(f"expression {self.text!r} needs values for {missing}")
        out = self._fn(values)
        return jnp.asarray(out, dtype=jnp.float64) if not isinstance(out, bool) else jnp.asarray(float(out))

    def __repr__(self) -> str:
        return f"Expression({self.text!r})"


def compile_expression(text: str | float | int, variables: Sequence[str] = ("t", "i"),
                       field: str = "") -> Expression:
    """Parse ``text`` and return an :class:`Expression` (JAX-traceable, differentiable in ``t``)."""
    if isinstance(text, bool):
        raise ExpressionError("booleans are not expressions", str(text), field)
    if isinstance(text, int | float):
        value = float(text)
        return Expression(repr(value), lambda env: value, tuple(variables))
    if not isinstance(text, str):
        raise ExpressionError(f"expected a string or number, got {type(text).__name__}", str(text), field)
    return _compile_cached(text, tuple(variables), field)


def compile_vector_expression(texts: Sequence[str | float], field: str = "") -> Callable:
    """Per-axis expressions in ``t`` and ``i`` -> ``f(t, i)`` returning shape ``i.shape + (len(texts),)``.

    ``i`` is typically the array of 1-based spacecraft numbers, so ``f(t, idx)`` gives an (N, 3) array.
    Errors name ``field[k]`` of the offending component.
    """
    fns = [compile_expression(s, ("t", "i"), field=f"{field}[{k}]") for k, s in enumerate(texts)]
    return lambda t, i: jnp.stack([jnp.broadcast_to(f(t=t, i=i), jnp.shape(i)) for f in fns], axis=-1)


@lru_cache(maxsize=4096)
def _compile_cached(text: str, variables: tuple[str, ...], field: str) -> Expression:
    if len(text) > 2000:
        raise ExpressionError("expression longer than 2000 characters", text[:40] + "...", field)
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        col = (exc.offset or 1) - 1
        raise ExpressionError(f"syntax error ({exc.msg})", text, field, col) from None
    fn = _Compiler(text, set(variables), field).visit(tree.body)
    return Expression(text, fn, variables)


class _Compiler:
    def __init__(self, text: str, variables: set[str], field: str):
        self.text, self.variables, self.field = text, variables, field

    def fail(self, node: ast.AST, message: str):
        raise ExpressionError(message, self.text, self.field, getattr(node, "col_offset", None))

    def visit(self, node: ast.AST) -> Callable[[Env], object]:
        method = getattr(self, f"visit_{type(node).__name__}", None)
        if method is None:
            token = ast.get_source_segment(self.text, node) or type(node).__name__
            self.fail(node, f"{type(node).__name__.lower()} {token!r} is not allowed")
        return method(node)

    def visit_Constant(self, node: ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, int | float):
            self.fail(node, f"constant {node.value!r} is not a number")
        v = float(node.value)
        return lambda env: v

    def visit_Name(self, node: ast.Name):
        name = node.id
        if name in self.variables:
            return lambda env: env[name]
        if name in CONSTANTS:
            v = CONSTANTS[name]
            return lambda env: v
        allowed = sorted(self.variables) + sorted(CONSTANTS)
        hint = " (functions must be called)" if name in FUNCTIONS else ""
        self.fail(node, f"unknown name {name!r}{hint}; allowed names: {', '.join(allowed)}")

    def visit_BinOp(self, node: ast.BinOp):
        op = _BINOPS.get(type(node.op))
        if op is None:
            self.fail(node, f"operator {type(node.op).__name__} is not allowed")
        a, b = self.visit(node.left), self.visit(node.right)
        return lambda env: op(a(env), b(env))

    def visit_UnaryOp(self, node: ast.UnaryOp):
        x = self.visit(node.operand)
        if isinstance(node.op, ast.USub):
            return lambda env: -x(env)
        if isinstance(node.op, ast.UAdd):
            return x
        if isinstance(node.op, ast.Not):
            return lambda env: jnp.logical_not(x(env))
        self.fail(node, f"operator {type(node.op).__name__} is not allowed")

    def visit_BoolOp(self, node: ast.BoolOp):
        parts = [self.visit(v) for v in node.values]
        op = jnp.logical_and if isinstance(node.op, ast.And) else jnp.logical_or
        return lambda env: _reduce(op, [p(env) for p in parts])

    def visit_Compare(self, node: ast.Compare):
        left = self.visit(node.left)
        rights = [self.visit(c) for c in node.comparators]
        ops = []
        for o in node.ops:
            if type(o) not in _CMPOPS:
                self.fail(node, f"comparison {type(o).__name__} is not allowed")
            ops.append(_CMPOPS[type(o)])

        def fn(env):
            out, a = None, left(env)
            for op, r in zip(ops, rights, strict=True):
                b = r(env)
                c = op(a, b)
                out = c if out is None else jnp.logical_and(out, c)
                a = b
            return out

        return fn

    def visit_IfExp(self, node: ast.IfExp):
        c, a, b = self.visit(node.test), self.visit(node.body), self.visit(node.orelse)
        return lambda env: jnp.where(c(env), a(env), b(env))

    def visit_Call(self, node: ast.Call):
        if not isinstance(node.func, ast.Name):
            token = ast.get_source_segment(self.text, node.func) or "?"
            self.fail(node, f"call of {token!r} is not allowed (only plain function names)")
        name = node.func.id
        if name not in FUNCTIONS:
            self.fail(node, f"unknown function {name!r}; allowed: {', '.join(sorted(FUNCTIONS))}")
        if node.keywords:
            self.fail(node, f"keyword arguments are not allowed in {name}()")
        fn, (lo, hi) = FUNCTIONS[name]
        n = len(node.args)
        if n < lo or (hi is not None and n > hi):
            want = f"{lo}" if lo == hi else f"at least {lo}" if hi is None else f"{lo}..{hi}"
            self.fail(node, f"{name}() takes {want} argument(s), got {n}")
        if name == "piecewise" and n % 2 == 0:
            self.fail(node, "piecewise() needs (condition, value) pairs followed by a default value")
        args = [self.visit(a) for a in node.args]
        return lambda env: fn(*[a(env) for a in args])
