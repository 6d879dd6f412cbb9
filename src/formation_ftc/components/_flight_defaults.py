"""The flight knowledge a law assumes when a scenario states none: one table.

A flight component (controller, estimator, supervisor) never reads the truth; what it knows of the
spacecraft it flies -- masses, inertias -- is stated in its section (``nominal_mass``,
``nominal_inertia``), and where a scenario leaves a field out, the law takes the value below. Each is a
nominal value documented with its origin, never copied from a plant (the conformance suite checks that
perturbing the truth leaves every flight component unchanged).

| name | value | used by | origin |
|---|---|---|---|
| ``NOMINAL_MASS`` | 100 kg | every translational law and filter not listed below | the scenarios' spacecraft (Li2020 / Gui2022 class) |
| ``YANG2013_NOMINAL_MASS`` | 150 kg | ``yang2013-translational``, ``yang2013-relative``, ``yang2013-force-torque`` | Yang2013's spacecraft |
| ``NOMINAL_INERTIA`` | diag(25, 25, 25) kg m^2 | ``attitude-pd``, ``yang2013-attitude`` | the Yang2013 scenarios' spacecraft |
| ``MEHRABIAN_NOMINAL_INERTIA`` | diag(20, 18, 15) kg m^2 | ``networked-el-hinf``, ``attitude-residual-fdi`` | Mehrabian's nominal J^ (our choice, docs/errata.md E003-10) |
"""

from __future__ import annotations

__all__ = ["NOMINAL_MASS", "YANG2013_NOMINAL_MASS", "NOMINAL_INERTIA", "MEHRABIAN_NOMINAL_INERTIA"]

#: on-board mass of a translational law that states none [kg]
NOMINAL_MASS = 100.0
#: on-board mass of Yang2013's translational laws that state none [kg]
YANG2013_NOMINAL_MASS = 150.0
#: principal model inertia of an attitude law that states none [kg m^2]
NOMINAL_INERTIA = (25.0, 25.0, 25.0)
#: principal model inertia of Mehrabian's Euler-Lagrange law and its FDI that state none [kg m^2]
MEHRABIAN_NOMINAL_INERTIA = (20.0, 18.0, 15.0)
