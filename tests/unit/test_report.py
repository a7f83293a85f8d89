"""``fluidem report``: one self-contained HTML page per run, checked by parsing it and by
opening it in headless Chromium (every image decoded, no console messages).

Chromium is Debian's ``chromium`` package; when it is missing the test installs it if
running as root, and skips with a message otherwise.
"""
from __future__ import annotations

import base64
import contextlib
import html
import io
import json
import os
import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import pytest

pytest.importorskip("matplotlib")

from fluidem.plotting.report import SCRIPT  # noqa: E402

from _helpers.plotting import PNG_SIGNATURE, fluidem  # noqa: E402

URL_ATTRIBUTES = {"src", "href", "srcset", "action", "poster", "data", "xlink:href", "formaction", "background"}
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--no-first-run",
                  "--enable-logging=stderr", "--v=0", "--dump-dom"]


def quiet(*argv):
    """``fluidem(*argv)`` with its stdout and stderr captured: (status, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = fluidem(*argv)
    return rc, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def report(pour_run, tmp_path_factory):
    """``fluidem report POUR --out FILE``: (FILE, stderr)."""
    path = tmp_path_factory.mktemp("report") / "report.html"
    rc, stdout, stderr = quiet("report", pour_run, "--out", path)
    assert rc == 0 and stdout.strip() == str(path)
    return path, stderr


class Page(HTMLParser):
    """Collects images, every URL-bearing attribute, <pre> text and table rows."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.images, self.urls, self.tags = [], [], []
        self.pre, self.rows, self._in_pre, self._row = [], [], False, None
        self._cell = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.tags.append(tag)
        if tag == "img":
            self.images.append(a.get("src", ""))
        self.urls += [(tag, k, v or "") for k, v in attrs if k in URL_ATTRIBUTES]
        if tag == "pre":
            self._in_pre = True
            self.pre.append("")
        if tag == "tr":
            self._row = []
        if tag in ("td", "th"):
            self._cell = ""

    def handle_endtag(self, tag):
        if tag == "pre":
            self._in_pre = False
        if tag in ("td", "th") and self._row is not None:
            self._row.append(self._cell)
            self._cell = None
        if tag == "tr" and self._row is not None:
            self.rows.append(self._row)
            self._row = None

    def handle_data(self, data):
        if self._in_pre:
            self.pre[-1] += data
        if self._cell is not None:
            self._cell += data


def parse(path: Path) -> Page:
    page = Page()
    page.feed(path.read_text())
    return page


def test_report_is_one_self_contained_page(report, pour_run):
    path, stderr = report
    page = parse(path)
    text = path.read_text()
    # nothing outside the page: every URL is an embedded data: URL, no <link>, no CSS url()/@import
    assert all(v.startswith("data:") for _, _, v in page.urls), page.urls
    assert "link" not in page.tags and "iframe" not in page.tags
    assert "@import" not in text and "url(" not in text
    assert not re.search(r"<script[^>]*\bsrc=", text)
    # every figure is an embedded PNG that decodes
    assert len(page.images) == 5  # snapshots, energy, contacts, multicontact, bed height
    for src in page.images:
        head, data = src.split(",", 1)
        assert head == "data:image/png;base64"
        png = base64.b64decode(data, validate=True)
        assert png[:8] == PNG_SIGNATURE
        from PIL import Image

        with Image.open(io.BytesIO(png)) as im:
            im.verify()
    # the case as the run wrote it, the summary, the published numbers
    assert page.pre == [(pour_run / "case.toml").read_text()]
    summary = json.loads((pour_run / "summary.json").read_text())
    cells = {r[0]: r[1:] for r in page.rows}
    assert set(summary) <= set(cells)
    assert cells["n_particles"] == ["500"]
    packing = cells["packing fraction of the settled bed (area fraction, 2D)"]
    assert packing[0].startswith("0.832 ± 0.010 (Hoomans et al. 1996 §5.1)")
    assert "0.80 (Hogue & Newland)" in packing[0] and "0.805 (Rosato et al.)" in packing[0]
    assert packing[1].startswith(f"{summary['packing_fraction']:.3g} (outside the published range)")
    assert cells["energy conservation error"][1].startswith("n/a for soft spheres")
    assert "This run stopped at t = 0.05" in html.unescape(text)
    no_gas = "the run has no gas phase (its case.toml has no [gas] section)"
    assert stderr.strip().splitlines() == [
        f"fluidem report: skipped pressure: probes.csv has no pressure columns (pressure*, *_Pa), and {no_gas}",
        f"fluidem report: skipped voidage: {no_gas}",
        f"fluidem report: skipped solids_fraction: {no_gas}",
        f"fluidem report: skipped forces: {no_gas}"]


def test_report_of_an_incomplete_modified_run(pour_run, tmp_path):
    """Missing probes: the figures that need them are skipped and listed; a changed built-in case is noted."""
    run = Path(shutil.copytree(pour_run, tmp_path / "run", ignore=shutil.ignore_patterns("restart.h5")))
    (run / "probes.csv").unlink()
    case = run / "case.toml"
    case.write_text(case.read_text().replace("restitution = 0.9", "restitution = 1.0"))
    rc, stdout, stderr = quiet("report", run)
    assert rc == 0
    path = run / "report.html"
    assert stdout.strip() == str(path)
    assert sorted(re.findall(r"skipped (\w+):", stderr)) == ["contacts", "energy", "forces", "multicontact",
                                                             "pressure", "solids_fraction", "voidage"]
    assert len(stderr.splitlines()) == 7
    page = parse(path)
    assert len(page.images) == 2  # snapshots and bed height (from the snapshots)
    text = html.unescape(path.read_text())
    assert "energy: the run has no probes.csv" in text
    assert "differs from the built-in case in: particles.contact.restitution = 1.0 (built-in: 0.9)" in text


def test_report_rows_follow_the_case_name_and_settings(pour_run, tmp_path):
    """The published table follows the case name in case.toml (here a pour run named as Hoomans' orifice
    case, with a bubble in its summary) and shows the restitution and friction the outcome depends on."""
    run = Path(shutil.copytree(pour_run, tmp_path / "run", ignore=shutil.ignore_patterns("restart.h5")))
    case = run / "case.toml"
    case.write_text(case.read_text().replace('name = "pour"', 'name = "hoomans-orifice"', 1))
    summary = json.loads((run / "summary.json").read_text())
    (run / "summary.json").write_text(json.dumps({**summary, "bubble_detected": True, "bubble_max_area_m2": 2e-3}))
    rc, _, _ = quiet("report", run)
    assert rc == 0
    cells = {r[0]: r[1:] for r in parse(run / "report.html").rows}
    pub, ours = cells["bubble at the orifice (jet 10 u_mf)"]
    assert "bubble (turning into a slug) for non-ideal particles" in pub and "§5.3.1" in pub
    assert ours == "bubble, largest 20 cm² (this run: e = 0.9, μ = 0.3)"


# ---------------------------------------------------------------- headless Chromium
@pytest.fixture(scope="module")
def chromium():
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        pytest.skip("chromium is not installed and the tests do not run as root to install it; "
                    "install Debian's chromium package (apt-get install chromium) to run this test")
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    install = ["apt-get", "install", "-y", "--no-install-recommends", "chromium"]
    proc = subprocess.run(install, capture_output=True, text=True, env=env, timeout=1200)
    if proc.returncode != 0:  # stale package lists: refresh once
        subprocess.run(["apt-get", "update"], capture_output=True, text=True, env=env, timeout=600)
        proc = subprocess.run(install, capture_output=True, text=True, env=env, timeout=1200)
    path = shutil.which("chromium")
    if proc.returncode != 0 or path is None:
        pytest.skip(f"could not install chromium: {(proc.stderr or proc.stdout).strip()[-300:]}")
    return path


def open_in_chromium(chromium: str, page: Path, tmp_path: Path) -> tuple[dict, list[str]]:
    """Load ``page`` headless: (the <body> attributes after load, console lines from stderr)."""
    profile = tmp_path / f"profile-{page.stem}"
    proc = subprocess.run([chromium, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", page.resolve().as_uri()],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    body = re.search(r"<body([^>]*)>", proc.stdout)
    assert body, f"no <body> in the dumped DOM: {proc.stdout[:500]!r}"
    attrs = dict(re.findall(r'([\w-]+)="([^"]*)"', body.group(1)))
    console = [line for line in proc.stderr.splitlines() if ":CONSOLE" in line]
    return attrs, console


def test_report_opens_in_headless_chromium_with_every_image_loaded(report, chromium, tmp_path):
    path, _ = report
    n_images = len(parse(path).images)
    attrs, console = open_in_chromium(chromium, path, tmp_path)
    assert attrs.get("data-images-total") == str(n_images), attrs
    assert attrs.get("data-images-ok") == str(n_images), attrs
    assert console == []


def test_the_chromium_check_catches_a_broken_image_and_a_console_error(chromium, tmp_path):
    """The check above can fail: a page with an undecodable image and a script error is caught."""
    bad = tmp_path / "bad.html"
    bad.write_text('<!DOCTYPE html><html><head><meta charset="utf-8"></head><body>'
                   '<img alt="ok" src="data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42'
                   'mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg==">'
                   '<img alt="broken" src="data:image/png;base64,AAAA">'
                   f"<script>{SCRIPT}</script><script>undefinedFunction();</script></body></html>")
    attrs, console = open_in_chromium(chromium, bad, tmp_path)
    assert (attrs.get("data-images-total"), attrs.get("data-images-ok")) == ("2", "1")
    assert any("undefinedFunction" in line for line in console), console
