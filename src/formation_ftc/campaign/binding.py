"""Campaigns vary parameters, not scenarios: a sampled field's path is the leaf it sets.

The runs of one structural group share one template build (a
:class:`~formation_ftc.sim.loop.ClosedLoop`) and each sampled field is written into the leaf its
path names:

* ``slot.field`` is ``loop.<slot>.<field>``: the attribute ``field`` of the slot's component, or
  of a component it wraps one level down (``AccelerationToForce.law``); exactly one match (a section's
  field names are its component's field names: the TOML path is the pytree path);
* ``slot.field.k`` (``.k.l``) is one element of that leaf; ``slot.field`` as one number fills
  every element (a per-spacecraft field); ``simulation.seed`` is the loop's ``seed``; the other
  ``simulation.*`` fields are structural.

:func:`bind_fields` checks on the template that each leaf holds its field's value: a derived leaf
(an orbit radius turned into a mean motion, an onset snapped to the step grid, a unit conversion)
or a path naming no leaf is not bound, and the group is built run by run. The runner also builds
each chunk's last run the slow way and compares it with the bound one (:func:`params_close`): a
field that moves another leaf too, or interacting fields, fall back the same way. Nothing is
silently wrong.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import jax
import numpy as np

__all__ = ["FieldBinding", "bind_fields", "apply_bindings", "take_run", "params_close"]

_RTOL = 1e-12
SEED_PATH = "simulation.seed"


@dataclass(frozen=True)
class FieldBinding:
    """Where a sampled field is written: elements ``index`` (flat) of parameter leaf ``leaf``."""

    path: str  # the campaign's dotted path
    leaf: int  # position in the flattened parameter pytree
    index: np.ndarray  # flat element indices inside the leaf


def _leaves(params) -> tuple[list[np.ndarray], Any]:
    leaves, treedef = jax.tree_util.tree_flatten(params)
    return [np.asarray(x) for x in leaves], treedef


def _leaf_keys(loop) -> dict[str, int]:
    """Key path of every leaf of ``loop`` (``.plant.mass``) -> its position in the flattened tree."""
    flat, _ = jax.tree_util.tree_flatten_with_path(loop)
    return {jax.tree_util.keystr(kp): n for n, (kp, _) in enumerate(flat)}


def _leaf_of(path: str, keys: Mapping[str, int]) -> tuple[int, tuple[int, ...]] | None:
    """(leaf position, element indices) named by a campaign path, or None when it names no leaf."""
    if path == SEED_PATH:
        return (keys[".seed"], ()) if ".seed" in keys else None
    slot, _, rest = path.partition(".")
    name, *idx = rest.split(".")
    if slot == "simulation" or not name or not all(i.lstrip("-").isdigit() for i in idx):
        return None
    # the slot's component itself, or a component it wraps one level down: exactly one match
    own, wrapped = f".{slot}.{name}", re.compile(rf"\.{re.escape(slot)}\.\w+\.{re.escape(name)}")
    found = [n for k, n in keys.items() if k == own or wrapped.fullmatch(k)]
    if len(found) != 1:
        return None
    return found[0], tuple(int(i) for i in idx)


def bind_fields(loop, values: Mapping[str, float]) -> dict[str, FieldBinding] | None:
    """Bindings of every field of ``values`` in the template ``loop`` built with those values, or
    None when a field names no leaf whose elements hold its value (the group is then built per run),
    or two fields write the same element.

    Parameters
    ----------
    loop : ClosedLoop
        The template's compiled parameters.
    values : Mapping[str, float]
        Dotted path -> the template's value of each sampled field (``simulation.seed`` included).

    Returns
    -------
    dict[str, FieldBinding] or None
        One binding per field.
    """
    keys = _leaf_keys(loop)
    leaves, _ = _leaves(loop)
    out: dict[str, FieldBinding] = {}
    seen: set[tuple[int, int]] = set()
    for path, v in values.items():
        where = _leaf_of(path, keys)
        if where is None:
            return None
        n, idx = where
        leaf = leaves[n]
        try:
            index = np.arange(leaf.size).reshape(leaf.shape)[idx].ravel()
        except IndexError:
            return None
        if index.size == 0 or not np.all(leaf.ravel()[index] == v):
            return None  # a derived leaf (or another element layout): not the field's value
        elements = {(n, i) for i in index.tolist()}
        if elements & seen:
            return None  # two fields write the same element
        seen |= elements
        out[path] = FieldBinding(path, n, index)
    return out


def apply_bindings(
    template, bindings: Mapping[str, FieldBinding], values: Mapping[str, np.ndarray], size: int
) -> tuple[Any, Any]:
    """Batch of ``size`` parameter pytrees: the template with every bound field's per-run values
    written into its elements. Returns ``(batch, in_axes)`` as
    :func:`formation_ftc.sim.batch.stack_params`: untouched leaves stay shared (``in_axes`` None)."""
    leaves, treedef = _leaves(template)
    axes: list[int | None] = [None] * len(leaves)
    batched: dict[int, np.ndarray] = {}
    for path, b in bindings.items():
        v = np.asarray(values[path], dtype=np.float64)
        if v.shape[0] < size:  # pad with the last run (so every chunk has one shape)
            v = np.concatenate([v, np.repeat(v[-1:], size - v.shape[0])])
        base = leaves[b.leaf]
        arr = batched.get(b.leaf)
        if arr is None:
            arr = np.broadcast_to(base.reshape(-1), (size, base.size)).copy()
            batched[b.leaf] = arr
        arr[:, b.index] = v[:, None].astype(base.dtype) if base.dtype.kind in "ui" else v[:, None]
    for n, arr in batched.items():
        leaves[n] = arr.reshape((size,) + leaves[n].shape).astype(leaves[n].dtype)
        axes[n] = 0
    return jax.tree_util.tree_unflatten(treedef, leaves), jax.tree_util.tree_unflatten(
        treedef, axes
    )


def take_run(batch, in_axes, j: int):
    """Parameters of run ``j`` of a batch from :func:`apply_bindings`."""
    leaves, treedef = jax.tree_util.tree_flatten(batch)
    axes = treedef.flatten_up_to(in_axes)  # type: ignore[attr-defined]  # PyTreeDef unresolved in jax stubs  # fields that are None are empty subtrees, not leaves
    return jax.tree_util.tree_unflatten(
        treedef, [a if ax is None else np.asarray(a)[j] for a, ax in zip(leaves, axes, strict=True)]
    )


def params_close(a, b) -> bool:
    """Same structure and every leaf equal to 1e-12 relative (exact for integers)."""
    la, ta = _leaves(a)
    lb, tb = _leaves(b)
    return ta == tb and all(
        x.shape == y.shape
        and (
            np.allclose(x, y, rtol=_RTOL, atol=0.0, equal_nan=True)
            if x.dtype.kind in "fc"
            else np.array_equal(x, y)
        )
        for x, y in zip(la, lb, strict=True)
    )
