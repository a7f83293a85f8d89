"""Simulation state as structures of arrays: every particle field is a NumPy array, (N, 3) for vectors."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class ParticleState:
    """Particle fields in SI units; the engine updates them in place.

    position, velocity, omega, force, torque : (N, 3) float64 [m, m/s, rad/s, N, N m]
    radius, mass, inertia : (N,) float64 [m, kg, kg m^2]
    species : (N,) int64 index into the case's species list
    ids : (N,) int64 each particle's number at creation (0 … N−1). A soft-sphere engine may renumber its
        particles in cell order for speed (``neighbours.reorder_interval``); ``ids`` follows them, and
        output files list the particles by it.
    image : (N, 3) int64 how many times each particle has crossed each periodic side of its box, + for
        the upper side (0 where no side is periodic): its unwrapped position is position + image · L.
    """

    position: np.ndarray
    velocity: np.ndarray
    omega: np.ndarray
    force: np.ndarray
    torque: np.ndarray
    radius: np.ndarray
    mass: np.ndarray
    inertia: np.ndarray
    species: np.ndarray
    ids: np.ndarray | None = None
    image: np.ndarray | None = None

    def __post_init__(self):
        if self.ids is None:
            self.ids = np.arange(self.position.shape[0], dtype=np.int64)
        if self.image is None:
            self.image = np.zeros((self.position.shape[0], 3), dtype=np.int64)

    @classmethod
    def create(cls, position, velocity, diameter, species, densities) -> "ParticleState":
        n = position.shape[0]
        radius = 0.5 * np.asarray(diameter, float)
        mass = np.asarray(densities)[species] * (4.0 / 3.0) * np.pi * radius**3
        return cls(
            position=np.ascontiguousarray(position, float),
            velocity=np.ascontiguousarray(velocity, float),
            omega=np.zeros((n, 3)),
            force=np.zeros((n, 3)),
            torque=np.zeros((n, 3)),
            radius=radius,
            mass=mass,
            inertia=0.4 * mass * radius**2,  # solid sphere
            species=np.ascontiguousarray(species, np.int64),
        )

    @property
    def n(self) -> int:
        return self.position.shape[0]

    def arrays(self) -> dict[str, np.ndarray]:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}
