"""Boundary conditions of the gas phase: small objects on named sides, turned into cell flags once.

Each condition carries the integer ``flag`` of Hoomans 1996 Table 1 that
``StaggeredGrid.cell_flags`` writes into the ring of boundary cells, plus the values
the solver needs (inflow velocities, outlet pressure). Nothing here runs in a time
step except evaluating time-dependent values.

Sign convention: inflow velocities are positive *into* the domain on every side.
Positions along a side (``Segment.start``/``end``) are the x coordinate on the bottom
and top sides and the y coordinate on the left and right sides [m].

=================  ====  ===================================================================
condition          flag  on the boundary face / in the boundary cell
=================  ====  ===================================================================
``FreeSlip()``     2     normal velocity 0; tangential velocity mirrored (no shear)
``Wall()``         3     normal velocity 0; tangential velocity 0 on the wall (no slip)
``Inflow(...)``    4     normal velocity prescribed (segments); tangential velocity 0 in
                         the influx cell; voidage of the influx cell fixed (Hoomans §3.5)
``PressureOutlet`` 5     pressure prescribed at the boundary-cell centre, half a cell
                         outside the domain; normal velocity from momentum; free slip
``Outflow()``      6     continuous outflow: zero normal gradient of velocity and pressure;
                         total outflow closes the mass balance; free slip
``Periodic()``     8     the boundary cell is the interior cell on the opposite side
=================  ====  ===================================================================
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, ClassVar, Union

import numpy as np

from ..errors import CaseError
from ..registry import Registry
from .grid import FREE_SLIP, INFLOW, NO_SLIP, OUTFLOW, PERIODIC, PRESSURE

Value = Union[float, Callable[[float], float]]

boundary_conditions: Registry = Registry("gas boundary condition")


def _check_value(where: str, value, *, positive: bool = False) -> None:
    if callable(value):
        return
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise CaseError(f"{where} = {value!r}: must be a number or a function of time t [s]")
    if not math.isfinite(value) or (positive and value <= 0.0):
        raise CaseError(f"{where} = {value!r}: must be {'> 0' if positive else 'finite'}")


def evaluate(value: Value, t: float) -> float:
    """A constant, or a function of time evaluated at ``t`` [s]."""
    return float(value(t)) if callable(value) else float(value)


class BoundaryCondition:
    """Base class: a condition on one side; ``flag`` is its Hoomans 1996 Table 1 cell flag."""

    flag: ClassVar[int]
    kind: ClassVar[str]


@boundary_conditions.register("free_slip")
@dataclass(frozen=True)
class FreeSlip(BoundaryCondition):
    """Impermeable free-slip wall (Hoomans 1996 Table 1, flag 2): u_n = 0, ∂u_t/∂n = 0."""

    flag: ClassVar[int] = FREE_SLIP
    kind: ClassVar[str] = "free_slip"


@boundary_conditions.register("wall")
@dataclass(frozen=True)
class Wall(BoundaryCondition):
    """Impermeable no-slip wall (Hoomans 1996 Table 1, flag 3): u_n = 0, u_t = 0 on the wall."""

    flag: ClassVar[int] = NO_SLIP
    kind: ClassVar[str] = "wall"


@dataclass(frozen=True)
class Pulse:
    """A velocity that is ``value`` for ``start <= t < start + duration`` and ``otherwise`` outside.

    Times within 1e-9 (relative) of an edge count as on it, so that a time summed from
    steps (0.1 + 0.2) switches where it should (0.3).

    Example: the 200 ms pulse of Hoomans 1996 §5.4 through the orifice,
    ``Segment(superficial=Pulse(2.5, start=0.0, duration=0.2, otherwise=0.5), ...)``.
    Values in [m/s]; times in [s].
    """

    value: float
    start: float = 0.0
    duration: float = math.inf
    otherwise: float = 0.0

    def __post_init__(self):
        for name in ("value", "start", "otherwise"):
            _check_value(f"Pulse.{name}", getattr(self, name))
        if not (self.duration > 0.0):
            raise CaseError(f"Pulse.duration = {self.duration!r}: must be > 0 [s]")

    def __call__(self, t: float) -> float:
        end = self.start + self.duration
        tol = 1e-9 * max(1.0, abs(self.start), abs(end) if math.isfinite(end) else 0.0)
        return self.value if self.start - tol <= t < end - tol else self.otherwise


@dataclass(frozen=True)
class Table:
    """A velocity interpolated linearly in time between ``(t, value)`` points, constant beyond the ends.

    Example: a slow sweep of the superficial velocity from 0 to 0.4 m/s over 2 s for a
    minimum-fluidisation measurement, ``Table(((0.0, 0.0), (2.0, 0.4)))``. [s], [m/s].
    """

    points: tuple[tuple[float, float], ...]

    def __post_init__(self):
        pts = tuple((float(t), float(v)) for t, v in self.points)
        if not pts:
            raise CaseError("Table.points: give at least one (t, value) pair")
        for k, (t, v) in enumerate(pts):
            _check_value(f"Table.points[{k}] time", t)
            _check_value(f"Table.points[{k}] value", v)
        times = [t for t, _ in pts]
        if any(b <= a for a, b in zip(times, times[1:])):
            raise CaseError(f"Table.points: times {times} must increase strictly")
        object.__setattr__(self, "points", pts)

    def __call__(self, t: float) -> float:
        times = [p[0] for p in self.points]
        return float(np.interp(t, times, [p[1] for p in self.points]))


@dataclass(frozen=True)
class Segment:
    """One stretch of an inflow side with one velocity: the background or an orifice/jet.

    Parameters
    ----------
    interstitial, superficial : float or callable t -> float
        Inflow velocity [m/s], positive into the domain; give exactly one. Hoomans 1996
        §5.2: superficial = voidage of the influx cell × interstitial, so a
        superficial velocity is converted with the ``Inflow.voidage`` of its side.
    start, end : float, optional
        Extent along the side [m] (x on bottom/top, y on left/right). Default: the
        whole side. A face partly covered gets the covered fraction of the velocity,
        so the mass flow of a segment does not depend on how it meets the grid.
    """

    interstitial: Value | None = None
    superficial: Value | None = None
    start: float | None = None
    end: float | None = None

    def __post_init__(self):
        if (self.interstitial is None) == (self.superficial is None):
            raise CaseError("gas inflow segment: give exactly one of interstitial= or superficial= "
                            f"(got interstitial={self.interstitial!r}, superficial={self.superficial!r})")
        name = "interstitial" if self.interstitial is not None else "superficial"
        _check_value(f"gas inflow segment {name}", getattr(self, name))
        for k in ("start", "end"):
            if getattr(self, k) is not None:
                _check_value(f"gas inflow segment {k}", getattr(self, k))
        if self.start is not None and self.end is not None and not self.end > self.start:
            raise CaseError(f"gas inflow segment: end = {self.end!r} must exceed start = {self.start!r} [m]")

    def interstitial_velocity(self, t: float, voidage: float) -> float:
        """Interstitial velocity [m/s] at time ``t`` [s]: superficial / voidage when given as superficial."""
        if self.interstitial is not None:
            return evaluate(self.interstitial, t)
        return evaluate(self.superficial, t) / voidage


@boundary_conditions.register("inflow")
@dataclass(frozen=True)
class Inflow(BoundaryCondition):
    """Influx side (Hoomans 1996 Table 1, flag 4): prescribed normal velocity, segment by segment.

    Parameters
    ----------
    segments : sequence of Segment
        Later segments override earlier ones where they overlap, so list the
        background first and the orifices after it. Parts of the side that no
        segment covers have zero inflow (an impermeable plate with no-slip).
    voidage : float
        Voidage of the influx cells, in (0, 1] (0.4 in Hoomans 1996 §3.5, to mimic a
        distributor plate). It sets the mass flux through the inflow faces,
        ε ρ u_interstitial, and converts superficial to interstitial velocities.
    superficial, interstitial : float or callable, optional
        Shortcut for one background segment over the whole side.

    Notes
    -----
    The tangential gas velocity in the influx cells is zero. The gas density of the
    inflow is that of the adjacent interior cell (its pressure is extrapolated).
    Velocities are evaluated at the end of the step, t + dt.
    """

    segments: tuple[Segment, ...] = ()
    voidage: float = 1.0
    superficial: Value | None = None
    interstitial: Value | None = None

    flag: ClassVar[int] = INFLOW
    kind: ClassVar[str] = "inflow"

    def __post_init__(self):
        segs = tuple(self.segments)
        if self.superficial is not None or self.interstitial is not None:
            segs = (Segment(superficial=self.superficial, interstitial=self.interstitial),) + segs
        if not segs:
            raise CaseError("gas Inflow: give segments=[Segment(...), ...] or superficial=/interstitial= "
                            "for the whole side")
        for s in segs:
            if not isinstance(s, Segment):
                raise CaseError(f"gas Inflow segments: {s!r} is not a Segment(...)")
        _check_value("gas Inflow voidage", self.voidage, positive=True)
        if callable(self.voidage) or self.voidage > 1.0:
            raise CaseError(f"gas Inflow voidage = {self.voidage!r}: must be a number in (0, 1]")
        object.__setattr__(self, "segments", segs)
        object.__setattr__(self, "voidage", float(self.voidage))
        object.__setattr__(self, "superficial", None)  # now the first segment
        object.__setattr__(self, "interstitial", None)

    def face_weights(self, edges: np.ndarray) -> np.ndarray:
        """(n_segments, n_faces) covered fraction of each boundary face by each segment.

        ``edges`` are the n_faces + 1 face edges along the side [m]. A later segment
        replaces earlier ones where it covers a face.
        """
        edges = np.asarray(edges, float)
        ends = np.array([[edges[0] if s.start is None else s.start, edges[-1] if s.end is None else s.end]
                         for s in self.segments])
        # pieces between all breakpoints; each belongs to the last segment covering it
        points = np.unique(np.clip(np.concatenate([edges, ends.ravel()]), edges[0], edges[-1]))
        a, b = points[:-1], points[1:]
        mid = 0.5 * (a + b)
        covers = (ends[:, :1] <= mid) & (mid < ends[:, 1:])  # (n_segments, n_pieces)
        owner = np.where(covers.any(axis=0), covers.shape[0] - 1 - np.argmax(covers[::-1], axis=0), -1)
        face = np.clip(np.searchsorted(edges, mid, side="right") - 1, 0, edges.size - 2)
        w = np.zeros((len(self.segments), edges.size - 1))
        keep = owner >= 0
        np.add.at(w, (owner[keep], face[keep]), (b - a)[keep])
        return w / np.diff(edges)

    def velocities(self, t: float) -> np.ndarray:
        """(n_segments,) interstitial velocities [m/s] at time ``t`` [s], positive inward."""
        return np.array([s.interstitial_velocity(t, self.voidage) for s in self.segments])


@boundary_conditions.register("pressure_outlet")
@dataclass(frozen=True)
class PressureOutlet(BoundaryCondition):
    """Prescribed-pressure side (Hoomans 1996 Table 1, flag 5), free slip.

    Parameters
    ----------
    pressure : float or callable t -> float, optional
        Pressure [Pa] in the boundary cells, i.e. at their centres, half a cell
        outside the domain (Hoomans' prescribed-pressure cell). Default: the gas's
        ``reference_pressure``. Gas may leave or enter; entering gas has the
        voidage of the adjacent interior cell and the density of this pressure.
    """

    pressure: Value | None = None

    flag: ClassVar[int] = PRESSURE
    kind: ClassVar[str] = "pressure_outlet"

    def __post_init__(self):
        if self.pressure is not None:
            _check_value("gas PressureOutlet pressure", self.pressure, positive=True)


@boundary_conditions.register("outflow")
@dataclass(frozen=True)
class Outflow(BoundaryCondition):
    """Continuous-outflow side (Hoomans 1996 Table 1, flag 6), free slip.

    The velocity through each boundary face copies the adjacent interior face
    (zero normal gradient, taken from the start of the step) and all such faces are
    scaled together so that the outflow closes the domain's mass balance (Versteeg
    & Malalasekera 2007 §11.9). The pressure in the boundary cells copies the interior.
    Outflow sets no pressure level: with no ``PressureOutlet`` the constant-density
    gas keeps the level of its initial state and the ideal gas the level its mass gives.
    """

    flag: ClassVar[int] = OUTFLOW
    kind: ClassVar[str] = "outflow"


@boundary_conditions.register("periodic")
@dataclass(frozen=True)
class Periodic(BoundaryCondition):
    """Periodic side (flag 8, not in Hoomans 1996): leaving gas re-enters through the opposite side.

    Both opposite sides must be ``Periodic()``.
    """

    flag: ClassVar[int] = PERIODIC
    kind: ClassVar[str] = "periodic"


__all__ = ["BoundaryCondition", "FreeSlip", "Wall", "Inflow", "Segment", "Pulse", "PressureOutlet", "Outflow",
           "Periodic", "boundary_conditions", "evaluate"]
