"""Values printed in Azizi & Khorasani 2009 (Sec. V, Figs. 2-4), kept in one place."""

from __future__ import annotations

__all__ = ["PUBLISHED", "TITLE", "CITATION"]

TITLE = (
    "A hierarchical architecture for cooperative fault accommodation of formation flying satellites in "
    "deep space"
)
CITATION = "S.M. Azizi, K. Khorasani, American Control Conference 2009"

#: max |e_ij| fault-free [m] and LLFR-only [m], simulated minimum alpha_2 for e_s = 0.03 m, analytic
#: alpha_2 of eq. (11) per violation probability pi
PUBLISHED = {
    "max_err_fault_free": 1e-4,
    "max_err_llfr": 0.072,
    "alpha2_min_simulated": 5.6,
    "alpha2_analytic": {0.0: 7.6, 0.15: 6.0, 0.2: 5.4, 0.4: 3.4},
}
