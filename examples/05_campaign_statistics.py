# %% [markdown]
# # A 1,000-run Monte Carlo campaign and its statistics
#
# A campaign is a base scenario plus sampled and swept fields. Runs are grouped into `vmap` batches,
# stored as Parquet files as they finish (a killed campaign resumes), and every run's inputs derive
# from the campaign seed and its run id only. The same campaign from a terminal:
# `formation-ftc campaign run FILE.toml --out DIR` and `formation-ftc campaign report DIR`.

# %%
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
from _common import save_figure, size

from formation_ftc.campaign import run_campaign, write_report

runs = size(500, 20)  # per kd value: 2 x 500 = 1,000 runs at full size
campaign = {
    "campaign": {
        "name": "kp-kd-study",
        "base": "cw-pd-fault",
        "runs": runs,
        "seed": 7,
        "chunk_size": min(runs, 250),
        "metrics": ["max_position_error", "final_position_error_mean", "delta_v_total"],
    },
    "overrides": {"simulation.horizon": size(300.0, 100.0)},
    "sample": {
        "controller.kp": {"dist": "uniform", "low": 1.0, "high": 4.0},  # N/m
        "controller.kd": {"grid": [30.0, 60.0]},  # N s/m
        "plant.mass.0": {"dist": "normal", "mean": 100.0, "std": 5.0, "low": 80.0},  # kg
    },
}
out = Path(tempfile.mkdtemp()) / "kp-kd-study"
outcome = run_campaign(campaign, out)
print(outcome)

# %% [markdown]
# `outcome.results` is a pandas DataFrame: one row per run with its inputs (`input:<path>`), status
# and metrics (`metric:<name>`).

# %%
df = outcome.results
print(df.groupby("input:controller.kd")["metric:final_position_error_mean"].describe().round(4))

# %%
fig, ax = plt.subplots(figsize=(7, 4))
for kd, group in df.groupby("input:controller.kd"):
    ax.scatter(
        group["input:controller.kp"], group["metric:delta_v_total"], s=8, label=f"kd = {kd:g} N s/m"
    )
ax.set(xlabel="kp [N/m]", ylabel="total delta-v [m/s]", title=f"{len(df)} runs")
ax.legend()
fig.tight_layout()
save_figure(fig, "delta_v_vs_kp")

# %% [markdown]
# `write_report` writes `summary.json`, `summary.csv` and sensitivity plots into `DIR/report`.

# %%
summary, figures = write_report(out, plots=False)
print(sorted(summary))
