"""Typed scenario configuration (pydantic v2): the sections every scenario has.

A scenario file is TOML. Its ``[scenario]`` table names the ``method`` (a registered method such as
``"li2020"``, ``"cw-formation"``); that method's schema (a subclass of :class:`ScenarioBase`)
validates the whole file. Unknown fields are rejected (``extra="forbid"``), every numeric field
carries its unit in its description, and cross-field rules (the step divides the horizon, matrix sizes
match the number of spacecraft) are model validators whose messages name the field.
"""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, model_validator

from formation_ftc.core.expressions import ExpressionError, compile_expression

__all__ = [
    "StrictModel",
    "ScenarioMeta",
    "SimulationSection",
    "ScenarioBase",
    "ExprText",
    "expression_validator",
]


class StrictModel(BaseModel):
    """Base for every configuration model: unknown fields are errors, assignments are validated."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True, frozen=False)


def expression_validator(variables: tuple[str, ...] = ("t", "i")):
    """A ``BeforeValidator`` that parses an expression string (or number) and keeps its text."""

    def _check(v: Any) -> str:
        if isinstance(v, bool):
            raise ValueError("expected an expression string or a number, got a boolean")
        if isinstance(v, int | float):
            return repr(float(v))
        if not isinstance(v, str):
            raise ValueError(f"expected an expression string or a number, got {type(v).__name__}")
        try:
            compile_expression(v, variables)
        except ExpressionError as exc:
            raise ValueError(str(exc)) from None
        return v

    return BeforeValidator(_check)


#: A math expression in ``t`` [s] and ``i`` (1-based spacecraft number); see core.expressions.
ExprText = Annotated[str, expression_validator(("t", "i"))]


class ScenarioMeta(StrictModel):
    name: str = Field(description="Scenario name (built-in scenarios use paper-prefixed names).")
    method: str = Field(description="Registered method that simulates this scenario, e.g. 'li2020'.")
    description: str = Field("", description="One-line description shown by `formation-ftc list`.")
    paper: str | None = Field(None, description="Paper short name this scenario reproduces, if any.")


class SimulationSection(StrictModel):
    horizon: float = Field(gt=0, description="Simulated time span [s].")
    dt: float = Field(gt=0, description="Fixed integration step [s]; must divide the horizon.")
    record_every: int = Field(1, ge=1, description="Record every k-th step (output decimation) [-].")
    seed: int = Field(0, ge=0, description="Root random seed of the run [-].")
    unroll: int = Field(1, ge=1, le=64, description="lax.scan unroll factor (performance only) [-].")

    @model_validator(mode="after")
    def _step_divides_horizon(self) -> SimulationSection:
        n = round(self.horizon / self.dt)
        if n < 1 or abs(n * self.dt - self.horizon) > 1e-9 * max(self.horizon, 1.0):
            raise ValueError(
                f"simulation.dt = {self.dt} s must divide simulation.horizon = {self.horizon} s "
                f"(horizon/dt = {self.horizon / self.dt:.6g} is not an integer)"
            )
        if n % self.record_every:
            raise ValueError(
                f"simulation.record_every = {self.record_every} must divide the number of steps "
                f"horizon/dt = {n}"
            )
        return self

    @property
    def n_steps(self) -> int:
        """horizon / dt [-]."""
        return round(self.horizon / self.dt)


class ScenarioBase(StrictModel):
    """Sections common to every scenario; methods subclass this with their own sections."""

    scenario: ScenarioMeta
    simulation: SimulationSection
