"""Named, versioned fault batteries: the same faults for every method of a league.

A battery is a TOML file ``league/data/battery-NAME.toml``::

    [battery]   name, version, description
    [defaults]  spacecraft, axis, onset            (any case field; a case overrides it)
    [[cases]]   name, kind, description and the kind's magnitudes

Case kinds are the actuator fault kinds of the ``fault-battery`` actuator (``none``,
``loss_of_effectiveness``, ``bias``, ``stuck``, ``outage``, ``intermittent``, ``degrading``) and two
communication kinds for methods with a network: ``link_loss`` (``lost_links``: receiver i stops
hearing sender j) and ``larger_delays`` (``delay_scale``, delayed networks only).

:func:`load_battery` returns a :class:`Battery` of typed :class:`BatteryCase`; a case gives the fields
of the composed ``[actuator] type = "fault-battery"`` section (:meth:`BatteryCase.actuator_fields`) and
of ``[network] type = "graph-link-loss"`` (:meth:`BatteryCase.network_fields`). Every case yields the
same set of fields (a communication case has actuator kind ``none``, an actuator case loses no link),
so all the cases of one method share one compiled program. :attr:`Battery.version` and
:attr:`Battery.sha256` (of the file's bytes) identify the battery in a league's records.
"""

from __future__ import annotations

import hashlib
import math
import tomllib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import ConfigDict, Field, ValidationError, field_validator, model_validator

from formation_ftc.components.actuators.fault_battery import FAULT_KINDS
from formation_ftc.config.base import StrictModel
from formation_ftc.errors import InputError
from formation_ftc.league.definition import _format, builtin_files

__all__ = [
    "Battery",
    "BatteryCase",
    "BatteryError",
    "CASE_KINDS",
    "COMMUNICATION_KINDS",
    "builtin_batteries",
    "load_battery",
]

#: communication fault kinds (act on the network; the actuator has no fault)
COMMUNICATION_KINDS: tuple[str, ...] = ("link_loss", "larger_delays")
#: every case kind of a battery
CASE_KINDS: tuple[str, ...] = FAULT_KINDS + COMMUNICATION_KINDS

#: the magnitudes each kind needs (a case of that kind must give them, here or in [defaults])
_NEEDS: dict[str, tuple[str, ...]] = {
    "loss_of_effectiveness": ("effectiveness",),
    "bias": ("bias_fraction", "bias_force", "bias_torque"),
    "intermittent": ("period", "duty"),
    "degrading": ("rate", "min_effectiveness"),
    "link_loss": ("lost_links",),
    "larger_delays": ("delay_scale",),
}


class BatteryError(InputError):
    """A battery that does not exist or cannot be read (the message names the battery and the field)."""


class _CaseModel(StrictModel):
    name: str = Field(min_length=1, description="Case name (unique in the battery).")
    kind: str = Field(description=f"One of {', '.join(CASE_KINDS)}.")
    description: str = Field("", description="One line shown in reports.")
    spacecraft: int = Field(1, ge=1, description="Faulty spacecraft (1-based) [-].")
    axis: int = Field(0, ge=0, le=2, description="Faulty axis 0, 1, 2 [-].")
    onset: float = Field(0.0, ge=0.0, description="Fault onset [s] (a league may draw its own).")
    effectiveness: float | None = Field(
        None, ge=0.0, le=1.0, description="Loss of effectiveness gain [-]."
    )
    bias_fraction: float | None = Field(
        None, description="Bias as a fraction of the saturation limit [-]."
    )
    bias_force: float | None = Field(
        None, description="Bias without saturation on a force plant [N]."
    )
    bias_torque: float | None = Field(
        None, description="Bias without saturation on a torque plant [N m]."
    )
    period: float | None = Field(None, gt=0.0, description="Intermittent period [s].")
    duty: float | None = Field(None, ge=0.0, le=1.0, description="Intermittent on-fraction [-].")
    rate: float | None = Field(None, ge=0.0, description="Degrading effectiveness loss rate [1/s].")
    min_effectiveness: float | None = Field(
        None, ge=0.0, le=1.0, description="Degrading floor [-]."
    )
    lost_links: list[tuple[int, int]] | None = Field(
        None, description="Links [i, j] lost (1-based, i <- j)."
    )
    delay_scale: float | None = Field(
        None, gt=0.0, description="Delay multiplier after the onset [-]."
    )

    @field_validator("kind")
    @classmethod
    def _kind(cls, v: str) -> str:
        if v not in CASE_KINDS:
            raise ValueError(f"kind = {v!r} is not a fault kind (allowed: {', '.join(CASE_KINDS)})")
        return v

    @model_validator(mode="after")
    def _magnitudes(self):
        missing = [f for f in _NEEDS.get(self.kind, ()) if getattr(self, f) is None]
        if missing:
            raise ValueError(f"kind {self.kind} needs {', '.join(missing)}")
        for k, (i, j) in enumerate(self.lost_links or []):
            if i < 1 or j < 1 or i == j:
                raise ValueError(
                    f"lost_links[{k}] = [{i}, {j}]: 1-based spacecraft numbers, receiver != sender"
                )
        return self


class _Meta(StrictModel):
    name: str = Field(description="Battery name (the file is battery-NAME.toml).")
    version: int = Field(ge=1, description="Battery version (bump on any change of its content).")
    description: str = Field("", description="One line.")


class _BatteryModel(StrictModel):
    battery: _Meta
    defaults: dict[str, Any] = Field(
        default_factory=dict, description="Fields every case inherits."
    )
    cases: list[dict[str, Any]] = Field(min_length=1, description="The fault cases.")


class BatteryCase(_CaseModel):
    """One fault case of a battery, validated (fields as in the battery file; a magnitude None: not
    given); its communication fields filled in (no lost link, ``delay_scale`` 1 by default)."""

    model_config = ConfigDict(frozen=True)

    # frozen: a tuple where the file's model takes a list
    lost_links: tuple[tuple[int, int], ...] = Field((), description="Links (i, j) lost.")  # type: ignore[assignment]
    delay_scale: float = Field(1.0, gt=0.0, description="Delay multiplier after the onset [-].")
    #: the largest delay_scale of the battery (sizes a delayed network's history alike for every case)
    max_delay_scale: float = Field(1.0, description="Largest delay_scale of the battery [-].")

    @property
    def communication(self) -> bool:
        """True for a network fault (the actuator is healthy)."""
        return self.kind in COMMUNICATION_KINDS

    def applies_to(self, *, network: bool, delayed: bool = False) -> bool:
        """Whether the case means something for a method with (``network``) or without a network and a
        ``delayed`` one or not: communication cases need a network, ``larger_delays`` a delayed one."""
        return {"link_loss": network, "larger_delays": network and delayed}.get(self.kind, True)

    def actuator_fields(
        self,
        saturation: float | Sequence[float] | None = None,
        quantity: str = "force",
        onset: float | None = None,
    ) -> dict[str, Any]:
        """Fields of the ``fault-battery`` actuator section for this case.

        Parameters
        ----------
        saturation
            The league level's per-axis limit [N or N m] (one number or one per spacecraft); None or inf:
            unsaturated (the key is left out).
        quantity
            ``"force"`` or ``"torque"``: which absolute bias applies without saturation.
        onset
            Override of the case's onset [s] (e.g. a league's drawn onset).

        The bias is ``bias_fraction`` times the faulty spacecraft's limit when saturated, else
        ``bias_force`` [N] or ``bias_torque`` [N m]. A communication case gives kind ``none``.
        """
        if quantity not in ("force", "torque"):
            raise BatteryError(
                f"case {self.name}: quantity = {quantity!r}, expected 'force' or 'torque'"
            )
        limits = None
        if saturation is not None:
            sat = [float(x) for x in np.atleast_1d(saturation)]
            if all(math.isfinite(x) for x in sat):
                limits = sat
            elif any(math.isfinite(x) for x in sat):
                raise BatteryError(
                    f"case {self.name}: saturation {sat}: all limits finite or all inf"
                )
        bias = 0.0
        if self.kind == "bias":
            if limits is not None:
                lim = limits[0] if len(limits) == 1 else limits[self.spacecraft - 1]
                bias = float(self.bias_fraction) * lim  # type: ignore[arg-type]  # required for bias
            else:
                bias = float(self.bias_force if quantity == "force" else self.bias_torque)  # type: ignore[arg-type]
        out: dict[str, Any] = {
            "kind": "none" if self.communication else self.kind,
            "spacecraft": self.spacecraft,
            "axis": self.axis,
            "onset": float(self.onset if onset is None else onset),
            "effectiveness": 1.0 if self.effectiveness is None else self.effectiveness,
            "bias": bias,
            "period": 60.0 if self.period is None else self.period,
            "duty": 0.5 if self.duty is None else self.duty,
            "rate": 0.0 if self.rate is None else self.rate,
            "min_effectiveness": 0.0 if self.min_effectiveness is None else self.min_effectiveness,
        }
        if limits is not None:
            out["saturation"] = limits[0] if len(limits) == 1 else limits
        return out

    def network_fields(self, delayed: bool = False, onset: float | None = None) -> dict[str, Any]:
        """Fields added to a method's network section (its ``adjacency`` / ``delays`` / ``max_delay``) to
        make it a ``graph-link-loss`` network for this case; an actuator case loses no link.

        ``delayed``: the method's network has delays (then ``delay_scale`` and ``max_delay_scale`` are
        given; without delays a ``larger_delays`` case raises :class:`BatteryError`). ``onset``: override
        of the case's onset [s]."""
        if not delayed and self.kind == "larger_delays":
            raise BatteryError(f"case {self.name}: larger_delays needs a network with delays")
        out: dict[str, Any] = {
            "type": "graph-link-loss",
            "lost_links": [list(p) for p in self.lost_links],
            "onset": float(self.onset if onset is None else onset),
        }
        if delayed:
            out["delay_scale"] = self.delay_scale
            out["max_delay_scale"] = max(self.max_delay_scale, self.delay_scale)
        return out


@dataclass(frozen=True)
class Battery:
    """A named, versioned battery of fault cases."""

    name: str
    version: int
    description: str
    sha256: str  # of the battery file's bytes
    source: Path
    cases: tuple[BatteryCase, ...]

    def __iter__(self) -> Iterator[BatteryCase]:
        return iter(self.cases)

    def __len__(self) -> int:
        return len(self.cases)

    def __getitem__(self, name: str) -> BatteryCase:
        for c in self.cases:
            if c.name == name:
                return c
        raise BatteryError(
            f"battery {self.name}: no case {name!r} (cases: {', '.join(self.names)})"
        )

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.cases)

    @property
    def label(self) -> str:
        """``NAME vVERSION sha256:PREFIX`` for records and reports."""
        return f"{self.name} v{self.version} sha256:{self.sha256[:12]}"


def builtin_batteries() -> dict[str, Path]:
    """Built-in battery name -> file."""
    return builtin_files("battery")


def load_battery(name: str | Path = "v1") -> Battery:
    """The built-in battery ``name`` (``league/data/battery-NAME.toml``) or a battery TOML file.

    Raises :class:`BatteryError` naming the battery, the case and the field for an unknown name, a file
    that is not TOML, an unknown field or kind, a missing magnitude or duplicate case names."""
    known = builtin_batteries()
    path = known.get(str(name)) or Path(name)
    if path.suffix != ".toml" or not path.is_file():  # a built-in battery's file is one
        raise BatteryError(
            f"unknown fault battery {str(name)!r} (known: {', '.join(known) or 'none'}; "
            "or give a battery .toml file)"
        )
    data = path.read_bytes()
    try:
        raw = tomllib.loads(data.decode("utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise BatteryError(f"{path}: not valid TOML: {exc}") from None
    try:
        model = _BatteryModel.model_validate(raw)
    except ValidationError as exc:
        raise BatteryError(_format(exc, str(path), ".", "; ")) from None
    inherited = [f for f in _CaseModel.model_fields if f not in ("name", "kind")]
    unknown_defaults = sorted(set(model.defaults) - set(inherited))
    if unknown_defaults:
        raise BatteryError(
            f"{path}: defaults: {', '.join(unknown_defaults)} cannot be defaults "
            f"(case fields: {', '.join(inherited)})"
        )
    parsed = []
    for k, body in enumerate(model.cases):
        try:
            parsed.append(_CaseModel.model_validate({**model.defaults, **body}))
        except ValidationError as exc:
            named = f" ({body['name']})" if isinstance(body.get("name"), str) else ""
            raise BatteryError(_format(exc, f"{path}: cases[{k}]{named}", ".", "; ")) from None
    if str(name) in known and model.battery.name != str(name):
        raise BatteryError(
            f"{path}: battery.name = {model.battery.name!r} differs from the file name ({name!r})"
        )
    names = [c.name for c in parsed]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise BatteryError(f"{path}: duplicate case names {', '.join(dup)}")
    max_scale = max([1.0, *(c.delay_scale for c in parsed if c.delay_scale is not None)])
    cases = tuple(
        BatteryCase(
            **c.model_dump(exclude={"lost_links", "delay_scale"}),
            lost_links=tuple((int(i), int(j)) for i, j in (c.lost_links or [])),
            delay_scale=1.0 if c.delay_scale is None else c.delay_scale,
            max_delay_scale=max_scale,
        )
        for c in parsed
    )
    sha256 = hashlib.sha256(data).hexdigest()
    return Battery(**model.battery.model_dump(), sha256=sha256, source=path.resolve(), cases=cases)
