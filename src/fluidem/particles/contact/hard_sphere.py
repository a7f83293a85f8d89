"""Instantaneous binary collisions of hard spheres (Hoomans et al. 1996, eqs 1–29).

Chosen with ``model = "hard_sphere"``; it selects the event-driven engine
(``particles/hardsphere.py``) instead of the soft-sphere one. A collision is fixed by
the restitution e (Newton's law, eq. 16) and the Coulomb friction μ (eq. 17); the
sticking class (eq. 25) ends with zero slip (eq. 28). Walls are bodies of infinite
mass; their e_w, μ_w come from ``wall_contact``/``wall_pairs`` as for soft spheres.

Inelastic collapse (infinitely many collisions in finite time, McNamara & Young 1994)
is prevented with the TC model of Luding & McNamara (1998, Granular Matter 1,
113–128): a collision in which either particle had its previous collision less than
``collapse_time`` t_c ago is treated as elastic and frictionless (e = 1, μ = 0). t_c is
the duration of a real contact. A particle that meets others more often than that is in
a lasting multi-particle contact, where a sequence of separate dissipative impacts is
the wrong picture. The default 1e-5 s is the Hertzian contact time of mm-sized glass or
aluminium spheres at impact speeds of about 1 m/s (10–40 µs from 1 down to 0.01 m/s).
Hoomans 1996 used no remedy; ``collapse_time = 0`` reproduces that.

Why the remedy is on by default. Under either force step (``particles.force_step``: the two
give the same trajectories under gravity), gravity is added as impulses, g DT every DT (eqs
33–34). In a resting bed that impulse reaches the floor
through a cascade of collisions microseconds or less apart, and without the remedy
dense frictional beds collapse. Measured:

* the Table 2 bed without gas (2400 spheres of 4 mm in a box 0.15 m wide, e = 0.9,
  μ = 0.3; benchmarks/hardsphere_collisions.py). Remedy off: 1.7 million collisions per
  step at t = 0.17 s, then a step with more than 25 million events, and the event
  limit stopped the run. Remedy on: the bed settles at 30–40 thousand collisions per
  step.
* 150 spheres of 3–4 mm, e = 0.6, μ = 0.5, in a box 0.04 m wide. Remedy off: collapse
  against the walls by t = 0.08 s. Remedy on: the bed settles at about 600 collisions
  per step.

Where the remedy fails: equal spheres that pack in a row fitting exactly between two
parallel walls. The built-in pour case is such a box, 24 diameters wide. Such a row has
gaps of round-off size. The remedy keeps its collisions elastic, so their energy never
leaves, and with t_c = 1e-5 s that row chattered at 2–5 million collisions per step
until the event limit stopped the run at t = 0.24 s. With ``collapse_time = 0`` the same
bed settles, at about 0.25 million collisions per step. Neither setting is safe in such
boxes: 120 spheres of 4 mm (e = 0.8) in a box 10 diameters wide hit the event limit at
t = 0.19 s with the remedy and at t = 0.20 s without it. A bed at rest under gravity and
without gas is the hardest case for Hoomans' scheme. The engine's per-step event limit
turns each such failure into a clear error instead of a hang. Three things help: a box
width that is not a whole number of diameters, a size distribution, or a smaller DT.

Packed row: slot 0 CODE (3), slot 1 restitution e, slot 2 collapse time t_c [s],
slot 7 friction μ. ``impulse`` is the collision law itself (eqs 10–29), which the event-driven
engine's kernels (``particles/_hardsphere_kernels.py``) apply to each collision.
"""
from __future__ import annotations

import math
from typing import ClassVar, Literal

import numpy as np
from numba import njit
from pydantic import Field

from .base import ContactModel, contact_models, empty_row

CODE = 3
SLOT_RESTITUTION, SLOT_COLLAPSE_TIME = 1, 2
# collision classes
NO_COLLISION, SLIDING, STICKING = 0, 1, 2


@contact_models.register("hard_sphere")
class HardSphere(ContactModel):
    """Hard-sphere collision law of Hoomans 1996: restitution e and friction μ, no stiffness.

    ``collapse_time`` t_c [s] is the TC-model time (Luding & McNamara 1998): a collision
    less than t_c after the previous collision of either particle is elastic and
    frictionless. 0 disables the remedy (as in Hoomans 1996); see the module docstring for
    when to do that.
    """

    model: Literal["hard_sphere"] = "hard_sphere"
    collapse_time: float = Field(
        1e-5, ge=0.0, lt=1.0,
        description="TC-model time t_c [s] (Luding & McNamara 1998): a collision within t_c of the previous one "
                    "of either particle is elastic and frictionless; 0 switches the remedy off (Hoomans 1996)")

    code: ClassVar[int] = CODE
    instantaneous: ClassVar[bool] = True
    reference_test: ClassVar[str] = "test_2d_pair_collision_follows_hoomans_eqs"  # Hoomans 1996 eqs 10-29

    def pack(self, body_i, body_j) -> np.ndarray:
        row = empty_row(CODE, self.friction)
        row[SLOT_RESTITUTION] = self.restitution
        row[SLOT_COLLAPSE_TIME] = self.collapse_time
        return row

    def contact_time(self, m_eff, r_eff, impact_velocity, body_i=None, body_j=None) -> float:
        """Collisions are instantaneous: no contact time limits the step."""
        return 0.0


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def impulse(nx, ny, nz, ux, uy, uz, inv_ma, inv_mb, ka, kb, e, mu):
    """Impulse on body a of a binary collision (Hoomans 1996 eqs 10–29, slip as a vector).

    n : unit normal from b to a; u : velocity of a's contact point relative to b's
    (u·n < 0 approaching); inv_m : 1/m [1/kg] (0 for a wall); k = R²/I [1/kg] (0 for a wall).

    Returns (P_n, P_t (3), E_n, E_t, kind): normal impulse magnitude along n [N s],
    tangential impulse on a [N s], energy dissipated by each part [J], and the class:
    SLIDING (eq. 24), STICKING (eq. 25) or NO_COLLISION when u·n >= 0.
    """
    c0 = ux * nx + uy * ny + uz * nz  # compression velocity C_0, eq. 14 (spin adds nothing along n)
    if c0 >= 0.0:  # not approaching (round-off after the prediction): no impulse
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, NO_COLLISION
    sx = ux - c0 * nx  # initial slip S_0, eq. 11 as a vector in the tangent plane
    sy = uy - c0 * ny
    sz = uz - c0 * nz
    b2 = inv_ma + inv_mb  # eq. 15
    b1 = b2 + ka + kb  # eq. 12
    pn = -(1.0 + e) * c0 / b2  # eq. 22
    en = c0 * c0 / (2.0 * b2) * (1.0 - e * e)  # eq. 23
    s = math.sqrt(sx * sx + sy * sy + sz * sz)
    if s >= mu * b1 * pn:  # sliding, eq. 24
        if s > 0.0:
            f = -mu * pn / s  # eq. 26: P_t = −μ P_n ŝ
            ptx = f * sx
            pty = f * sy
            ptz = f * sz
        else:
            ptx = 0.0
            pty = 0.0
            ptz = 0.0
        et = -mu * (1.0 + e) * c0 / b2 * (s + mu * b1 * (1.0 + e) * c0 / (2.0 * b2))  # eq. 27
        return pn, ptx, pty, ptz, en, et, SLIDING
    # sticking, eq. 25: the slip ends at zero
    ptx = -sx / b1  # eq. 28
    pty = -sy / b1
    ptz = -sz / b1
    et = s * s / (2.0 * b1)  # eq. 29
    return pn, ptx, pty, ptz, en, et, STICKING
