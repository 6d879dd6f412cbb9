"""Values held over a step are computed once (``formation_ftc.sim.loop._once``): the materialisation
must not change them, whether the step index is traced or batched under ``vmap`` (then the
conditional becomes a select of both branches), and it must pass empty leaves through.

The reference is the same draw compiled without it (``jax.jit``): an eager draw, evaluated operation
by operation, can differ from any compiled one in the last bit (the inverse-erf polynomial is
contracted differently), which is not what is tested here."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from formation_ftc.core.disturbances import gaussian_noise, run_key, step_key
from formation_ftc.sim.loop import _held, _once


def _draw(k):
    return {"d": gaussian_noise(step_key(run_key(7), k), (8, 3), 0.03), "none": None}


def test_held_draw_is_the_compiled_draw_bit_for_bit():
    plain = jax.jit(lambda k_: _draw(k_)["d"])
    for k in (0, 1, 12345):
        kk = jnp.asarray(k, dtype=jnp.int64)
        direct = np.asarray(plain(kk))
        held = jax.jit(lambda k_: _once(k_, _draw(k_)))(kk)
        assert np.array_equal(np.asarray(held["d"]), direct) and held["none"] is None
        # one draw read by several consumers in one program, as the RK stages read it
        stages = jax.jit(lambda k_: (lambda d: [d, 2.0 * d, d + 1.0])(_once(k_, _draw(k_))["d"]))(
            kk
        )
        assert np.array_equal(np.asarray(stages[0]), direct)
        np.testing.assert_array_equal(np.asarray(stages[1]), 2.0 * direct)  # exact: a power of two
        np.testing.assert_allclose(np.asarray(stages[2]), direct + 1.0, rtol=1e-15)
        # the draw is a standard normal scaled by 0.03 (not zeros, not the other branch)
        assert 0.0 < np.std(direct) < 0.1 and np.count_nonzero(direct) == direct.size


def test_batched_step_index_and_no_index():
    ks = jnp.arange(4, dtype=jnp.int64)
    batched = jax.jit(jax.vmap(lambda k_: _once(k_, _draw(k_))["d"]))(ks)
    plain = jax.jit(jax.vmap(lambda k_: _draw(k_)["d"]))(ks)
    assert np.array_equal(np.asarray(batched), np.asarray(plain))
    values = _draw(3)
    assert _held(None, values) is values  # no step index: the values as they are
