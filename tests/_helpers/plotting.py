"""The plotting commands driven in-process, and PNG figures decoded and compared."""
from __future__ import annotations

import argparse
import re
from pathlib import Path

import numpy as np

from fluidem.cli_plot import add_commands

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def fluidem(*argv):
    """Run a plotting subcommand as the main CLI would; CaseError propagates to the test."""
    parser = argparse.ArgumentParser(prog="fluidem")
    sub = parser.add_subparsers(dest="command")
    add_commands(sub)
    args = parser.parse_args([str(a) for a in argv])
    return args.func(args)


def read_png(path: Path) -> np.ndarray:
    """Decode a PNG (checking its signature and integrity) to an (H, W, 3) uint8 array."""
    from PIL import Image

    assert path.read_bytes()[:8] == PNG_SIGNATURE, f"{path} is not a PNG"
    with Image.open(path) as im:
        im.verify()
    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"))


def assert_not_blank(img: np.ndarray, what: str) -> None:
    """A drawn figure: over 1 % of the pixels not white and over 20 colours (anti-aliased text and
    lines alone give hundreds); an empty white or one-colour canvas fails both."""
    non_white = np.mean(np.any(img < 250, axis=-1))
    packed = (img[..., 0].astype(np.uint32) << 16) | (img[..., 1].astype(np.uint32) << 8) | img[..., 2]
    colours = len(np.unique(packed))
    assert img.shape[0] > 100 and img.shape[1] > 100, f"{what}: tiny image {img.shape}"
    assert non_white > 0.01, f"{what}: {non_white:.2%} of the pixels are not white"
    assert colours > 20, f"{what}: only {colours} distinct colours"


def fraction_changed(a: np.ndarray, b: np.ndarray) -> float:
    """Fraction of pixels that differ. Agg drawing is deterministic, so equal data give 0 exactly; tests
    ask for > 1e-3 (over ~1000 pixels of a ~1 Mpx figure) when the data change, which one moved curve
    or a shifted set of particles clears by far and a stray pixel would not."""
    if a.shape != b.shape:
        return 1.0
    return float(np.mean(np.any(a != b, axis=-1)))


def stderr_notes(err: str, command: str) -> dict[str, str]:
    """{figure: reason} from the 'fluidem CMD: skipped NAME: reason' lines (each one line)."""
    notes = {}
    for line in err.splitlines():
        m = re.fullmatch(rf"fluidem {command}: skipped (\w+): (.+)", line)
        assert m, f"unexpected stderr line: {line!r}"
        notes[m.group(1)] = m.group(2)
    return notes
