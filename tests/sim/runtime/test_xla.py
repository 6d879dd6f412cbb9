"""XLA:CPU compile options (sim/runtime/xla.py): which options apply, that an unknown one is dropped instead of
aborting, and that compiling with them leaves the arithmetic alone.

Independent truth for the last point: the same program compiled by plain ``jax.jit`` (XLA's defaults).
The options only change which kernels XLA emits (no fast-math), so a 1-orbit free drift, whose state is
a sum of bounded trigonometric terms, must agree to 1e-12 relative (a few units in the last place
accumulated over the orbit's steps); the closed form itself is checked in tests/core/test_cw.py.
"""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys

import jax
import numpy as np
import pytest

from formation_ftc.api import build_loop, load_scenario
from formation_ftc.sim import batch as batch_mod
from formation_ftc.sim.runtime import xla


def test_options_on_cpu_and_switch_off(monkeypatch):
    monkeypatch.delenv(xla.ENV_SWITCH, raising=False)
    opts = xla.compiler_options()

    assert opts == {k: v for k, v in xla.DEFAULT_OPTIONS.items() if xla._supported(k, v)}
    assert set(xla.compiler_options(fast_compile=True)) >= set(opts)
    monkeypatch.setenv(xla.ENV_SWITCH, "off")
    assert xla.compiler_options() == {} and xla.compiler_options(fast_compile=True) == {}


def test_unknown_option_is_dropped_not_fatal(monkeypatch):
    monkeypatch.setattr(
        xla, "DEFAULT_OPTIONS", {**xla.DEFAULT_OPTIONS, "xla_cpu_no_such_option": "1"}
    )
    assert "xla_cpu_no_such_option" not in xla.compiler_options()
    assert not xla._supported("xla_cpu_opt_preset", "NOT_A_PRESET")
    f = xla.jit(lambda x: 2.0 * x)
    assert float(f(np.float64(1.5))) == 3.0


def test_options_leave_the_arithmetic_alone():
    c = build_loop(load_scenario("cw-free-drift"))
    ours = jax.device_get(xla.jit(type(c).run)(c))
    plain = jax.device_get(jax.jit(type(c).run)(c))
    for a, b in zip(
        jax.tree_util.tree_leaves(ours["final"]),
        jax.tree_util.tree_leaves(plain["final"]),
        strict=True,
    ):
        a, b = np.asarray(a), np.asarray(b)
        if np.issubdtype(a.dtype, np.floating):
            scale = max(float(np.max(np.abs(b))), 1e-300)
            assert float(np.max(np.abs(a - b))) <= 1e-12 * scale


def test_elementwise_functions_give_the_same_bits_with_the_options():
    """The emitter options change how XLA writes loops, not its math: sin, cos, exp, log, sqrt, tanh, pow,
    arctan2 and arccos of 20,000 arguments are bit-identical to XLA's default build."""
    rng = np.random.default_rng(0)
    x, y = rng.uniform(-20.0, 20.0, 20_000), rng.uniform(0.01, 50.0, 20_000)

    def f(a, b):
        return (
            jax.numpy.sin(a),
            jax.numpy.cos(a),
            jax.numpy.exp(a),
            jax.numpy.log(b),
            jax.numpy.sqrt(b),
            jax.numpy.tanh(a),
            b**1.5,
            jax.numpy.arctan2(a, 3.0),
            jax.numpy.arccos(a / 21.0),
        )

    ours = jax.device_get(xla.jit(f)(x, y))
    plain = jax.device_get(jax.jit(f)(x, y))
    for a, b in zip(ours, plain, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("fast", [False, True])
def test_batched_programs_ask_for_the_preset_of_their_controller(monkeypatch, fast):
    c = build_loop(
        load_scenario("cw-free-drift", {"simulation.horizon": 584.0, "simulation.record_every": 1})
    )
    monkeypatch.setattr(type(c.controller), "batch_fast_compile", fast, raising=False)
    seen = []
    real = xla.jit

    def spy(fn, **kw):
        seen.append(kw.get("fast_compile", False))
        return real(fn, **kw)

    monkeypatch.setattr(xla, "jit", spy)
    batch_mod.clear()
    runs = [dataclasses.replace(c, seed=np.uint32(s)) for s in (1, 2)]
    P, axes = batch_mod.stack_params(runs)
    out = batch_mod.batched_run(c, axes, 2)(P)
    batch_mod.clear()
    assert seen == [fast]
    assert np.asarray(out["diverged_step"]).tolist() == [-1, -1]


_DRAWS = """
import json, sys
import formation_ftc, jax, jax.numpy as jnp
from formation_ftc.sim.runtime import xla
xla.use_unrolled_threefry()  # what a configured runtime does (off: FORMATION_FTC_XLA_OPTIONS=off)
key = jax.random.fold_in(jax.random.PRNGKey(7), 123)
k1, k2 = jax.random.split(key)
draws = {"normal": jax.random.normal(k1, (4, 3), jnp.float64), "uniform": jax.random.uniform(k2, (5,), jnp.float64),
         "bits": jax.random.bits(key, (6,), jnp.uint32).astype(jnp.float64),
         "vmapped": jax.jit(jax.vmap(lambda s: jax.random.normal(jax.random.PRNGKey(s), (2,))))(jnp.arange(3))}
json.dump({k: [float(x) for x in jnp.ravel(v)] for k, v in draws.items()}, sys.stdout)
"""


def test_unrolled_threefry_draws_the_same_numbers(monkeypatch):
    """The unrolled threefry lowering (this process, package default) against JAX's own rolled CPU
    lowering (a process with the options off): the same random numbers, bit for bit. On a JAX without
    the lowering internals, the registration must report that it kept JAX's own lowering."""
    monkeypatch.delenv(xla.ENV_SWITCH, raising=False)
    try:
        from jax._src.random import threefry2x32 as threefry

        has_internals = hasattr(threefry, "_threefry2x32_lowering_rule")
    except ImportError:
        has_internals = False
    assert (
        xla.use_unrolled_threefry() is has_internals
    )  # registered exactly when the internals exist
    env_on = {k: v for k, v in os.environ.items() if k != xla.ENV_SWITCH}
    runs = {}
    for name, env in (("unrolled", env_on), ("rolled", {**env_on, xla.ENV_SWITCH: "off"})):
        out = subprocess.run(
            [sys.executable, "-c", _DRAWS], env=env, capture_output=True, text=True, check=True
        )
        runs[name] = json.loads(out.stdout)
    assert runs["unrolled"] == runs["rolled"]
