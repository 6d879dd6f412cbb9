"""Campaigns vary parameters, not scenarios: bind sampled scenario fields to parameter leaves.

A campaign run differs from its base scenario only in a few numeric fields (a gain, a mass, a fault
onset, the seed). Rebuilding and re-validating the whole scenario for every run costs far more than
the run itself on a GPU, so :class:`FieldBinding` finds, once per structural group, where each sampled
field lands in the compiled parameter pytree (a :class:`~formation_ftc.sim.loop.ClosedLoop`) and how:

1. *probe*: the scenario is built at three values of the field (the template's value and two
   others inside the sampler's validated range); the parameter leaves whose elements change are the
   field's targets, and each changed element must be an affine function ``a v + b`` of the field value
   (identity for a gain or a mass; a scale for a unit conversion) -- checked on the third value;
2. *apply*: for a batch of runs, the values of every bound field are written into the target
   elements as arrays (``a v + b``; exactly ``v`` where ``a = 1, b = 0``) -- a few numpy operations per
   chunk, no per-run Python;
3. *verify*: the chunk's last run is also built the slow way and its parameters compared with the
   bound ones (to 1e-12 relative); any difference -- a field whose effect is not affine (e.g. a fault
   onset snapped to the step grid, an orbit radius turned into a mean motion), a field that changes
   the structure, two fields that interact -- makes the group fall back to one build per run.

A field that is not bindable falls back the same way; nothing is ever silently wrong.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import jax
import numpy as np

__all__ = [
    "FieldBinding",
    "Target",
    "bind_field",
    "bind_fields",
    "apply_bindings",
    "take_run",
    "params_close",
]

_RTOL = 1e-12


@dataclass(frozen=True)
class Target:
    """Elements of one parameter leaf set by a field: ``leaf.flat[index] = scale * v + offset``."""

    leaf: int  # position in the flattened parameter pytree
    index: np.ndarray  # flat element indices inside the leaf
    scale: np.ndarray
    offset: np.ndarray

    @property
    def identity(self) -> bool:
        return bool(np.all(self.scale == 1.0) and np.all(self.offset == 0.0))


@dataclass(frozen=True)
class FieldBinding:
    path: str
    targets: tuple[Target, ...]


def _leaves(params) -> tuple[list[np.ndarray], Any]:
    leaves, treedef = jax.tree_util.tree_flatten(params)
    return [np.asarray(x) for x in leaves], treedef


def _probe_values(v0: float, candidates: Sequence[float], integer: bool) -> list[float]:
    """Two probe values different from ``v0`` (validated extremes first, then small steps)."""
    out: list[float] = []
    for c in candidates:
        if c is not None and np.isfinite(c) and c != v0 and c not in out:
            out.append(float(c))
    step = 1.0 if integer else max(abs(v0) * 1e-3, 1e-6)
    k = 1
    while len(out) < 2:
        c = v0 + k * step
        if c not in out:
            out.append(c)
        k += 1
    return out[:2]


def bind_field(
    build: Callable[[Mapping[str, Any]], Any],
    values0: Mapping[str, Any],
    path: str,
    candidates: Sequence[float],
    integer: bool = False,
) -> FieldBinding | None:
    """Affine binding of ``path`` or None when the field changes the structure or is not affine.

    ``build(values)`` returns the compiled parameter pytree for the template values with ``values``
    applied (it may raise for invalid values: the field is then not bindable).
    """
    v0 = float(values0[path])
    probes = _probe_values(v0, candidates, integer)
    try:
        p0 = build(values0)
        p1 = build({**values0, path: int(probes[0]) if integer else probes[0]})
        p2 = build({**values0, path: int(probes[1]) if integer else probes[1]})
    except Exception:  # noqa: BLE001 - an invalid probe: fall back to per-run builds
        return None
    l0, t0 = _leaves(p0)
    l1, t1 = _leaves(p1)
    l2, t2 = _leaves(p2)
    if (
        t0 != t1
        or t0 != t2
        or any(a.shape != b.shape or a.shape != c.shape for a, b, c in zip(l0, l1, l2, strict=True))
    ):
        return None  # structural field
    v1, v2 = probes
    targets = []
    for n, (a0, a1, a2) in enumerate(zip(l0, l1, l2, strict=True)):
        f0, f1, f2 = (np.asarray(x, dtype=np.float64).ravel() for x in (a0, a1, a2))
        changed = np.flatnonzero((f0 != f1) | (f0 != f2))
        if changed.size == 0:
            continue
        scale = (f1[changed] - f0[changed]) / (v1 - v0)
        offset = f0[changed] - scale * v0
        pred = scale * v2 + offset
        if not np.allclose(pred, f2[changed], rtol=1e-10, atol=0.0):
            return None
        # snap exact identities (a gain or a mass copied into a leaf)
        ident = np.isclose(scale, 1.0, rtol=1e-12, atol=0) & np.isclose(
            offset, 0.0, rtol=0, atol=1e-12 * max(1.0, abs(v0))
        )
        scale = np.where(ident, 1.0, scale)
        offset = np.where(ident, 0.0, offset)
        targets.append(Target(n, changed, scale, offset))
    return FieldBinding(path, tuple(targets))


def bind_fields(
    build: Callable[[Mapping[str, Any]], Any],
    values0: Mapping[str, Any],
    candidates: Mapping[str, Sequence[float]],
    integer: Mapping[str, bool],
) -> dict[str, FieldBinding] | None:
    """Bindings of every field in ``candidates`` (None when any field is not bindable, or two fields
    write the same element)."""
    out = {}
    seen: dict[tuple[int, int], str] = {}
    for path, cands in candidates.items():
        b = bind_field(build, values0, path, cands, integer.get(path, False))
        if b is None:
            return None
        for t in b.targets:
            for i in t.index.tolist():
                if (t.leaf, i) in seen:
                    return None
                seen[(t.leaf, i)] = path
        out[path] = b
    return out


def apply_bindings(
    template, bindings: Mapping[str, FieldBinding], values: Mapping[str, np.ndarray], size: int
) -> tuple[Any, Any]:
    """Batch of ``size`` parameter pytrees: the template with every bound field's per-run values
    written into its targets. Returns ``(batch, in_axes)`` as :func:`formation_ftc.sim.batch.stack_params`:
    untouched leaves stay shared (``in_axes`` None)."""
    leaves, treedef = _leaves(template)
    axes: list[int | None] = [None] * len(leaves)
    batched: dict[int, np.ndarray] = {}
    for path, b in bindings.items():
        v = np.asarray(values[path], dtype=np.float64)
        if v.shape[0] < size:  # pad with the last run (so every chunk has one shape)
            v = np.concatenate([v, np.repeat(v[-1:], size - v.shape[0])])
        for t in b.targets:
            base = leaves[t.leaf]
            arr = batched.get(t.leaf)
            if arr is None:
                arr = np.broadcast_to(base.reshape(-1), (size, base.size)).copy()
                batched[t.leaf] = arr
            new = v[:, None] if t.identity else v[:, None] * t.scale[None, :] + t.offset[None, :]
            arr[:, t.index] = new.astype(base.dtype) if base.dtype.kind in "ui" else new
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
    if ta != tb:
        return False
    for x, y in zip(la, lb, strict=True):
        if x.shape != y.shape:
            return False
        if x.dtype.kind in "fc":
            if not np.allclose(x, y, rtol=_RTOL, atol=0.0, equal_nan=True):
                return False
        elif not np.array_equal(x, y):
            return False
    return True
