# %% [markdown]
# # A batch of runs on the GPU (or the CPU)
#
# A scenario builds a closed loop whose run is a pure function of the loop. `sim.batch.stack_params`
# stacks the leaves that differ between runs (here the PD gains and the noise seed) and keeps the
# shared ones once; `sim.batch.batched_run` is the jitted `vmap` of the run. The same code runs on a GPU when JAX
# sees one (`pip install -e '.[gpu]'` in the clone); otherwise on the CPU, as in this page's build.

# %%
import time

import jax
import numpy as np
from _common import size

import formation_ftc as ftc
from formation_ftc.api import build_loop
from formation_ftc.sim.batch import batched_run, stack_params

print("JAX devices:", jax.devices())
n_runs = size(1024, 16)
rng = np.random.default_rng(0)
kps = rng.uniform(1.0, 4.0, n_runs)
loops = []
for k, kp in enumerate(kps):
    scn = ftc.load_scenario(
        "cw-pd-fault",
        overrides={"simulation.horizon": 200.0, "controller.kp": float(kp), "simulation.seed": k},
    )
    loops.append(build_loop(scn))
batch, in_axes = stack_params(loops)
run = batched_run(loops[0], in_axes, n_runs)

# %%
t0 = time.perf_counter()
out = jax.block_until_ready(run(batch))
first = time.perf_counter() - t0
t0 = time.perf_counter()
out = jax.block_until_ready(run(batch))
second = time.perf_counter() - t0
steps = n_runs * scn.simulation.n_steps
print(
    f"{n_runs} runs x {scn.simulation.n_steps} steps: {first:.2f} s with compilation, {second:.3f} s after "
    f"({steps / second:,.0f} run-steps/s on {jax.devices()[0].platform})"
)

# %% [markdown]
# Each run's metrics come from its slice of the batched output.

# %%
per_run = [
    loops[r].metric_values(jax.tree_util.tree_map(lambda a, r=r: np.asarray(a[r]), out))
    for r in range(n_runs)
]
errs = np.array([m["final_position_error_mean"] for m in per_run])
order = np.argsort(kps)
print("kp [N/m]   final mean error [m]")
for r in order[:: max(1, n_runs // 8)]:
    print(f"{kps[r]:8.3f}   {errs[r]:.5f}")
