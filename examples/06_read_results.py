# %% [markdown]
# # Read results with xarray and pandas
#
# `formation-ftc run` (or `ftc.save_result`) writes `result.nc` (NetCDF, readable by any NetCDF tool)
# and `metrics.json`. The dataset carries the scenario it came from, the seed, the package versions
# and the git commit, so a result file is enough to rerun it.

# %%
import json
import tempfile
from pathlib import Path

import xarray as xr

import formation_ftc as ftc

out = Path(tempfile.mkdtemp()) / "run1"
scn = ftc.load_scenario("cw-pd-fault", overrides={"simulation.horizon": 200.0})
ds, metrics = ftc.simulate_with_metrics(scn)
paths = ftc.save_result(ds, out, metrics)
print({k: Path(v).name for k, v in paths.items()})

# %%
loaded = xr.open_dataset(paths["result"])
print(loaded.position)
print("seed", loaded.attrs["seed"], "| commit", loaded.attrs["git_commit"][:12])

# %% [markdown]
# The scenario text travels inside the file: reload it and you have the exact scenario again.

# %%
again = ftc.load_scenario(__import__("tomllib").loads(loaded.attrs["scenario_toml"]))
print(again == scn)

# %% [markdown]
# Into pandas: a long table of one variable, or the metrics as a Series.

# %%
table = loaded.position.sel(axis="x").to_dataframe().reset_index()
print(table.head())
print(table.groupby("spacecraft")["position"].agg(["min", "max"]).round(2))
m = json.loads(Path(paths["metrics"]).read_text())
print({k: round(v, 4) for k, v in m.items() if isinstance(v, float)})
loaded.close()
