"""Influx sides of the gas (Hoomans 1996 Table 1, flag 4): a background and orifices, each a ``Segment``;
on a 3D grid also rectangular and circular patches (``patches.py``)."""
from __future__ import annotations

from typing import Annotated, Any, Callable, ClassVar, Literal, Union

import numpy as np
from pydantic import Field, field_validator, model_validator

from ...errors import CaseError
from ..grid import INFLOW
from .base import BoundaryCondition, InflowVelocity, Value, boundary_conditions, check_number, fastest
from .patches import Circle, Rectangle, overlap

PatchChoice = Annotated[Union[Rectangle, Circle], Field(discriminator="shape")]


class Segment(InflowVelocity):
    """One stretch of an inflow side with one velocity: the background or an orifice/jet.

    Parameters
    ----------
    interstitial, superficial : float, Pulse, Table or callable t -> float
        Inflow velocity [m/s], positive into the domain; give exactly one. Hoomans 1996
        §5.2: superficial = voidage of the influx cell × interstitial, so a
        superficial velocity is converted with the ``Inflow.voidage`` of its side.
    start, end : float, optional
        Extent along the side [m] (x on bottom/top, y on left/right). Default: the
        whole side. A face partly covered gets the covered fraction of the velocity,
        so the mass flow of a segment does not depend on how it meets the grid.
        On a 3D grid the extent is along the side's first in-plane axis (y on left/right,
        x on the other sides) and the segment spans the whole of the second (a slot).
    """

    start: float | None = Field(None, description="[m] along the side (x on bottom/top, y on left/right); "
                                                  "default its start")
    end: float | None = Field(None, description="[m] along the side; default its end")

    @field_validator("start", "end", mode="before")
    @classmethod
    def _number(cls, v):
        return None if v is None else check_number(v)

    @model_validator(mode="after")
    def _extent(self):
        if self.start is not None and self.end is not None and not self.end > self.start:
            raise ValueError(f"end = {self.end!r} must exceed start = {self.start!r} [m]")
        return self


@boundary_conditions.register("inflow")
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
    superficial, interstitial : float, Pulse, Table or callable, optional
        Shortcut for one background segment over the whole side (it becomes the first segment).
    patches : sequence of Rectangle or Circle, 3D grids only
        Pieces of the side with their own velocity (a central jet, nozzles of a distributor),
        in the side's in-plane coordinates ((y, z) on left/right, (x, z) on bottom/top,
        (x, y) on front/back). They replace the segments where they lie and must not overlap
        one another. Each boundary face takes the exact fraction of its area inside a patch,
        so a circle's mass flow is ε ρ u π r² whatever the grid. With patches the segments
        may be left out: the rest of the side then has no inflow.

    Notes
    -----
    The tangential gas velocity in the influx cells is zero. The gas density of the
    inflow is that of the adjacent interior cell (its pressure is extrapolated).
    Velocities are evaluated at the end of the step, t + dt.
    """

    kind: Literal["inflow"] = "inflow"
    segments: tuple[Segment, ...] = Field((), description="stretches of the side with their velocity; later ones "
                                                          "override earlier ones where they overlap")
    voidage: float = Field(1.0, description="voidage of the influx cells [-], in (0, 1]")
    superficial: Value | None = Field(None, description="superficial velocity over the whole side [m/s] (a first "
                                                        "segment)")
    interstitial: Value | None = Field(None, description="interstitial velocity over the whole side [m/s] (a first "
                                                         "segment)")
    patches: tuple[PatchChoice, ...] = Field(
        (), description="3D grids: rectangles {shape = \"rectangle\", start, end} and circles {shape = \"circle\", "
                        "centre, radius}, each with its interstitial or superficial velocity, in the side's in-plane "
                        "coordinates [m]; they replace the segments where they lie")
    flag: ClassVar[int] = INFLOW
    reference_test: ClassVar[str] = "test_inflow_segments_set_interstitial_face_velocities_and_the_mass_flow"

    @model_validator(mode="before")
    @classmethod
    def _shortcut_first(cls, data: Any):
        """``superficial=``/``interstitial=`` become the first segment."""
        if not isinstance(data, dict):
            return data
        data = dict(data)
        shortcut = {k: data.pop(k) for k in ("superficial", "interstitial") if data.get(k) is not None}
        segs = data.get("segments", ())
        if shortcut:
            data["segments"] = [shortcut, *(segs if isinstance(segs, (list, tuple)) else [segs])]
        elif not segs and not data.get("patches"):
            raise ValueError("give segments=[Segment(...), ...] or superficial=/interstitial= for the whole side")
        return data

    @model_validator(mode="after")
    def _patches_apart(self):
        for i, p in enumerate(self.patches):
            for j in range(i):
                if overlap(self.patches[j], p):
                    raise ValueError(f"patches {j} and {i} overlap; patches must not share area (touching is allowed)")
        return self

    @field_validator("segments", mode="before")
    @classmethod
    def _segments(cls, v):
        for s in v if isinstance(v, (list, tuple)) else [v]:
            if not isinstance(s, (Segment, dict)):
                raise ValueError(f"{s!r} is not a Segment(...)")
        return v

    @field_validator("voidage", mode="before")
    @classmethod
    def _voidage(cls, v):
        v = check_number(v, positive=True)
        if callable(v) or isinstance(v, dict) or v > 1.0:
            raise ValueError("must be a number in (0, 1]")
        return v

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

    def face_velocity(self, side: str, edges) -> Callable[[float], np.ndarray]:
        """t ↦ Σ_segments covered fraction × interstitial velocity on each boundary face [m/s].

        ``edges``: the face edges along a side of a 2D grid (one array: the result is (n_faces,)), or the
        pair of them along a side of a 3D grid (the result is (n_a, n_b); ``face_velocity_3d``)."""
        if isinstance(edges, tuple):
            return self.face_velocity_3d(side, edges)
        if self.patches:
            raise CaseError(f"gas.boundaries.{side}: inflow patches need a 3D grid; on a 2D grid give segments")
        weights = self.face_weights(edges)
        for k in np.flatnonzero(weights.sum(axis=1) == 0.0):
            seg = self.segments[k]
            raise CaseError(f"gas.boundaries.{side}: inflow segment {k} (start = {seg.start}, end = {seg.end}) "
                            f"covers no part of the side (0 to {edges[-1]:g} m): it lies outside it or under "
                            "later segments")
        return lambda t: weights.T @ self.velocities(t)

    def face_velocity_3d(self, side: str, edges: tuple[np.ndarray, np.ndarray]) -> Callable[[float], np.ndarray]:
        """t ↦ (n_a, n_b) interstitial velocity [m/s] on the boundary faces of a side of a 3D grid, ``edges``
        the face edges along its two in-plane axes: the segments along the first axis (each across the whole
        second), on the part of each face that no patch covers, plus each patch's velocity × the fraction of
        the face's area inside it."""
        ea, eb = (np.asarray(e, float) for e in edges)
        cover = np.zeros((ea.size - 1, eb.size - 1))
        fractions = []
        for k, patch in enumerate(self.patches):
            f = patch.fractions(ea, eb)
            if not f.any():
                a0, a1, b0, b1 = patch.bounds()
                raise CaseError(f"gas.boundaries.{side}: inflow patch {k} ({patch.shape}, from ({a0:g}, {b0:g}) to "
                                f"({a1:g}, {b1:g}) m) covers no part of the side ({ea[0]:g} to {ea[-1]:g} m by "
                                f"{eb[0]:g} to {eb[-1]:g} m)")
            fractions.append(f)
            cover += f
        background = np.clip(1.0 - cover, 0.0, 1.0)  # the patches do not overlap: cover <= 1 up to round-off
        seg_weights = self.face_weights(ea) if self.segments else np.zeros((0, ea.size - 1))
        for k in np.flatnonzero(seg_weights.sum(axis=1) == 0.0):
            seg = self.segments[k]
            raise CaseError(f"gas.boundaries.{side}: inflow segment {k} (start = {seg.start}, end = {seg.end}) "
                            f"covers no part of the side (0 to {ea[-1]:g} m): it lies outside it or under "
                            "later segments")
        patch_weights = np.array(fractions).reshape(len(fractions), ea.size - 1, eb.size - 1)
        patches = self.patches

        def velocity(t: float) -> np.ndarray:
            out = background * (seg_weights.T @ self.velocities(t))[:, None]
            for w, patch in zip(patch_weights, patches):
                out = out + w * patch.interstitial_velocity(t, self.voidage)
            return out

        return velocity

    @property
    def time_dependent(self) -> bool:
        return any(s.time_dependent for s in self.segments) or any(p.time_dependent for p in self.patches)

    def fastest_inflow(self) -> float:
        return max([fastest(s.interstitial) if s.interstitial is not None else fastest(s.superficial) / self.voidage
                    for s in (*self.segments, *self.patches)])


__all__ = ["Inflow", "Segment", "Rectangle", "Circle"]
