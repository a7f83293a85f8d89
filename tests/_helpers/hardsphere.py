"""The built-in ``pour`` case turned into hard spheres (Hoomans et al. 1996 §5.1), its energy error and overlap.

e = e_w = 0.9, μ = μ_w = 0.3 (the case sets no wall_contact, so the walls use the particle law) and the
TC collapse remedy off (collapse_time = 0) and Hoomans' force step (eqs 33–34), as in Hoomans 1996.
"""
from __future__ import annotations

import numpy as np

from fluidem.case import load_case

HARD = {"model": "hard_sphere", "restitution": 0.9, "friction": 0.3, "collapse_time": 0.0}


def pour_case(dt=1e-4, force_step="hoomans", **over):
    """The hard-sphere pour with force step ``dt`` [s] of the kind ``force_step`` and further ``--set`` style
    overrides."""
    return load_case("pour", {"particles.contact": dict(HARD), "particles.force_step": force_step, "time.dt": dt,
                              **over})


def relative_energy_error(eng, e0):
    """(E − E_0) / E_0 of an engine whose energies include the dissipated energy (Hoomans 1996 eq. 51)."""
    return (eng.energies()["total_J"] - e0) / e0


def max_overlap(eng):
    """Largest overlap between two particles or a particle and a wall, over the largest diameter."""
    st = eng.state
    r = st.position[:, None, :2] - st.position[None, :, :2]
    dist = np.sqrt(np.einsum("ijk,ijk->ij", r, r))
    np.fill_diagonal(dist, np.inf)
    sig = st.radius[:, None] + st.radius[None, :]
    wall = max(float(np.max(st.radius - (st.position - p.point) @ p.normal)) for p in eng.walls.planes)
    return max(float(np.max(sig - dist)), wall) / (2 * st.radius.max())
