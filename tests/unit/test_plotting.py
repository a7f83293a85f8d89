"""``fluidem plot | animate | compare`` and the published-numbers table.

Most tests share one short pour run (0.05 s, 3 snapshots, 11 probe rows) made once per
test run; tests that change data work on a copy. The commands are driven through the
parser that ``fluidem.cli_plot.add_commands`` builds, as the main CLI does.
"""
from __future__ import annotations

import argparse
import contextlib
import csv
import io
import json
import re
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

pytest.importorskip("matplotlib")

from fluidem.cli_plot import add_commands  # noqa: E402
from fluidem.errors import CaseError  # noqa: E402
from fluidem.plotting import PlotOptions, RunData, comparison_rows, render  # noqa: E402
from fluidem.plotting.figures import parse_times, select_snapshots, view_of  # noqa: E402
from fluidem.plotting.published import PUBLISHED  # noqa: E402

from _helpers.plotting import assert_not_blank, fluidem, fraction_changed, read_png, stderr_notes  # noqa: E402

ALL_FIGURES = {"snapshots_height", "energy", "contacts", "multicontact", "bed_height"}  # what a DEM run has
GAS_ONLY = {"pressure", "voidage", "solids_fraction", "forces"}  # what a DEM run lacks: pressure probes, gas, gas force


@pytest.fixture
def run_copy(pour_run, tmp_path):
    """``run_copy(name)`` -> a copy of the pour run (without its restart file) to modify."""

    def _copy(name="modified"):
        return Path(shutil.copytree(pour_run, tmp_path / name, ignore=shutil.ignore_patterns("restart.h5", "figures")))

    return _copy


# ---------------------------------------------------------------- plot
@pytest.fixture(scope="module")
def plotted(pour_run, tmp_path_factory):
    """``fluidem plot POUR --out DIR`` once for the module: (DIR, stdout, stderr)."""
    out = tmp_path_factory.mktemp("plotted") / "figs"
    stdout, stderr = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
        assert fluidem("plot", pour_run, "--out", out) == 0
    return out, stdout.getvalue(), stderr.getvalue()


def test_plot_writes_every_figure_of_a_dem_run_as_a_nonblank_png(plotted):
    out, stdout, err = plotted
    assert {p.stem for p in out.glob("*.png")} == ALL_FIGURES
    assert sorted(Path(s) for s in stdout.split()) == sorted(out.glob("*.png"))
    for path in out.glob("*.png"):
        assert_not_blank(read_png(path), path.name)
    # a DEM run has no gas: the gas figures are skipped with one line each, nothing else is
    assert set(stderr_notes(err, "plot")) == GAS_ONLY


def test_default_output_folder_and_svg(pour_run, run_copy, capsys):
    run = run_copy()
    assert fluidem("plot", run, "--only", "energy", "--format", "svg,png") == 0
    assert sorted(p.name for p in (run / "figures").iterdir()) == ["energy.png", "energy.svg"]
    assert "<svg" in (run / "figures" / "energy.svg").read_text()[:2000]


def test_every_axis_is_labelled_with_a_unit(pour_run):
    unit = re.compile(r".+ \[.+\]$")
    for spec, fig, why in render(RunData(pour_run), PlotOptions(color="speed")):
        if fig is None:
            continue
        labels = [lab for ax in fig.axes for lab in (ax.get_xlabel(), ax.get_ylabel()) if lab]
        xs = [ax.get_xlabel() for ax in fig.axes if ax.get_xlabel()]
        ys = [ax.get_ylabel() for ax in fig.axes if ax.get_ylabel()]
        assert xs and ys, f"{spec.name}: axes without labels"
        assert all(unit.match(lab) for lab in labels), f"{spec.name}: label without unit in {labels}"


def test_figures_change_when_the_data_change(pour_run, plotted, run_copy, tmp_path):
    """Each figure is drawn from its data: the same data give the same pixels, changed data others."""
    mod = run_copy()
    path = mod / "probes.csv"
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for k, r in enumerate(rows):
        r["kinetic_J"] = repr(3.0 * float(r["kinetic_J"]))
        r["coordination"] = repr(float(r["coordination"]) + 0.5)
        r["multicontact_ratio"] = repr(0.5 + 0.4 * np.sin(k))
        r["contacts"] = str(int(r["contacts"]) + 10)
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    with h5py.File(mod / "particles.h5", "a") as f:
        last = f["snapshots"][sorted(f["snapshots"])[-1]]["position"]
        last[:, 1] = last[:, 1] * 0.7  # the last snapshot's bed is lower

    a, b, again = plotted[0], tmp_path / "b", tmp_path / "again"
    assert fluidem("plot", mod, "--out", b) == 0
    assert fluidem("plot", pour_run, "--out", again, "--only", "energy") == 0
    assert fraction_changed(read_png(a / "energy.png"), read_png(again / "energy.png")) == 0.0
    for name in ALL_FIGURES:
        changed = fraction_changed(read_png(a / f"{name}.png"), read_png(b / f"{name}.png"))
        assert changed > 1e-3, f"{name}.png: only {changed:.4%} of the pixels changed with the data"


def test_colour_modes_and_times_change_the_snapshot_figure(pour_run, tmp_path):
    imgs = {}
    for key, extra in {"height": [], "speed": ["--color", "speed"], "species": ["--color", "species"],
                       "t0": ["--times", "0"]}.items():
        out = tmp_path / key
        times = [] if key == "t0" else ["--times", "0.04"]
        assert fluidem("plot", pour_run, "--only", "snapshots", "--out", out, *times, *extra) == 0
        (png,) = out.glob("*.png")
        imgs[key] = read_png(png)
        assert_not_blank(imgs[key], key)
    for x, y in [("height", "speed"), ("height", "species"), ("speed", "species"), ("height", "t0")]:
        assert fraction_changed(imgs[x], imgs[y]) > 1e-3, (x, y)


def test_snapshot_selection():
    three = np.array([0.0, 0.02, 0.04])
    assert select_snapshots(three, None) == [0, 1, 2]
    ten = np.linspace(0.0, 0.9, 10)
    assert select_snapshots(ten, None) == [0, 3, 6, 9]  # 4 evenly spaced, first and last included
    assert select_snapshots(three, [0.041, 0.019, 0.02]) == [2, 1]  # nearest, in order, no repeats
    assert parse_times("0, 0.5,1") == [0.0, 0.5, 1.0]
    with pytest.raises(CaseError, match=r"--times 0\.2: outside .* 0 s to 0\.04 s"):
        select_snapshots(three, [0.2])
    with pytest.raises(CaseError, match="--times 'soon': not a number"):
        parse_times("0,soon")


def test_plot_help_lists_every_registered_figure():
    """The --only help names the figures without importing the plotting package at CLI start-up;
    this keeps it in step with the registry."""
    from fluidem.plotting import figures

    parser = argparse.ArgumentParser(prog="fluidem")
    add_commands(parser.add_subparsers(dest="command"))
    plot = parser._subparsers._group_actions[0].choices["plot"]
    only = next(a for a in plot._actions if "--only" in a.option_strings)
    assert [n.strip() for n in only.help.split(":", 1)[1].split(",")] == [name for name, _ in figures.items()]


@pytest.mark.parametrize("argv, message", [
    (["--times", "7"], r"--times 7: outside the snapshots"),
    (["--times", "x"], r"--times 'x': not a number"),
    (["--format", "jpg"], r"--format 'jpg': allowed are png, svg, pdf"),
    (["--only", "energie"], r"unknown figure 'energie'.*did you mean 'energy'"),
    (["--bands", "0"], r"--bands 0"),
    (["--window", "1,2"], r"--window 1,2: no probe row in it; the probe rows run from 0 s to 0.05"),
])
def test_bad_options_are_case_errors_and_write_nothing(pour_run, tmp_path, argv, message):
    out = tmp_path / "figs"
    with pytest.raises(CaseError, match=message):
        fluidem("plot", pour_run, "--out", out, *argv)
    assert not out.exists()


@pytest.mark.parametrize("remove, skipped", [
    (["probes.csv"], {"energy", "contacts", "multicontact"} | GAS_ONLY),
    (["particles.h5"], {"snapshots", "bed_height"} | GAS_ONLY),
    (["probes.csv", "particles.h5", "summary.json"],
     {"snapshots", "energy", "contacts", "multicontact", "bed_height"} | GAS_ONLY),
    ("truncate probes.csv", {"energy", "contacts", "multicontact"} | GAS_ONLY),
    ("corrupt particles.h5", {"snapshots", "bed_height"} | GAS_ONLY),
])
def test_a_missing_quantity_skips_its_figure_with_a_one_line_note(run_copy, tmp_path, capsys, remove, skipped):
    run = run_copy()
    if remove == "truncate probes.csv":  # header only, as after a crash before the first probe
        path = run / "probes.csv"
        path.write_text(path.read_text().splitlines()[0] + "\n")
    elif remove == "corrupt particles.h5":
        (run / "particles.h5").write_bytes(b"not an HDF5 file")
    else:
        for name in remove:
            (run / name).unlink()
    out = tmp_path / "figs"
    assert fluidem("plot", run, "--out", out) == 0
    _, err = capsys.readouterr()
    notes = stderr_notes(err, "plot")  # every stderr line is a one-line note
    assert set(notes) == skipped
    names = {"snapshots": "snapshots_height"}
    written = {p.stem for p in out.glob("*.png")} if out.exists() else set()
    assert written == ALL_FIGURES - {names.get(s, s) for s in skipped}


@pytest.mark.parametrize("command", ["plot", "animate", "compare", "report"])
def test_a_path_that_is_not_a_run_directory_is_a_case_error(tmp_path, command):
    (tmp_path / "file.txt").write_text("not a run")
    (tmp_path / "empty").mkdir()
    for path, message in [(tmp_path / "empty", "not a run directory: it has no case.toml"),
                          (tmp_path / "nowhere", "does not exist"),
                          (tmp_path / "file.txt", "not a run directory")]:
        with pytest.raises(CaseError, match=message):
            fluidem(command, path)


# ---------------------------------------------------------------- N_c colours (Sun et al. 2007 Figs 6/10)
def rewrite_probes(run: Path, change) -> None:
    """Rewrite probes.csv with ``change({column: float array}) -> {column: array}``."""
    cols = {k: v.copy() for k, v in RunData(run).probes.items()}
    cols = change(cols)
    with open(run / "probes.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(list(cols))
        w.writerows(zip(*[[repr(float(x)) for x in v] for v in cols.values()]))


def set_last_contacts(run: Path, contacts) -> None:
    with h5py.File(run / "particles.h5", "a") as f:
        g = f["snapshots"][max(f["snapshots"])]
        g["contacts"][...] = contacts


def test_nc_colours_follow_each_particles_contact_number(run_copy, tmp_path):
    """--color nc: N_c 0, 1, 2, 3 and >= 4 get the five colours of style.NC_COLOURS, keyed in a legend;
    other contact numbers draw other pixels."""
    from matplotlib.colors import to_rgba_array

    from fluidem.plotting import style
    from fluidem.plotting.figures import Colourer

    run = run_copy("nc")
    n = len(RunData(run).snapshot(-1)["diameter"])
    set_last_contacts(run, np.arange(n) % 7)  # 0..6: the classes 0, 1, 2, 3 and >= 4
    data = RunData(run)
    first, last = data.snapshot(0), data.snapshot(-1)
    colours = Colourer("nc", data, view_of(data, first), first).colours(last)
    expected = to_rgba_array(style.NC_COLOURS)[np.minimum(np.arange(n) % 7, 4)]
    np.testing.assert_array_equal(colours, expected)
    [(_, fig, why)] = list(render(data, PlotOptions(color="nc", times=[0.05]), only=["snapshots"]))
    assert why is None
    assert [t.get_text() for leg in fig.legends for t in leg.get_texts()] == list(style.NC_LABELS)
    imgs = {}
    for key, contacts, colour in [("nc", None, "nc"), ("height", None, "height"), ("zero", 0, "nc")]:
        if contacts is not None:
            set_last_contacts(run, contacts)
        out = tmp_path / key
        assert fluidem("plot", run, "--only", "snapshots", "--times", "0.05", "--color", colour, "--out", out) == 0
        imgs[key] = read_png(out / f"snapshots_{colour}.png")
        assert_not_blank(imgs[key], key)
    assert fraction_changed(imgs["nc"], imgs["height"]) > 1e-3
    assert fraction_changed(imgs["nc"], imgs["zero"]) > 1e-3


def test_nc_colours_without_a_contacts_field_skip_with_a_note(run_copy, tmp_path, capsys):
    run = run_copy("old")
    with h5py.File(run / "particles.h5", "a") as f:  # a run written before N_c was stored
        for key in f["snapshots"]:
            del f["snapshots"][key]["contacts"]
    out = tmp_path / "figs"
    assert fluidem("plot", run, "--only", "snapshots,energy", "--color", "nc", "--out", out) == 0
    notes = stderr_notes(capsys.readouterr().err, "plot")
    assert set(notes) == {"snapshots"} and "particles.h5 has no field contacts" in notes["snapshots"]
    assert [p.name for p in out.iterdir()] == ["energy.png"]
    with pytest.raises(CaseError, match="no field contacts"):
        fluidem("animate", run, "--color", "nc", "--out", tmp_path / "nc.mp4")


# ---------------------------------------------------------------- multicontact (Sun et al. 2007 Figs 5/11)
def test_multicontact_figure_shows_both_traces_and_their_window_means(run_copy, tmp_path):
    run = run_copy("mc")
    rewrite_probes(run, lambda c: {**c, "multicontact_ratio": 0.3 + 0.2 * np.sin(200.0 * c["time_s"]),
                                   "coordination": 1.2 + np.cos(300.0 * c["time_s"])})
    p = RunData(run).probes
    t = p["time_s"]
    for window, inside in [(None, t >= 0.5 * t[-1] - 1e-12),  # pour has no summary window: the second half
                           ((0.01, 0.03), (t >= 0.01 - 1e-12) & (t <= 0.03 + 1e-12))]:
        [(_, fig, why)] = list(render(RunData(run), PlotOptions(window=window), only=["multicontact"]))
        assert why is None
        for ax, col in zip(fig.axes, ("coordination", "multicontact_ratio")):
            np.testing.assert_array_equal(ax.lines[0].get_ydata(), p[col])
            legend = [x.get_text() for x in ax.get_legend().get_texts()]
            mean = float(re.search(r": (\S+)$", legend[1]).group(1))
            assert mean == pytest.approx(p[col][inside].mean(), rel=1e-2), (col, window)
    # summary.json's window (coupled runs) is the default
    summary = json.loads((run / "summary.json").read_text())
    (run / "summary.json").write_text(json.dumps({**summary, "averages_window_s": [0.0, 0.02]}))
    [(_, fig, _)] = list(render(RunData(run), PlotOptions(), only=["multicontact"]))
    assert fig.axes[0].get_legend().get_texts()[1].get_text().startswith("mean over 0–0.02 s")

    base, mod = tmp_path / "base", tmp_path / "mod"
    assert fluidem("plot", run, "--only", "multicontact", "--out", base) == 0
    rewrite_probes(run, lambda c: {**c, "multicontact_ratio": 0.9 - 0.3 * c["multicontact_ratio"]})
    assert fluidem("plot", run, "--only", "multicontact", "--out", mod) == 0
    a = read_png(base / "multicontact.png")
    assert_not_blank(a, "multicontact")
    assert fraction_changed(a, read_png(mod / "multicontact.png")) > 1e-3


def test_multicontact_without_its_column_is_skipped_with_a_note(run_copy, tmp_path, capsys):
    run = run_copy("nomc")
    rewrite_probes(run, lambda c: {k: v for k, v in c.items() if k != "multicontact_ratio"})
    assert fluidem("plot", run, "--only", "multicontact,contacts", "--out", tmp_path / "f") == 0
    notes = stderr_notes(capsys.readouterr().err, "plot")
    assert notes == {"multicontact": "probes.csv has no column multicontact_ratio"}


# ---------------------------------------------------------------- hard-sphere energy (Hoomans et al. 1996 Fig 9)
def test_hard_sphere_energy_adds_the_dissipated_energy_and_a_conserved_sum(pour_run, run_copy, tmp_path):
    run = run_copy("hard")

    def hard_sphere_columns(c):  # what collisions dissipated: everything the soft-sphere run lost, 80 % normal
        lost = (c["potential_J"][0] - c["potential_J"]) - c["kinetic_J"] - c["rotational_J"]
        return {**c, "dissipated_normal_J": 0.8 * lost, "dissipated_tangential_J": 0.2 * lost,
                "total_energy_J": c["kinetic_J"] + c["rotational_J"] + c["potential_J"] + lost}

    rewrite_probes(run, hard_sphere_columns)
    summary = json.loads((run / "summary.json").read_text())
    (run / "summary.json").write_text(json.dumps({**summary, "energy_error_rel": 5e-5}))
    p = RunData(run).probes
    [(_, fig, why)] = list(render(RunData(run), PlotOptions(), only=["energy"]))
    assert why is None
    ax = fig.axes[0]
    lines = {ln.get_label(): np.asarray(ln.get_ydata()) for ln in ax.lines}
    assert list(lines) == ["kinetic", "rotational", "potential − final potential", "dissipated in collisions", "sum"]
    np.testing.assert_allclose(lines["dissipated in collisions"],
                               p["dissipated_normal_J"] + p["dissipated_tangential_J"], rtol=1e-12)
    # kinetic + rotational + potential + dissipated is conserved: the sum is flat at the potential energy released
    released = p["potential_J"][0] - p["potential_J"][-1]
    np.testing.assert_allclose(lines["sum"], released, rtol=1e-9, atol=1e-12 * released)
    assert ax.get_title() == "energy budget (energy conservation error 0.005 %)"
    out = tmp_path / "hard"
    assert fluidem("plot", run, "--only", "energy", "--out", out) == 0
    soft = tmp_path / "soft"
    assert fluidem("plot", pour_run, "--only", "energy", "--out", soft) == 0
    assert fraction_changed(read_png(out / "energy.png"), read_png(soft / "energy.png")) > 1e-3


# ---------------------------------------------------------------- 3D projection
def write_fake_3d_run(folder: Path) -> Path:
    """A hand-made 3D run directory: box 20 × 60 × 100 mm (x × y × z), gravity −z, two species."""
    folder.mkdir()
    (folder / "case.toml").write_text(
        'name = "fake3d"\ngravity = [0.0, 0.0, -9.81]\n'
        "[particles]\ndimensions = 3\n"
        '[[particles.species]]\nname = "glass"\ndiameter = 0.004\ndensity = 2500.0\ncount = 60\n'
        '[[particles.species]]\nname = "steel"\ndiameter = 0.006\ndensity = 7800.0\ncount = 20\n'
        '[particles.contact]\nmodel = "linear_spring_dashpot"\nstiffness = 800.0\n'
        '[[walls]]\nname = "box"\nkind = "box"\nlower = [0.0, 0.0, 0.0]\nupper = [0.02, 0.06, 0.1]\n'
        "[time]\nend = 0.1\n")
    rng = np.random.default_rng(0)
    n = 80
    species = np.r_[np.zeros(60, np.int32), np.ones(20, np.int32)]
    diameter = np.where(species == 0, 0.004, 0.006)
    with h5py.File(folder / "particles.h5", "w") as f:
        for k, t in enumerate([0.0, 0.05, 0.1]):
            g = f.create_group(f"snapshots/{k:06d}")
            g.attrs["time"] = t
            g.attrs["step"] = k * 100
            pos = rng.uniform([0.003, 0.003, 0.003], [0.017, 0.057, 0.097 - 0.3 * t], size=(n, 3))
            g["position"] = pos
            g["velocity"] = rng.normal(size=(n, 3))
            g["omega"] = np.zeros((n, 3))
            g["diameter"] = diameter
            g["species"] = species
            g["id"] = np.arange(n)
    return folder


def test_3d_runs_are_projected_onto_the_vertical_plane_of_the_wider_axis(tmp_path):
    run = RunData(write_fake_3d_run(tmp_path / "fake3d"))
    first = run.snapshot(0)
    view = view_of(run, first)
    assert (view.horizontal, view.vertical, view.depth) == (1, 2, 0)  # y is wider than x: depth is x
    np.testing.assert_array_equal(view.project(first["position"]), first["position"][:, [1, 2]])
    [(spec, fig, why)] = [r for r in render(run, PlotOptions(color="species")) if r[0].name == "snapshots"]
    assert why is None
    legend = [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    assert legend == ["glass", "steel"]
    assert fig.axes[0].get_xlabel() == "y [m]" and fig.axes[0].get_ylabel() == "z [m]"
    out = tmp_path / "figs"
    assert fluidem("plot", run.path, "--out", out, "--color", "species", "--only", "snapshots,bed_height") == 0
    for path in out.glob("*.png"):
        assert_not_blank(read_png(path), path.name)


# ---------------------------------------------------------------- animate
def test_animation_has_one_frame_per_snapshot_of_the_promised_size(pour_run, tmp_path, capsys):
    iio = pytest.importorskip("imageio.v2")
    pytest.importorskip("imageio_ffmpeg")
    out = tmp_path / "movie.mp4"
    assert fluidem("animate", pour_run, "--out", out, "--fps", "10", "--height", "320", "--color", "speed") == 0
    stdout, _ = capsys.readouterr()
    m = re.search(r"\((\d+) frames, (\d+)×(\d+) px, 10 fps\)", stdout)
    assert m, stdout
    frames, width, height = map(int, m.groups())
    with h5py.File(pour_run / "particles.h5") as f:
        n_snapshots = len(f["snapshots"])
    assert frames == n_snapshots == 4  # 0, 0.02 and 0.04 s on the schedule, and the end time 0.05 s
    assert height == 320 and width % 16 == 0
    assert 0.4 * height < width < 1.2 * height  # a 24 × 48 diameter container, plus labels and colour bar
    reader = iio.get_reader(out)
    try:
        meta = reader.get_meta_data()
        images = [np.asarray(im) for im in reader]
    finally:
        reader.close()
    assert len(images) == n_snapshots
    assert meta["size"] == (width, height) and meta["fps"] == 10
    assert all(im.shape == (height, width, 3) for im in images)
    assert_not_blank(images[-1], "last frame")
    assert fraction_changed(images[0], images[-1]) > 0.01  # the particles moved


def test_animate_rejects_bad_input(pour_run, run_copy, tmp_path):
    with pytest.raises(CaseError, match="ending in .mp4"):
        fluidem("animate", pour_run, "--out", tmp_path / "movie.gif")
    with pytest.raises(CaseError, match="--fps 0"):
        fluidem("animate", pour_run, "--out", tmp_path / "movie.mp4", "--fps", "0")
    run = run_copy()
    (run / "particles.h5").unlink()
    with pytest.raises(CaseError, match=r"nothing to animate: the run has no particle snapshots"):
        fluidem("animate", run)
    assert not list(tmp_path.glob("**/*.mp4"))


# ---------------------------------------------------------------- compare
def test_compare_overlays_traces_and_tabulates_summaries(pour_run, run_copy, tmp_path, capsys):
    other = run_copy("elastic")
    path = other / "probes.csv"
    text = path.read_text().splitlines()
    header = text[0].split(",")
    k = header.index("kinetic_J")
    rows = [r.split(",") for r in text[1:]]
    for r in rows:
        r[k] = repr(2.0 * float(r[k]))
    path.write_text("\n".join([text[0]] + [",".join(r) for r in rows]) + "\n")

    out = tmp_path / "cmp"
    assert fluidem("compare", pour_run, other, "--quantity", "kinetic_J,coordination", "--out", out) == 0
    stdout, _ = capsys.readouterr()
    lines = stdout.splitlines()
    assert lines[0].split() == ["quantity", pour_run.name, "elastic"]
    pf = next(line.split() for line in lines if line.startswith("packing_fraction"))
    assert len(pf) == 3 and float(pf[1]) == pytest.approx(float(pf[2]), rel=1e-5)
    assert_not_blank(read_png(out / "compare_probes.png"), "compare_probes.png")
    with open(out / "compare_summary.csv", newline="") as f:
        table = list(csv.reader(f))
    assert table[0] == ["quantity", pour_run.name, "elastic"]
    assert "packing_fraction" in [r[0] for r in table]

    single = tmp_path / "single"
    assert fluidem("compare", pour_run, "--quantity", "kinetic_J,coordination", "--out", single) == 0
    assert fraction_changed(read_png(out / "compare_probes.png"), read_png(single / "compare_probes.png")) > 1e-3
    with pytest.raises(CaseError, match=r"--quantity 'speed_J': not a probe column .* allowed are kinetic_J"):
        fluidem("compare", pour_run, other, "--quantity", "speed_J", "--out", out)


# ---------------------------------------------------------------- published numbers
def test_published_table_for_pour():
    rows = {q: (pub, ours) for q, pub, ours in comparison_rows("pour", {"packing_fraction": 0.8301})}
    pub, ours = rows["packing fraction of the settled bed (area fraction, 2D)"]
    assert "0.832 ± 0.010 (Hoomans et al. 1996 §5.1)" in pub and "0.80 (Hogue & Newland)" in pub
    assert "0.805 (Rosato et al.)" in pub
    assert ours == "0.83 (inside the published range)"
    pub, ours = rows["energy conservation error"]
    assert pub.startswith("0.005 %") and ours.startswith("n/a for soft spheres")
    rows = comparison_rows("pour", {"packing_fraction": 0.7, "energy_error_rel": 5e-5})
    assert rows[0][2] == "0.7 (outside the published range)" and rows[1][2] == "0.005 %"
    assert comparison_rows("no-such-case", {}) == []


def test_published_tables_of_the_sun_cases_show_this_runs_window_means():
    summary = {"mean_particle_height_avg_m": 0.0871, "coordination_number_avg": 0.47, "multicontact_ratio_avg": 0.28,
               "averages_window_s": [5.0, 10.0], "pressure_20cm_dominant_frequency_Hz": 3.4}
    rows = {q: (pub, ours) for q, pub, ours in comparison_rows("goldschmidt", summary)}
    pub, ours = rows["mean particle height"]
    assert pub.startswith("8.9 cm (TF-DEM") and "9.16 cm (two-fluid model)" in pub and "11.4 cm (experiment" in pub
    assert ours == "8.71 cm (mean over 5–10 s)"
    assert rows["bulk coordination number"] == ("about 0.5 (Sun et al. 2007 Fig 5, uniform inflow)",
                                                "0.47 (mean over 5–10 s)")
    assert rows["multicontact ratio"][1] == "0.28 (mean over 5–10 s)"
    key = "largest contact force / drag (cell means; this run: the largest cell's, averaged over time)"
    assert rows[key][1] == "not measured; see the forces figure"
    rows = {q: ours for q, _, ours in comparison_rows("goldschmidt", {**summary, "contact_drag_ratio_max_avg": 12.345})}
    assert rows[key] == "12.3 (mean over 5–10 s)"
    short = {**summary, "averages_window_s": [0.25, 0.5]}  # a shorter run: its second half, and the table says so
    rows = {q: (pub, ours) for q, pub, ours in comparison_rows("tsuji-jet-background", short)}
    assert rows["bulk coordination number"] == ("about 1.2 (Sun et al. 2007 Fig 5, central jet)",
                                                "0.47 (mean over 0.25–0.5 s)")
    assert rows["multicontact ratio"][0].startswith("above 0.6")
    pub, ours = rows["dominant frequency of the pressure drop 20 cm above the inlet"]
    assert pub.startswith("Fig 3 (not given numerically)") and ours == "3.4 Hz (power spectrum over 0.25–0.5 s)"
    assert comparison_rows("tsuji-jet-background", {})[0][2] == "not measured by this run"


def test_published_tables_of_the_hoomans_cases():
    rows = comparison_rows("hoomans-pour", {"packing_fraction": 0.8301, "energy_error_rel": 2.6e-5})
    assert rows[0][1].startswith("0.832 ± 0.010") and rows[0][2] == "0.83 (inside the published range)"
    assert rows[1][1].startswith("0.005 %") and rows[1][2] == "0.0026 %"
    assert comparison_rows("hoomans-pour", {})[1][2] == "not measured by this run"
    non_ideal = {"particles": {"contact": {"model": "hard_sphere", "restitution": 0.9, "friction": 0.3}}}
    ideal = {"particles": {"contact": {"model": "hard_sphere", "restitution": 1.0, "friction": 0.0}}}
    [(_, pub, ours)] = comparison_rows("hoomans-orifice", {"bubble_detected": True, "bubble_max_area_m2": 1.2e-3},
                                       non_ideal)
    assert "bubble (turning into a slug) for non-ideal" in pub and "none for ideal" in pub
    assert ours == "bubble, largest 12 cm² (this run: e = 0.9, μ = 0.3)"
    assert comparison_rows("hoomans-slug", {"bubble_detected": False}, ideal)[0][2] == "no bubble (this run: e = 1, μ = 0)"
    assert comparison_rows("hoomans-tsuji", {"bubble": False})[0][2] == "no bubble"  # the older key
    assert comparison_rows("hoomans-tsuji", {})[0][1].startswith("no bubble")
    for case in ("hoomans-orifice", "hoomans-slug", "hoomans-tsuji", "hoomans-experiment"):
        assert comparison_rows(case, {"status": "completed"}, non_ideal)[0][2] == "—"  # not measured
    assert comparison_rows("hoomans-experiment", {})[0][1].startswith("a bubble forms at the orifice")


@pytest.mark.parametrize("case", sorted(PUBLISHED))
def test_published_entries_are_complete(case):
    for v in PUBLISHED[case]:
        assert v.quantity and v.published and v.source
        keys = [k for k in (v.summary_key, *v.fallback_keys, v.window_key, *(d[1] for d in v.details)) if k]
        assert all(re.fullmatch(r"[a-z0-9_]+(_Hz|_Pa)?", k) for k in keys), keys  # summary.json keys, units as suffix
        assert v.this_run({}) in (v.when_missing, "not measured yet") or v.this_run({}).startswith("not measured yet; see ")
