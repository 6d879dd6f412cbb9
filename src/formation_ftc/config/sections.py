"""Scenario sections shared by several methods."""

from __future__ import annotations

from pydantic import Field, model_validator

from formation_ftc.config.base import StrictModel

__all__ = ["SpacecraftSection"]


class SpacecraftSection(StrictModel):
    """Point-mass spacecraft of a translational formation (LVLH initial states)."""

    mass: list[float] = Field(
        description="True mass m_i of each spacecraft [kg], > 0 (unknown to adaptive controllers)."
    )
    initial_position: list[tuple[float, float, float]] = Field(
        description="Initial LVLH position rho_i(0) per spacecraft [m]."
    )
    initial_velocity: list[tuple[float, float, float]] | None = Field(
        None, description="Initial LVLH velocity v_i(0) per spacecraft [m/s] (default 0)."
    )

    @model_validator(mode="after")
    def _sizes(self):
        n = len(self.mass)
        if n < 1:
            raise ValueError("spacecraft.mass: at least one spacecraft is required")
        for k, m in enumerate(self.mass):
            if not m > 0:
                raise ValueError(f"spacecraft.mass[{k}] = {m}: masses must be > 0 kg")
        if len(self.initial_position) != n:
            raise ValueError(
                f"spacecraft.initial_position: {len(self.initial_position)} rows for {n} spacecraft (need {n})"
            )
        if self.initial_velocity is not None and len(self.initial_velocity) != n:
            raise ValueError(
                f"spacecraft.initial_velocity: {len(self.initial_velocity)} rows for {n} spacecraft (need {n})"
            )
        return self

    @property
    def count(self) -> int:
        """Number of spacecraft [-]."""
        return len(self.mass)
