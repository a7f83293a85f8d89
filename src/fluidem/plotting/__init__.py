"""Figures, animations, comparisons and reports of run directories (``fluidem plot|animate|compare|report``).

Needs the ``plot`` extra (matplotlib); ``animate`` also needs imageio and imageio-ffmpeg.
"""
