"""Particle engines: soft-sphere DEM (``softsphere``), walls, neighbour lists and contact laws."""
