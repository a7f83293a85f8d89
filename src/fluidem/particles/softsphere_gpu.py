"""Soft-sphere DEM on an NVIDIA GPU (numba-cuda): the ``SoftSphereEngine`` interface with the step on the device.

``SoftSphereGPUEngine`` shares the CPU engine's set-up (contact tables from the registry, time step,
walls, the renumbering in cell order at set-up) and its physics: the contact laws are the CPU's own code
compiled for the GPU (``contact._dispatch_cuda``), and the step is the CPU's velocity-Verlet step in
per-particle kernels (``_softsphere_cuda``, ``_neighbours_cuda``). The particles stay on the device
between ``advance`` calls. ``state`` is a ``ParticleState`` whose arrays are fetched from the device when
read (output, analyses, checkpoints) and sent back before the next step, so callers that read or change
them (the gas coupling's ``ext_force``, a writer) need not know where the particles live.

Checkpoints hold the CPU engine's arrays under the same names (the half neighbour list made from
``ref_pos`` by the CPU's ``build_pairs``, springs relative to each pair's owner), so that a run continues
on either engine. ``choose_device(case)`` reads the case's ``device`` key; ``gpu_refusals(case)`` lists
what the GPU engine does not do for a case.
"""
from __future__ import annotations

import logging
from dataclasses import fields

import numpy as np

from ..errors import CaseError
from ..state import ParticleState
from . import _softsphere_kernels as K
from ._fulllist_kernels import full_rows, half_history, upper_rows
from ._neighbours_kernels import _grid, build_pairs, contacts_first
from .engine import ParticleEngine
from .softsphere import SoftSphereEngine

log = logging.getLogger(__name__)

STATE_FIELDS = tuple(f.name for f in fields(ParticleState))
ON_DEVICE = ("position", "velocity", "omega", "force", "torque", "radius", "mass", "inertia", "species",
             "ext_force", "ext_damping")  # arrays with a device copy (ids stay on the host: the GPU never renumbers)
STEPPED = ("position", "velocity", "omega", "force", "torque")  # what a step changes on the device
FIRST_ROW_LENGTH = {2: 16, 3: 24}  # partners per row of the first list (grown when a row is longer)
FIRST_CELL_CAPACITY = 8  # particles per grid cell of the first build (grown on overflow)


# ---------------------------------------------------------------- choosing the device
def gpu_refusals(case) -> list[str]:
    """What in ``case`` the GPU engine does not do, one line each (empty: the case runs on the GPU)."""
    out = []
    if case.particles.contact.instantaneous:
        out.append(f"particles.contact.model = {case.particles.contact.model!r} (event-driven hard spheres run "
                   "on the CPU only)")
    if case.inlets or case.outlets:
        out.append("[[inlets]] / [[outlets]] (particles added and removed during a run: the CPU engine only)")
    for i, w in enumerate(case.walls):
        if getattr(w, "periodic", None):
            out.append(f"walls.{i}.periodic = {list(w.periodic)} (periodic sides run on the CPU only)")
    from .shapes import refusal

    shapes = refusal(case)
    if shapes:
        out.append(shapes)
    found = set()

    def visit(node, path):  # every contact law of the case: the default, the wall law, the override tables
        if isinstance(node, dict):
            if node.get("model") == "hertz_mindlin_jkr":
                found.add(f"{path}.model = 'hertz_mindlin_jkr' (JKR adhesion)")
            if (node.get("rolling_friction") or 0.0) > 0.0:
                found.add(f"{path}.rolling_friction = {node['rolling_friction']:g} (rolling resistance)")
            if node.get("nonlinearity") not in (None, "none"):
                found.add(f"{path}.nonlinearity = {node['nonlinearity']!r} (Sun 2007's Hertzian linear law)")
            for k, v in node.items():
                visit(v, f"{path}.{k}" if path else k)
        elif isinstance(node, list):
            for i, v in enumerate(node):
                visit(v, f"{path}.{i}")

    visit(case.model_dump(mode="python", include={"particles", "walls"}), "")
    out.extend(sorted(found))
    return out


def cuda_available() -> bool:
    """True if numba.cuda finds a usable GPU (or the CUDA simulator, NUMBA_ENABLE_CUDASIM=1)."""
    try:
        from numba import cuda

        return bool(cuda.is_available())
    except Exception:  # noqa: BLE001 - no numba.cuda, no driver: no GPU
        return False


def choose_device(case) -> str:
    """"cpu" or "gpu" for ``case.device``: "gpu" raises ``CaseError`` naming what the GPU engine lacks for the
    case, or that no GPU is found; "auto" takes the GPU when one is found and the case is supported."""
    wanted = getattr(case, "device", "cpu")
    if wanted == "cpu":
        return "cpu"
    refusals = gpu_refusals(case)
    if wanted == "gpu":
        if refusals:
            raise CaseError("device = 'gpu': the GPU engine does not support " + "; ".join(refusals)
                            + ". Use device = 'cpu' (or 'auto', which falls back to the CPU)")
        if not cuda_available():
            raise CaseError("device = 'gpu': no CUDA GPU is available (numba.cuda.is_available() is False: no "
                            "NVIDIA driver or GPU, or numba-cuda is not installed: pip install 'fluidem[gpu]'). "
                            "Use device = 'cpu' or 'auto'")
        return "gpu"
    if refusals:
        log.info("device = 'auto': running on the CPU, the GPU engine does not support %s", "; ".join(refusals))
        return "cpu"
    if not cuda_available():
        log.info("device = 'auto': no CUDA GPU found, running on the CPU")
        return "cpu"
    return "gpu"


# ---------------------------------------------------------------- state fetched on demand
class DeviceParticleState:
    """The ``ParticleState`` interface over a GPU engine's particles: each array is fetched from the device
    when read and sent back before the engine's next step (it may have been changed)."""

    def __init__(self, engine: "SoftSphereGPUEngine"):
        self._engine = engine

    @property
    def n(self) -> int:
        return self._engine._n

    def arrays(self) -> dict[str, np.ndarray]:
        return {k: getattr(self, k) for k in STATE_FIELDS}


def _field(name):
    def get(self):
        return self._engine._get(name)

    def put(self, value):
        self._engine._get(name)[...] = value

    return property(get, put, doc=f"``ParticleState.{name}``, fetched from the device")


for _name in STATE_FIELDS:
    setattr(DeviceParticleState, _name, _field(_name))


def _mirrored(name):
    def get(self):
        return self._get(name)

    def put(self, value):
        if name in self._dev:
            self._get(name)[...] = value
        else:
            self._host[name] = np.ascontiguousarray(value)

    return property(get, put)


# ---------------------------------------------------------------- the engine
class SoftSphereGPUEngine(SoftSphereEngine):
    """Velocity-Verlet soft-sphere DEM on the GPU (Sun 2007 eqs 15–26): ``SoftSphereEngine``'s interface,
    set-up and physics, with a full neighbour list on a cell grid (``_neighbours_cuda``).

    The host attributes the CPU engine has (``row_start``, ``partner``, ``hist``, ``wall_hist``, ``ref_pos``)
    are read-only copies made from the device on request (a half list, as the CPU's, for the analyses).
    The particles are numbered in cell order at set-up as on the CPU; they are not renumbered during the
    run (``reorder_interval`` is kept for checkpoints)."""

    ext_force = _mirrored("ext_force")
    ext_damping = _mirrored("ext_damping")

    def __init__(self, case, state: ParticleState | None = None):
        from numba import cuda

        from . import _neighbours_cuda, _softsphere_cuda

        self._cuda, self._nc, self._sc = cuda, _neighbours_cuda, _softsphere_cuda
        self._host: dict[str, np.ndarray | None] = {}
        self._dev: dict = {}
        self._valid: set[str] = set()  # host copies that are current
        self._dirty: set[str] = set()  # host copies handed out since the last step (to send back)
        self._list_cache = None
        ParticleEngine.__init__(self, case, state)
        st = self._host_state()
        self._n = st.n
        self.ext_damping = np.zeros(st.n)
        self.pp, self.pw, self.contact_times = self._contact_tables()
        nw = len(self.walls.planes)
        wall_hist = np.zeros((st.n, nw, 3))
        dmax = 2.0 * st.radius.max() if st.n else 0.0
        self.skin = case.neighbours.skin if case.neighbours.skin is not None else 0.25 * dmax
        self.dt = self._time_step()
        self.time = 0.0
        self.steps = 0
        self.rebuilds = 0
        self.reorder_interval = self._reorder_interval()
        self.last_reorder = 0
        self.reorders = 0
        if self.reorder_interval > 0 and st.n:  # as the CPU engine's set-up (SoftSphereEngine._renumber)
            no_list = (np.zeros(st.n + 1, dtype=np.int64), np.empty(0, dtype=np.int32), np.empty((0, 3)))
            K.reorder(st.position, st.velocity, st.omega, st.force, st.torque, st.radius, st.mass, st.inertia,
                      self.inv_mass, self.inv_inertia, st.species, st.ids, self._host["ext_force"],
                      self._host["ext_damping"], wall_hist, *no_list, self.skin, self.dim2)
        self.reorder_listeners = []  # kept for the coupling's interface; the GPU engine does not renumber
        self._upload(wall_hist)
        self._row_length = FIRST_ROW_LENGTH[3 if not self.dim2 else 2]
        self._cell_capacity = FIRST_CELL_CAPACITY
        self._lists = [self._empty_list(1), None]  # the current list and a spare of the same kind
        self._cells = None  # (counts, members) of the grid cells, kept from build to build
        self._dev["ref_pos"].copy_to_device(self._dev["position"])
        self._build_list()
        self._compute_forces(update=False)

    # ------------------------------------------------------------ host ↔ device
    def _host_state(self) -> ParticleState:
        return ParticleState(**{k: self._host[k] for k in STATE_FIELDS})

    @property
    def state(self):
        return DeviceParticleState(self)

    @state.setter
    def state(self, value: ParticleState) -> None:  # ParticleEngine.__init__: the particles to start from
        for k in STATE_FIELDS:
            self._host[k] = getattr(value, k)

    def _get(self, name: str) -> np.ndarray:
        """The host copy of a mirrored array, fetched if the device has changed it; it counts as changed
        (sent back before the next step)."""
        if name in self._dev and name not in self._valid:
            self._dev[name].copy_to_host(self._host[name])
            self._valid.add(name)
        if name in self._dev:
            self._dirty.add(name)
        return self._host[name]

    def _push(self) -> None:
        """Send the host copies handed out since the last step to the device."""
        if not self._dirty:
            return
        for name in self._dirty:
            self._dev[name].copy_to_device(np.ascontiguousarray(self._host[name]))
        if self._dirty & {"mass", "inertia"}:
            self._derive_inverses()
        if self._dirty & {"ext_force", "ext_damping"}:
            self._has_ext = bool(np.any(self._host["ext_force"]) or np.any(self._host["ext_damping"]))
        self._dirty.clear()

    def _stepped(self) -> None:
        """The device changed the particles (positions, velocities, forces) and the list."""
        self._valid.difference_update(STEPPED)
        self._list_cache = None

    def device_arrays(self) -> dict:
        """The particles' device arrays by name (``ON_DEVICE``: ``position``, ``velocity``, ``force``,
        ``ext_force``, ...), current: host copies changed since the last step are sent first. For kernels that
        read or write the particles where they live (the gas coupling's ``coupling.exchange_gpu``); one that
        writes some of them says so with ``device_changed``."""
        self._push()
        return self._dev

    def device_changed(self, names) -> None:
        """Kernels other than the engine's have written these device arrays: their host copies are stale."""
        names = set(names)
        self._valid.difference_update(names)
        if names & {"ext_force", "ext_damping"}:
            self._has_ext = True

    def _derive_inverses(self) -> None:
        ParticleEngine._derive_inverses(self)
        if "inv_mass" in self._dev:
            self._dev["inv_mass"].copy_to_device(self.inv_mass)
            self._dev["inv_inertia"].copy_to_device(self.inv_inertia)

    def _upload(self, wall_hist: np.ndarray) -> None:
        """Every array the kernels read onto the device (at set-up)."""
        cuda = self._cuda
        for k in ON_DEVICE:
            self._host[k] = np.ascontiguousarray(self._host[k])
            self._dev[k] = cuda.to_device(self._host[k])
            self._valid.add(k)
        d = self._dev
        d["inv_mass"] = cuda.to_device(self.inv_mass)
        d["inv_inertia"] = cuda.to_device(self.inv_inertia)
        nw = self.wall_normal.shape[0]
        self._nw = nw
        pad = max(nw, 1)  # no zero-sized device arrays
        d["pp"] = cuda.to_device(np.ascontiguousarray(self.pp))
        d["pw"] = cuda.to_device(np.ascontiguousarray(self.pw))
        for k, width in (("wall_motion", 6), ("wall_point0", 3), ("wall_normal", 3)):
            d[k] = cuda.to_device(np.ascontiguousarray(getattr(self, k)) if nw else np.zeros((1, width)))
        d["gravity"] = cuda.to_device(self.gravity)
        d["ref_pos"] = cuda.device_array((self._n, 3))
        d["wall_hist"] = cuda.device_array((pad, 3, self._n))
        d["wall_touch"] = cuda.device_array((pad, self._n), dtype=np.uint8)
        self._set_wall_hist(wall_hist)
        d["flag"] = cuda.to_device(np.zeros(1, dtype=np.int32))
        self._has_ext = bool(np.any(self._host["ext_force"]) or np.any(self._host["ext_damping"]))

    def _set_wall_hist(self, wall_hist: np.ndarray) -> None:
        """(N, W, 3) wall springs onto the device ((W, 3, N), and where each is set)."""
        pad = max(self._nw, 1)
        wh = np.zeros((pad, 3, self._n))
        wh[:self._nw] = np.transpose(wall_hist, (1, 2, 0))
        self._dev["wall_hist"].copy_to_device(wh)
        touch = np.zeros((pad, self._n), dtype=np.uint8)
        touch[:self._nw] = np.any(wall_hist != 0.0, axis=2).T
        self._dev["wall_touch"].copy_to_device(touch)

    def _blocks(self, threads: int) -> int:
        return max(1, (self._n + threads - 1) // threads)

    # ------------------------------------------------------------ the neighbour list
    def _empty_list(self, k: int) -> dict:
        cuda = self._cuda
        n = max(self._n, 1)
        return {"k": k, "nbr": cuda.device_array((k, n), dtype=np.int32),
                "count": cuda.to_device(np.zeros(n, dtype=np.int32)), "hist": cuda.device_array((3, k, n))}

    def _build_list(self) -> None:
        """A new list around the current positions, springs carried over; ``ref_pos`` ← positions."""
        if self._n == 0:
            return
        cuda, nc, d = self._cuda, self._nc, self._dev
        pos, radius = d["position"], d["radius"]
        box = cuda.to_device(np.array([np.inf, np.inf, np.inf, -np.inf, -np.inf, -np.inf, 0.0]))
        nc.bounds[min(self._blocks(nc.BOUNDS_THREADS), 1024), nc.BOUNDS_THREADS](pos, radius, box)
        b = box.copy_to_host()
        inv, ncell = _grid(b[0:3].copy(), b[3:6].copy(), float(b[6]), self.skin, self.dim2, self._n)  # the CPU's grid
        grid = (float(b[0]), float(b[1]), float(b[2]), float(inv[0]), float(inv[1]), float(inv[2]),
                int(ncell[0]), int(ncell[1]), int(ncell[2]))
        ncells = int(ncell[0] * ncell[1] * ncell[2])
        threads = self._sc.THREADS
        flag = d["flag"]
        while True:  # particles into cells, the cells grown until every one holds its particles
            cells = self._cells
            if cells is None or cells[0].shape[0] < ncells or cells[1].shape[1] != self._cell_capacity:
                cells = self._cells = (cuda.device_array(ncells, dtype=np.int32),
                                       cuda.device_array((ncells, self._cell_capacity), dtype=np.int32))
            counts, members = cells
            nc.fill_int[max(1, (ncells + threads - 1) // threads), threads](counts, 0)
            nc.fill_int[1, 1](flag, 0)
            nc.bin_cells[self._blocks(threads), threads](pos, *grid, counts, members, flag)
            if flag.copy_to_host()[0] == 0:
                break
            self._cell_capacity *= 2
        old = self._lists[0]
        while True:  # rows, grown until the longest fits
            new = self._lists[1]
            if new is None or new["k"] < self._row_length:
                new = self._lists[1] = self._empty_list(self._row_length)
            nc.fill_int[1, 1](flag, 0)
            nc.fill_rows[self._blocks(threads), threads](pos, radius, self.skin, *grid, counts, members, new["nbr"],
                                                       new["count"], flag)
            longest = int(flag.copy_to_host()[0])
            if longest <= new["k"]:
                break
            self._row_length = max(self._row_length + 8, (longest + 7) // 8 * 8 + 8)
        nc.carry_history[self._blocks(threads), threads](old["nbr"], old["count"], old["hist"], new["nbr"],
                                                         new["count"], new["hist"])
        self._lists = [new, old]
        d["ref_pos"].copy_to_device(pos)
        self._list_cache = None

    def _host_list(self):
        """(count (N,), nbr (K, N), fhist (3, K, N)) of the current list, fetched."""
        cur = self._lists[0]
        return cur["count"].copy_to_host(), cur["nbr"].copy_to_host(), cur["hist"].copy_to_host()

    def _half_list(self):
        """(row_start, partner): the pairs once each (the row of the smaller index), for the analyses."""
        if self._list_cache is None:
            cur = self._lists[0]
            self._list_cache = upper_rows(cur["count"].copy_to_host(), cur["nbr"].copy_to_host())
        return self._list_cache

    @property
    def row_start(self) -> np.ndarray:
        return self._half_list()[0]

    @property
    def partner(self) -> np.ndarray:
        return self._half_list()[1]

    @property
    def hist(self) -> np.ndarray:
        """(P, 3) springs of the pairs of ``row_start``/``partner``, relative to the row's particle."""
        row_start, partner = self._half_list()
        return half_history(row_start, partner, *self._host_list())

    @property
    def ref_pos(self) -> np.ndarray:
        return self._dev["ref_pos"].copy_to_host()

    @property
    def wall_hist(self) -> np.ndarray:
        """(N, W, 3) wall springs, fetched."""
        return np.ascontiguousarray(np.transpose(self._dev["wall_hist"].copy_to_host()[:self._nw], (2, 0, 1)))

    # ------------------------------------------------------------ stepping
    def _forces(self, t: float, update: bool) -> None:
        d, cur, threads = self._dev, self._lists[0], self._sc.THREADS
        self._sc.pair_and_wall_forces[self._blocks(threads), threads](
            d["position"], d["velocity"], d["omega"], d["radius"], d["mass"], d["species"], d["pp"], cur["nbr"],
            cur["count"], cur["hist"], d["pw"], d["wall_motion"], d["wall_point0"], d["wall_normal"], self._nw,
            d["wall_hist"], d["wall_touch"], d["gravity"], d["ext_force"], d["ext_damping"], self._has_ext, self.dim2, float(t),
            float(self.dt), update, d["force"], d["torque"])

    def _kick(self, kicks: int, drift: bool) -> bool:
        """Half kicks (and the drift); True if a particle moved more than skin/2 since the last build."""
        d, nc, threads = self._dev, self._nc, self._sc.THREADS
        if drift:
            nc.fill_int[1, 1](d["flag"], 0)
        self._sc.kick_drift[self._blocks(threads), threads](
            d["position"], d["velocity"], d["omega"], d["force"], d["torque"], d["inv_mass"], d["inv_inertia"],
            float(self.dt), kicks, drift, d["ref_pos"], float((0.5 * self.skin) ** 2), d["flag"])
        return bool(drift and d["flag"].copy_to_host()[0])

    def _compute_forces(self, update: bool) -> None:
        """Forces and torques at the current state (no integration; springs updated only if ``update``)."""
        if self._n == 0:
            return
        self._push()
        self._forces(self.time, update)
        self._stepped()

    def advance(self, nsteps: int) -> None:
        """Run ``nsteps`` DEM steps of ``self.dt`` on the device, in the order of ``_softsphere_cuda``."""
        if nsteps <= 0 or self._n == 0:
            if nsteps > 0:
                self.steps += nsteps
                self.time = self.steps * self.dt
            return
        self._push()
        moved = self._kick(1, True)
        for s in range(nsteps):
            if moved:
                self._build_list()
                self.rebuilds += 1
            self._forces((self.steps + s + 1) * self.dt, True)
            if s < nsteps - 1:
                moved = self._kick(2, True)
            else:
                self._kick(1, False)
        self._cuda.synchronize()
        self.steps += nsteps
        self.time = self.steps * self.dt
        self._stepped()

    def positions_finite(self) -> bool:
        """True if every position is finite (checked on the device)."""
        if self._n == 0:
            return True
        d, threads = self._dev, self._sc.THREADS
        self._push()
        self._nc.fill_int[1, 1](d["flag"], 0)
        self._sc.all_finite[self._blocks(threads), threads](d["position"], d["flag"])
        return not bool(d["flag"].copy_to_host()[0])

    # ------------------------------------------------------------ checkpoint
    def checkpoint_arrays(self) -> dict[str, np.ndarray]:
        """The CPU engine's checkpoint arrays (``SoftSphereEngine.checkpoint_arrays``): the half list made
        from ``ref_pos`` as the CPU engine makes it, with the springs of the device's list."""
        st = self.state
        out = {f"state/{k}": np.array(v) for k, v in st.arrays().items()}
        ref_pos = self.ref_pos
        row_start, partner, slab_start, slab_members = build_pairs(ref_pos, out["state/radius"], self.skin, self.dim2,
                                                                   0)
        count, nbr, fhist = self._host_list()
        hist = half_history(row_start, partner, count, nbr, fhist)
        contacts_first(ref_pos, out["state/radius"], row_start, partner, hist)  # the CPU's row order after a build
        out.update({
            "engine/wall_hist": self.wall_hist, "engine/ref_pos": ref_pos, "engine/row_start": row_start,
            "engine/partner": partner, "engine/hist": hist, "engine/slab_start": slab_start,
            "engine/slab_members": slab_members, "engine/ext_force": np.array(self.ext_force),
            "engine/ext_damping": np.array(self.ext_damping),
        })
        return out

    def restore(self, arrays: dict[str, np.ndarray], scalars: dict) -> None:
        """Continue from a checkpoint of either engine (the half list becomes the device's full list)."""
        self.restore_state(arrays)
        self.last_reorder = int(scalars.get("last_reorder", 0))
        self.reorders = int(scalars.get("reorders", 0))
        self.ext_force[...] = arrays["engine/ext_force"]
        self.ext_damping[...] = arrays.get("engine/ext_damping", 0.0)
        n = self._n
        ref_pos = np.ascontiguousarray(arrays["engine/ref_pos"], dtype=float)
        wall_hist = np.asarray(arrays["engine/wall_hist"], dtype=float)
        row_start = np.ascontiguousarray(arrays["engine/row_start"], dtype=np.int64)
        partner = np.ascontiguousarray(arrays["engine/partner"], dtype=np.int32)
        hist = np.ascontiguousarray(arrays["engine/hist"], dtype=float)
        if ref_pos.shape != (n, 3) or wall_hist.shape != (n, self._nw, 3) or row_start.shape != (n + 1,):
            raise ValueError(f"checkpoint arrays of {ref_pos.shape[0]} particles and {wall_hist.shape[1]} walls "
                             f"for an engine of {n} and {self._nw}")
        self._dev["ref_pos"].copy_to_device(ref_pos)
        self._set_wall_hist(wall_hist)
        count, nbr, fhist = full_rows(n, row_start, partner, hist, self._row_length)
        self._row_length = nbr.shape[0]
        cuda = self._cuda
        self._lists = [{"k": nbr.shape[0], "nbr": cuda.to_device(nbr), "count": cuda.to_device(count),
                        "hist": cuda.to_device(fhist)}, None]
        self._list_cache = None
        self.dt = float(scalars["dt"])
        self.steps = int(scalars["steps"])
        self.rebuilds = int(scalars["rebuilds"])
        self.time = self.steps * self.dt
        self._push()
