# %% [markdown]
# # First simulation and plot
#
# Load a built-in scenario, simulate it, and plot what happened. `cw-pd-fault` has four deputies on
# Clohessy-Wiltshire relative dynamics about a 7,000 km circular orbit, PD formation keeping towards a
# rotating desired formation, and thruster faults from 200 s on (loss of effectiveness on x, a bias on
# y). Run it from a terminal with `formation-ftc run cw-pd-fault --out out/run1`; here we use the
# Python API.

# %%
import matplotlib.pyplot as plt
from _common import save_figure, size

import formation_ftc as ftc

horizon = size(600.0, 300.0)  # s
scenario = ftc.load_scenario("cw-pd-fault", overrides={"simulation.horizon": horizon})
print(scenario.scenario.description)
print(f"{scenario.simulation.n_steps} steps of {scenario.simulation.dt} s")

# %% [markdown]
# `simulate_with_metrics` compiles the scenario into one jitted `lax.scan`, runs it and returns an
# `xarray.Dataset` (named dimensions `time`, `spacecraft`, `axis`; units as attributes; provenance
# such as the seed and the git commit) and the method's scalar metrics.

# %%
ds, metrics = ftc.simulate_with_metrics(scenario)
print(ds.position.dims, ds.position.attrs.get("units"))
for name in ("max_position_error", "final_position_error_mean", "delta_v_total"):
    print(f"{name:28s} {metrics[name]:.4g}")

# %%
fig, axes = plt.subplots(1, 2, figsize=(10, 4))
for sc in ds.spacecraft.values:
    p = ds.position.sel(spacecraft=sc)
    axes[0].plot(p.sel(axis="x"), p.sel(axis="y"), label=f"deputy {sc}")
axes[0].set(xlabel="x (radial) [m]", ylabel="y (along-track) [m]", title="Trajectories in LVLH")
axes[0].axis("equal")
axes[0].legend()
err = (ds.position_error**2).sum("axis") ** 0.5
for sc in ds.spacecraft.values:
    axes[1].semilogy(ds.time, err.sel(spacecraft=sc), label=f"deputy {sc}")
axes[1].axvline(200.0, color="k", ls="--", lw=0.8)
axes[1].set(xlabel="t [s]", ylabel="|position error| [m]", title="Tracking error (fault at 200 s)")
fig.tight_layout()
save_figure(fig, "trajectories")
