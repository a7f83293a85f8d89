"""The ``fluidem segregation`` subcommand: which species of a binary fluidised bed rises, and the chart.

::

    fluidem segregation --system D1,RHO1,D2,RHO2,X1 [--system ...] [--voidage 0.4] [--json]
    fluidem segregation --chart [--system ...] [--voidage 0.4] [--out segregation-chart.png]

The criterion is ``fluidem.analysis.segregation.segregation_criterion`` (Di Renzo & Di Maio 2012,
eqs 10-19). Each ``--system`` gives the two species' diameters [m] and densities [kg/m³] and the
volume fraction of species 1 in the solids. Stdout holds the result: a table per system, or with
``--json`` one JSON object ``{"voidage", "systems": [...], "chart"}``; with ``--chart`` the path of
the chart written (last line of the tables; in the JSON's ``"chart"``). Bad input raises
``CaseError`` (exit status 2, one message naming the option and value) before anything is written.
"""
from __future__ import annotations

import json
import logging
from pathlib import Path

from .errors import CaseError

DEFAULT_CHART = "segregation-chart.png"
SYSTEM_FIELDS = ("D1", "RHO1", "D2", "RHO2", "X1")

log = logging.getLogger(__name__)


def _number(option: str, text: str) -> float:
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise CaseError(f"{option} {text!r}: give a number") from None
    return value


def parse_system(text: str, voidage: float, viscosity: float, tolerance: float):
    """``"D1,RHO1,D2,RHO2,X1"`` → a ``SegregationResult``; CaseError naming the option, the field and the value."""
    from .analysis.segregation import segregation_criterion

    items = [t.strip() for t in str(text).split(",")]
    if len(items) != len(SYSTEM_FIELDS) or any(not t for t in items):
        got = len([t for t in items if t])
        raise CaseError(f"--system {text!r}: give five numbers, {','.join(SYSTEM_FIELDS)}: the diameter [m] and "
                        f"density [kg/m³] of species 1 and of species 2, and the volume fraction of species 1 in "
                        f"the solids (got {got})")
    values = []
    for name, t in zip(SYSTEM_FIELDS, items):
        try:
            values.append(float(t))
        except ValueError:
            raise CaseError(f"--system {text!r}: {name} = {t!r} is not a number") from None
    d1, r1, d2, r2, x1 = values
    try:
        return segregation_criterion((d1, d2), (r1, r2), x1, voidage, viscosity=viscosity, tolerance=tolerance)
    except CaseError as err:
        raise CaseError(f"--system {text!r}: {err}") from None


def _check_option(option: str, value: float, check) -> float:
    try:
        return check(value)
    except CaseError as err:
        raise CaseError(f"{option}: {err}") from None


def _chart_path(text: str) -> tuple[Path, str]:
    from .plotting.style import FORMATS

    path = Path(text)
    fmt = path.suffix.lower().lstrip(".")
    if fmt not in FORMATS:
        raise CaseError(f"--out {text!r}: the chart's file name must end in {', '.join('.' + f for f in FORMATS)}")
    return path, fmt


def _compositions(text: str | None) -> list[float]:
    from .analysis.segregation import CHART_COMPOSITIONS, _check_composition

    if text is None:
        return list(CHART_COMPOSITIONS)
    out = []
    for t in str(text).split(","):
        if t.strip():
            x = _number("--compositions", t.strip())
            out.append(_check_option("--compositions", x, lambda v: _check_composition(v, "x1")))
    if not out:
        raise CaseError(f"--compositions {text!r}: give at least one volume fraction x1 in [0, 1]")
    return out


def cmd_segregation(args) -> int:
    from .analysis.segregation import _check_voidage, _positive
    from .analysis.segregation import _number as _finite

    voidage = _check_option("--voidage", _number("--voidage", args.voidage), _check_voidage)
    viscosity = _check_option("--viscosity", _number("--viscosity", args.viscosity),
                              lambda v: _positive("mu", v, "the gas viscosity [Pa s]"))
    tolerance = _check_option("--tolerance", _number("--tolerance", args.tolerance), lambda v: _finite("tol", v))
    if tolerance < 0.0:
        raise CaseError(f"--tolerance {args.tolerance}: must be zero or positive")
    results = [parse_system(text, voidage, viscosity, tolerance) for text in args.system or []]
    if not results and not args.chart:
        raise CaseError("fluidem segregation needs --system D1,RHO1,D2,RHO2,X1 (one or more) or --chart")
    if not args.chart and (args.out is not None or args.compositions is not None):
        raise CaseError(f"{'--out' if args.out is not None else '--compositions'} is for the chart: add --chart")

    chart = None
    if args.chart:
        from .cli_plot import _require_matplotlib

        path, fmt = _chart_path(args.out if args.out is not None else DEFAULT_CHART)
        compositions = _compositions(args.compositions)
        _require_matplotlib("segregation --chart")
        from .plotting import style
        from .plotting.figures.segregation import draw_segregation_chart

        with style.context():
            fig = draw_segregation_chart(results, voidage=voidage, compositions=compositions)
            try:
                path.parent.mkdir(parents=True, exist_ok=True)
            except OSError as err:
                raise CaseError(f"--out {str(path)!r}: cannot create the folder: {err.strerror or err}") from None
            chart = style.save(fig, path.with_suffix(""), [fmt])[0]

    if args.json:
        print(json.dumps({"voidage": voidage, "systems": [r.as_dict() for r in results],
                          "chart": None if chart is None else str(chart)}, indent=2))
        return 0
    for i, (text, r) in enumerate(zip(args.system or [], results)):
        if i:
            print()
        print(f"system {i + 1}: --system {text} (voidage {voidage:g})")
        print(r.table())
    if chart is not None:
        if results:
            print()
        print(chart)
    return 0


def add_command(subparsers) -> None:
    """Register ``segregation`` on an argparse subparsers object."""
    p = subparsers.add_parser(
        "segregation", help="flotsam or jetsam: which species of a binary fluidised bed rises (Di Renzo & Di Maio)",
        description="The Di Renzo-Di Maio force balance (2012, eqs 10-19) on a binary mixture at minimum "
                    "fluidisation: which species rises to the surface (flotsam) and which sinks (jetsam), with "
                    "the quantities it goes through; --chart draws the equilibrium lines (Figs 1-2) with the "
                    "systems on them.")
    p.add_argument("--system", action="append", metavar="D1,RHO1,D2,RHO2,X1",
                   help="a binary system: diameter [m] and density [kg/m³] of species 1 and of species 2, and the "
                        "volume fraction of species 1 in the solids, e.g. 3e-4,2600,6e-4,1200,0.25 (repeatable)")
    p.add_argument("--voidage", default="0.4", metavar="EPS",
                   help="bed voidage at minimum fluidisation, between 0 and 1 (default 0.4, the chapter's Fig 1)")
    p.add_argument("--viscosity", default="1.8e-5", metavar="MU",
                   help="gas viscosity [Pa s] for the reported u_mf (default 1.8e-5, air; the verdict does not "
                        "depend on it)")
    p.add_argument("--tolerance", default="1e-9", metavar="TOL",
                   help="relative distance |s/s_eq - 1| from the equilibrium line at or below which a system "
                        "counts as mixed (default 1e-9: round-off only)")
    p.add_argument("--json", action="store_true", help="print JSON instead of tables")
    p.add_argument("--chart", action="store_true",
                   help="draw the chart: equilibrium lines at several compositions, the systems on them")
    p.add_argument("--compositions", metavar="X1[,X1]",
                   help="volume fractions of species 1 of the chart's lines (default 0.1,0.3,0.5,0.7,0.9)")
    p.add_argument("--out", metavar="FILE", help=f"the chart's file, .png, .svg or .pdf (default {DEFAULT_CHART})")
    p.set_defaults(func=cmd_segregation)
