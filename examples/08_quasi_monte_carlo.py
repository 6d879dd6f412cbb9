# %% [markdown]
# # Sweep a gain with quasi-Monte Carlo sampling
#
# With `sampling = "sobol"` (scrambled Sobol' points) or `"lhs"` (Latin hypercube) in `[campaign]`,
# the sampled fields fill their range evenly instead of at random, so averages over the runs converge
# faster. Each run's values still depend only on the campaign seed and the run's replicate number.

# %%
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from _common import save_figure, size

from formation_ftc.campaign import make_plan, run_campaign

runs = size(256, 16)


def campaign(sampling):
    return {
        "campaign": {
            "name": f"kp-{sampling}",
            "base": "cw-pd-fault",
            "runs": runs,
            "seed": 3,
            "chunk_size": runs,
            "sampling": sampling,
            "metrics": ["delta_v_total"],
        },
        "overrides": {"simulation.horizon": 100.0},
        "sample": {
            "controller.kp": {"dist": "uniform", "low": 1.0, "high": 4.0},
            "controller.kd": {"dist": "loguniform", "low": 10.0, "high": 100.0},
        },
    }


# %% [markdown]
# The first 16 points of each design in the (kp, kd) plane: Sobol' and LHS put one point in every
# column of a 16-column grid, pseudo-random sampling leaves gaps and clusters.

# %%
fig, axes = plt.subplots(1, 3, figsize=(12, 3.6), sharey=True)
for ax, sampling in zip(axes, ["random", "sobol", "lhs"], strict=True):
    plan = make_plan(campaign(sampling), runs=16)
    pts = np.array(
        [
            [plan.run_inputs(r).values["controller.kp"], plan.run_inputs(r).values["controller.kd"]]
            for r in range(16)
        ]
    )
    ax.scatter(pts[:, 0], pts[:, 1])
    for x in np.linspace(1.0, 4.0, 17):
        ax.axvline(x, color="0.85", lw=0.5)
    ax.set(title=sampling, xlabel="kp [N/m]", yscale="log")
axes[0].set_ylabel("kd [N s/m]")
fig.tight_layout()
save_figure(fig, "designs")

# %% [markdown]
# Running both campaigns and plotting the running mean of the total delta-v against the number of runs
# shows how each estimate settles (at full size, 256 runs; the documentation build runs 16).

# %%
means = {}
for sampling in ["random", "sobol"]:
    out = run_campaign(campaign(sampling), Path(tempfile.mkdtemp()) / sampling)
    dv = out.results.sort_values("run_id")["metric:delta_v_total"].to_numpy()
    means[sampling] = np.cumsum(dv) / np.arange(1, len(dv) + 1)
    print(f"{sampling:6s}: mean total delta-v over {len(dv)} runs = {dv.mean():.4f} m/s")
fig, ax = plt.subplots(figsize=(7, 4))
for sampling, m in means.items():
    ax.plot(np.arange(1, len(m) + 1), m, label=sampling)
ax.set(xscale="log", xlabel="runs", ylabel="running mean of total delta-v [m/s]")
ax.legend()
fig.tight_layout()
save_figure(fig, "running_mean")
