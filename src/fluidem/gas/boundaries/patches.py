"""Inflow patches on a side of a 3D gas grid: rectangles and circles, each with its own velocity.

A patch is a piece of an ``Inflow`` side of a 3D grid (a distributor's central jet, one of its
nozzles) with one interstitial or superficial velocity, constant or a function of time. Its
coordinates are the side's two in-plane coordinates [m], in the order x, y, z with the side's normal
left out: (y, z) on left/right, (x, z) on bottom/top, (x, y) on front/back.

Faces are assigned by exact area: a boundary face takes the fraction of its area that lies inside
the patch (for a circle, the exact area of the circle–rectangle intersection), so a patch's mass
flow is ε ρ u × (its area inside the side), π r² u ε ρ for a circle within the side, however it
meets the grid. Patches replace the side's background (its ``segments``) where they lie and must not
overlap one another.
"""
from __future__ import annotations

import math
from typing import Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from .base import InflowVelocity


def _arcsin_area(u, r):
    """∫_0^u sqrt(r² − s²) ds for |u| ≤ r."""
    u = np.clip(u, -r, r)
    return 0.5 * (u * np.sqrt(np.maximum(r * r - u * u, 0.0)) + r * r * np.arcsin(u / r))


def circle_rectangle_area(x0, x1, y0, y1, radius):
    """Exact area [m²] of the intersection of the disc x² + y² ≤ radius² with the rectangles
    [x0, x1] × [y0, y1] (arrays of one shape, x0 ≤ x1, y0 ≤ y1).

    The integral over x of the length of [y0, y1] ∩ [−h(x), h(x)], h = sqrt(r² − x²), split where the
    integrand changes form (x = ±r, h(x) = |y0|, h(x) = |y1|): on each piece it is 0, a constant, or
    a constant ± h, integrated in closed form (``_arcsin_area``).
    """
    x0, x1, y0, y1 = np.broadcast_arrays(*(np.asarray(a, float) for a in (x0, x1, y0, y1)))
    r = float(radius)
    s0 = np.sqrt(np.maximum(r * r - y0 * y0, 0.0))
    s1 = np.sqrt(np.maximum(r * r - y1 * y1, 0.0))
    pts = np.stack([x0, x1, np.full_like(x0, -r), np.full_like(x0, r), -s0, s0, -s1, s1], axis=-1)
    pts = np.sort(np.clip(pts, x0[..., None], x1[..., None]), axis=-1)
    a, b = pts[..., :-1], pts[..., 1:]
    m = 0.5 * (a + b)
    h = np.sqrt(np.maximum(r * r - m * m, 0.0))
    Y0, Y1 = y0[..., None], y1[..., None]
    top_is_h = h < Y1  # the upper end of the chord is the circle (else y1)
    bottom_is_h = -h > Y0  # the lower end is the circle (else y0)
    ih = _arcsin_area(b, r) - _arcsin_area(a, r)  # ∫ h over the piece
    top = np.where(top_is_h, ih, Y1 * (b - a))
    bottom = np.where(bottom_is_h, -ih, Y0 * (b - a))
    inside = (np.abs(m) < r) & (np.minimum(Y1, h) > np.maximum(Y0, -h)) & (b > a)
    return np.where(inside, top - bottom, 0.0).sum(axis=-1)


class Patch(InflowVelocity):
    """Base of the inflow patches: one velocity (``InflowVelocity``) over a shape of the side."""

    def fractions(self, edges_a: np.ndarray, edges_b: np.ndarray) -> np.ndarray:
        """(n_a, n_b) fraction of each boundary face's area inside the patch, for the face edges ``edges_a``,
        ``edges_b`` [m] along the side's two in-plane axes."""
        raise NotImplementedError

    def area(self) -> float:
        """The patch's area [m²]."""
        raise NotImplementedError

    def bounds(self) -> tuple[float, float, float, float]:
        """(a0, a1, b0, b1): the bounding box [m] in the side's coordinates."""
        raise NotImplementedError


class Rectangle(Patch):
    """A rectangular inflow patch from ``start = (a0, b0)`` to ``end = (a1, b1)`` [m] in the side's in-plane
    coordinates (a slot, a porous plate's section)."""

    shape: Literal["rectangle"] = Field("rectangle", description="the patch's shape: a rectangle")
    start: tuple[float, float] = Field(description="(a0, b0): lower corner [m] in the side's in-plane coordinates")
    end: tuple[float, float] = Field(description="(a1, b1): upper corner [m]")

    @model_validator(mode="after")
    def _ordered(self):
        if not all(math.isfinite(v) for v in (*self.start, *self.end)):
            raise ValueError(f"start = {list(self.start)} and end = {list(self.end)} must be finite [m]")
        if not (self.end[0] > self.start[0] and self.end[1] > self.start[1]):
            raise ValueError(f"end = {list(self.end)} must exceed start = {list(self.start)} in both coordinates [m]")
        return self

    def fractions(self, edges_a, edges_b):
        ea, eb = np.asarray(edges_a, float), np.asarray(edges_b, float)
        la = np.clip(np.minimum(ea[1:], self.end[0]) - np.maximum(ea[:-1], self.start[0]), 0.0, None) / np.diff(ea)
        lb = np.clip(np.minimum(eb[1:], self.end[1]) - np.maximum(eb[:-1], self.start[1]), 0.0, None) / np.diff(eb)
        return np.outer(la, lb)

    def area(self) -> float:
        return (self.end[0] - self.start[0]) * (self.end[1] - self.start[1])

    def bounds(self):
        return self.start[0], self.end[0], self.start[1], self.end[1]


class Circle(Patch):
    """A circular inflow patch of ``radius`` [m] about ``centre = (a, b)`` [m] in the side's in-plane
    coordinates (a nozzle, a central jet)."""

    shape: Literal["circle"] = Field("circle", description="the patch's shape: a circle")
    centre: tuple[float, float] = Field(description="(a, b): centre [m] in the side's in-plane coordinates")
    radius: float = Field(gt=0.0, description="[m]")

    @field_validator("centre")
    @classmethod
    def _finite(cls, v):
        if not all(math.isfinite(c) for c in v):
            raise ValueError("must be finite [m]")
        return v

    def fractions(self, edges_a, edges_b):
        ea, eb = np.asarray(edges_a, float) - self.centre[0], np.asarray(edges_b, float) - self.centre[1]
        A0, B0 = np.meshgrid(ea[:-1], eb[:-1], indexing="ij")
        A1, B1 = np.meshgrid(ea[1:], eb[1:], indexing="ij")
        return circle_rectangle_area(A0, A1, B0, B1, self.radius) / ((A1 - A0) * (B1 - B0))

    def area(self) -> float:
        return math.pi * self.radius**2

    def bounds(self):
        (a, b), r = self.centre, self.radius
        return a - r, a + r, b - r, b + r


def overlap(p: Patch, q: Patch) -> bool:
    """True if the patches ``p`` and ``q`` share a positive area (touching is allowed)."""
    if isinstance(p, Circle) and isinstance(q, Circle):
        return math.dist(p.centre, q.centre) < p.radius + q.radius
    if isinstance(p, Rectangle) and isinstance(q, Rectangle):
        return p.start[0] < q.end[0] and q.start[0] < p.end[0] and p.start[1] < q.end[1] and q.start[1] < p.end[1]
    c, rect = (p, q) if isinstance(p, Circle) else (q, p)
    nearest = [min(max(c.centre[k], rect.start[k]), rect.end[k]) for k in range(2)]
    return math.dist(nearest, c.centre) < c.radius


__all__ = ["Circle", "Patch", "Rectangle", "circle_rectangle_area", "overlap"]
