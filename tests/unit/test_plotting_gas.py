"""Gas figures of ``fluidem plot``: voidage maps, time-averaged solids fraction, pressure and its spectrum,
and the contact / gas force maps drawn on the gas grid.

The figures are drawn from a tiny coupled run (``_helpers.gas_fields.tiny_jet_case``: 0.02 s,
11 gas-field snapshots) made once for the module; tests that change data work on copies.
"""
from __future__ import annotations

import csv
import re
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

pytest.importorskip("matplotlib")

from fluidem.errors import CaseError  # noqa: E402
from fluidem.io.gas_fields import read_gas_fields  # noqa: E402
from fluidem.plotting import PlotOptions, RunData, render, style  # noqa: E402
from fluidem.plotting.figures import (averaging_window, parse_window, power_spectrum,  # noqa: E402
                                      pressure_probe_cell)

from _helpers.gas_fields import run_tiny_jet  # noqa: E402
from _helpers.plotting import assert_not_blank, fluidem, fraction_changed, read_png, stderr_notes  # noqa: E402

GAS_FIGURES = ("voidage", "solids_fraction", "pressure")
ONLY_GAS = ("--only", ",".join(GAS_FIGURES))  # plotting every figure of a run takes a few seconds


@pytest.fixture(scope="module")
def jet_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("jet") / "run"
    run_tiny_jet(out)
    return out


@pytest.fixture
def copy_run(jet_run, tmp_path):
    """``copy_run(name, pressure_probes=True)`` -> a copy of the jet run to change (without restart and figures);
    ``pressure_probes=False`` removes the pressure columns from probes.csv, so the pressure figure reads gas.h5."""

    def _copy(name="copy", pressure_probes=True):
        run = Path(shutil.copytree(jet_run, tmp_path / name, ignore=shutil.ignore_patterns("restart.h5", "figures")))
        if not pressure_probes:
            edit_probes(run, lambda cols: {k: v for k, v in cols.items()
                                           if not (k.startswith("pressure") or k.endswith("_Pa"))})
        return run

    return _copy


def edit_probes(run: Path, change) -> None:
    """Rewrite probes.csv with ``change({column: [str values]}) -> {column: values}``."""
    path = run / "probes.csv"
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    cols = {name: [r[k] for r in rows[1:]] for k, name in enumerate(rows[0])}
    cols = change(cols)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(list(cols))
        w.writerows(zip(*cols.values()))


def plot(run, out, *argv):
    assert fluidem("plot", run, "--out", out, *argv) == 0
    return out


def figure_of(run: Path, name: str, **options):
    [(_, fig, why)] = [r for r in render(RunData(run), PlotOptions(**options), only=[name])]
    assert why is None, why
    return fig


# ---------------------------------------------------------------- written, non-blank, from their data
def test_a_coupled_run_has_every_figure(jet_run, tmp_path, capsys):
    out = plot(jet_run, tmp_path / "figs")
    stdout, err = capsys.readouterr()
    assert stderr_notes(err, "plot") == {}
    assert {Path(p).stem for p in stdout.split()} == {"snapshots_height", "energy", "contacts", "multicontact",
                                                      "bed_height", *GAS_FIGURES, "forces"}
    for name in GAS_FIGURES:
        assert_not_blank(read_png(out / f"{name}.png"), name)
    svg = plot(jet_run, tmp_path / "svg", "--only", "voidage", "--format", "svg")
    assert "<svg" in (svg / "voidage.svg").read_text()[:2000]


def test_gas_figures_change_when_the_data_change(copy_run, tmp_path):
    """Same data, same pixels; a denser bed and a pressure oscillation in gas.h5 change every gas figure."""
    base = copy_run("base", pressure_probes=False)
    mod = copy_run("mod", pressure_probes=False)
    with h5py.File(mod / "gas.h5", "a") as f:
        for k, key in enumerate(sorted(f["snapshots"])):
            g = f["snapshots"][key]
            g["voidage"][...] = 1.0 - 1.5 * (1.0 - g["voidage"][...])
            g["p"][...] = g["p"][...] + 50.0 * np.sin(k)
    a, b = (plot(run, tmp_path / name, *ONLY_GAS) for run, name in [(base, "a"), (mod, "b")])
    again = plot(base, tmp_path / "again", "--only", "voidage")  # Agg is deterministic: one figure shows it
    assert fraction_changed(read_png(a / "voidage.png"), read_png(again / "voidage.png")) == 0.0
    for name in GAS_FIGURES:
        changed = fraction_changed(read_png(a / f"{name}.png"), read_png(b / f"{name}.png"))
        assert changed > 1e-3, f"{name}.png: only {changed:.4%} of the pixels changed with the data"


def test_every_gas_axis_is_labelled_with_a_unit(jet_run):
    unit = re.compile(r".+ \[.+\]$")
    for name in (*GAS_FIGURES, "forces"):
        fig = figure_of(jet_run, name)
        labels = [lab for ax in fig.axes for lab in (ax.get_xlabel(), ax.get_ylabel()) if lab]
        assert labels and all(unit.match(lab) for lab in labels), (name, labels)


# ---------------------------------------------------------------- voidage maps
def test_voidage_maps_at_chosen_times_with_and_without_particles(jet_run, tmp_path):
    g = read_gas_fields(jet_run)
    fig = figure_of(jet_run, "voidage", times=[0.01, 0.02])
    maps = [ax for ax in fig.axes if ax.get_title()]
    assert [ax.get_title() for ax in maps] == ["t = 0.010 s", "t = 0.020 s"]
    mesh = maps[1].collections[0]
    np.testing.assert_array_equal(np.asarray(mesh.get_array()).reshape(24, 6).T, g["voidage"][-1])
    assert len(maps[1].collections) == 2  # the map and the particles over it
    bare = figure_of(jet_run, "voidage", times=[0.01, 0.02], overlay=False)
    assert all(len(ax.collections) == 1 for ax in bare.axes if ax.get_title())
    with_p = plot(jet_run, tmp_path / "p", "--only", "voidage", "--times", "0.02")
    without = plot(jet_run, tmp_path / "n", "--only", "voidage", "--times", "0.02", "--no-overlay")
    assert fraction_changed(read_png(with_p / "voidage.png"), read_png(without / "voidage.png")) > 1e-3


# ---------------------------------------------------------------- time-averaged solids fraction
def test_solids_fraction_is_the_mean_over_the_window(jet_run, tmp_path):
    g = read_gas_fields(jet_run)
    for window, expected in [(None, g["time"] >= 0.01 - 1e-12), ((0.0, 0.004), g["time"] <= 0.004 + 1e-12)]:
        fig = figure_of(jet_run, "solids_fraction", window=window)
        mesh = fig.axes[0].collections[0]
        mean = np.asarray(mesh.get_array()).reshape(24, 6).T
        np.testing.assert_allclose(mean, (1.0 - g["voidage"][expected]).mean(axis=0), rtol=1e-12)
    first = plot(jet_run, tmp_path / "a", "--only", "solids_fraction", "--window", "0,0.004")
    second = plot(jet_run, tmp_path / "b", "--only", "solids_fraction")
    assert fraction_changed(read_png(first / "solids_fraction.png"), read_png(second / "solids_fraction.png")) > 1e-3


def test_averaging_window():
    assert averaging_window(np.linspace(0.0, 12.0, 121))[:2] == (5.0, 10.0)  # Sun 2007: 5-10 s
    t0, t1, mask = averaging_window(np.linspace(0.0, 4.0, 41))
    assert (t0, t1, int(mask.sum())) == (2.0, 4.0, 21)  # else the second half
    assert averaging_window(np.linspace(0.0, 4.0, 41), (1.0, 1.5))[2].sum() == 6
    with pytest.raises(CaseError, match=r"--window 5,6: no gas-field snapshot in it; .* 0 s to 4 s"):
        averaging_window(np.linspace(0.0, 4.0, 41), (5.0, 6.0))
    assert parse_window("5, 10") == (5.0, 10.0)
    for bad in ("5", "a,b", "1,2,3"):
        with pytest.raises(CaseError, match="--window"):
            parse_window(bad)
    with pytest.raises(CaseError, match="T0 < T1"):
        PlotOptions(window=(2.0, 1.0))


@pytest.mark.parametrize("argv, message", [
    (["--window", "1,2"], r"--window 1,2: no gas-field snapshot in it"),
    (["--window", "0.02,0.01"], r"T0 < T1"),
    (["--window", "soon"], r"--window 'soon'"),
])
def test_a_bad_window_is_a_case_error_and_writes_nothing(jet_run, tmp_path, argv, message):
    out = tmp_path / "figs"
    with pytest.raises(CaseError, match=message):
        fluidem("plot", jet_run, "--out", out, *argv)
    assert not out.exists()


# ---------------------------------------------------------------- pressure and its spectrum
def test_power_spectrum_finds_the_frequency_of_a_noisy_sine():
    rng = np.random.default_rng(1)
    t = np.arange(0.0, 10.0, 0.01) + rng.uniform(0.0, 2e-4, 1000)  # probes fire on the step after each 10 ms
    y = 300.0 + 40.0 * np.sin(2 * np.pi * 2.7 * t) + 5.0 * rng.normal(size=t.size)
    f, _, dominant = power_spectrum(t, y)
    assert abs(dominant - 2.7) <= f[1]  # within one frequency bin (0.2 Hz: segments of half the 1000 samples)
    assert power_spectrum(t[:7], y[:7]) is None


def test_pressure_probe_columns_give_the_traces_and_dominant_frequencies(copy_run):
    run = copy_run("probes")
    t = np.arange(0.0, 2.0, 0.005)

    def synthetic(cols):  # two probes, 4 Hz and 7 Hz, as another writer's columns would hold them
        return {"time_s": [repr(float(v)) for v in t],
                "pressure_drop_20cm_Pa": [repr(float(v)) for v in 900.0 + 80.0 * np.sin(2 * np.pi * 4.0 * t)],
                "p_probe_Pa": [repr(float(v)) for v in 101325.0 + 30.0 * np.sin(2 * np.pi * 7.0 * t)]}

    edit_probes(run, synthetic)
    fig = figure_of(run, "pressure")
    trace, spectrum = fig.axes
    assert trace.get_title() == "pressure (probes.csv)"
    assert [ln.get_label() for ln in trace.lines] == ["pressure drop 20cm", "p probe"]
    legend = [tx.get_text() for tx in spectrum.get_legend().get_texts()]
    assert [lab.split(":")[0] for lab in legend] == ["pressure drop 20cm", "p probe"]
    found = [float(re.fullmatch(r".+: dominant ([0-9.]+) Hz", lab).group(1)) for lab in legend]
    # 0.78 Hz: within a bin of the former 256-sample segments; the 200-sample segments of power_spectrum have
    # 1 Hz bins and place the dominant frequency between them
    bin_width = 1.0 / (256 * 0.005)
    assert abs(found[0] - 4.0) < bin_width and abs(found[1] - 7.0) < bin_width, found
    assert spectrum.get_xlabel() == "frequency [Hz]" and spectrum.get_yscale() == "log"


def test_without_pressure_probes_the_pressure_comes_from_gas_h5_20_cm_up(copy_run):
    run = copy_run("gas", pressure_probes=False)
    g = read_gas_fields(run)
    i, j = pressure_probe_cell(g["x"], g["y"], 0.01)
    assert (i, j) == (2, 20)  # x = 0.025 m next to the centre line, y = 0.205 m: the cell holding 0.2 m
    fig = figure_of(run, "pressure")
    trace = fig.axes[0]
    assert trace.get_title() == "pressure (gas.h5)"
    np.testing.assert_allclose(trace.lines[0].get_ydata(), g["p"][:, i, j] - 101325.0)
    assert trace.get_ylabel() == "p − 101325 Pa [Pa]"
    x, y = np.linspace(0.005, 0.145, 15), np.linspace(0.01, 0.89, 45)
    assert pressure_probe_cell(x, y, 0.02) == (7, 10)  # the tsuji-jet-background grid: x = 0.075 m, y = 0.21 m


# ---------------------------------------------------------------- runs without gas fields
@pytest.mark.parametrize("change, reason", [
    ("remove", "the run has no gas fields (gas.h5)"),
    ("corrupt", "gas.h5 cannot be read: "),
    ("empty", "gas.h5 holds no complete snapshots"),
])
def test_without_gas_fields_the_gas_figures_are_skipped_with_one_line(copy_run, tmp_path, capsys, change, reason):
    run = copy_run(change, pressure_probes=False)
    if change == "remove":
        (run / "gas.h5").unlink()
    elif change == "corrupt":
        (run / "gas.h5").write_bytes(b"not an HDF5 file")
    else:  # a run killed before its first gas snapshot was complete
        with h5py.File(run / "gas.h5", "a") as f:
            for key in list(f["snapshots"]):
                del f["snapshots"][key].attrs["complete"]
    out = plot(run, tmp_path / "figs", "--only", "snapshots," + ",".join(GAS_FIGURES))
    _, err = capsys.readouterr()
    notes = stderr_notes(err, "plot")  # every stderr line is a one-line note, no traceback
    assert set(notes) == set(GAS_FIGURES)
    assert notes["voidage"].startswith(reason) and notes["solids_fraction"].startswith(reason)
    assert notes["pressure"].startswith("probes.csv has no pressure columns (pressure*, *_Pa), and " + reason)
    assert (out / "snapshots_height.png").exists()
    assert not any((out / f"{name}.png").exists() for name in GAS_FIGURES)


def test_pressure_probes_alone_still_give_the_pressure_figure(copy_run, tmp_path, capsys):
    run = copy_run("probes-only")
    edit_probes(run, lambda cols: {**cols, "pressure_drop_20cm_Pa": [repr(float(k)) for k in range(len(cols["time_s"]))]})
    (run / "gas.h5").unlink()
    out = plot(run, tmp_path / "figs", *ONLY_GAS)
    _, err = capsys.readouterr()
    assert set(stderr_notes(err, "plot")) == {"voidage", "solids_fraction"}
    assert_not_blank(read_png(out / "pressure.png"), "pressure")


# ---------------------------------------------------------------- force maps (Sun et al. 2007 Figs 7/12)
def edit_snapshots(run: Path, change) -> None:
    """``change(group)`` on every particle snapshot of ``run`` (h5py groups, datasets writable)."""
    with h5py.File(run / "particles.h5", "a") as f:
        for key in sorted(f["snapshots"]):
            change(f["snapshots"][key])


def reference_force_sums(run: Path, t0: float, t1: float, nx=6, ny=24, dx=0.01, dy=0.01):
    """Per-cell sums of |F_contact| / (m g), |F_gas| / (m g) and particle counts over the snapshots in
    [t0, t1], particle by particle (the reference for the vectorised maps): 4 mm glass, 2500 kg/m^3."""
    weight = 2500.0 * np.pi / 6.0 * 0.004**3 * 9.81
    sc, sd, n = np.zeros((nx, ny)), np.zeros((nx, ny)), np.zeros((nx, ny))
    with h5py.File(run / "particles.h5", "r") as f:
        for key in sorted(f["snapshots"]):
            g = f["snapshots"][key]
            if not (t0 - 1e-12 <= g.attrs["time"] <= t1 + 1e-12):
                continue
            for x, c, d in zip(g["position"][...], g["contact_force"][...], g["gas_force"][...]):
                i, j = min(int(x[0] / dx), nx - 1), min(int(x[1] / dy), ny - 1)
                sc[i, j] += np.linalg.norm(c) / weight
                sd[i, j] += np.linalg.norm(d) / weight
                n[i, j] += 1
    return sc, sd, n


def test_force_maps_are_cell_means_of_the_snapshots_forces(jet_run, tmp_path):
    """Bottom row: the mean over every particle sample of a cell in the window (default the second half,
    0.01-0.02 s); top row: the last snapshot of the window; both against a particle-by-particle sum."""
    from fluidem.plotting.figures import force_maps

    inst, avg = force_maps(RunData(jet_run))
    assert (avg.t0, avg.t1, avg.snapshots) == (0.01, 0.02, 6) and inst.t1 == 0.02
    with np.errstate(invalid="ignore", divide="ignore"):
        for maps, (t0, t1) in [(avg, (0.01, 0.02)), (inst, (0.02, 0.02))]:
            sc, sd, n = reference_force_sums(jet_run, t0, t1)
            np.testing.assert_array_equal(maps.particles, n)
            np.testing.assert_allclose(maps.contact_force, np.where(n > 0, sc / n, np.nan), rtol=1e-12)
            np.testing.assert_allclose(maps.drag_force, np.where(n > 0, sd / n, np.nan), rtol=1e-12)
            ratio = np.where(n > 0, np.where(sd > 0, sc / sd, -1.0), np.nan)
            np.testing.assert_allclose(maps.force_ratio, ratio, rtol=1e-12)
    fig = figure_of(jet_run, "forces")
    panels = [ax for ax in fig.axes if ax.get_title()]
    assert [ax.get_title().split("\n") for ax in panels[::3]] == [
        ["contact force / m g", "t = 0.02 s"], ["mean 0.01–0.02 s", "(6 snapshots)"]]
    assert panels[2].get_title().split("\n") == ["contact / gas force", "(grey: −1, no gas force)", "t = 0.02 s"]
    for row, maps in enumerate((inst, avg)):
        for col, data in enumerate((maps.contact_force, maps.drag_force, maps.force_ratio)):
            shown = np.asarray(panels[3 * row + col].collections[0].get_array(), float).reshape(24, 6).T
            np.testing.assert_array_equal(np.isnan(shown), np.isnan(data))
            np.testing.assert_allclose(shown[~np.isnan(shown)], data[~np.isnan(data)], rtol=1e-12)
    labels = [ax.get_xlabel() or ax.get_ylabel() for ax in fig.axes if not ax.get_title()]  # the colour bars
    assert labels == ["contact force / m g [–]", "gas force / m g [–]", "contact / gas force [–]"]
    (tmp_path / "forces.png").write_bytes(style.png_bytes(fig))
    assert_not_blank(read_png(tmp_path / "forces.png"), "forces")


def test_force_ratio_is_minus_one_where_the_gas_force_is_zero_and_the_figure_follows_the_data(copy_run, tmp_path):
    base = copy_run("base")
    mod = copy_run("mod")

    def change(g):  # no gas force in the left column; contact forces tripled in the right half
        x = g["position"][:, 0]
        gas, contact = g["gas_force"][...], g["contact_force"][...]
        gas[x < 0.01] = 0.0
        contact[x > 0.03] = 3.0 * contact[x > 0.03] + [0.0, 2e-3, 0.0]
        g["gas_force"][...], g["contact_force"][...] = gas, contact

    edit_snapshots(mod, change)
    from fluidem.plotting.figures import force_maps

    for maps in force_maps(RunData(mod)):
        left = maps.particles[0] > 0
        assert left.any()
        np.testing.assert_array_equal(maps.force_ratio[0, left], -1.0)
        np.testing.assert_array_equal(maps.drag_force[0, left], 0.0)
    a, b = (plot(run, tmp_path / name, "--only", "forces") for run, name in [(base, "a"), (mod, "b")])
    assert fraction_changed(read_png(a / "forces.png"), read_png(b / "forces.png")) > 1e-3


def test_force_maps_window_and_missing_forces(copy_run, jet_run, tmp_path, capsys):
    fig = figure_of(jet_run, "forces", window=(0.0, 0.004))
    assert fig.axes[3].get_title() == "mean 0–0.004 s\n(3 snapshots)"
    assert fig.axes[0].get_title().endswith("t = 0.004 s")  # the last snapshot of the window
    with pytest.raises(CaseError, match=r"--window 1,2: no particle snapshot in it; .* 0 s to 0.02 s"):
        fluidem("plot", jet_run, "--only", "forces", "--window", "1,2", "--out", tmp_path / "none")
    assert not (tmp_path / "none").exists()
    run = copy_run("hard")  # as a hard-sphere coupled run: a gas force, no contact force
    edit_snapshots(run, lambda g: g.__delitem__("contact_force"))
    plot(run, tmp_path / "figs", "--only", "forces,multicontact")
    notes = stderr_notes(capsys.readouterr().err, "plot")
    assert set(notes) == {"forces"} and notes["forces"].startswith("particles.h5 has no field contact_force (")


def test_the_gas_grid_comes_from_case_toml_else_from_gas_h5(copy_run):
    run = copy_run("grid")
    grid = RunData(run).gas_grid()
    assert (grid.cells, grid.size, grid.depth) == ((6, 24), (0.06, 0.24), 0.004)
    text = (run / "case.toml").read_text()
    start = text.index("[gas.grid]")
    end = text.index("\n[", start + 1)
    (run / "case.toml").write_text(text[:start] + text[end + 1:])  # [gas] without its grid table
    fallback = RunData(run).gas_grid()
    assert fallback.cells == (6, 24) and np.allclose(fallback.size, (0.06, 0.24)) and fallback.depth == 0.004
    (run / "gas.h5").unlink()
    with pytest.raises(Exception, match=r"neither case.toml \[gas.grid\] nor gas.h5 gives the gas grid"):
        RunData(run).gas_grid()
