# %% [markdown]
# # Check a theorem's conditions before a run
#
# Every method declares the conditions its guarantees need (graph properties, gain bounds, LMI
# feasibility, dwell times). `ftc.check` evaluates them without simulating; `formation-ftc check NAME`
# does the same from a terminal and exits with status 1 when a required condition fails.

# %%
import formation_ftc as ftc


def show(conditions):
    for c in conditions:
        mark = "unproven" if c.unproven else {True: "holds", False: "FAILS", None: "n/a"}[c.holds]
        kind = "required" if c.required else "info"
        print(f"  [{mark:8s}] ({kind}, {c.basis}) {c.name}: {c.value}  (needs {c.requirement})")


scenario = ftc.load_scenario("li2020-thm1")
print(scenario.scenario.description)
show(ftc.check(scenario))

# %% [markdown]
# Each condition states its basis: `exact` (exact arithmetic, or floating point with a stated rounding
# margin), `verified` (a rigorous bound, e.g. interval arithmetic over the whole horizon), `sampled` or
# `heuristic` (a pass is only "unproven"; a violation found is real) and `informative`.
#
# The communication graph printed in the paper is not balanced, which the theorem assumes. The
# scenario `li2020-thm2-balanced` uses a balanced graph; checking it shows which conditions now hold.

# %%
balanced = ftc.load_scenario("li2020-thm2-balanced")
conds = ftc.check(balanced)
show(conds)
print("all required conditions hold:", all(c.holds is not False for c in conds if c.required))

# %% [markdown]
# A condition that fails does not stop you from simulating; it tells you the guarantee does not apply.
# A bad *value* (out of its range) is different: the scenario does not validate, and the message names
# the field.

# %%
try:
    ftc.load_scenario("cw-pd-fault", overrides={"controller.kp": -1.0})
except ValueError as exc:
    print(exc)
