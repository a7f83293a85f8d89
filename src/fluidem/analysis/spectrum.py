"""Power spectrum of a probe signal: the one estimate behind the summary and the figures.

``power_spectrum(t, signal)`` is Welch's estimate of the one-sided power spectral density of a
sampled signal; ``spectral_peaks`` lists the highest local maxima of that spectrum and
``dominant_frequency`` locates the highest one. The summary (``pressure_20cm_dominant_frequency_Hz``,
``pressure_20cm_spectral_peaks_Hz``) and the ``pressure`` figure use these and no other spectrum.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

MIN_SAMPLES = 16  # two Welch segments of at least 8 samples each; fewer give no spectrum


class Spectrum(NamedTuple):
    """A power spectrum and its dominant frequency.

    frequency : (K,) float64 [Hz], from 0 to the Nyquist frequency in steps of 1 / (segment length).
    power : (K,) float64 [unit²/Hz], the one-sided power spectral density of the signal's fluctuations.
    dominant : float [Hz], where the highest peak above 0 Hz lies (between bins, see ``power_spectrum``);
        NaN when the spectrum has no peak (a constant signal).
    """

    frequency: np.ndarray
    power: np.ndarray
    dominant: float


def _uniform(t, signal, least: int = MIN_SAMPLES) -> tuple[float, np.ndarray] | None:
    """(sample spacing [s], the signal resampled on a uniform time grid (M,)), or None.

    Samples whose time or value is not finite are dropped and the rest sorted by time; the spacing
    is the median interval (probes fire on the first step after each multiple of their interval, so
    they are uniform up to one step already) and the grid runs from the first sample to the last,
    linear between samples. None when fewer than ``least`` finite samples remain or their times do
    not advance.
    """
    t, s = np.asarray(t, float), np.asarray(signal, float)
    ok = np.isfinite(t) & np.isfinite(s)
    t, s = t[ok], s[ok]
    if s.size < least:
        return None
    order = np.argsort(t, kind="stable")
    t, s = t[order], s[order]
    dt = float(np.median(np.diff(t)))
    if not dt > 0.0:
        return None
    n = int(np.floor((t[-1] - t[0]) / dt + 1e-9)) + 1
    return dt, np.interp(t[0] + dt * np.arange(n), t, s)


def _peaks(power: np.ndarray) -> np.ndarray:
    """Indices of the local maxima of ``power`` above 0 Hz (the last bin may be one), highest first."""
    from scipy.signal import find_peaks

    if power.size < 2 or not power[1:].max() > 0.0:
        return np.zeros(0, np.int64)
    where, _ = find_peaks(np.concatenate(([-np.inf], power[1:], [-np.inf])))  # the padded index is the bin
    return where[np.argsort(power[where], kind="stable")[::-1]]


def _peak_frequency(frequency: np.ndarray, power: np.ndarray, k: int) -> float:
    """Frequency [Hz] of the peak at bin ``k``: the vertex of the parabola through the logarithms of the
    power at bins k − 1, k, k + 1 (Gaussian interpolation; the main lobe of a Hann window is close to a
    Gaussian, so a pure tone is placed within a fortieth of a bin). Bin ``k`` itself at the ends of the
    spectrum (bin 0 holds the removed mean) or where a neighbour has no power."""
    if k < 2 or k + 1 >= power.size or not (power[k - 1] > 0.0 and power[k + 1] > 0.0):
        return float(frequency[k])
    a, b, c = np.log(power[k - 1]), np.log(power[k]), np.log(power[k + 1])
    curvature = a - 2.0 * b + c
    if not curvature < 0.0:
        return float(frequency[k])
    shift = float(np.clip(0.5 * (a - c) / curvature, -0.5, 0.5))
    return float(frequency[k] + shift * (frequency[1] - frequency[0]))


def power_spectrum(t, signal) -> Spectrum | None:
    """Welch's estimate of the one-sided power spectral density of a sampled signal.

    The samples go on a uniform time grid (``_uniform``); ``scipy.signal.welch`` then averages the
    periodograms of Hann-windowed segments of half the record, overlapping by half (three segments),
    each with its mean removed.

    Why this parametrisation: a fluidised bed's pressure signal is broad-band with one or two modes
    of a few hertz (the tsuji-jet-background bed: near 2 and 6 Hz). A single periodogram of the whole record has
    the finest resolution (1/T) but a scatter of 100 % in every bin, so its highest bin jumps between
    modes of like power from record to record; averaging three half-record segments cuts that scatter
    while the resolution, 2/T (0.4 Hz over Sun's 5 s window), still separates such modes. The segment
    is a fraction of the record, not a number of samples, so the resolution does not depend on the
    probe interval. The dominant frequency is placed between bins by Gaussian interpolation of the
    highest peak (``_peak_frequency``), so it is not limited to the 2/T grid.

    Parameters
    ----------
    t : (M,) sample times [s], nearly uniform; need not be sorted.
    signal : (M,) samples [unit]; samples with a non-finite time or value are left out.

    Returns
    -------
    Spectrum (frequency [Hz], power [unit²/Hz], dominant [Hz]), or None with fewer than
    ``MIN_SAMPLES`` finite samples.
    """
    from scipy.signal import welch

    u = _uniform(t, signal)
    if u is None:
        return None
    dt, samples = u
    frequency, power = welch(samples - samples.mean(), fs=1.0 / dt, window="hann", nperseg=samples.size // 2,
                             detrend="constant")
    top = _peaks(power)
    dominant = _peak_frequency(frequency, power, int(top[0])) if top.size else math.nan
    return Spectrum(frequency, power, dominant)


def dominant_frequency(t, signal) -> float:
    """Frequency [Hz] of the highest peak of ``power_spectrum`` (between bins); NaN without a spectrum or peak."""
    spectrum = power_spectrum(t, signal)
    return math.nan if spectrum is None else spectrum.dominant


def spectral_peaks(t, signal, count: int = 3) -> tuple[list[float], list[float]]:
    """The ``count`` highest peaks of ``power_spectrum``: (frequencies [Hz], heights relative to the highest),
    highest first; empty lists without a spectrum or peak.

    The frequencies are those of the peaks' bins (the highest is ``dominant_frequency`` before its
    interpolation). A fluidised bed's pressure signal often has two modes of like power, and which one is
    the highest then changes from record to record; the second height says how close the call was.
    """
    spectrum = power_spectrum(t, signal)
    if spectrum is None:
        return [], []
    top = _peaks(spectrum.power)[:count]
    if top.size == 0:
        return [], []
    frequency, power = spectrum.frequency, spectrum.power
    return [float(frequency[k]) for k in top], [float(power[k] / power[top[0]]) for k in top]
