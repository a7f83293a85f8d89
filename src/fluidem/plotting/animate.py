"""MP4 of a run's particle snapshots, one frame per snapshot (``fluidem animate``).

Frames are drawn exactly as the panels of the ``snapshots`` figure (same projection,
colours and walls) on a canvas of fixed pixel size, and encoded with imageio-ffmpeg
(H.264, yuv420p, so browsers and presentation software play it). The frame width and
height are multiples of 16, so the encoder never rescales.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import CaseError
from . import style
from .figures import Colourer, draw_particles, setup_particle_axes, speed_max, time_title, view_of
from .run import RunData, Unavailable

BLOCK = 16  # H.264 macro block: frame sizes are multiples of this
DPI = 100


@dataclass
class AnimationResult:
    path: Path
    frames: int
    width: int  # [px]
    height: int  # [px]
    fps: float


def frame_size(aspect: float, height_px: int, colour_mode: str) -> tuple[int, int]:
    """(width, height) [px] of a frame for a domain of width/height ``aspect``, both multiples of 16."""
    height = max(BLOCK, int(round(height_px / BLOCK)) * BLOCK)
    plot_h = height - 110  # title and x labels
    extra = 190 if colour_mode in ("speed", "nc") else 110  # y labels (+ colour bar or N_c key)
    width = plot_h * aspect + extra
    width = int(np.clip(np.ceil(width / BLOCK) * BLOCK, 12 * BLOCK, 160 * BLOCK))
    return width, height


def require_imageio():
    try:
        import imageio.v2 as iio
        import imageio_ffmpeg  # noqa: F401
    except ImportError:
        raise CaseError("fluidem animate needs imageio and imageio-ffmpeg: "
                        "pip install 'fluidem[animate]' (or pip install imageio imageio-ffmpeg)") from None
    return iio


def animate_run(run: RunData, out_file: str | Path, color: str = "height", fps: float = 20.0,
                height_px: int = 640, bands: int = 6) -> AnimationResult:
    """Write ``out_file`` (MP4) with one frame per snapshot of ``run``.

    Raises CaseError when the run has no snapshots, ``fps`` or ``height_px`` is not
    positive, or the output cannot be written.
    """
    from .figures import PlotOptions

    PlotOptions(color=color, bands=bands)  # validates the colour mode
    if not fps > 0:
        raise CaseError(f"--fps {fps}: give a positive number of frames per second")
    if int(height_px) < 4 * BLOCK:
        raise CaseError(f"--height {height_px}: give at least {4 * BLOCK} pixels")
    why = run.lacks_snapshots()
    if why is not None:
        raise CaseError(f"{run.path}: nothing to animate: {why}")
    out_file = Path(out_file)
    if out_file.suffix.lower() != ".mp4":
        raise CaseError(f"--out {str(out_file)!r}: the animation is an MP4; give a file name ending in .mp4")
    iio = require_imageio()
    try:
        out_file.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise CaseError(f"--out {str(out_file)!r}: cannot create its folder: {err.strerror or err}") from None

    tmp = out_file.with_name(f".{out_file.stem}.partial.mp4")  # ffmpeg picks the container by suffix
    try:
        frames, width, height = _write_frames(iio, run, tmp, color, fps, height_px, bands)
        os.replace(tmp, out_file)
    except Unavailable as err:
        raise CaseError(f"{run.path}: {err}") from None
    finally:
        if tmp.exists():
            tmp.unlink()
    return AnimationResult(out_file, frames, width, height, float(fps))


def _write_frames(iio, run: RunData, path: Path, color: str, fps: float, height_px: int,
                  bands: int) -> tuple[int, int, int]:
    """Draw and encode every snapshot into ``path``: (frames, width, height)."""
    first = run.snapshot(0)
    view = view_of(run, first)
    vmax = speed_max(run) if color == "speed" else None
    colourer = Colourer(color, run, view, first, bands, vmax)
    width, height = frame_size(view.aspect, height_px, color)
    frames = 0
    with style.context():
        fig = style.new_figure(width / DPI, height / DPI, dpi=DPI)
        ax = fig.subplots()
        setup_particle_axes(ax, view)
        if color == "speed":
            colourer.decorate(fig, [ax], [first])
        elif color in ("species", "nc"):
            colourer.decorate(fig, [ax], [first, run.snapshot(-1)])
        writer = iio.get_writer(path, format="FFMPEG", mode="I", fps=fps, codec="libx264",
                                pixelformat="yuv420p", macro_block_size=BLOCK, quality=8,
                                ffmpeg_log_level="error")
        try:
            coll = None
            for k in range(len(run.snapshot_times)):
                snap = first if k == 0 else run.snapshot(k)
                if coll is not None:
                    coll.remove()
                coll = draw_particles(ax, view, snap, colourer.colours(snap))
                ax.set_title(time_title(snap["time"]))
                fig.canvas.draw()
                if k == 0:
                    fig.set_layout_engine("none")  # freeze the layout: every frame the same
                writer.append_data(_frame(fig, width, height))
                frames += 1
        finally:
            writer.close()
    return frames, width, height


def _frame(fig, width: int, height: int) -> np.ndarray:
    """The canvas as an RGB array of exactly (height, width, 3)."""
    rgba = np.asarray(fig.canvas.buffer_rgba())
    out = np.full((height, width, 3), 255, np.uint8)
    h, w = min(height, rgba.shape[0]), min(width, rgba.shape[1])
    out[:h, :w] = rgba[:h, :w, :3]
    return out
