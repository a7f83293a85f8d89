"""The base of the gas boundary conditions, their registry, and the time-dependent values they take.

A condition is a small pydantic model on a named side (``left``, ``right``, ``bottom``, ``top``; on a 3D grid
also ``front`` and ``back``, the z sides), chosen by its
``kind`` in a case file or built in Python (``Wall()``, ``Inflow(superficial=1.8, voidage=0.4)``): the same
object either way. It carries the integer ``flag`` of Hoomans 1996 Table 1 that ``StaggeredGrid.cell_flags``
writes into the ring of boundary cells, and answers the solver's three questions, each evaluated at set-up
or once per gas step, never inside a kernel:

``face_velocity(side, edges)``
    the interstitial normal velocity it prescribes on each boundary face of its side, positive into the
    domain, as a function of time (None: it prescribes none). On a 2D grid ``edges`` is the (n + 1,) array
    of face edges along the side and the velocity an (n,) array; on a 3D grid ``edges`` is the pair of such
    arrays along the side's two in-plane axes (``StaggeredGrid.side_axes``) and the velocity an
    (n_a, n_b) array over the side's faces;
``prescribed_pressure(t)``
    the pressure it holds in its boundary cells [Pa] (None: the gas's ``reference_pressure``);
``fastest_inflow()``
    the largest interstitial inflow speed it takes at any time [m/s], for the Courant check of the gas step.

Sign convention: inflow velocities are positive *into* the domain on every side.
Positions along a side are the x coordinate on the bottom and top sides and the y coordinate on the
left and right sides [m]; on a 3D grid a side's in-plane coordinates are (y, z) on left/right, (x, z) on
bottom/top and (x, y) on front/back. A new condition is one file in this package whose class registers itself
with ``@boundary_conditions.register("kind")`` and sets ``kind`` and ``flag``; the case schema builds
its choice of kinds from the registry.
"""
from __future__ import annotations

import math
from typing import Any, Callable, ClassVar, Union

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from ...errors import CaseError
from ...registry import Registry

boundary_conditions: Registry = Registry("gas boundary condition")


def problems_of(err: ValidationError, model: type[BaseModel]) -> list[tuple[tuple, object, str]]:
    """(key path, value, what is wrong) of each error in building ``model``, with those of nested building
    blocks under their key."""
    out = []
    for e in err.errors():
        loc = tuple(x for x in e["loc"] if not str(x).startswith("function-"))
        inner = (e.get("ctx") or {}).get("error")
        if isinstance(inner, CaseError) and inner.problems:
            out += [(loc + sub, value, msg) for sub, value, msg in inner.problems]
        elif e["type"] == "extra_forbidden" and len(loc) == 1:
            kind = model.model_fields["kind"].default if "kind" in model.model_fields else None
            what = f"kind {kind!r}" if isinstance(kind, str) else model.__name__
            out.append((loc, e.get("input"), f"{what} does not take {loc[0]}; allowed keys: "
                                             f"{', '.join(sorted(model.model_fields))}"))
        else:
            out.append((loc, e.get("input"), e["msg"].removeprefix("Value error, ")))
    return out


def describe_problems(problems, where: str) -> str:
    """One line per problem: ``where: key = value: what is wrong`` (``where: what is wrong`` for the whole)."""
    return "\n".join(f"{where}: {'.'.join(map(str, loc))} = {value!r}: {msg}" if loc else f"{where}: {msg}"
                     for loc, value, msg in problems)


class Model(BaseModel):
    """A building block of the gas section: unknown keys are errors, and one built in Python with a bad value
    raises ``CaseError`` (the case loader reports the same problems with their dotted key)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True, arbitrary_types_allowed=True)

    def __init__(self, /, **data: Any):
        try:
            super().__init__(**data)
        except ValidationError as err:
            problems = problems_of(err, type(self))
            raise CaseError(describe_problems(problems, f"gas {type(self).__name__}"), problems) from None


def check_number(value, *, positive: bool = False):
    """``value`` if it is a finite number (> 0 with ``positive``) or a function of time; else ValueError."""
    if callable(value) or isinstance(value, dict):
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise ValueError("must be a number or a function of time t [s]")
    if not math.isfinite(value) or (positive and value <= 0.0):
        raise ValueError(f"must be {'> 0' if positive else 'finite'}")
    return float(value)


class Pulse(Model):
    """A value (velocity or pressure) that is ``pulse`` for ``start <= t < start + duration`` and ``otherwise`` outside.

    Times within 1e-9 (relative) of an edge count as on it, so that a time summed from
    steps (0.1 + 0.2) switches where it should (0.3).

    Example: the 200 ms pulse of Hoomans 1996 §5.4 through the orifice,
    ``Segment(superficial=Pulse(2.5, start=0.0, duration=0.2, otherwise=0.5))``, in TOML
    ``superficial = {pulse = 2.5, start = 0.0, duration = 0.2, otherwise = 0.5}``.
    Values in [m/s]; times in [s].
    """

    pulse: float = Field(description="value during the pulse (a velocity [m/s] or a pressure [Pa])")
    start: float = Field(0.0, description="start of the pulse [s]")
    duration: float = Field(math.inf, allow_inf_nan=True, description="duration of the pulse [s] (inf: for ever)")
    otherwise: float = Field(0.0, description="value outside the pulse (the unit of pulse)")

    def __init__(self, pulse: float | None = None, /, **data: Any):
        super().__init__(**({"pulse": pulse} if pulse is not None else {}), **data)

    @field_validator("pulse", "start", "otherwise", mode="before")
    @classmethod
    def _finite(cls, v):
        return check_number(v)

    @field_validator("duration")
    @classmethod
    def _positive(cls, v):
        if not v > 0.0:
            raise ValueError("must be > 0 [s]")
        return v

    def __call__(self, t: float) -> float:
        end = self.start + self.duration
        tol = 1e-9 * max(1.0, abs(self.start), abs(end) if math.isfinite(end) else 0.0)
        return self.pulse if self.start - tol <= t < end - tol else self.otherwise

    def fastest(self) -> float:
        """Largest |velocity| at any time [m/s]."""
        return max(abs(self.pulse), abs(self.otherwise))


class Table(Model):
    """A value (velocity or pressure) interpolated linearly in time between ``[t, value]`` points, constant beyond the ends.

    Example: a slow sweep of the superficial velocity from 0 to 0.4 m/s over 2 s for a
    minimum-fluidisation measurement, ``Table([(0.0, 0.0), (2.0, 0.4)])``, in TOML
    ``superficial = {table = [[0.0, 0.0], [2.0, 0.4]]}``. [s], [m/s].
    """

    table: tuple[tuple[float, float], ...] = Field(
        min_length=1, description="[[t [s], value], ...]: a velocity [m/s] or a pressure [Pa], linear between "
                                 "the points")

    def __init__(self, table=None, /, **data: Any):
        super().__init__(**({"table": table} if table is not None else {}), **data)

    @field_validator("table")
    @classmethod
    def _increasing(cls, pts):
        for k, (t, v) in enumerate(pts):
            if not (math.isfinite(t) and math.isfinite(v)):
                raise ValueError(f"point {k} = {[t, v]}: time and value must be finite")
        times = [t for t, _ in pts]
        if any(b <= a for a, b in zip(times, times[1:])):
            raise ValueError(f"times {times} must increase strictly")
        return pts

    def __call__(self, t: float) -> float:
        return float(np.interp(t, [p[0] for p in self.table], [p[1] for p in self.table]))

    def fastest(self) -> float:
        """Largest |velocity| at any time [m/s]."""
        return max(abs(v) for _, v in self.table)


# a number [m/s or Pa], a pulse or table of time, or (from Python only) any function of time t [s]
Value = Union[float, Pulse, Table, Callable[[float], float]]


def evaluate(value, t: float) -> float:
    """A constant, or a function of time evaluated at ``t`` [s]."""
    return float(value(t)) if callable(value) else float(value)


def fastest(value) -> float:
    """Largest |value| at any time of a ``Value`` (a Python function: its value at t = 0)."""
    if isinstance(value, (Pulse, Table)):
        return value.fastest()
    return abs(evaluate(value, 0.0))


class InflowVelocity(Model):
    """One inflow velocity of a piece of an inflow side (a segment, a patch): give exactly one of
    ``interstitial`` and ``superficial``, positive into the domain [m/s]; a superficial velocity is
    converted with the voidage of its side (Hoomans 1996 §5.2: superficial = voidage × interstitial)."""

    interstitial: Value | None = Field(None, description="interstitial inflow velocity [m/s]")
    superficial: Value | None = Field(None, description="superficial inflow velocity [m/s] (interstitial × the "
                                                        "side's voidage)")

    @field_validator("interstitial", "superficial", mode="before")
    @classmethod
    def _velocity_number(cls, v):
        return None if v is None else check_number(v)

    @model_validator(mode="after")
    def _one_velocity(self):
        if (self.interstitial is None) == (self.superficial is None):
            raise ValueError("give exactly one of interstitial= or superficial= (got interstitial="
                             f"{self.interstitial!r}, superficial={self.superficial!r})")
        return self

    def interstitial_velocity(self, t: float, voidage: float) -> float:
        """Interstitial velocity [m/s] at time ``t`` [s]: superficial / voidage when given as superficial."""
        if self.interstitial is not None:
            return evaluate(self.interstitial, t)
        return evaluate(self.superficial, t) / voidage

    @property
    def time_dependent(self) -> bool:
        return callable(self.interstitial) or callable(self.superficial)


class BoundaryCondition(Model):
    """Base class: a condition on one side; ``flag`` is its Hoomans 1996 Table 1 cell flag."""

    flag: ClassVar[int]
    kind: str
    # the test that checks this condition against an analytic result (a function name under tests/)
    reference_test: ClassVar[str] = ""

    def face_velocity(self, side: str, edges) -> Callable[[float], np.ndarray] | None:
        """t ↦ (n_faces,) interstitial normal velocity [m/s] on the boundary faces of ``side``, positive into
        the domain, for the face edges ``edges`` [m] along the side; None if the condition prescribes none.
        3D grid: ``edges`` is a pair of edge arrays (the side's two in-plane axes) and the velocity (n_a, n_b)."""
        return None

    def prescribed_pressure(self, t: float) -> float | None:
        """Pressure held in the boundary cells at time ``t`` [Pa]; None: the gas's reference pressure (or none
        held, for conditions whose flag holds no pressure)."""
        return None

    @property
    def time_dependent(self) -> bool:
        """True if a value of the condition changes in time (then it is evaluated every gas step)."""
        return False

    def fastest_inflow(self) -> float:
        """Largest interstitial inflow speed through the side at any time [m/s]."""
        return 0.0


__all__ = ["BoundaryCondition", "Model", "Pulse", "Table", "Value", "boundary_conditions", "evaluate", "fastest",
           "check_number", "problems_of", "describe_problems"]
