"""Section fields the residual FDIs share (``residual-fdi``, ``attitude-residual-fdi``): the
sequential test per (spacecraft, axis) and its drift and threshold."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

__all__ = [
    "FdiTest",
    "FdiDrift",
    "FdiThreshold",
    "FdiIdentification",
    "FdiForgetting",
    "FdiIdentificationStd",
]

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
FdiIdentification = Annotated[
    Literal["off", "rls"],
    Field(
        description="Fault identification: off, or each channel's effectiveness and bias by recursive "
        "least squares with exponential forgetting on the residual (provides fault-identification)."
    ),
]
FdiForgetting = Annotated[
    float,
    Field(
        gt=0,
        le=1,
        description="RLS forgetting factor lambda; the memory is about 1 / (1 - lambda) steps [-].",
    ),
]
FdiIdentificationStd = Annotated[
    float,
    Field(
        gt=0,
        description="Standard deviation of a channel's effectiveness estimate at or below which the "
        "channel counts as identified (before: reported as NaN) [-].",
    ),
]
