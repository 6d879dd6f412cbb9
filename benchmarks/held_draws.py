"""Random draws held over a step, evaluated once per step (``formation_ftc.sim.loop._once``) against
the plain program in which XLA fuses each draw into every RK stage that reads it, in one run.

For each case the closed loop is traced twice -- as the package builds it, and with ``_once`` replaced
by the identity (the reference: the draw's producers are free to be fused into, and duplicated in,
every consumer) -- and both are compiled (persistent cache off) and timed alternately (fastest of
``--repeats``; a shared 2-core machine varies by 10-40 % between single passes). Printed per case:
compile time of each, microseconds per run-step of each, their ratios (package / reference; < 1 is
better), the number of optimised-HLO fusions that evaluate a normal draw (an ``erf_inv`` in their
op names), and the largest difference of the final state relative to its leaf's scale (the same
operations; moved fusion boundaries may round differently in the last bit).

Cases: single runs of mehrabian-isolation (FDI noise and disturbance), compose-li2020-on-cw (sensor
noise on a chattering adaptive law), azizi2009-llfr with measurement noise on, and the Mehrabian
seed-study batch (3 cases x 20 seeds, its fast-compile preset).

Run: ``python benchmarks/held_draws.py [--horizon-scale 1.0] [--repeats 3]``. Exit status 0 always
(a measurement, not a gate).
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import time
from pathlib import Path

os.environ.setdefault("FORMATION_FTC_JAX_CACHE", "off")  # every compile measured cold

import jax  # noqa: E402
import numpy as np  # noqa: E402

from formation_ftc.api import build_loop, load_scenario  # noqa: E402
from formation_ftc.sim import loop  # noqa: E402
from formation_ftc.sim.runtime import xla  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from xla_options import _mehrabian  # noqa: E402  (the Mehrabian seed-study batch, built as there)


def _single(name: str, horizon: float, overrides: dict | None = None):
    def make(scale: float):
        c = build_loop(
            load_scenario(name, {**(overrides or {}), "simulation.horizon": horizon * scale})
        )
        return f"{name} (single run)", type(c).run, c, c.n_steps, False

    return make


CASES = [
    _single("mehrabian-isolation", 20.0),
    _single("compose-li2020-on-cw", 100.0),
    _single(
        "azizi2009-llfr",
        30.0,
        {"sensors.position_noise_std": 1e-5, "sensors.velocity_noise_std": 1e-5},
    ),
    _mehrabian,
]


def _normal_fusions(hlo: str) -> int:
    """Fusion computations of the optimised HLO whose op names include an inverse-erf (a normal draw)."""
    return sum(
        1 for comp in re.split(r"\n(?=\S)", hlo) if comp.startswith("%fused") and "erf_inv" in comp
    )


def _final(out) -> list[np.ndarray]:
    return [
        np.asarray(x, dtype=float)
        for x in jax.tree_util.tree_leaves(out["final"])
        if np.asarray(x).dtype.kind == "f"
    ]


def _build(case, scale: float, materialise: bool):
    """(label, executable, params, run-steps, compile seconds, normal-draw fusions) with ``_once`` as
    the package has it (``materialise``) or replaced by the identity."""
    original = loop._once
    if not materialise:
        loop._once = lambda k, values: values
    try:
        label, fn, params, run_steps, fast = case(scale)
        jax.clear_caches()
        lowered = jax.jit(fn).lower(params)
        t0 = time.perf_counter()
        exe = lowered.compile(compiler_options=xla.compiler_options(fast_compile=fast))
        compile_s = time.perf_counter() - t0
    finally:
        loop._once = original
    return label, exe, params, run_steps, compile_s, _normal_fusions(exe.as_text())


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--horizon-scale", type=float, default=1.0, help="scale every case's horizon")
    ap.add_argument("--repeats", type=int, default=3, help="alternate timed passes per executable")
    args = ap.parse_args(argv)
    print(
        f"{'case':44s} {'compile ref / pkg':>18s} {'ratio':>6s} {'us/run-step ref / pkg':>22s} {'ratio':>6s}"
        f"  {'normal fusions':>14s}  final state"
    )
    for case in CASES:
        ref = _build(case, args.horizon_scale, materialise=False)
        pkg = _build(case, args.horizon_scale, materialise=True)
        outs = [jax.device_get(jax.block_until_ready(b[1](b[2]))) for b in (ref, pkg)]
        best = [float("inf")] * 2
        for _ in range(args.repeats):
            for i, b in enumerate((ref, pkg)):
                t0 = time.perf_counter()
                jax.block_until_ready(b[1](b[2]))
                best[i] = min(best[i], time.perf_counter() - t0)
        diffs = []
        for a, b in zip(_final(outs[0]), _final(outs[1]), strict=True):
            fin = np.isfinite(a) & np.isfinite(b)
            scale = float(np.max(np.abs(a[fin]))) if fin.any() else 0.0
            diffs.append(float(np.max(np.abs(a[fin] - b[fin]))) / scale if scale > 0 else 0.0)
        worst = max(diffs, default=0.0)
        us = [t / ref[3] * 1e6 for t in best]
        print(
            f"{ref[0]:44s} {ref[4]:7.2f} / {pkg[4]:5.2f} s {pkg[4] / ref[4]:6.2f} {us[0]:10.2f} / {us[1]:8.2f}"
            f" {us[1] / us[0]:6.2f}  {ref[5]:6d} / {pkg[5]:<5d}  "
            f"{'bitwise' if worst == 0.0 else f'max diff {worst:.1e} of scale'}",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
