"""Builders of the condition rows the papers' ``conditions`` modules return
(:class:`~formation_ftc.registry.Condition`): an exact comparison, an informative row, and a condition
sampled for a violation that a verified bound may prove; and the list format their values share."""

from __future__ import annotations

from typing import Any

from formation_ftc.registry import Condition


def fmt_list(values: Any) -> str:
    """``values`` as ``[a, b, ...]``, each to 4 significant digits."""
    return "[" + ", ".join(f"{x:.4g}" for x in values) + "]"


def exact(
    name: str,
    reference: str,
    value: str,
    requirement: str,
    holds: Any,
    detail: str,
    required: bool = True,
) -> Condition:
    """A condition decided by exact arithmetic (basis "exact"); ``holds`` as computed (None: not
    evaluated)."""
    return Condition(name, reference, value, requirement, holds, required, detail, basis="exact")


def informative(
    name: str, reference: str, value: str, requirement: str, holds: Any, detail: str
) -> Condition:
    """A condition shown for information only (basis "informative", not required)."""
    return Condition(name, reference, value, requirement, holds, False, detail, basis="informative")


def sampled_or_verified(
    name: str,
    reference: str,
    value: str,
    requirement: str,
    violation: str | None,
    proof: tuple[str, str] | None,
    unproven: str,
    required: bool = True,
) -> Condition:
    """A condition sampled for a violation and bounded by a verified computation, in that order:

    * ``violation`` (the detail of a violation found by sampling, None: none found): it fails, basis
      "sampled" (a violation found is real);
    * else ``proof`` ((text appended to the value, detail), None: the bound is inconclusive): it holds,
      basis "verified";
    * else it is unproven (holds None, basis "sampled", detail ``unproven``).
    """
    if violation is not None:
        return Condition(
            name, reference, value, requirement, False, required, violation, basis="sampled"
        )
    if proof is not None:
        shown, detail = proof
        return Condition(
            name, reference, value + shown, requirement, True, required, detail, basis="verified"
        )
    return Condition(name, reference, value, requirement, None, required, unproven, basis="sampled")
