"""Requirements as signal temporal logic (STL): a parser and the quantitative (robustness) semantics
on the recorded samples of a run, computed in JAX inside the compiled run.

Grammar (whitespace free; bounds in seconds, ``inf`` allowed as an upper bound)::

    formula := disj ('->' formula)?                       implication (right associative)
    disj    := conj (('or' | '|') conj)*
    conj    := unary (('and' | '&') unary)*
    unary   := ('not' | '!') unary
             | ('G' | 'F') ('[' a ',' b ']')? unary        always / eventually, within [t + a, t + b]
             | '(' formula ')'
             | SIGNAL ('<=' | '<' | '>=' | '>') NUMBER      an atom on a recorded signal

``G`` and ``F`` without a bound mean ``[0, inf]``: to the end of the run.

Semantics (Donze and Maler 2010, discrete time): the robustness ``rho(phi, k)`` of a formula at sample
``k`` is a real number whose sign says whether the formula holds there (>= 0: holds) and whose
magnitude says by how much. For an atom ``x <= c`` it is ``c - x_k``, for ``x >= c`` it is ``x_k - c``
(strict and non-strict comparisons have the same robustness); a signal with spacecraft or vector axes
counts its worst component (``c - max x_k``, ``min x_k - c``): the atom holds for every spacecraft.
``not``: ``-rho``; ``and``: min; ``or``: max; ``a -> b``: ``max(-rho_a, rho_b)``; ``G[a, b] phi`` at
``k``: the min of ``rho(phi, j)`` over the samples ``j`` with ``t_j - t_k`` in ``[a, b]`` (``F``: the
max), the window cut at the last sample (a window wholly past the end: +inf for ``G``, -inf for
``F``). The requirement's robustness is ``rho(phi, 0)``; it passes when it is >= 0.

The samples are the run's records (``[simulation] record_every``): an excursion between two records is
not seen (a metric folded at every step is; keep the record interval short where that matters).
``tests/sim/test_stl.py`` compares the robustness with rtamt's discrete-time offline monitor on
recorded signals.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any

from formation_ftc.errors import InputError

__all__ = ["StlError", "parse", "signals_of", "robustness", "Atom", "Unary", "Binary", "Temporal"]


class StlError(InputError):
    """A formula that does not parse (exit code 2); the message names the position."""


@dataclass(frozen=True)
class Atom:
    signal: str
    op: str  # "<=" or ">=" (a strict comparison has the same robustness)
    value: float


@dataclass(frozen=True)
class Unary:
    op: str  # "not"
    arg: Any


@dataclass(frozen=True)
class Binary:
    op: str  # "and", "or", "->"
    left: Any
    right: Any


@dataclass(frozen=True)
class Temporal:
    op: str  # "G" or "F"
    low: float  # [s]
    high: float  # [s], inf: to the end
    arg: Any


_TOKEN = re.compile(
    r"\s*(?:(?P<num>[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|inf\b)"
    r"|(?P<op><=|>=|->|<|>|\[|\]|\(|\)|,|!|&|\|)"
    r"|(?P<name>[A-Za-z_][A-Za-z0-9_]*))"
)


def _tokens(text: str) -> list[tuple[str, str, int]]:
    out, pos = [], 0
    while text[pos:].strip():  # up to trailing whitespace
        m = _TOKEN.match(text, pos)
        if m is None or m.end() == pos:
            at = len(text) - len(text[pos:].lstrip())
            raise StlError(f"STL formula {text!r}: unexpected character at position {at}")
        kind = m.lastgroup or ""
        out.append((kind, m.group(kind), m.start(kind)))
        pos = m.end()
    return out


class _Parser:
    def __init__(self, text: str):
        self.text = text
        self.toks = _tokens(text)
        self.i = 0

    def error(self, what: str, back: int = 0) -> StlError:
        """The error at the next token (``back = 1``: at the one just taken), or at the end."""
        i = self.i - back
        pos = self.toks[i][2] if i < len(self.toks) else len(self.text)
        return StlError(f"STL formula {self.text!r}: {what} at position {pos}")

    def peek(self) -> str | None:
        return self.toks[self.i][1] if self.i < len(self.toks) else None

    def take(self, want: str | None = None) -> tuple[str, str, int]:
        if self.i >= len(self.toks):
            raise self.error(f"expected {want!r}" if want else "unexpected end")
        tok = self.toks[self.i]
        if want is not None and tok[1] != want:
            raise self.error(f"expected {want!r}, found {tok[1]!r}")
        self.i += 1
        return tok

    def formula(self) -> Any:
        left = self.disj()
        if self.peek() == "->":
            self.take()
            return Binary("->", left, self.formula())
        return left

    def disj(self) -> Any:
        return self.chain("or", "|", self.conj)

    def conj(self) -> Any:
        return self.chain("and", "&", self.unary)

    def chain(self, op: str, symbol: str, operand) -> Any:
        """``operand (op operand)*``, left associative (``symbol``: the operator's other spelling)."""
        left = operand()
        while self.peek() in (op, symbol):
            self.take()
            left = Binary(op, left, operand())
        return left

    def number(self) -> float:
        kind, text, _ = self.take()
        if kind != "num":
            raise self.error(f"expected a number, found {text!r}", back=1)
        return math.inf if text == "inf" else float(text)

    def unary(self) -> Any:
        tok = self.peek()
        if tok in ("not", "!"):
            self.take()
            return Unary("not", self.unary())
        if tok in ("G", "F"):
            self.take()
            low, high = 0.0, math.inf
            if self.peek() == "[":
                self.take("[")
                low = self.number()
                self.take(",")
                high = self.number()
                self.take("]")
                if not (0 <= low <= high) or math.isinf(low):
                    self.i -= 1
                    raise self.error(f"interval [{low:g}, {high:g}] needs 0 <= a <= b, a finite")
            return Temporal(tok, low, high, self.unary())
        if tok == "(":
            self.take("(")
            inner = self.formula()
            self.take(")")
            return inner
        kind, name, _ = self.take()
        if kind != "name" or name in ("and", "or", "not", "G", "F"):
            raise self.error(f"expected a signal, '(', 'not', 'G' or 'F', found {name!r}", back=1)
        if self.peek() not in ("<=", "<", ">=", ">"):
            raise self.error(f"expected a comparison (<=, <, >=, >) after signal {name!r}")
        op = self.take()[1]
        value = self.number()
        if not math.isfinite(value):
            raise self.error("a comparison needs a finite number", back=1)
        return Atom(name, "<=" if op in ("<=", "<") else ">=", value)


def parse(text: str) -> Any:
    """The syntax tree of an STL formula; :class:`StlError` naming the position of what does not
    parse.

    Parameters
    ----------
    text : str
        The formula (grammar in the module docstring).

    Returns
    -------
    Atom, Unary, Binary or Temporal
        Its syntax tree.

    Examples
    --------
    >>> parse("F[0,300](G(shape_error <= 1))")
    Temporal(op='F', low=0.0, high=300.0, arg=Temporal(op='G', low=0.0, high=inf, arg=Atom(signal='shape_error', op='<=', value=1.0)))
    >>> parse("G(x <=)")
    Traceback (most recent call last):
    ...
    formation_ftc.sim.stl.StlError: STL formula 'G(x <=)': expected a number, found ')' at position 6
    """
    if not isinstance(text, str) or not text.strip():
        raise StlError("STL formula: empty; give e.g. 'G[300,inf](shape_error <= 1)'")
    p = _Parser(text)
    tree = p.formula()
    if p.i != len(p.toks):
        raise p.error(f"unexpected {p.toks[p.i][1]!r}")
    return tree


def signals_of(tree: Any) -> set[str]:
    """The signals a formula's atoms read.

    Parameters
    ----------
    tree : Atom, Unary, Binary or Temporal
        A formula from :func:`parse`.

    Returns
    -------
    set of str
        The signal names.

    Examples
    --------
    >>> sorted(signals_of(parse("G(fault_active >= 0.5 -> F[0,120](G(shape_error <= 1)))")))
    ['fault_active', 'shape_error']
    """
    if isinstance(tree, Atom):
        return {tree.signal}
    if isinstance(tree, Binary):
        return signals_of(tree.left) | signals_of(tree.right)
    return signals_of(tree.arg)


def _window(r, lo: int, hi: int | None, is_min: bool):
    """``out[k]`` = min (max) of ``r[k + lo .. k + hi]`` cut at the end (``hi`` None: to the end);
    an empty window gives +inf (-inf)."""
    import jax
    import jax.numpy as jnp

    n = r.shape[0]
    fill = jnp.inf if is_min else -jnp.inf
    if hi is None:
        acc = (jax.lax.cummin if is_min else jax.lax.cummax)(r, reverse=True)
        return jnp.concatenate([acc[lo:], jnp.full((min(lo, n),), fill)])[:n]
    # van Herk / Gil-Werman: O(n) whatever the width (a window of minutes holds thousands of samples)
    width = hi - lo + 1
    shifted = jnp.concatenate([r, jnp.full((hi + 1,), fill)])[lo:]  # shifted[k] = r[k + lo]
    blocks = -(-(n + width - 1) // width)
    extra = max(blocks * width - shifted.shape[0], 0)
    padded = jnp.concatenate([shifted, jnp.full((extra,), fill)])
    padded = padded[: blocks * width].reshape(blocks, width)
    scan = jax.lax.cummin if is_min else jax.lax.cummax
    prefix = scan(padded, axis=1).reshape(-1)
    suffix = scan(padded, axis=1, reverse=True).reshape(-1)
    pick = jnp.minimum if is_min else jnp.maximum
    return pick(suffix[:n], prefix[width - 1 : width - 1 + n])


def _rho(tree: Any, signals: dict[str, Any], step: float):
    import jax.numpy as jnp

    if isinstance(tree, Atom):
        x = jnp.asarray(signals[tree.signal], dtype=jnp.float64)
        x = x.reshape(x.shape[0], -1)
        if tree.op == "<=":
            return tree.value - jnp.max(x, axis=1)
        return jnp.min(x, axis=1) - tree.value
    if isinstance(tree, Unary):
        return -_rho(tree.arg, signals, step)
    if isinstance(tree, Binary):
        a, b = _rho(tree.left, signals, step), _rho(tree.right, signals, step)
        if tree.op == "and":
            return jnp.minimum(a, b)
        if tree.op == "or":
            return jnp.maximum(a, b)
        return jnp.maximum(-a, b)
    r = _rho(tree.arg, signals, step)
    eps = 1e-9
    lo = int(math.ceil(tree.low / step - eps))
    hi = None if math.isinf(tree.high) else int(math.floor(tree.high / step + eps))
    if hi is not None and hi < lo:
        raise StlError(
            f"STL interval [{tree.low:g}, {tree.high:g}] s holds no sample at the record interval "
            f"{step:g} s"
        )
    return _window(r, lo, hi, is_min=tree.op == "G")


def robustness(tree: Any, signals: dict[str, Any], step: float):
    """Robustness of a formula at the first sample; pure JAX (jittable, vmappable).

    Parameters
    ----------
    tree : Atom, Unary, Binary or Temporal
        A formula from :func:`parse`.
    signals : dict of str to array
        Recorded signals, the sample axis first (more axes: the worst component counts).
    step : float
        Time between samples [s].

    Returns
    -------
    jax.Array
        The robustness [units of the atoms]: >= 0 when the formula holds.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.array([3.0, 2.0, 0.5, 0.2, 0.4])
    >>> float(robustness(parse("F[0,2](G(x <= 1))"), {"x": x}, 1.0))  # from t = 2 s on: <= 0.5
    0.5
    >>> float(robustness(parse("G(x <= 1)"), {"x": x}, 1.0))
    -2.0
    """
    return _rho(tree, signals, float(step))[0]
