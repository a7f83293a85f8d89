"""``fluidem segregation``: the table and the JSON of a system, the chart written (png, svg, pdf), and
bad input (exit 2, one message naming the option and value, no chart written)."""
from __future__ import annotations

import json
import traceback

import pytest

from fluidem.analysis.segregation import segregation_criterion
from fluidem.cli import main

SYSTEM = "3e-4,2600,6e-4,1200,0.25"  # glass 0.3 mm with a 0.6 mm polymer: the larger, lighter one rises


def cli(argv, capsys):
    """``fluidem ARGV`` in-process: (exit status, stdout, stderr); an escaping exception is a crash (1)."""
    try:
        rc = main([str(a) for a in argv])
    except SystemExit as exc:  # argparse usage errors
        rc = exc.code
    except Exception:  # noqa: BLE001 - the test inspects it
        out, err = capsys.readouterr()
        return 1, out, err + traceback.format_exc()
    out, err = capsys.readouterr()
    return rc, out, err


def test_table(capsys):
    rc, out, err = cli(["segregation", "--system", SYSTEM], capsys)
    assert rc == 0, err
    assert out.startswith(f"system 1: --system {SYSTEM} (voidage 0.4)\n")
    assert "Sauter mean diameter" in out and "0.00048" in out  # eq. 10 by hand: 4.8e-4 m
    assert "1.18833" in out  # eq. 17's left side by hand: 1426/1200
    assert "flotsam (rises): species 2 (larger, lighter)" in out
    assert "jetsam (sinks):  species 1 (smaller, denser)" in out


def test_json_matches_the_api(capsys):
    rc, out, err = cli(["segregation", "--system", SYSTEM, "--system", "5e-4,2500,5e-4,2500,0.5",
                        "--voidage", "0.45", "--json"], capsys)
    assert rc == 0, err
    data = json.loads(out)
    assert data["voidage"] == 0.45 and data["chart"] is None
    first, second = data["systems"]
    expected = segregation_criterion((3e-4, 6e-4), (2600.0, 1200.0), 0.25, 0.45).as_dict()
    assert first == expected
    assert first["flotsam"] == 2 and first["jetsam"] == 1
    assert second["flotsam"] == "mixed"


def test_mixed_within_tolerance(capsys):
    """A system 0.1 % off the line counts as mixed with --tolerance 0.01, not with the default."""
    line = segregation_criterion((3e-4, 6e-4), (2600.0, 1200.0), 0.25).equilibrium_density_ratio
    system = f"3e-4,2600,6e-4,{2600 * line * 1.001!r},0.25"
    rc, out, _ = cli(["segregation", "--system", system, "--json"], capsys)
    assert rc == 0 and json.loads(out)["systems"][0]["flotsam"] == 1
    rc, out, _ = cli(["segregation", "--system", system, "--tolerance", "0.01", "--json"], capsys)
    assert rc == 0 and json.loads(out)["systems"][0]["flotsam"] == "mixed"


@pytest.mark.parametrize("name", ["chart.png", "sub/dir/chart.svg", "chart.pdf"])
def test_chart_written(tmp_path, capsys, name):
    out_file = tmp_path / name
    rc, out, err = cli(["segregation", "--chart", "--system", SYSTEM, "--system", "6e-4,1200,3e-4,2600,0.75",
                        "--out", out_file], capsys)
    assert rc == 0, err
    assert out_file.is_file() and out_file.stat().st_size > 1000
    assert out.splitlines()[-1] == str(out_file)
    assert "flotsam (rises)" in out  # the systems' tables come first
    magic = {"png": b"\x89PNG", "svg": b"<?xml", "pdf": b"%PDF"}[out_file.suffix[1:]]
    assert out_file.read_bytes().startswith(magic)
    assert not list(tmp_path.rglob("*.tmp"))


def test_chart_alone_default_name_and_json(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    rc, out, err = cli(["segregation", "--chart", "--compositions", "0.2,0.8"], capsys)
    assert rc == 0, err
    assert out == "segregation-chart.png\n" and (tmp_path / "segregation-chart.png").is_file()
    rc, out, err = cli(["segregation", "--chart", "--json", "--out", "c.svg", "--system", SYSTEM], capsys)
    assert rc == 0, err
    data = json.loads(out)
    assert data["chart"] == "c.svg" and (tmp_path / "c.svg").is_file() and len(data["systems"]) == 1


BAD = [
    (["--system", "3e-4,2600"], "--system '3e-4,2600': give five numbers", "got 2"),
    (["--system", "3e-4,2600,6e-4,1200"], "give five numbers", "got 4"),
    (["--system", "3e-4,2600,6e-4,1200,0.25,1"], "give five numbers", "got 6"),
    (["--system", "3e-4,glass,6e-4,1200,0.25"], "RHO1 = 'glass' is not a number", ""),
    (["--system", "0,2600,6e-4,1200,0.25"], "d1 = 0.0", "must be positive"),
    (["--system", "3e-4,2600,-6e-4,1200,0.25"], "d2 = -0.0006", "must be positive"),
    (["--system", "3e-4,-2600,6e-4,1200,0.25"], "rho1 = -2600.0", "must be positive"),
    (["--system", "3e-4,2600,6e-4,inf,0.25"], "rho2 = inf", "finite"),
    (["--system", "3e-4,2600,nan,1200,0.25"], "d2 = nan", "finite"),
    (["--system", "3e-4,2600,6e-4,1200,1.5"], "composition = 1.5", "[0, 1]"),
    (["--system", "3e-4,2600,6e-4,1200,-0.1"], "composition = -0.1", "[0, 1]"),
    (["--system", SYSTEM, "--voidage", "1"], "--voidage", "voidage = 1.0"),
    (["--system", SYSTEM, "--voidage", "0"], "--voidage", "voidage = 0.0"),
    (["--system", SYSTEM, "--voidage", "abc"], "--voidage 'abc'", "give a number"),
    (["--system", SYSTEM, "--viscosity", "-1"], "--viscosity", "-1.0"),
    (["--system", SYSTEM, "--tolerance", "-1"], "--tolerance -1", "zero or positive"),
    ([], "needs --system", "--chart"),
    (["--system", SYSTEM, "--out", "c.png"], "--out is for the chart", "--chart"),
]


@pytest.mark.parametrize("argv, message, detail", BAD, ids=[" ".join(a) for a, _, _ in BAD])
@pytest.mark.parametrize("chart", [False, True], ids=["table", "chart"])
def test_bad_input_exit_2_nothing_written(tmp_path, capsys, argv, message, detail, chart):
    if chart and (not argv or "--out" in argv):
        pytest.skip("good input with --chart: the chart of the lines alone; --out with --chart")
    extra = ["--chart", "--out", tmp_path / "chart.png"] if chart else []
    rc, out, err = cli(["segregation", *argv, *extra], capsys)
    assert rc == 2, err
    assert out == ""
    assert message in err and detail in err
    assert "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


def test_bad_chart_options_write_nothing(tmp_path, capsys):
    for argv, message in ((["--out", tmp_path / "chart.jpg"], "must end in .png, .svg, .pdf"),
                          (["--compositions", "0.5,1.2"], "x1 = 1.2"),
                          (["--compositions", "0.5,x"], "--compositions 'x': give a number"),
                          (["--system", "3e-4,2600,6e-4,1200,2"], "composition = 2.0")):
        rc, out, err = cli(["segregation", "--chart", "--out", tmp_path / "c.png", *argv], capsys)
        assert rc == 2, err
        assert message in err and out == ""
        assert list(tmp_path.iterdir()) == []


def test_help_lists_the_command(capsys):
    rc, out, _ = cli(["--help"], capsys)
    assert rc == 0 and "segregation" in out


def test_chart_relabels_larger_first_and_refuses_mixed_voidages():
    from fluidem.errors import CaseError
    from fluidem.plotting import style
    from fluidem.plotting.figures.segregation import chart_convention, draw_segregation_chart

    given = segregation_criterion((6e-4, 3e-4), (1200.0, 2600.0), 0.75, 0.4)  # the larger first
    charted, swapped = chart_convention(given)
    assert swapped and charted.diameters == (3e-4, 6e-4) and charted.composition == 0.25
    assert charted.size_ratio == 0.5 and given.flotsam == 1 and charted.flotsam == 2  # the same species
    assert chart_convention(charted) == (charted, False)
    with style.context():
        fig = draw_segregation_chart([given])
        assert len(fig.axes) == 2
        with pytest.raises(CaseError, match=r"results\[1\].voidage = 0.5"):
            draw_segregation_chart([given, segregation_criterion((3e-4, 6e-4), (2600.0, 1200.0), 0.25, 0.5)])
