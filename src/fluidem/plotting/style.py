"""One look for every fluidem figure: rc settings, colours, axis labels with units, saving.

Figures are ``matplotlib.figure.Figure`` objects drawn by the Agg canvas; pyplot and
the global backend are never touched, so plotting works headless and inside a user's
notebook alike. Build and save figures inside ``with style.context():``.
"""
from __future__ import annotations

import io
import re
from contextlib import contextmanager
from pathlib import Path

RC = {
    "font.size": 9.0,
    "axes.titlesize": 9.0,
    "axes.labelsize": 9.0,
    "legend.fontsize": 8.0,
    "xtick.labelsize": 8.0,
    "ytick.labelsize": 8.0,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "grid.linewidth": 0.6,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "lines.linewidth": 1.4,
    "legend.frameon": False,
    "savefig.dpi": 150,
    "figure.dpi": 100,
    "svg.fonttype": "none",   # text stays text in SVG
    "svg.hashsalt": "fluidem",  # deterministic SVG ids
}

# Okabe–Ito: distinguishable with colour-vision deficiencies and in greyscale print.
LINE_COLOURS = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442", "#000000"]
# Initial-height bands alternate between two colours, as Hoomans et al. 1996 Figs 8/10/12 do.
BAND_COLOURS = ("#1B3A5C", "#F2C14E")
UNBANDED_COLOUR = "#9E9E9E"  # particles that were not in the first snapshot
SPEED_COLOURMAP = "viridis"
WALL_COLOUR = "#404040"
VOIDAGE_COLOURMAP = "cividis"  # gas voidage maps: dense bed dark, bubbles and freeboard light
SOLIDS_COLOURMAP = "magma_r"  # solids fraction maps: dense bed dark, freeboard white
# N_c classes 0, 1, 2, 3, ≥4 (Sun et al. 2007 Figs 6/10): free particles pale, multicontacts warm.
NC_COLOURS = ("#D9D9D9", "#56B4E9", "#009E73", "#E69F00", "#D55E00")
NC_LABELS = ("N_c = 0", "N_c = 1", "N_c = 2", "N_c = 3", "N_c ≥ 4")  # contacting particles of a particle
FORCE_COLOURMAP = "plasma"  # contact / gas force maps, scaled by the particle weight
RATIO_COLOURMAP = "viridis"  # contact / gas force ratio maps
NO_DRAG_COLOUR = "#BDBDBD"  # ratio −1: particles in the cell, no gas force on them
MAP_PARTICLE_FACE = (1.0, 1.0, 1.0, 0.35)  # particles drawn over a gas map: translucent, so the map shows
MAP_PARTICLE_EDGE = "#202020"

PANEL_HEIGHT_IN = 4.2  # height of one particle-snapshot panel [in]
TRACE_SIZE_IN = (6.4, 3.6)  # one time-trace panel [in]

LABELS = {  # probe and summary columns with their names and units
    "time_s": "time [s]",
    "kinetic_J": "kinetic energy [J]",
    "rotational_J": "rotational energy [J]",
    "potential_J": "potential energy [J]",
    "contacts": "particle contacts [–]",
    "wall_contacts": "wall contacts [–]",
    "coordination": "coordination number [–]",
    "multicontact_ratio": "multicontact ratio [–]",
    "dissipated_normal_J": "dissipated energy, normal [J]",
    "dissipated_tangential_J": "dissipated energy, tangential [J]",
    "total_energy_J": "total energy [J]",
    "max_overlap_rel": "largest overlap / diameter [–]",
    "mean_bed_height_m": "mean particle height [m]",
    "bed_height_m": "bed height [m]",
    "packing_fraction": "packing fraction [–]",
    "voidage": "voidage ε [–]",
    "solids_fraction": "solids fraction 1 − ε [–]",
    "p": "pressure [Pa]",
    "frequency_Hz": "frequency [Hz]",
}
UNIT_SUFFIXES = {"J": "J", "m": "m", "s": "s", "Pa": "Pa", "N": "N", "W": "W", "m_s": "m/s", "kg": "kg",
                 "rel": "–", "per_s": "1/s", "Hz": "Hz", "m2": "m²"}


def label(column: str) -> str:
    """Axis label with unit for a probe or summary column, e.g. ``pressure_drop_Pa`` → 'pressure drop [Pa]'."""
    if column in LABELS:
        return LABELS[column]
    for suffix in sorted(UNIT_SUFFIXES, key=len, reverse=True):
        m = re.fullmatch(rf"(.+)_{re.escape(suffix)}", column)
        if m:
            return f"{m.group(1).replace('_', ' ')} [{UNIT_SUFFIXES[suffix]}]"
    return f"{column.replace('_', ' ')} [–]"


def _rc() -> dict:
    from cycler import cycler

    return dict(RC, **{"axes.prop_cycle": cycler(color=LINE_COLOURS)})


@contextmanager
def context():
    """Apply the fluidem style for the figures built and saved inside the block."""
    import matplotlib

    with matplotlib.rc_context(_rc()):
        yield


def new_figure(width_in: float, height_in: float, **kw):
    """A Figure on an Agg canvas with constrained layout (no pyplot, no global backend)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    kw.setdefault("layout", "constrained")
    fig = Figure(figsize=(width_in, height_in), **kw)
    FigureCanvasAgg(fig)
    return fig


FORMATS = ("png", "svg", "pdf")


def parse_formats(text: str) -> list[str]:
    """``"png,svg"`` → ["png", "svg"]; raises CaseError naming a format that is not allowed."""
    from ..errors import CaseError

    out = []
    for item in str(text).split(","):
        fmt = item.strip().lower().lstrip(".")
        if not fmt:
            continue
        if fmt not in FORMATS:
            raise CaseError(f"--format {item.strip()!r}: allowed are {', '.join(FORMATS)}")
        if fmt not in out:
            out.append(fmt)
    if not out:
        raise CaseError(f"--format {text!r}: give at least one of {', '.join(FORMATS)}")
    return out


def save(fig, stem: Path, formats: list[str]) -> list[Path]:
    """Write ``fig`` as ``stem.<fmt>`` for each format, each file replaced atomically; returns the paths."""
    from ..io.atomic import atomic_path

    paths = []
    for fmt in formats:
        path = Path(f"{stem}.{fmt}")
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format=fmt, metadata=_metadata(fmt))
        paths.append(path)
    return paths


def png_bytes(fig, dpi: float | None = None) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, metadata=_metadata("png"))
    return buf.getvalue()


def _metadata(fmt: str) -> dict:
    # no creation dates: the same data gives the same file
    if fmt == "png":
        return {"Software": "fluidem"}
    if fmt == "svg":
        return {"Date": None, "Creator": "fluidem"}
    if fmt == "pdf":
        return {"CreationDate": None, "Creator": "fluidem"}
    return {}
