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
column. Validation is total: an expression longer than :data:`MAX_LENGTH` characters, nested deeper
than :data:`MAX_DEPTH` levels or with more than :data:`MAX_NODES` syntax nodes is refused before it is
compiled (the compiler never recurses deeper than that), a number literal must be a finite float64,
and every constant sub-expression (one without variables, e.g. ``1/0``, ``10**400``, ``log(0)``) is
evaluated at validation in numpy float64 with floating-point errors raised, so a division by zero, an
overflow or an invalid operation in a constant is a validation error, not a non-finite value at run
time.
"""

from __future__ import annotations

import ast
import math
import operator
from collections.abc import Callable, Sequence
from functools import lru_cache, reduce
from typing import Any, NoReturn, cast

import numpy as np

from formation_ftc.errors import InputError

__all__ = [
    "ExpressionError",
    "Expression",
    "compile_expression",
    "compile_vector_expression",
    "FUNCTIONS",
    "CONSTANTS",
    "MAX_LENGTH",
    "MAX_DEPTH",
    "MAX_NODES",
]

#: longest accepted expression text [characters]
MAX_LENGTH = 2000
#: deepest accepted nesting of the syntax tree (operator chains such as ``1+1+...+1`` count one level
#: per operator) [-]
MAX_DEPTH = 200
#: most syntax-tree nodes in one expression [-]
MAX_NODES = 5000


class ExpressionError(InputError):
    """An expression that cannot be parsed or uses something outside the whitelist."""

    def __init__(self, message: str, expression: str = "", field: str = "", col: int | None = None):
        where = f"{field}: " if field else ""
        shown = expression
        if len(expression) > 120:  # keep the message readable; the caret only within what is shown
            shown = expression[:100] + "..."
            col = col if col is not None and col < 100 else None
        caret = f"\n    {shown}\n    {' ' * col}^" if shown and col is not None else ""
        super().__init__(f"{where}{message} in expression {shown!r}{caret}")
        self.field = field
        self.expression = expression
        self.col = col


class _LazyJaxNumpy:
    """:mod:`jax.numpy`, imported when an expression is first evaluated (each name is kept after its
    first use): parsing and checking an expression -- what validating a scenario does -- needs no JAX."""

    def __getattr__(self, name: str) -> Any:
        import jax.numpy

        value = getattr(jax.numpy, name)
        setattr(self, name, value)
        return value


jnp: Any = _LazyJaxNumpy()


def _first_true(where: Callable, args):
    """``piecewise(c1, v1, c2, v2, ..., default)``: the value of the first true condition."""
    out = args[-1]
    for k in range(len(args) - 3, -1, -2):
        out = where(args[k], args[k + 1], out)
    return out


def _function_table(xp: Any) -> dict[str, Callable]:
    """The whitelisted functions over the array module ``xp``: :mod:`jax.numpy` for the compiled
    expression, :mod:`numpy` (float64) to fold constant sub-expressions at validation. Each name is
    looked up in ``xp`` when called, so that building the table imports no JAX."""

    def lookup(name: str) -> Callable:
        return lambda *args: getattr(xp, name)(*args)

    same_name = "sin cos tan sinh cosh tanh exp log log10 sqrt abs sign floor ceil clip where"
    table = {name: lookup(name) for name in same_name.split()}
    table.update(
        asin=lookup("arcsin"),
        acos=lookup("arccos"),
        atan=lookup("arctan"),
        atan2=lookup("arctan2"),
        min=lambda *a: reduce(xp.minimum, a),
        max=lambda *a: reduce(xp.maximum, a),
        step=lambda x: xp.where(x >= 0, 1.0, 0.0),
        window=lambda x, lo, hi: xp.where((x >= lo) & (x <= hi), 1.0, 0.0),
        piecewise=lambda *a: _first_true(xp.where, a),
    )
    return table


#: (min args, max args) of the functions that do not take exactly one argument
_ARITY: dict[str, tuple[int, int | None]] = {
    "atan2": (2, 2),
    "min": (2, None),
    "max": (2, None),
    "clip": (3, 3),
    "where": (3, 3),
    "window": (3, 3),
    "piecewise": (3, None),
}
FUNCTIONS: dict[str, tuple[Callable, tuple[int, int | None]]] = {
    # name: (function, (min args, max args))
    name: (fn, _ARITY.get(name, (1, 1)))
    for name, fn in _function_table(jnp).items()
}
CONSTANTS = {"pi": math.pi, "e": math.e}
#: numpy float64 twins of FUNCTIONS, used to fold constant sub-expressions at validation
_NP_FUNCTIONS = _function_table(np)

#: operator -> (Python operator, traced by JAX; its numpy float64 twin for constant folding)
_BINOPS = {
    ast.Add: (operator.add, np.add),
    ast.Sub: (operator.sub, np.subtract),
    ast.Mult: (operator.mul, np.multiply),
    ast.Div: (operator.truediv, np.true_divide),
    ast.Pow: (operator.pow, np.power),
    ast.Mod: (operator.mod, np.remainder),
}
#: comparison -> name of its function in jax.numpy and numpy
_CMPOPS = {
    ast.Lt: "less",
    ast.LtE: "less_equal",
    ast.Gt: "greater",
    ast.GtE: "greater_equal",
    ast.Eq: "equal",
    ast.NotEq: "not_equal",
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
        return (
            jnp.asarray(out, dtype=jnp.float64)
            if not isinstance(out, bool)
            else jnp.asarray(float(out))
        )

    def __repr__(self) -> str:
        return f"Expression({self.text!r})"


def compile_expression(
    text: str | float | int, variables: Sequence[str] = ("t", "i"), field: str = ""
) -> Expression:
    """Parse ``text`` and return an :class:`Expression` (JAX-traceable, differentiable in ``t``)."""
    if isinstance(text, bool):
        raise ExpressionError("booleans are not expressions", str(text), field)
    if isinstance(text, int | float):
        try:
            value = float(text)
        except OverflowError:
            value = math.inf
        if not math.isfinite(value):
            raise ExpressionError(
                "a number used as an expression must be finite", str(text)[:40], field
            )
        return Expression(repr(value), lambda env: value, tuple(variables))
    if not isinstance(text, str):
        raise ExpressionError(
            f"expected a string or number, got {type(text).__name__}", str(text), field
        )
    return _compile_cached(text, tuple(variables), field)


def compile_vector_expression(texts: Sequence[str | float], field: str = "") -> Callable:
    """Per-axis expressions in ``t`` and ``i`` -> ``f(t, i)`` returning shape ``i.shape + (len(texts),)``.

    ``i`` is typically the array of 1-based spacecraft numbers, so ``f(t, idx)`` gives an (N, 3) array.
    Errors name ``field[k]`` of the offending component.
    """
    fns = [compile_expression(s, ("t", "i"), field=f"{field}[{k}]") for k, s in enumerate(texts)]
    return lambda t, i: jnp.stack(
        [jnp.broadcast_to(f(t=t, i=i), jnp.shape(i)) for f in fns], axis=-1
    )


@lru_cache(maxsize=4096)
def _compile_cached(text: str, variables: tuple[str, ...], field: str) -> Expression:
    if len(text) > MAX_LENGTH:
        raise ExpressionError(
            f"expression longer than {MAX_LENGTH} characters ({len(text)})",
            text[:40] + "...",
            field,
        )
    if "\x00" in text:
        raise ExpressionError("NUL character in expression", text.replace("\x00", "\\x00"), field)
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        col = (exc.offset or 1) - 1
        raise ExpressionError(f"syntax error ({exc.msg})", text, field, col) from None
    except (RecursionError, MemoryError, ValueError) as exc:
        raise ExpressionError(
            f"expression too deeply nested to parse ({type(exc).__name__}); at most "
            f"{MAX_DEPTH} levels",
            text,
            field,
        ) from None
    _check_size(tree.body, text, field)
    compiler = _Compiler(text, set(variables), field)
    fn = compiler.visit(tree.body)
    _Folder(compiler).fold(tree.body)
    return Expression(text, fn, variables)


def _check_size(root: ast.AST, text: str, field: str) -> None:
    """Iterative walk: refuse trees deeper than MAX_DEPTH or larger than MAX_NODES (before compiling)."""
    stack = [(root, 1)]
    n = 0
    while stack:
        node, depth = stack.pop()
        n += 1
        if n > MAX_NODES:
            raise ExpressionError(
                f"expression too large (more than {MAX_NODES} syntax nodes); split it or "
                f"simplify it",
                text,
                field,
            )
        if depth > MAX_DEPTH:
            raise ExpressionError(
                f"expression nested too deeply (more than {MAX_DEPTH} levels, e.g. a chain "
                f"of more than {MAX_DEPTH} operators); simplify it",
                text,
                field,
                getattr(node, "col_offset", None),
            )
        stack.extend((child, depth + 1) for child in ast.iter_child_nodes(node))


class _Folder:
    """Evaluate every constant sub-expression in numpy float64 with floating-point errors raised.

    ``fold(node)`` returns the value of a constant node or None when it depends on a variable; a
    division by zero, overflow or invalid operation raises :class:`ExpressionError` at that node.
    The tree was already checked by :class:`_Compiler` (whitelist) and :func:`_check_size` (depth).
    """

    def __init__(self, compiler: _Compiler):
        self.c = compiler

    def fold(self, node: ast.AST):
        with np.errstate(all="raise"):
            return self._fold(node)

    def _apply(self, node: ast.AST, fn: Callable, *args):
        try:
            out = fn(*args)
        except FloatingPointError as exc:
            token = ast.get_source_segment(self.c.text, node) or type(node).__name__
            reason = str(exc).replace("encountered in ", "in ")
            self.c.fail(node, f"constant {token!r} is not a finite float64 ({reason})")
        except (OverflowError, ZeroDivisionError, ValueError) as exc:  # pragma: no cover
            # numpy raises FloatingPointError (above) instead
            self.c.fail(node, f"constant cannot be evaluated ({exc})")
        if np.ndim(out) == 0 and not np.isfinite(out):  # a truth value is always finite
            token = ast.get_source_segment(self.c.text, node) or type(node).__name__
            self.c.fail(node, f"constant {token!r} is not finite ({out})")
        return out

    def _fold(self, node: ast.AST):
        if isinstance(node, ast.Constant):
            return np.float64(cast(float, node.value))  # the compiler admitted only int | float
        if isinstance(node, ast.Name):
            return np.float64(CONSTANTS[node.id]) if node.id not in self.c.variables else None
        # the operands, in source order (the operators themselves are not expressions)
        operands = node.args if isinstance(node, ast.Call) else ast.iter_child_nodes(node)
        vals = [self._fold(a) for a in operands if isinstance(a, ast.expr)]
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div | ast.Mod):
            if vals[1] is not None and vals[1] == 0:
                op = "division" if isinstance(node.op, ast.Div) else "modulo"
                self.c.fail(node.right, f"{op} by a constant zero")
        if any(v is None for v in vals):
            return None
        if isinstance(node, ast.BinOp):
            a, b = np.float64(vals[0]), np.float64(vals[1])
            return self._apply(node, _BINOPS[type(node.op)][1], a, b)
        if isinstance(node, ast.UnaryOp):
            if isinstance(node.op, ast.USub):
                return self._apply(node, np.negative, vals[0])
            return np.logical_not(vals[0]) if isinstance(node.op, ast.Not) else vals[0]
        if isinstance(node, ast.BoolOp):
            return reduce(np.logical_and if isinstance(node.op, ast.And) else np.logical_or, vals)
        if isinstance(node, ast.Compare):
            out = np.bool_(True)
            for cmp, a, b in zip(node.ops, vals[:-1], vals[1:], strict=True):
                out = np.logical_and(out, getattr(np, _CMPOPS[type(cmp)])(a, b))
            return out
        if isinstance(node, ast.IfExp):
            return np.where(*vals)
        # a call (the compiler rejected every other node; its function is a plain name)
        return self._apply(node, _NP_FUNCTIONS[cast(ast.Name, cast(ast.Call, node).func).id], *vals)


class _Compiler:
    def __init__(self, text: str, variables: set[str], field: str):
        self.text, self.variables, self.field = text, variables, field

    def fail(self, node: ast.AST, message: str) -> NoReturn:
        raise ExpressionError(message, self.text, self.field, getattr(node, "col_offset", None))

    def visit(self, node: ast.AST) -> Callable[[Env], Any]:
        method = getattr(self, f"visit_{type(node).__name__}", None)
        if method is None:
            token = ast.get_source_segment(self.text, node) or type(node).__name__
            self.fail(node, f"{type(node).__name__.lower()} {token!r} is not allowed")
        return method(node)

    def visit_Constant(self, node: ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, int | float):
            self.fail(node, f"constant {node.value!r} is not a number")
        try:
            v = float(node.value)
        except OverflowError:
            v = math.inf
        if not math.isfinite(v):
            token = ast.get_source_segment(self.text, node) or repr(node.value)
            if len(token) > 24:
                token = token[:20] + "..."
            self.fail(node, f"number {token} is outside the float64 range (|x| < 1.8e308)")
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
        if type(node.op) not in _BINOPS:
            self.fail(node, f"operator {type(node.op).__name__} is not allowed")
        op = _BINOPS[type(node.op)][0]
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
        op = "logical_and" if isinstance(node.op, ast.And) else "logical_or"
        return lambda env: reduce(getattr(jnp, op), [p(env) for p in parts])

    def visit_Compare(self, node: ast.Compare):
        parts = [self.visit(v) for v in (node.left, *node.comparators)]
        for o in node.ops:
            if type(o) not in _CMPOPS:
                self.fail(node, f"comparison {type(o).__name__} is not allowed")
        ops = [_CMPOPS[type(o)] for o in node.ops]

        def fn(env):
            vals = [p(env) for p in parts]
            tests = [
                getattr(jnp, op)(a, b) for op, a, b in zip(ops, vals[:-1], vals[1:], strict=True)
            ]
            return reduce(jnp.logical_and, tests)

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
            self.fail(
                node, "piecewise() needs (condition, value) pairs followed by a default value"
            )
        args = [self.visit(a) for a in node.args]
        return lambda env: fn(*[a(env) for a in args])
