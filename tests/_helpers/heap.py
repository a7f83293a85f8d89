"""Angle of repose of a 2D heap of discs (the rolling-resistance tests)."""
from __future__ import annotations

import math

import numpy as np


def heap_angle(pos, radius):
    """Angle of repose [deg] of a 2D heap: the slope of its flanks, fitted to the top particles of columns one
    diameter wide between 20 % and 80 % of the heap's height, both sides together."""
    d = 2.0 * radius.max()
    x, y = pos[:, 0], pos[:, 1] + radius
    on = y < 20 * d  # left-overs that rolled far still count (they lie on the floor)
    centre = np.median(x[on])
    bins = np.floor((x - centre) / d).astype(int)
    tops = {}
    for b, yy in zip(bins, y):
        tops[b] = max(tops.get(b, 0.0), yy)
    b = np.array(sorted(tops))
    top = np.array([tops[k] for k in b])
    height = top.max()
    keep = (top > 0.2 * height) & (top < 0.8 * height)
    dist = np.abs((b[keep] + 0.5) * d)
    slope = -np.polyfit(dist, top[keep], 1)[0]
    return math.degrees(math.atan(slope))
