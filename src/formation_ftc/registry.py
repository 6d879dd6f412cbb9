"""The method / reproduction registry and the contracts that plug a paper into the toolkit.

A **method** turns a validated scenario into a :class:`~formation_ftc.sim.loop.ClosedLoop`; the generic
:func:`formation_ftc.simulate`, the ``run``/``check`` commands and Monte Carlo campaigns all go through
it. A **reproduction** runs a paper's study and returns a :class:`PaperReport` (figures, published vs
reproduced rows, condition checks) that ``formation-ftc reproduce`` and the HTML report consume.

Plug-ins register themselves when their module is imported. :func:`load_plugins` imports every module
named by an entry point of the group ``formation_ftc.plugins`` in the installed package metadata --
the built-in methods and papers declare theirs in ``pyproject.toml``, and a third-party package adds
its own the same way (see ``docs/extending.md``). A plug-in that fails to import is reported
(:data:`PLUGIN_ERRORS`), never fatal.
"""

from __future__ import annotations

import dataclasses
import importlib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel

# a condition is what a method's check and a component's ``conditions(loop)`` return: defined with the
# component contract (a layer below the components), public here
from formation_ftc.sim.contract import BASES, CERTIFYING_BASES, Condition

if TYPE_CHECKING:
    from formation_ftc.sim.loop import ClosedLoop


__all__ = [
    "Method",
    "Condition",
    "BASES",
    "CERTIFYING_BASES",
    "ComparisonRow",
    "basis_holds",
    "Figure",
    "PaperReport",
    "Reproduction",
    "register_method",
    "get_method",
    "methods",
    "register_reproduction",
    "resolve_reference",
    "get_reproduction",
    "reproductions",
    "load_plugins",
    "PAPER_MODULES",
    "PLUGIN_ERRORS",
    "PLUGIN_GROUP",
    "plugin_modules",
]


@dataclass(frozen=True)
class Method:
    name: str
    schema: type[BaseModel]
    build: Callable[[Any], ClosedLoop]
    description: str = ""
    check: Callable[[Any], list[Condition]] | None = None
    # (dataset, scenario, out_dir) -> PNGs
    plot: Callable[[Any, Any, Path], list[Path]] | None = None


#: Relations a verdict basis may use: name -> (arity, predicate on (lhs, rhs, tol)).
BASIS_RELATIONS: dict[str, Callable[..., bool]] = {
    "<": lambda a, b, tol=0.0: a < b,
    "<=": lambda a, b, tol=0.0: a <= b,
    ">": lambda a, b, tol=0.0: a > b,
    ">=": lambda a, b, tol=0.0: a >= b,
    "abs<=": lambda a, b, tol: abs(a - b) <= tol,  # |a - b| <= tol
    "rel<=": lambda a, b, tol: abs(a - b) <= tol * abs(b),  # |a - b| <= tol |b|
    "true": lambda a, b=None, tol=None: bool(a),
    "decreasing": lambda a, b=None, tol=None: all(y < x for x, y in zip(a, a[1:], strict=False)),
}


def basis_holds(basis: tuple) -> bool:
    """True when every clause ``(relation, lhs[, rhs[, tol]])`` of a verdict basis holds.

    Relations: ``<``, ``<=``, ``>``, ``>=`` (lhs against rhs), ``abs<=`` (|lhs - rhs| <= tol), ``rel<=``
    (|lhs - rhs| <= tol |rhs|), ``true`` (lhs is true) and ``decreasing`` (lhs is a strictly decreasing
    sequence). A NaN makes every numeric relation false.
    """
    if not basis:
        raise ValueError("empty verdict basis")
    for clause in basis:
        rel, *args = clause
        if rel not in BASIS_RELATIONS:
            raise ValueError(f"unknown relation {rel!r} in verdict basis {clause!r}")
        if not BASIS_RELATIONS[rel](*args):
            return False
    return True


def _plain(x: Any) -> Any:
    """numpy scalars / arrays -> Python floats / lists (the basis goes into report.json)."""
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if hasattr(x, "tolist"):
        return x.tolist()
    return x


@dataclass(frozen=True)
class ComparisonRow:
    """One row of a reproduction report: the paper's value, a reference value, ours, and the verdict.

    Columns
    -------
    quantity : what is compared.
    published : the paper's value *and where it is printed* (equation, figure, table or text), or "" when
        the paper prints no number for it. Never a number the paper did not print.
    ours : our value.
    criterion : the rule that decides the verdict, in words.
    verdict : "match", "differs" or "not stated" (no number to compare with).
    note : free text.
    reference : a value the paper does not print, with how it was obtained (documented in
        docs/references.md and recomputed there by an independent implementation).
    basis : the verdict's machine-checkable form, a tuple of clauses ``(relation, lhs[, rhs[, tol]])``
        (see :func:`basis_holds`). A row with verdict "match"/"differs" must carry one, and the verdict
        must equal what the basis gives: a verdict is computed, never written by hand. Build rows with
        :meth:`judged` to get the verdict from the basis.
    """

    quantity: str
    published: str
    ours: str
    criterion: str
    verdict: str
    note: str = ""
    reference: str = ""
    basis: tuple = ()

    def __post_init__(self) -> None:
        if self.verdict not in {"match", "differs", "not stated"}:
            raise ValueError(f"verdict must be match/differs/not stated, got {self.verdict!r}")
        if self.verdict != "not stated":
            if not self.basis:
                raise ValueError(f"row {self.quantity!r}: a {self.verdict!r} verdict needs a basis")
            want = "match" if basis_holds(self.basis) else "differs"
            if want != self.verdict:
                raise ValueError(
                    f"row {self.quantity!r}: verdict {self.verdict!r} but its basis gives {want!r}"
                )

    @classmethod
    def judged(
        cls,
        quantity: str,
        published: str,
        ours: str,
        criterion: str,
        basis: tuple,
        note: str = "",
        reference: str = "",
    ) -> ComparisonRow:
        """Row whose verdict is computed from ``basis`` ("match" when every clause holds)."""
        basis = tuple(tuple(_plain(x) for x in c) for c in basis)
        verdict = "match" if basis_holds(basis) else "differs"
        return cls(quantity, published, ours, criterion, verdict, note, reference, basis)

    @property
    def paper(self) -> str:
        """Alias of ``published``: the paper's printed value and where it is printed."""
        return self.published

    def as_dict(self) -> dict[str, Any]:
        return {**dataclasses.asdict(self), "basis": [list(c) for c in self.basis]}


@dataclass(frozen=True)
class Figure:
    path: str  # relative to the reproduction's output directory
    number: str  # the paper's figure number, e.g. "4" or "12"
    caption: str


@dataclass
class PaperReport:
    paper: str
    summary: dict[str, Any]
    rows: list[ComparisonRow] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)
    checks: list[Condition] = field(default_factory=list)
    scenarios: list[str] = field(default_factory=list)
    seeds: list[int] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    wall_time_s: float = 0.0


@dataclass(frozen=True)
class Reproduction:
    """A paper's reproducible study. ``run(out_dir, progress)`` writes figures into ``out_dir`` and
    returns the report; ``progress(done_fraction, message)`` may be called to update a progress bar."""

    paper: str
    title: str
    citation: str
    description: str
    errata: list[tuple[str, str]]
    run: Callable[[Path, Callable[[float, str], None]], PaperReport]


_METHODS: dict[str, Method] = {}
# a str: "module:attribute", see resolve_reference
_REPRODUCTIONS: dict[str, Reproduction | str] = {}

#: Display order of the built-in papers in the report (loading is by entry point, not by this list).
PAPER_MODULES = ["li2020", "yang2013", "gui2022", "mehrabian", "azizi2009"]
#: entry-point group that plug-ins (built-in and third-party) register under
PLUGIN_GROUP = "formation_ftc.plugins"


def register_method(method: Method) -> Method:
    _METHODS[method.name] = method
    return method


def get_method(name: str) -> Method:
    load_plugins()
    if name not in _METHODS:
        raise _unknown(f"method {name!r}; registered: {', '.join(sorted(_METHODS))}")
    return _METHODS[name]


def methods() -> dict[str, Method]:
    load_plugins()
    return dict(_METHODS)


def resolve_reference(ref: Any) -> Any:
    """``ref`` itself, or for a ``"module:attribute"`` string the attribute, its module imported on
    first use: a plug-in registers its conditions, figures and reproduction by such references so that
    importing it (which every lookup does) does not import JAX or matplotlib (issue 37)."""
    if isinstance(ref, str):
        module, _, attr = ref.partition(":")
        return getattr(importlib.import_module(module), attr)
    return ref


def register_reproduction(rep: Reproduction | str, paper: str | None = None) -> Reproduction | str:
    """Register a reproduction, or by a ``"module:attribute"`` reference (give ``paper``), imported
    when it is looked up."""
    if not isinstance(rep, str):
        paper = rep.paper
    elif paper is None:
        raise ValueError(f"register_reproduction({rep!r}): a reference needs its paper")
    _REPRODUCTIONS[paper] = rep
    return rep


def _resolved_reproduction(paper: str) -> Reproduction:
    rep = _REPRODUCTIONS[paper]
    if isinstance(rep, str):
        rep = _REPRODUCTIONS[paper] = resolve_reference(rep)
    return rep


def get_reproduction(paper: str) -> Reproduction:
    load_plugins()
    if paper not in _REPRODUCTIONS:
        raise _unknown(f"paper {paper!r}; valid: {', '.join(reproductions())}, all")
    return _resolved_reproduction(paper)


def reproductions() -> dict[str, Reproduction]:
    """The registered reproductions; one whose reference fails to import is recorded in
    :data:`PLUGIN_ERRORS` (under its module) and left out, like a plug-in that fails to import."""
    load_plugins()
    import traceback

    for paper, rep in list(_REPRODUCTIONS.items()):
        try:
            _resolved_reproduction(paper)
        except Exception:  # noqa: BLE001 - recorded and reported on lookup
            module = rep.partition(":")[0] if isinstance(rep, str) else paper
            PLUGIN_ERRORS[module] = traceback.format_exc()
            del _REPRODUCTIONS[paper]
    order = {p: k for k, p in enumerate(PAPER_MODULES)}
    return {
        paper: _resolved_reproduction(paper)
        for paper in sorted(_REPRODUCTIONS, key=lambda p: order.get(p, 99))
    }


_LOADED = False
#: plug-in module -> traceback text of an import that failed (the others still load)
PLUGIN_ERRORS: dict[str, str] = {}


def plugin_modules() -> list[str]:
    """Modules to import: every ``formation_ftc.plugins`` entry point's value (a module name), built-in
    ones first (the package declares its methods and papers as entry points in ``pyproject.toml``)."""
    from importlib.metadata import entry_points

    names = [ep.value.split(":")[0] for ep in entry_points(group=PLUGIN_GROUP)]
    own = [n for n in names if n.startswith("formation_ftc.")]
    return list(dict.fromkeys(own + [n for n in names if not n.startswith("formation_ftc.")]))


def load_plugins() -> None:
    """Import every plug-in module (idempotent).

    A module that fails to import is recorded in :data:`PLUGIN_ERRORS` and skipped, so one broken
    plug-in does not take the others (or the CLI) down; lookups of its names then report the error.
    """
    global _LOADED
    if _LOADED:
        return
    _LOADED = True
    import traceback

    for module in plugin_modules():
        try:
            importlib.import_module(module)
        except Exception:  # noqa: BLE001 - recorded and reported on lookup
            PLUGIN_ERRORS[module] = traceback.format_exc()


def _unknown(what: str) -> KeyError:
    """The KeyError of a lookup of an unknown ``what``, naming the plug-ins that failed to import."""
    failed = ", ".join(f"{m}: {tb.strip().splitlines()[-1]}" for m, tb in PLUGIN_ERRORS.items())
    return KeyError(
        f"unknown {what}" + (f" (plug-ins that failed to import: {failed})" if failed else "")
    )
