# %% [markdown]
# # Design an observer with the LMI tools
#
# `formation_ftc.design.lmi.design_ilo_gains` solves the linear matrix inequalities of the iterative
# learning observer (a Lyapunov inequality, a relaxed fault-distribution equality and a pole region
# `S(c, r)`, the disk of centre `c` and radius `r` in the complex plane) with cvxpy (CLARABEL, SCS as
# fallback), and returns the gains with the residuals of every inequality; an infeasible problem
# raises `DesignInfeasible` naming the conflicting inequalities. Here the plant is the
# Clohessy-Wiltshire model of one deputy with full state measurement and thrusters on every axis.

# %%
import matplotlib.pyplot as plt
import numpy as np
from _common import save_figure

from formation_ftc.core.dynamics.cw import cw_matrices
from formation_ftc.design.lmi import design_ilo_gains

n = 0.0011  # mean motion [rad/s] (about a 6,900 km orbit)
A, B = cw_matrices(n)
C = np.eye(6)
design = design_ilo_gains(A, C, B, disk_center=-5.0, disk_radius=2.0)
print("solver:", design.solver, "status:", design.status)
print("L1 =\n", np.array2string(design.L1, precision=3, suppress_small=True))
print("largest eigenvalue of each LMI at the solution (< 0: the strict inequality holds):")
for name, value in design.residuals.items():
    if name.startswith("max_eig"):
        print(f"  {name:14s} {value: .3e}")

# %% [markdown]
# The observer error poles `eig(A - L1 C)` lie in the requested disk:

# %%
poles = design.poles
print("max |pole - c| =", float(np.max(np.abs(poles + 5.0))), "<= r = 2")
fig, ax = plt.subplots(figsize=(5, 4))
t = np.linspace(0, 2 * np.pi, 200)
ax.plot(-5 + 2 * np.cos(t), 2 * np.sin(t), "k--", lw=0.8, label="S(-5, 2)")
ax.plot(poles.real, poles.imag, "x", ms=9, label="eig(A - L1 C)")
ax.set(xlabel="Re [1/s]", ylabel="Im [1/s]", title="Observer poles")
ax.axis("equal")
ax.legend()
fig.tight_layout()
save_figure(fig, "poles")
