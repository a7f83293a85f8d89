"""Wall shapes of the soft-sphere engine: 2D polylines, flat polygons, cylinders and STL meshes, each a set of
elements (segments, triangles, a cylinder's lateral surface) moving rigidly with its wall's motion.

``build_shapes(case)`` turns the case's shape walls (``Wall.kind`` polyline, polygon, cylinder, mesh) into a
``ShapeSet``: the element tables in each shape's body frame (the geometry as the case gives it), the motion
table, the contact-law table per species and shape, and the per-particle near lists and history slots that
``_shape_kernels.shape_forces`` works on. ``ShapeSet.load`` holds the force and torque on each shape at the
last step (the reaction of its contacts; torque about its reference point: the rotation axis point of a
rotating shape, else the centroid of its corners, moving with it).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..case import SHAPE_KINDS
from ..errors import CaseError
from . import _shape_kernels as S
from .contact.base import uses_rolling_spring

NEAR_CAPACITY = 16  # near elements per particle at first (widened when a list needs more)
HISTORY_SLOTS = 6  # shape contacts per particle that keep a tangential spring
CYLINDER_SIDES = 32  # a cylinder drawn for output: this many quads of two triangles round its side
MAX_GRID_CELLS = 200_000  # cells of the broad-phase grid at most (coarser cells beyond)


@dataclass
class Shape:
    name: str
    source: object  # the case's Wall entry (material, contact overrides, motion)
    kind: np.ndarray  # (E,) int64 element kinds
    geom: np.ndarray  # (E, 9) float64 element geometry (``_shape_kernels`` layout)
    box: np.ndarray  # (E, 6) float64 element bounding boxes (lo, hi)
    centre: np.ndarray  # (3,) reference point: rotation axis point, else the centroid of the corners
    reach: float  # largest distance of a point of the shape from centre [m]
    table: np.ndarray | None = None  # (T, 5) poses t, dx, dy, dz, θ of a table motion
    body: dict | None = None  # a free body: mass, inertia (3, 3) about centre, velocity, angular_velocity, free axes


@dataclass
class ShapeSet:
    shapes: list[Shape] = field(default_factory=list)

    @property
    def names(self) -> list[str]:
        return [s.name for s in self.shapes]

    def __len__(self) -> int:
        return len(self.shapes)

    # ------------------------------------------------------------ tables
    def element_tables(self):
        """(kind (E,), owner (E,), geom (E, 9), box (E, 6)) over all shapes, owner the shape index."""
        if not self.shapes:
            return (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 9)), np.zeros((0, 6)))
        kind = np.concatenate([s.kind for s in self.shapes])
        owner = np.concatenate([np.full(len(s.kind), k, np.int64) for k, s in enumerate(self.shapes)])
        geom = np.ascontiguousarray(np.concatenate([s.geom for s in self.shapes]))
        box = np.ascontiguousarray(np.concatenate([s.box for s in self.shapes]))
        return kind, owner, geom, box

    def motion_table(self, gravity=(0.0, 0.0, 0.0), dim2: bool = False) -> np.ndarray:
        """(S, MOTION_COLS + max(5 T, BODY_COLS)) float64: kind, v or A (1:4), f (4), φ (5), centre c (6:9), unit
        axis (9:12), ω (12), table rows (13), then the rows t, dx, dy, dz, θ of a table motion (T: the longest
        table), or a free body's state (``_shape_kernels.BODY_*``; ``gravity`` acts on it, ``dim2``: it moves
        in the x-y plane and turns about z only)."""
        tables = [s.table for s in self.shapes]
        longest = max([len(t) for t in tables if t is not None], default=0)
        width = 5 * longest
        if any(s.body is not None for s in self.shapes):
            width = max(width, S.BODY_COLS)
        out = np.zeros((len(self.shapes), S.MOTION_COLS + width))
        for k, s in enumerate(self.shapes):
            m = s.source.motion
            out[k, 6:9] = s.centre
            out[k, 9:12] = (0.0, 0.0, 1.0)
            if m is None:
                out[k, 0] = S.STATIC
            elif m.kind == "free":
                out[k, 0] = S.FREE
                out[k, S.MOTION_COLS:S.MOTION_COLS + S.BODY_COLS] = _body_row(s.body, gravity, dim2)
            elif m.kind == "constant_velocity":
                out[k, 0] = S.CONSTANT_VELOCITY
                out[k, 1:4] = m.velocity
            elif m.kind == "oscillation":
                out[k, 0] = S.OSCILLATING
                out[k, 1:4] = m.amplitude
                out[k, 4] = m.frequency
                out[k, 5] = m.phase
            else:
                out[k, 0] = S.ROTATION if m.kind == "rotation" else S.TABLE
                if m.axis is not None:
                    axis = np.array(m.axis, float)
                    out[k, 9:12] = axis / np.linalg.norm(axis)
                if m.kind == "rotation":
                    out[k, 12] = m.angular_velocity
                else:
                    out[k, 13] = len(s.table)
                    out[k, S.MOTION_COLS:S.MOTION_COLS + s.table.size] = s.table.ravel()
        return out

    def contact_table(self, engine):
        """(species, shapes, N_SLOTS) packed laws (``law_for_wall``: wall_contact, the wall's overrides,
        wall_pairs) and the contact times [(t_c, what)] for the time step."""
        from .contact.base import N_SLOTS

        sp = engine.case.particles.species
        st = engine.state
        table = np.zeros((len(sp), max(len(self.shapes), 1), N_SLOTS))
        times = []
        v = engine.case.time.impact_velocity
        for a in range(len(sp)):
            here = st.species == a
            for k, s in enumerate(self.shapes):
                law = engine.law_for_wall(s, a)
                if law.adhesive:
                    raise CaseError(f"walls ({s.name!r}, kind {s.source.kind!r}): the adhesive contact law "
                                    f"{law.model!r} is not available on wall shapes; give the wall a non-adhesive "
                                    "law (particles.wall_contact or particles.wall_pairs)")
                table[a, k] = law.pack(sp[a], s.source)
                if np.any(here):
                    times.append((law.contact_time(st.mass[here].min(), st.radius[here].min(), v, sp[a], s.source),
                                  f"species {sp[a].name}–wall {s.name}"))
        return table, times

    # ------------------------------------------------------------ state
    def setup(self, engine) -> None:
        """Allocate the per-particle arrays for ``engine`` (a ``SoftSphereEngine``: state, skin, the table)
        and the broad-phase grid; the near lists are made at the first force evaluation."""
        st = engine.state
        n = st.n
        self._check_body_masses(engine)
        self.skin = float(engine.skin)
        self.kind, self.owner, self.geom, box = self.element_tables()
        self.motion = self.motion_table(engine.gravity, engine.dim2)
        self.reach = np.array([s.reach for s in self.shapes], float)
        self.table = np.ascontiguousarray(engine.shape_table)
        # the largest particle there or to come from an inlet (the broad-phase cells must reach it)
        rmax = float(getattr(engine, "largest_radius", st.radius.max() if n else 0.0))
        self.grid, self.dims, self.cell_start, self.cell_elems = _grid(box, rmax + self.skin, engine.dim2)
        self.grid[4] = self.skin
        self.near_count = np.zeros(n, np.int64)
        self.near_elem = np.zeros((n, NEAR_CAPACITY if len(self.kind) else 0), np.int64)
        self.active = np.zeros(n, np.int64)
        self.info = np.zeros(8, np.int64)
        self.info[S.INFO_REORDER] = engine.last_reorder
        self.info[S.INFO_BODIES] = sum(s.body is not None for s in self.shapes)
        self.slot_elem = np.full((n, HISTORY_SLOTS if len(self.kind) else 0), -1, np.int64)
        # an epsd law's rolling spring torque in columns 3-5 of a slot
        self.slot_hist = np.zeros((n, self.slot_elem.shape[1], 6 if uses_rolling_spring(self.table) else 3))
        self.ids_seen = st.ids.astype(np.int64).copy()
        self.ref_t = np.zeros(1)
        self.load = np.zeros((len(self.shapes), 6))

    def _check_body_masses(self, engine) -> None:
        """A free body must outweigh every particle: its contacts are those of the particle-wall law, whose
        damping and contact time take the particle's mass alone (the body as a wall of infinite mass), which
        holds for a body much heavier than the particles."""
        st = engine.state
        heaviest = float(st.mass.max()) if st.n else 0.0
        names = [w.name for w in engine.case.walls]
        for s in self.shapes:
            if s.body is not None and s.body["mass"] <= heaviest:
                raise CaseError(
                    f"walls.{names.index(s.name)}.motion.mass = {s.body['mass']:.4g} kg ({s.name!r}): a free body "
                    f"must be heavier than the heaviest particle ({heaviest:.4g} kg); its contacts take the "
                    "particle-wall law with the particle's mass alone, as for a wall")

    def kernel_arrays(self) -> tuple:
        """The tuple ``_shape_kernels.shape_forces`` unpacks."""
        return (self.kind, self.owner, self.geom, self.motion, self.reach, self.grid, self.dims, self.cell_start,
                self.cell_elems, self.table, self.near_count, self.near_elem, self.active, self.info, self.slot_elem,
                self.slot_hist, self.ids_seen, self.ref_t, self.load)

    def after_advance(self) -> bool:
        """After an ``advance`` call: widen the near lists where one overflowed (True: the arrays changed and
        the lists are made anew at the next call)."""
        if self.info[S.INFO_NEAR_OVERFLOW] == 0:
            return False
        self.info[S.INFO_NEAR_OVERFLOW] = 0
        k = max(2 * int(self.info[S.INFO_NEEDED]), 2 * self.near_elem.shape[1])
        self.near_elem = np.zeros((self.near_elem.shape[0], k), np.int64)
        self.info[S.INFO_FORCE_REBUILD] = 1
        return True

    def replace_particles(self, keep: np.ndarray, new_ids: np.ndarray) -> None:
        """The engine kept the rows where ``keep`` and appended particles of ``new_ids`` (inlets, outlets): the
        per-particle arrays follow, the new rows without shape contacts, the near lists made anew."""
        if not hasattr(self, "slot_elem"):
            return

        def grown(a, fill):
            add = np.full((len(new_ids),) + a.shape[1:], fill, dtype=a.dtype)
            return np.ascontiguousarray(np.concatenate([a[keep], add]))

        self.near_count, self.near_elem, self.active = grown(self.near_count, 0), grown(self.near_elem, 0), \
            grown(self.active, 0)
        self.slot_elem, self.slot_hist = grown(self.slot_elem, -1), grown(self.slot_hist, 0.0)
        self.ids_seen = np.ascontiguousarray(np.concatenate([self.ids_seen[keep], np.asarray(new_ids, np.int64)]))
        self.info[S.INFO_FORCE_REBUILD] = 1

    def checkpoint_arrays(self) -> dict[str, np.ndarray]:
        out = {"engine/shape_slot_elem": self.slot_elem, "engine/shape_slot_hist": self.slot_hist,
               "engine/shape_ids_seen": self.ids_seen, "engine/shape_info": self.info}
        if self.has_bodies:
            out["engine/shape_bodies"] = self.motion[:, S.MOTION_COLS:S.MOTION_COLS + S.BODY_COLS]
        return out

    def restore(self, arrays: dict[str, np.ndarray]) -> None:
        for k in ("slot_elem", "slot_hist", "ids_seen", "info"):
            key = f"engine/shape_{k}"
            if key in arrays:
                getattr(self, k)[...] = arrays[key]
        if self.has_bodies:
            if "engine/shape_bodies" not in arrays:
                raise CaseError("restart: the checkpoint holds no free-body state (engine/shape_bodies) for the "
                                f"free bodies {self.body_names}; it was written by a case without them")
            self.motion[:, S.MOTION_COLS:S.MOTION_COLS + S.BODY_COLS] = arrays["engine/shape_bodies"]
        self.info[S.INFO_FORCE_REBUILD] = 1  # near lists are derived: made anew from the restored positions

    @property
    def has_bodies(self) -> bool:
        return any(s.body is not None for s in self.shapes)

    @property
    def body_names(self) -> list[str]:
        return [s.name for s in self.shapes if s.body is not None]

    def body_state(self, k: int) -> dict[str, np.ndarray]:
        """Free body k's state: ``position`` of its centre of mass [m], ``velocity`` [m/s], ``quaternion``
        (w, x, y, z) of its rotation from rest, ``angular_velocity`` (world) [rad/s], ``angular_momentum``
        about its centre of mass (world) [kg m²/s], ``force`` [N] and ``torque`` [N m] of the last step
        (contacts and gravity)."""
        row = self.motion[k, S.MOTION_COLS:]
        P = np.empty((len(self.shapes), S.POSE_COLS))
        S.pose(self.motion, 0.0, P)
        R = P[k, 3:12].reshape(3, 3)
        Q = row[S.BODY_AXES:S.BODY_AXES + 9].reshape(3, 3)
        pi = row[S.BODY_PI:S.BODY_PI + 3]
        return {"position": self.shapes[k].centre + row[S.BODY_D:S.BODY_D + 3],
                "velocity": row[S.BODY_V:S.BODY_V + 3].copy(), "quaternion": row[S.BODY_Q:S.BODY_Q + 4].copy(),
                "angular_velocity": P[k, 15:18].copy(), "angular_momentum": R @ Q @ pi,
                "force": row[S.BODY_F:S.BODY_F + 3].copy(), "torque": row[S.BODY_T:S.BODY_T + 3].copy()}

    def displacement(self, k: int, t: float) -> tuple[np.ndarray, float]:
        """Shape k's displacement d(t) (3,) [m] and rotation angle θ(t) [rad] (0 unless it rotates; a free
        body: its present ones, the angle of its rotation from rest)."""
        P = np.empty((len(self.shapes), S.POSE_COLS))
        S.pose(self.motion, t, P)
        return P[k, 0:3].copy(), float(P[k, 21])

    def check_overlaps(self, state, t: float, tolerance: float) -> None:
        """CaseError if a particle overlaps a shape at time t by more than ``tolerance`` of its radius."""
        if not len(self.kind):
            return
        overlap = np.zeros(state.n)
        element = np.zeros(state.n, np.int64)
        S.deepest_contacts(self.kernel_arrays(), state.position, state.radius, t, overlap, element)
        bad = np.flatnonzero(overlap > tolerance * state.radius)
        if bad.size:
            i = bad[np.argmax(overlap[bad])]
            raise CaseError(
                f"particles.placement: initial particles cross wall {self.names[self.owner[element[i]]]}: "
                f"{bad.size} particle(s), e.g. particle {i} by {overlap[i]:.3g} m; particles must start apart "
                "from the walls (set particles.placement.region_lower and region_upper inside the shapes)")

    def contacts(self, state, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(contacts (N,) int64, deepest overlap (N,) [m], its shape index (N,), −1: none) of each particle with
        the shapes at time t (``_shape_kernels.contact_census``), from the near lists of the last force
        evaluation; zeros without shapes."""
        n = state.n
        count, overlap = np.zeros(n, np.int64), np.zeros(n)
        element = np.full(n, -1, np.int64)
        if len(self.shapes) and hasattr(self, "kind") and len(self.kind):
            S.contact_census(self.kernel_arrays(), state.position, state.radius, t, count, overlap, element)
        shape = np.full(n, -1, np.int64)
        hit = element >= 0
        shape[hit] = self.owner[element[hit]]
        return count, overlap, shape

    def triangle_shapes(self) -> np.ndarray:
        """(T,) int64: the shape index of each triangle of ``world_triangles`` (in its order)."""
        counts = [np.where(s.kind == S.CYLINDER, 2 * CYLINDER_SIDES, 1) for s in self.shapes]
        return np.repeat(np.arange(len(self.shapes)), [int(c.sum()) for c in counts]).astype(np.int64)

    def world_triangles(self, t: float) -> np.ndarray:
        """(T, 3, 3) corners of every triangle and segment (a degenerate triangle) at time t, for output; a
        cylinder is drawn as 32 quads of two triangles. Free bodies are drawn at rest (their pose is that of
        t = 0, the case's geometry)."""
        P = np.empty((len(self.shapes), S.POSE_COLS))
        motion = self.motion.copy()
        motion[motion[:, 0] == S.FREE, 0] = S.STATIC
        S.pose(motion, t, P)
        out = []
        for k, s in enumerate(self.shapes):
            for e in range(len(s.kind)):
                g = s.geom[e]
                if s.kind[e] == S.TRIANGLE:
                    tri = g[:9].reshape(3, 3)
                elif s.kind[e] == S.SEGMENT:
                    tri = np.array([g[0:3], g[3:6], g[3:6]])
                else:
                    tri = _cylinder_triangles(g)
                tri = tri.reshape(-1, 3)
                c = P[k, 18:21]
                R = P[k, 3:12].reshape(3, 3)
                out.append(((tri - c) @ R.T + c + P[k, 0:3]).reshape(-1, 3, 3))
        return np.concatenate(out) if out else np.zeros((0, 3, 3))


def _cylinder_triangles(g, n=CYLINDER_SIDES):
    c, u, rad, length = g[0:3], g[3:6], g[6], g[7]
    a = np.cross(u, [1.0, 0.0, 0.0] if abs(u[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(u, a)
    th = np.linspace(0.0, 2 * np.pi, n + 1)
    ring = c + rad * (np.cos(th)[:, None] * a + np.sin(th)[:, None] * b)
    top = ring + length * u
    tris = []
    for j in range(n):
        tris.append([ring[j], ring[j + 1], top[j + 1]])
        tris.append([ring[j], top[j + 1], top[j]])
    return np.array(tris)


def _grid(box, inflate, dim2):
    """Broad-phase grid over the element boxes inflated by ``inflate`` (the largest radius plus the skin):
    (grid (8,) origin and cell size, dims (3,), cell_start, cell_elems). In 2D one cell along z, which
    takes every z (``near_elements``)."""
    if box.shape[0] == 0:
        return np.zeros(8), np.ones(3, np.int64), np.zeros(2, np.int64), np.zeros(0, np.int64)
    big = box.copy()
    big[:, :3] -= inflate
    big[:, 3:] += inflate
    lo = big[:, :3].min(axis=0)
    hi = big[:, 3:].max(axis=0)
    ext = hi - lo
    axes = 2 if dim2 else 3
    h = 2.0 * inflate
    vol = float(np.prod(ext[:axes]))
    h = max(h, (vol / MAX_GRID_CELLS) ** (1.0 / axes))
    dims = np.ones(3, np.int64)
    dims[:axes] = np.maximum(1, np.ceil(ext[:axes] / h).astype(np.int64))
    grid = np.zeros(8)
    grid[:3] = lo
    grid[3] = h
    start, elems = S.bin_elements(big, lo, h, dims)
    return grid, dims, start, elems


# ---------------------------------------------------------------- building from the case
def build_shapes(case) -> ShapeSet:
    """The case's shape walls as a ``ShapeSet`` (CaseError naming the wall and key on bad geometry)."""
    dim2 = case.particles.dimensions == 2
    out = ShapeSet()
    for i, wall in enumerate(case.walls):
        if wall.kind not in SHAPE_KINDS:
            continue
        where = f"walls.{i} ({wall.name!r})"
        m = wall.motion
        if dim2 and m is not None:
            if m.kind == "rotation" and (abs(m.axis[0]) > 0 or abs(m.axis[1]) > 0):
                raise CaseError(f"{where}.motion.axis = {list(m.axis)}: in 2D a shape rotates about z only "
                                "(axis = [0, 0, 1])")
        if wall.kind == "polyline":
            if not dim2:
                raise CaseError(f"{where}.kind = 'polyline': a polyline is a 2D wall (particles.dimensions = 2); "
                                "in 3D use kind = 'polygon' or 'mesh'")
            kind, geom = _polyline(wall, where)
        elif wall.kind == "polygon":
            if dim2:
                raise CaseError(f"{where}.kind = 'polygon': a polygon is a 3D wall; in 2D use kind = 'polyline'")
            kind, geom = _polygon(wall, where)
        elif wall.kind == "cylinder":
            axis = np.array(wall.axis, float)
            axis /= np.linalg.norm(axis)
            if dim2 and (abs(axis[0]) > 1e-12 or abs(axis[1]) > 1e-12):
                raise CaseError(f"{where}.axis = {list(wall.axis)}: in 2D a cylinder (a circle in the x-y plane) "
                                "has its axis along z")
            geom = np.zeros((1, 9))
            geom[0, 0:3] = wall.point
            geom[0, 3:6] = axis
            geom[0, 6] = wall.radius
            geom[0, 7] = wall.length
            geom[0, 8] = 1.0 if wall.inside else -1.0
            kind = np.array([S.CYLINDER], np.int64)
        else:
            if dim2:
                raise CaseError(f"{where}.kind = 'mesh': a mesh is a 3D wall; in 2D use kind = 'polyline'")
            kind, geom = _mesh(wall, where)
        box = _boxes(kind, geom)
        corners = _corners(kind, geom)
        table = _pose_table(m, f"{where}.motion", dim2) if m is not None and m.kind == "table" else None
        body = None
        if m is not None and m.kind in ("rotation", "table") and m.axis_point is not None:
            centre = np.array(m.axis_point, float)
        elif m is not None and m.kind == "free":
            centre, body = _free_body(wall, kind, geom, corners, f"{where}.motion", dim2)
        else:
            centre = corners.mean(axis=0)
        reach = float(np.max(np.linalg.norm(corners - centre, axis=1)))
        out.shapes.append(Shape(wall.name, wall, kind, geom, box, centre, reach, table, body))
    return out


def _free_body(wall, kind, geom, corners, where, dim2):
    """(centre of mass (3,), body dict) of a wall whose motion is 'free' (CaseError naming the key where the
    body lacks what it needs)."""
    m = wall.motion
    from ..case import inertia_tensor

    solid = None
    if m.inertia is None and not m.fixed_rotation:
        if wall.kind != "mesh":
            raise CaseError(f"{where}.inertia: a free {wall.kind} needs its inertia [kg m^2] about the centre of mass "
                            "(three principal moments or a 3 x 3 tensor), or fixed_rotation = true; only a closed "
                            "mesh has a default (a uniform solid)")
        solid = _solid(geom, where, wall.file)
    if m.centre_of_mass is not None:
        centre = np.array(m.centre_of_mass, float)
    elif solid is not None:
        centre = solid[1]
    else:
        centre = corners.mean(axis=0)
    if m.inertia is not None:
        tensor = np.array(inertia_tensor(m.inertia), float)
    elif solid is not None:  # a uniform solid of the body's mass, about its centre of mass
        volume, centroid, second = solid
        r = centroid - centre
        tensor = m.mass / volume * second + m.mass * (np.dot(r, r) * np.eye(3) - np.outer(r, r))
    else:
        tensor = np.eye(3)  # not used: the body does not rotate
    velocity = np.array(m.velocity if m.velocity is not None else (0.0, 0.0, 0.0), float)
    omega = np.array(m.angular_velocity if m.angular_velocity is not None else (0.0, 0.0, 0.0), float)
    free = np.array([ax not in m.fixed_axes for ax in "xyz"], float)
    if dim2:
        if velocity[2] != 0.0:
            raise CaseError(f"{where}.velocity = {list(m.velocity)}: in 2D a free body moves in the x-y plane (vz = 0)")
        if omega[0] != 0.0 or omega[1] != 0.0:
            raise CaseError(f"{where}.angular_velocity = {list(m.angular_velocity)}: in 2D a free body turns about "
                            "z only ([0, 0, wz])")
        if not m.fixed_rotation and (abs(tensor[0, 2]) > 0.0 or abs(tensor[1, 2]) > 0.0):
            raise CaseError(f"{where}.inertia = {m.inertia}: in 2D z must be a principal axis of a free body that "
                            "turns (Ixz = Iyz = 0); give its moment about z as the third principal moment")
        free[2] = 0.0
    for j, ax in enumerate("xyz"):
        if free[j] == 0.0 and velocity[j] != 0.0 and ax in m.fixed_axes:
            raise CaseError(f"{where}.velocity = {list(m.velocity)}: the velocity along the fixed axis {ax} "
                            "(fixed_axes) must be 0")
    return centre, {"mass": float(m.mass), "inertia": tensor, "velocity": velocity, "angular_velocity": omega,
                    "free": free, "rotates": not m.fixed_rotation}


def _solid(geom, where, file):
    """(volume [m^3], volume centroid (3,), second moment tensor about the centroid per unit density (3, 3)) of
    the solid a closed triangle mesh bounds, summed over the tetrahedra of its triangles with the origin:
    C = V/20 (Σ v vᵀ + s sᵀ), s the sum of the four corners, I = tr(C) 1 − C (Tonon 2004); CaseError if the
    mesh is not closed (the triangles' area vectors must sum to zero)."""
    tri = geom.reshape(-1, 3, 3)
    shift = tri.reshape(-1, 3).mean(axis=0)  # sums about a point inside, for round-off
    a, b, c = tri[:, 0] - shift, tri[:, 1] - shift, tri[:, 2] - shift
    area = 0.5 * np.cross(b - a, c - a)
    total = float(np.sum(np.linalg.norm(area, axis=1)))
    if np.linalg.norm(area.sum(axis=0)) > 1e-6 * total:
        raise CaseError(f"{where}.inertia: not given, and the mesh {file!r} is not closed (its triangles' area "
                        "vectors do not sum to zero) or not consistently oriented, so it bounds no solid; give "
                        "inertia and centre_of_mass")
    vol = np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0
    volume = float(vol.sum())
    if volume < 0.0:  # inward normals: the same solid
        vol, volume = -vol, -volume
    if volume <= 0.0:
        raise CaseError(f"{where}.inertia: not given, and the mesh {file!r} bounds no volume; give inertia")
    s = a + b + c
    centroid = (vol[:, None] * s).sum(axis=0) / (4.0 * volume)
    cov = np.einsum("t,tij->ij", vol / 20.0, np.einsum("ti,tj->tij", a, a) + np.einsum("ti,tj->tij", b, b)
                    + np.einsum("ti,tj->tij", c, c) + np.einsum("ti,tj->tij", s, s))
    cov -= volume * np.outer(centroid, centroid)  # about the centroid
    return volume, centroid + shift, np.trace(cov) * np.eye(3) - cov


def _body_row(body, gravity, dim2) -> np.ndarray:
    """The BODY_COLS state columns of a free body at rest: d = 0, q = 1, π = I_k Qᵀ ω₀ in the principal axes
    Q (a proper rotation; in 2D its third column is z exactly, so that the body turns about z only)."""
    row = np.zeros(S.BODY_COLS)
    tensor = body["inertia"]
    if dim2:
        moments2, axes2 = np.linalg.eigh(tensor[:2, :2])
        moments = np.array([moments2[0], moments2[1], tensor[2, 2]])
        axes = np.eye(3)
        axes[:2, :2] = axes2
    else:
        moments, axes = np.linalg.eigh(tensor)
    if np.linalg.det(axes) < 0.0:
        axes[:, 0] = -axes[:, 0]
    row[S.BODY_V:S.BODY_V + 3] = body["velocity"] * body["free"]
    row[S.BODY_Q] = 1.0
    row[S.BODY_QREF] = 1.0
    if body["rotates"]:
        row[S.BODY_PI:S.BODY_PI + 3] = moments * (axes.T @ body["angular_velocity"])
    row[S.BODY_I:S.BODY_I + 3] = moments
    row[S.BODY_AXES:S.BODY_AXES + 9] = axes.ravel()
    row[S.BODY_MASS] = body["mass"]
    row[S.BODY_FREE:S.BODY_FREE + 3] = body["free"]
    row[S.BODY_ROTATES] = 1.0 if body["rotates"] else 0.0
    row[S.BODY_G:S.BODY_G + 3] = gravity
    row[S.BODY_PLANAR] = 1.0 if dim2 else 0.0
    return row


def _pose_table(motion, where, dim2):
    """(T, 5) rows t, dx, dy, dz, angle of a table motion's CSV file (header naming the columns)."""
    path = Path(motion.file)
    if not path.is_file():
        raise CaseError(f"{where}.file = {motion.file!r}: no such file (a CSV of t, dx, dy, dz, angle; a "
                        "relative path is taken from the case file's directory, or from the working directory "
                        f"{str(Path.cwd())!r} for a case not read from a file)")
    cols = ("t", "dx", "dy", "dz", "angle")
    try:
        data = np.genfromtxt(path, delimiter=",", names=True, dtype=float, encoding="utf-8")
    except Exception as exc:  # noqa: BLE001 - any reader failure is bad input
        raise CaseError(f"{where}.file = {motion.file!r}: not a readable CSV file ({exc})") from None
    names = data.dtype.names or ()
    missing = [c for c in cols if c not in names]
    if missing:
        raise CaseError(f"{where}.file = {motion.file!r}: no column {', '.join(missing)}; the header must name "
                        f"{', '.join(cols)}")
    table = np.column_stack([np.atleast_1d(data[c]) for c in cols])
    if not np.all(np.isfinite(table)):
        row = int(np.flatnonzero(~np.all(np.isfinite(table), axis=1))[0])
        raise CaseError(f"{where}.file = {motion.file!r}: row {row + 1} holds a value that is not a finite number")
    if np.any(np.diff(table[:, 0]) <= 0.0):
        row = int(np.flatnonzero(np.diff(table[:, 0]) <= 0.0)[0])
        raise CaseError(f"{where}.file = {motion.file!r}: t must increase from row to row; row {row + 2} has "
                        f"t = {table[row + 1, 0]:g} after {table[row, 0]:g}")
    if np.any(table[:, 4] != 0.0) and (motion.axis is None or motion.axis_point is None):
        raise CaseError(f"{where}: a table with angles needs axis_point and axis (the rotation axis)")
    if dim2 and np.any(table[:, 3] != 0.0):
        raise CaseError(f"{where}.file = {motion.file!r}: in 2D a shape moves in the x-y plane (dz = 0)")
    if dim2 and np.any(table[:, 4] != 0.0) and (abs(motion.axis[0]) > 0 or abs(motion.axis[1]) > 0):
        raise CaseError(f"{where}.axis = {list(motion.axis)}: in 2D a shape rotates about z only")
    return table


def _polyline(wall, where):
    pts = np.array(wall.points, float)
    if wall.closed:
        pts = np.vstack([pts, pts[:1]])
    geom = []
    for j in range(len(pts) - 1):
        if np.hypot(*(pts[j + 1] - pts[j])) == 0.0:
            raise CaseError(f"{where}.points.{j} and points.{(j + 1) % len(wall.points)} are the same point "
                            f"{list(wall.points[j])}: a segment needs two distinct ends")
        geom.append([pts[j, 0], pts[j, 1], 0.0, pts[j + 1, 0], pts[j + 1, 1], 0.0, 0.0, 0.0, 0.0])
    return np.full(len(geom), S.SEGMENT, np.int64), np.array(geom)


def _polygon(wall, where):
    pts = np.array(wall.points, float)
    # Newell's normal; the corners must lie in its plane and turn one way round it (convex)
    nrm = np.zeros(3)
    for j in range(len(pts)):
        p, q = pts[j], pts[(j + 1) % len(pts)]
        nrm += np.array([(p[1] - q[1]) * (p[2] + q[2]), (p[2] - q[2]) * (p[0] + q[0]), (p[0] - q[0]) * (p[1] + q[1])])
    size = float(np.max(np.ptp(pts, axis=0)))
    if np.linalg.norm(nrm) <= 1e-12 * size * size:
        raise CaseError(f"{where}.points = {wall.points}: the corners span no area")
    nrm /= np.linalg.norm(nrm)
    off = np.abs((pts - pts[0]) @ nrm)
    if off.max() > 1e-9 * size:
        j = int(np.argmax(off))
        raise CaseError(f"{where}.points.{j} = {wall.points[j]} lies {off[j]:.3g} m off the plane of the other "
                        "corners: a polygon is flat (use kind = 'mesh' for a curved surface)")
    for j in range(len(pts)):
        a, b, c = pts[j - 1], pts[j], pts[(j + 1) % len(pts)]
        if np.dot(np.cross(b - a, c - b), nrm) < -1e-12 * size * size:
            raise CaseError(f"{where}.points: the polygon is not convex at points.{j} = {wall.points[j]}; give "
                            "convex polygons (split a concave one) or a mesh")
    geom = [np.concatenate([pts[0], pts[j], pts[j + 1]]) for j in range(1, len(pts) - 1)]
    return np.full(len(geom), S.TRIANGLE, np.int64), np.array(geom)


def _mesh(wall, where):
    path = Path(wall.file)
    if not path.is_file():
        raise CaseError(f"{where}.file = {wall.file!r}: no such file (an STL file; a relative path is taken "
                        "from the case file's directory, or from the working directory "
                        f"{str(Path.cwd())!r} for a case not read from a file)")
    try:
        from stl import mesh as stl_mesh

        tri = np.array(stl_mesh.Mesh.from_file(str(path)).vectors, float)
    except Exception as exc:  # noqa: BLE001 - any reader failure is bad input
        raise CaseError(f"{where}.file = {wall.file!r}: not a readable STL file ({exc})") from None
    tri = tri * wall.scale + np.array(wall.offset, float)
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    size = float(np.max(np.ptp(tri.reshape(-1, 3), axis=0))) if len(tri) else 0.0
    tri = tri[area > 1e-14 * size * size]  # zero-area triangles touch nothing a face or edge does not
    if len(tri) == 0:
        raise CaseError(f"{where}.file = {wall.file!r}: the STL file holds no triangles of nonzero area")
    return np.full(len(tri), S.TRIANGLE, np.int64), np.ascontiguousarray(tri.reshape(-1, 9))


def _boxes(kind, geom):
    box = np.zeros((len(kind), 6))
    for e in range(len(kind)):
        if kind[e] == S.CYLINDER:
            c, u, rad, length = geom[e, 0:3], geom[e, 3:6], geom[e, 6], geom[e, 7]
            spread = rad * np.sqrt(np.clip(1.0 - u * u, 0.0, 1.0))
            ends = np.array([c, c + length * u])
            box[e, :3] = ends.min(axis=0) - spread
            box[e, 3:] = ends.max(axis=0) + spread
        else:
            pts = geom[e].reshape(3, 3)[: 3 if kind[e] == S.TRIANGLE else 2]
            box[e, :3] = pts.min(axis=0)
            box[e, 3:] = pts.max(axis=0)
    return box


def _corners(kind, geom):
    out = []
    for e in range(len(kind)):
        if kind[e] == S.CYLINDER:
            out.append(_cylinder_triangles(geom[e], 8).reshape(-1, 3))
        else:
            out.append(geom[e].reshape(3, 3)[: 3 if kind[e] == S.TRIANGLE else 2])
    return np.concatenate(out)


def refusal(case) -> str | None:
    """Why an engine other than the soft-sphere CPU one cannot run ``case``'s wall shapes (None: no shapes)."""
    names = [f"walls.{i} ({w.name!r}) kind = {w.kind!r}" for i, w in enumerate(case.walls) if w.kind in SHAPE_KINDS]
    if not names:
        return None
    free = [f"walls.{i} ({w.name!r}) motion.kind = 'free'" for i, w in enumerate(case.walls)
            if w.kind in SHAPE_KINDS and w.motion is not None and w.motion.kind == "free"]
    out = ", ".join(names) + " (wall shapes: the soft-sphere CPU engine only)"
    if free:
        out += "; free bodies " + ", ".join(free) + " (the soft-sphere CPU engine only)"
    return out


