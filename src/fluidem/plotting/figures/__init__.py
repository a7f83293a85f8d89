"""The figures of one run, one module per family, each figure a registered ``FigureSpec``.

A spec says why a run cannot have the figure (``lacks(run) -> str | None``, a one-line
reason such as "the run has no probes.csv") and draws it (``draw(run, options) ->
Figure``). ``render`` walks the registry in order and yields a figure or the reason it
was skipped; ``plot_run`` writes them. A new quantity (segregation indices, say) is one more
decorated function in the module of its family, imported here.

Registered, in this order: ``snapshots`` (``snapshots.py``: particles at chosen times, Hoomans
et al. 1996 Figs 8/10/12; coloured by N_c, Sun et al. 2007 Figs 6/10), ``energy``
(``energy.py``: budget against time, with the dissipated energy of hard-sphere runs, Hoomans
Fig 9), ``contacts`` and ``multicontact`` (``contacts.py``: coordination number and contacts,
Sun et al. 2007; bulk coordination number and multicontact ratio, Sun Figs 5/11),
``bed_height`` (``bed.py``: mean particle height, Sun 2007), ``pressure`` (``pressure.py``:
pressure probes against time and their power spectrum with the dominant frequency, Hoomans
Figs 11/13 and Sun Fig 3: probe columns ``pressure*`` / ``*_Pa``, else the gas field 0.2 m
above the bottom centre), ``voidage`` and ``solids_fraction`` (``voidage.py``: gas voidage
maps at chosen times with the particles over them, Hoomans Figs 10/12; time-averaged solids
fraction map, Sun Figs 4/8/13) and ``forces`` (``forces.py``: contact and gas force per
particle weight and their ratio on the gas grid, Sun Figs 7/12, from the particle snapshots'
``contact_force`` and ``gas_force``), ``segregation`` (``mixing.py``: species heights, segregation and
Lacey indices of a bed of several species, ``analysis.mixing``). ``_shared.py`` holds the registry, the options, the time
selection and the axes the families share. The gas figures read ``gas.h5``
(``fluidem.io.gas_fields``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...analysis.spectrum import power_spectrum  # the spectrum the pressure figure draws
from ...errors import CaseError
from .. import style
from ..run import RunData
# the family modules register their figures on import, in this order
from ._shared import (COLOR_MODES, DEFAULT_PANELS, FigureSpec, PlotOptions, averaging_window, figure, figures,
                      parse_names, parse_times, parse_window, render, select_snapshots, time_title)
from .snapshots import Colourer, View, draw_particles, draw_snapshots, setup_particle_axes, speed_max, view_of
from .energy import draw_energy
from .contacts import MULTICONTACT_COLUMNS, draw_contacts, draw_multicontact
from .bed import draw_bed_height
from .pressure import draw_pressure, pressure_probe_cell
from .voidage import draw_solids_fraction, draw_voidage
from .forces import FORCE_FIELDS, ForceMaps, draw_forces, force_maps, lacks_forces
from .mixing import draw_segregation

__all__ = ["COLOR_MODES", "DEFAULT_PANELS", "FigureSpec", "PlotOptions", "PlotResult", "figure", "figures", "render",
           "plot_run", "parse_names", "parse_times", "parse_window", "select_snapshots", "averaging_window",
           "time_title", "View", "view_of", "Colourer", "draw_particles", "setup_particle_axes", "speed_max",
           "pressure_probe_cell", "power_spectrum", "FORCE_FIELDS", "ForceMaps", "force_maps",
           "draw_snapshots", "draw_energy", "draw_contacts", "draw_multicontact", "draw_bed_height",
           "draw_pressure", "draw_voidage", "draw_solids_fraction", "draw_forces", "draw_segregation"]


@dataclass
class PlotResult:
    """What ``plot_run`` did: the files written and the figures skipped, each with its one-line reason."""

    written: list[Path] = field(default_factory=list)
    skipped: list[tuple[str, str]] = field(default_factory=list)  # (figure name, reason)


def plot_run(run: RunData, out_dir: Path, options: PlotOptions | None = None, formats=("png",),
             only: list[str] | None = None) -> PlotResult:
    """Write every figure that applies to ``run`` into ``out_dir``; the others are listed as skipped."""
    options = options or PlotOptions()
    # bad --times / --window: an error before anything is written
    if options.times is not None and run.lacks_snapshots() is None:
        select_snapshots(run.snapshot_times, options.times)
    elif options.times is not None and run.lacks_gas() is None and (only is None or "voidage" in only):
        select_snapshots(run.gas_times, options.times)
    if options.window is not None and run.lacks_gas() is None and (only is None or "solids_fraction" in only):
        averaging_window(run.gas_times, options.window)
    if options.window is not None and (only is None or "forces" in only) and lacks_forces(run) is None:
        averaging_window(run.snapshot_times, options.window, what="particle snapshot")
    if options.window is not None and (only is None or "multicontact" in only) \
            and run.lacks_probes(*MULTICONTACT_COLUMNS) is None:
        t = run.probes["time_s"]
        averaging_window(t[np.isfinite(t)], options.window, what="probe row")
    result = PlotResult()
    out_dir = Path(out_dir)
    with style.context():
        for spec, fig, why in render(run, options, only):
            if fig is None:
                result.skipped.append((spec.name, why))
                continue
            try:
                out_dir.mkdir(parents=True, exist_ok=True)
            except OSError as err:
                raise CaseError(f"--out {str(out_dir)!r}: cannot create the folder: {err.strerror or err}") from None
            result.written += style.save(fig, out_dir / spec.file_stem(options), list(formats))
    return result
