"""The choices of ``formation-ftc tune`` that its command line and the tuner share (no imports: the
parser answers ``--help`` at once)."""

from __future__ import annotations

__all__ = ["OPTIMISERS", "DEFAULT_OPTIMISER", "TRAIN_START"]

#: optimisers of :func:`formation_ftc.league.tuning.minimise`
OPTIMISERS = ("nelder-mead", "powell", "gradient")
#: the default: derivative-free (docs/tuning.md: measured against the gradient on the league)
DEFAULT_OPTIMISER = "nelder-mead"
#: training replicates start here by default (beyond the league's own seeds, which are held out)
TRAIN_START = 10_000
