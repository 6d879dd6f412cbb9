"""Section fields the residual FDIs share (``residual-fdi``, ``attitude-residual-fdi``): the
sequential test per (spacecraft, axis) and its drift and threshold."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

__all__ = ["FdiTest", "FdiDrift", "FdiThreshold"]

FdiTest = Annotated[
    Literal["cusum", "fixed"],
    Field(description="Test per (spacecraft, axis): Page's two-sided CUSUM or |z| > threshold."),
]
FdiDrift = Annotated[
    float, Field(ge=0, description="CUSUM drift (half the standardised shift to detect) [-].")
]
FdiThreshold = Annotated[
    float, Field(gt=0, description="Alarm threshold on the statistic (CUSUM g, or |z|) [-].")
]
