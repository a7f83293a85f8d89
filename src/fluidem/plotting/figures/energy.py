"""The energy budget against time (Hoomans et al. 1996 Fig 9), with the dissipated energy of hard-sphere runs."""
from __future__ import annotations

import numpy as np

from ..run import RunData
from ._shared import PlotOptions, figure, trace_axes

DISSIPATED_COLUMNS = ("dissipated_normal_J", "dissipated_tangential_J")  # hard-sphere runs (Hoomans eq. 51)


@figure("energy", "kinetic, rotational and potential energy (relative to its final value), in hard-sphere runs "
                  "the energy dissipated in collisions, and their sum against time (Hoomans et al. 1996 Fig 9)",
        lacks=lambda run: run.lacks_probes("kinetic_J", "potential_J"))
def draw_energy(run: RunData, options: PlotOptions):
    p = run.probes
    t = p["time_s"]
    kinetic = p["kinetic_J"]
    pe = p["potential_J"]
    finite = np.flatnonzero(np.isfinite(pe))
    pe_rel = pe - (pe[finite[-1]] if len(finite) else 0.0)
    fig, (ax,) = trace_axes()
    ax.plot(t, kinetic, label="kinetic")
    rotational = np.zeros_like(t)
    if "rotational_J" in p:  # hard-sphere runs without rotation may leave it out
        rotational = p["rotational_J"]
        ax.plot(t, rotational, label="rotational")
    ax.plot(t, pe_rel, label="potential − final potential")
    total = kinetic + rotational + pe_rel
    dissipated = [c for c in DISSIPATED_COLUMNS if c in p]
    if dissipated:  # hard spheres book what collisions take (Hoomans eqs 23, 27, 29): the sum is conserved
        lost = np.sum([p[c] for c in dissipated], axis=0)
        ax.plot(t, lost, label="dissipated in collisions")
        total = total + lost
    ax.plot(t, total, color="k", lw=1.8, label="sum")
    ax.set_ylabel("energy [J]")
    title = "energy budget"
    err = (run.summary or {}).get("energy_error_rel")
    if dissipated and isinstance(err, (int, float)) and not isinstance(err, bool) and np.isfinite(err):
        title += f" (energy conservation error {100.0 * err:.2g} %)"
    ax.set_title(title)
    ax.legend(loc="best")
    return fig
