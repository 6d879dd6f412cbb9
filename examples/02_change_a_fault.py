# %% [markdown]
# # Change a fault and compare
#
# Faults are expressions in `t` [s] and `i` (the 1-based spacecraft number) in the scenario file, so
# a different fault is an override, not new code. We compare the nominal `cw-pd-fault` faults with a
# stronger loss of effectiveness (70 % on every axis of deputy 2 from 100 s) and with no fault.

# %%
import matplotlib.pyplot as plt
from _common import save_figure, size

import formation_ftc as ftc

horizon = size(600.0, 300.0)
cases = {
    "no fault": {"actuator.effectiveness": ["1", "1", "1"], "actuator.bias": ["0", "0", "0"]},
    "nominal faults": {},
    "deputy 2 loses 70 %": {
        "actuator.effectiveness": ["where((t >= 100) and (i == 2), 0.3, 1)"] * 3
    },
}
results = {}
for label, overrides in cases.items():
    scn = ftc.load_scenario("cw-pd-fault", overrides={"simulation.horizon": horizon, **overrides})
    results[label] = ftc.simulate_with_metrics(scn)

# %%
print(
    f"{'case':22s} {'max error [m]':>14s} {'final mean error [m]':>21s} {'total delta-v [m/s]':>20s}"
)
for label, (_ds, m) in results.items():
    print(
        f"{label:22s} {m['max_position_error']:14.3f} {m['final_position_error_mean']:21.4f} "
        f"{m['delta_v_total']:20.3f}"
    )

# %%
fig, ax = plt.subplots(figsize=(7, 4))
for label, (ds, _) in results.items():
    err = (ds.position_error.sel(spacecraft=2) ** 2).sum("axis") ** 0.5
    ax.semilogy(ds.time, err, label=label)
ax.set(
    xlabel="t [s]",
    ylabel="deputy 2 |position error| [m]",
    title="Same controller, three fault cases",
)
ax.legend()
fig.tight_layout()
save_figure(fig, "fault_cases")
