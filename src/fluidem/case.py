"""The case schema: validated, SI-unit input of a run, read from and written to TOML.

Every choice is a named key; unknown keys are errors that list the allowed ones.
``load_case(name_or_path, overrides)`` is what ``fluidem run CASE --set k=v`` calls.
"""
from __future__ import annotations

import difflib
import math
import tomllib
from importlib import resources
from pathlib import Path
from typing import Annotated, Any, Literal, Union

import tomli_w
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from .checks import ChecksSection
from .coupling.schema import CouplingSection
from .coupling.voidage import check_method
from .errors import CaseError
from .gas.schema import GasSection
from .particles.contact import contact_models

Vec3 = tuple[float, float, float]

# the rule for the file keys (placement.file, walls[].file, walls[].motion.file), said in each one's description
RELATIVE_PATHS = ("a relative path is taken from the directory of the case file (a built-in case's: its "
                  "package folder) and stored absolute in the run's case.toml, so that a resume works from any "
                  "directory; from the working directory for a case given as data, not read from a file, and for "
                  "a --set value")


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, validate_assignment=True)


# every registered contact law, chosen by its ``model`` key (the registry is the only list of models)
ContactLaw = Annotated[Union[tuple(contact_models.get(n) for n in contact_models.names())],
                       Field(discriminator="model")]


class SizeDistribution(Strict):
    """Diameter distribution of a species; diameters are drawn once at set-up with the placement seed."""

    kind: Literal["uniform", "normal", "lognormal"] = Field(description="shape of the distribution")
    min: float | None = Field(None, gt=0.0, description="smallest diameter [m] (uniform: required)")
    max: float | None = Field(None, gt=0.0, description="largest diameter [m] (uniform: required)")
    std: float | None = Field(None, gt=0.0, description="standard deviation [m] (normal) or of ln d (lognormal)")

    @model_validator(mode="after")
    def _check(self):
        if self.kind == "uniform" and (self.min is None or self.max is None):
            raise ValueError("a uniform size_distribution needs min and max")
        if self.kind in ("normal", "lognormal") and self.std is None:
            raise ValueError(f"a {self.kind} size_distribution needs std")
        if self.min is not None and self.max is not None and self.min > self.max:
            raise ValueError(f"size_distribution min = {self.min} exceeds max = {self.max}")
        return self


class Species(Strict):
    """One kind of particle."""

    name: str = Field("particles", description="species name (pairs, wall_pairs and the output refer to it)")
    diameter: float = Field(gt=0.0, description="diameter [m] (the mean if a size_distribution is given)")
    density: float = Field(gt=0.0, description="material density [kg/m^3]")
    count: int = Field(ge=0, description="number of particles at t = 0 (0 only for a species an inlet feeds; with "
                                         "placement.method = 'file', the "
                                         "file's rows of this species)")
    size_distribution: SizeDistribution | None = Field(None, description="diameters drawn from a distribution; "
                                                                         "default all equal to diameter")
    youngs_modulus: float | None = Field(None, gt=0.0, description="E [Pa] for Hertz–Mindlin (default: the contact's)")
    poisson_ratio: float | None = Field(None, gt=-1.0, lt=0.5, description="nu [-] for Hertz–Mindlin")


class ContactOverride(Strict):
    """Contact parameters that replace those of the contact law where an override applies (None: kept)."""

    restitution: float | None = Field(None, gt=0.0, le=1.0, description="normal restitution coefficient e_n [-]")
    friction: float | None = Field(None, ge=0.0, description="Coulomb friction coefficient mu [-]")
    stiffness: float | None = Field(None, gt=0.0, description="normal stiffness k_n [N/m] (linear_spring_dashpot)")
    damping: float | None = Field(None, ge=0.0, description="normal damping eta_n [N s/m] (linear_spring_dashpot)")
    surface_energy: float | None = Field(None, ge=0.0, description="JKR surface energy gamma [J/m^2] "
                                                                  "(hertz_mindlin_jkr)")
    rolling_friction: float | None = Field(None, ge=0.0, description="rolling friction coefficient mu_r [-] "
                                                                    "(soft-sphere laws)")

    def changes(self) -> dict:
        """The parameters this override sets."""
        return {k: getattr(self, k) for k in ContactOverride.model_fields if getattr(self, k) is not None}


class PairContact(ContactOverride):
    """Override of contact parameters for one species pair (e.g. restitution between species a and b)."""

    species: tuple[str, str] = Field(description="the two species names (the same name twice: within a species)")


class WallPairContact(ContactOverride):
    """Override of particle–wall contact parameters for one species (optionally one wall)."""

    species: str = Field(description="species name")
    wall: str | None = Field(None, description="wall name (a box's planes share it); default every wall")


class Placement(Strict):
    """Initial positions: random non-overlapping fill, perturbed lattice (Hoomans 1996 §4.1) or a file."""

    method: Literal["random", "lattice", "file"] = Field(
        "random", description="random non-overlapping fill, perturbed lattice (Hoomans 1996 §4.1) or a file")
    region_lower: Vec3 | None = Field(None, description="lower corner of the fill region [m]; default: the wall box")
    region_upper: Vec3 | None = Field(None, description="upper corner of the fill region [m]; default: the wall box")
    spacing: float = Field(1.05, ge=1.0, description="lattice pitch in largest diameters [-]")
    perturbation: float = Field(0.02, ge=0.0, lt=0.5, description="lattice random shift, fraction of the diameter [-]")
    file: str | None = Field(None, description="CSV (x,y,z,diameter[,species][,vx,vy,vz]) or HDF5 with those "
                                                "datasets: finite numbers, as many rows of each species as its count; "
                                                + RELATIVE_PATHS)
    seed: int = Field(12345, description="random seed of placement and size draws")
    velocity: Vec3 = Field((0.0, 0.0, 0.0), description="initial velocity of every particle [m/s]")

    @model_validator(mode="after")
    def _check(self):
        if self.method == "file" and not self.file:
            raise ValueError("placement.method = 'file' needs placement.file")
        return self


class Motion(Strict):
    """Prescribed wall motion: constant velocity, sinusoidal oscillation x = A sin(2π f t + φ), or (wall
    shapes only) rotation at a constant rate about an axis, a table of poses, or a free rigid body moved by
    the particles' contact forces and gravity (Newton–Euler)."""

    kind: Literal["constant_velocity", "oscillation", "rotation", "table", "free"] = Field(
        description="kind of motion; 'rotation', 'table' (poses read from a CSV file) and 'free' (a rigid body "
        "moved by the contact forces of the particles and gravity; soft-sphere CPU engine) move the shapes "
        "(polyline, polygon, cylinder, mesh) only")
    velocity: Vec3 | None = Field(None, description="[m/s] for constant_velocity; free: the initial velocity of "
                                                    "the centre of mass (default at rest)")
    amplitude: Vec3 | None = Field(None, description="[m] displacement amplitude vector for oscillation")
    frequency: float | None = Field(None, gt=0.0, description="[Hz] for oscillation")
    phase: float = Field(0.0, description="[rad]")
    axis_point: Vec3 | None = Field(None, description="[m] a point of the rotation axis (rotation)")
    axis: Vec3 | None = Field(None, description="direction of the rotation axis (rotation; any length but zero; "
                                                "in 2D along z)")
    angular_velocity: float | Vec3 | None = Field(
        None, description="[rad/s] rotation: the rate, right-handed about axis (a number); free: the initial "
        "angular velocity vector in the world frame (default at rest)")
    file: str | None = Field(None, description="table: CSV file with columns t [s], dx, dy, dz [m] (displacement) "
                                               "and angle [rad] (about axis through axis_point), interpolated "
                                               "linearly in t; " + RELATIVE_PATHS)
    mass: float | None = Field(None, gt=0.0, description="free: [kg] mass of the body (required)")
    inertia: list[float] | list[list[float]] | None = Field(
        None, description="free: [kg m^2] moment of inertia about the centre of mass in the body frame (the axes "
        "of the case's geometry at rest): the 3 x 3 tensor (symmetric positive definite) or its principal moments "
        "[Ixx, Iyy, Izz] about x, y, z; default for a closed mesh: that of a uniform solid of the given mass; "
        "required for other shapes unless fixed_rotation")
    centre_of_mass: Vec3 | None = Field(
        None, description="free: [m] centre of mass in the case's coordinates at t = 0; default the shape's "
        "reference point (the centroid of its corners; a closed mesh with no inertia given: its volume centroid)")
    fixed_axes: list[Literal["x", "y", "z"]] = Field(
        default_factory=list, description="free: world axes along which the centre of mass does not move (the "
        "velocity and force components along them are held at zero); in 2D z is fixed always")
    fixed_rotation: bool = Field(False, description="free: the body does not rotate (translation only; the "
                                                    "torque is ignored)")

    @model_validator(mode="after")
    def _check(self):
        free_keys = [k for k in ("mass", "inertia", "centre_of_mass") if getattr(self, k) is not None]
        free_keys += ["fixed_axes"] if self.fixed_axes else []
        free_keys += ["fixed_rotation"] if self.fixed_rotation else []
        if self.kind != "free" and free_keys:
            raise ValueError(f"motion.{free_keys[0]} is a key of a free body (motion.kind = 'free'), not of "
                             f"motion.kind = {self.kind!r}")
        if self.kind == "free":
            self._check_free()
        elif isinstance(self.angular_velocity, tuple):
            raise ValueError(f"motion.angular_velocity = {list(self.angular_velocity)}: motion kind {self.kind!r} "
                             "takes a rate [rad/s] about axis (a number); a vector is the initial angular velocity "
                             "of a free body")
        if self.kind == "constant_velocity" and self.velocity is None:
            raise ValueError("motion kind 'constant_velocity' needs velocity")
        if self.kind == "oscillation" and (self.amplitude is None or self.frequency is None):
            raise ValueError("motion kind 'oscillation' needs amplitude and frequency")
        if self.kind == "rotation":
            if self.axis_point is None or self.axis is None or self.angular_velocity is None:
                raise ValueError("motion kind 'rotation' needs axis_point, axis and angular_velocity")
            if math.hypot(*self.axis) == 0:
                raise ValueError(f"motion.axis = {list(self.axis)}: the rotation axis must not be zero")
        if self.kind == "table":
            if not self.file:
                raise ValueError("motion kind 'table' needs file (a CSV of t, dx, dy, dz, angle)")
            if self.axis is not None and math.hypot(*self.axis) == 0:
                raise ValueError(f"motion.axis = {list(self.axis)}: the rotation axis must not be zero")
        return self

    def _check_free(self):
        """A free body: mass given, inertia a symmetric positive definite 3 x 3 tensor or three positive
        principal moments, no keys of the prescribed motions."""
        if self.mass is None:
            raise ValueError("motion kind 'free' needs mass [kg] (> 0)")
        other = [k for k in ("amplitude", "frequency", "axis_point", "axis", "file") if getattr(self, k) is not None]
        if other:
            raise ValueError(f"motion.{other[0]} is not a key of a free body (motion.kind = 'free'); it takes mass, "
                             "inertia, centre_of_mass, velocity, angular_velocity, fixed_axes and fixed_rotation")
        if self.angular_velocity is not None and not isinstance(self.angular_velocity, tuple):
            raise ValueError(f"motion.angular_velocity = {self.angular_velocity}: a free body takes the initial "
                             "angular velocity as a vector [wx, wy, wz] [rad/s]")
        if len(set(self.fixed_axes)) != len(self.fixed_axes):
            raise ValueError(f"motion.fixed_axes = {self.fixed_axes} names an axis twice")
        if self.fixed_rotation and self.angular_velocity is not None and any(self.angular_velocity):
            raise ValueError(f"motion.angular_velocity = {list(self.angular_velocity)} with fixed_rotation = true: "
                             "a body that does not rotate starts at rest (angular_velocity = [0, 0, 0])")
        if self.inertia is not None:
            inertia_tensor(self.inertia)


def inertia_tensor(inertia) -> list[list[float]]:
    """The 3 x 3 tensor of ``motion.inertia`` (principal moments on the diagonal); ValueError naming the key
    unless it is symmetric positive definite."""
    if all(isinstance(v, (int, float)) for v in inertia):
        if len(inertia) != 3:
            raise ValueError(f"motion.inertia = {inertia}: give three principal moments [Ixx, Iyy, Izz] or a 3 x 3 "
                             "tensor [kg m^2]")
        tensor = [[float(inertia[0]), 0.0, 0.0], [0.0, float(inertia[1]), 0.0], [0.0, 0.0, float(inertia[2])]]
    else:
        tensor = [list(map(float, row)) for row in inertia]
        if len(tensor) != 3 or any(len(row) != 3 for row in tensor):
            raise ValueError(f"motion.inertia = {inertia}: a tensor has 3 rows of 3 numbers [kg m^2]")
    scale = max(abs(v) for row in tensor for v in row)
    for i in range(3):
        for j in range(i):
            if abs(tensor[i][j] - tensor[j][i]) > 1e-12 * scale:
                raise ValueError(f"motion.inertia = {inertia}: the tensor is not symmetric (row {i}, column {j} is "
                                 f"{tensor[i][j]}, row {j}, column {i} is {tensor[j][i]})")
    # positive definite: the leading principal minors are positive (Sylvester's criterion)
    a = tensor
    minors = (a[0][0], a[0][0] * a[1][1] - a[0][1] * a[1][0],
              a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
              + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]))
    if not (scale > 0.0 and minors[0] > 0.0 and minors[1] > 1e-12 * scale**2 and minors[2] > 1e-12 * scale**3):
        raise ValueError(f"motion.inertia = {inertia}: an inertia tensor must be positive definite (every "
                         "principal moment > 0)")
    return tensor


class WallContact(ContactOverride):
    """Per-wall override of the particle–wall contact parameters."""


SHAPE_KINDS = ("polyline", "polygon", "cylinder", "mesh")


class Wall(Strict):
    """A plane (point + inward normal), an axis-aligned box of planes facing inwards, or a shape: a 2D
    polyline of segments, a flat polygon, a cylinder's lateral surface or an STL triangle mesh."""

    name: str = Field("wall", description="wall name (wall_pairs and the output refer to it)")
    kind: Literal["plane", "box", "polyline", "polygon", "cylinder", "mesh"] = Field(
        description="an infinite plane, an axis-aligned box of six planes, or a shape (soft spheres only): "
        "polyline (2D segments), polygon (3D flat convex polygon), cylinder (lateral surface of finite length), "
        "mesh (triangles of an STL file)")
    point: Vec3 | None = Field(None, description="a point of the plane [m]; cylinder: the centre of one end of "
                                                 "its axis")
    normal: Vec3 | None = Field(None, description="normal pointing into the particle region")
    lower: Vec3 | None = Field(None, description="box lower corner [m]")
    upper: Vec3 | None = Field(None, description="box upper corner [m]")
    open_top: bool = Field(False, description="box without its upper wall along gravity")
    periodic: list[Literal["x", "y", "z"]] = Field(
        default_factory=list, description="box only: the axes whose two sides are joined instead of being walls; a "
        "particle leaving through one side re-enters through the other and particles interact across them by nearest "
        "image (soft-sphere engine on the CPU; hard-sphere engine without gas). Not z in 2D; with [gas], the gas sides on that axis must be "
        "periodic too")
    points: list[list[float]] | None = Field(
        None, description="[m] corners: polyline, its points [x, y] in the x-y plane, joined in order (2D); "
        "polygon, its corners [x, y, z] in order round a convex flat polygon (3D)")
    closed: bool = Field(False, description="polyline: join the last point back to the first")
    axis: Vec3 | None = Field(None, description="cylinder: direction of the axis from point (any length but zero)")
    radius: float | None = Field(None, gt=0.0, description="cylinder radius [m]")
    length: float | None = Field(None, gt=0.0, description="cylinder length along the axis from point [m]")
    inside: bool = Field(True, description="cylinder: particles inside it (a drum, a pipe), else outside (a roll)")
    file: str | None = Field(None, description="mesh: STL file (ASCII or binary); " + RELATIVE_PATHS)
    scale: float = Field(1.0, gt=0.0, description="mesh: factor on the file's coordinates (e.g. 0.001 for mm)")
    offset: Vec3 = Field((0.0, 0.0, 0.0), description="mesh: [m] added to the scaled coordinates")
    motion: Motion | None = Field(None, description="prescribed motion; default at rest")
    contact: WallContact | None = Field(None, description="this wall's overrides of the particle–wall contact")
    youngs_modulus: float | None = Field(None, gt=0.0, description="E [Pa] of the wall for Hertz–Mindlin")
    poisson_ratio: float | None = Field(None, gt=-1.0, lt=0.5, description="nu [-] of the wall for Hertz–Mindlin")

    @model_validator(mode="after")
    def _check(self):
        if self.kind == "plane":
            if self.point is None or self.normal is None:
                raise ValueError(f"plane wall {self.name!r} needs point and normal")
            if math.hypot(*self.normal) == 0:
                raise ValueError(f"plane wall {self.name!r} has a zero normal")
            if self.periodic:
                raise ValueError(f"plane wall {self.name!r}: periodic = {self.periodic} needs kind = 'box' (a box's "
                                 "two sides on an axis are joined; a plane has no opposite side)")
        elif self.kind == "box":
            if self.lower is None or self.upper is None:
                raise ValueError(f"box wall {self.name!r} needs lower and upper")
            if len(set(self.periodic)) != len(self.periodic):
                raise ValueError(f"box wall {self.name!r}: periodic = {self.periodic} names an axis twice")
            if self.periodic and self.motion is not None:
                raise ValueError(f"box wall {self.name!r}: periodic = {self.periodic} needs a box at rest (no motion)")
            for a, b, ax in zip(self.lower, self.upper, "xyz"):
                if not b > a:
                    raise ValueError(f"box wall {self.name!r}: upper {ax} = {b} must exceed lower {ax} = {a}")
        elif self.kind in ("polyline", "polygon"):
            want = 2 if self.kind == "polyline" else 3
            least = 2 if self.kind == "polyline" else 3
            if self.points is None or len(self.points) < least:
                raise ValueError(f"{self.kind} wall {self.name!r} needs points: at least {least} corners of "
                                 f"{want} coordinates each")
            for j, p in enumerate(self.points):
                if len(p) != want:
                    raise ValueError(f"{self.kind} wall {self.name!r}: points.{j} = {p} has {len(p)} coordinates; "
                                     f"a {self.kind} takes {want} ({'x, y' if want == 2 else 'x, y, z'})")
        elif self.kind == "cylinder":
            if self.point is None or self.axis is None or self.radius is None or self.length is None:
                raise ValueError(f"cylinder wall {self.name!r} needs point, axis, radius and length")
            if math.hypot(*self.axis) == 0:
                raise ValueError(f"cylinder wall {self.name!r}: axis = {list(self.axis)} must not be zero")
        elif self.kind == "mesh":
            if not self.file:
                raise ValueError(f"mesh wall {self.name!r} needs file (an STL file)")
        if self.periodic and self.kind not in ("plane", "box"):
            raise ValueError(f"{self.kind} wall {self.name!r}: periodic = {self.periodic} needs kind = 'box'")
        if (self.motion is not None and self.motion.kind in ("rotation", "table", "free")
                and self.kind in ("plane", "box")):
            raise ValueError(f"{self.kind} wall {self.name!r}: motion.kind = {self.motion.kind!r} moves shapes only "
                             f"(kind one of {list(SHAPE_KINDS)}); a plane or box moves by constant_velocity or "
                             "oscillation")
        return self


class Inlet(Strict):
    """An insertion region: particles of one species added at a rate, at random places in a box without overlap
    (``particles/population.py``); soft spheres."""

    name: str = Field("inlet", description="inlet name (probes and summary columns refer to it)")
    species: str | None = Field(None, description="the species inserted (its diameter or size distribution and "
                                                  "density); default the first species")
    lower: Vec3 = Field(description="lower corner of the insertion box [m]")
    upper: Vec3 = Field(description="upper corner of the insertion box [m]")
    rate: float | None = Field(None, gt=0.0, description="particles per second [1/s] (give rate or mass_rate)")
    mass_rate: float | None = Field(None, gt=0.0, description="mass per second [kg/s] (give rate or mass_rate); "
                                    "the particles' sizes are drawn first, then as many as carry the mass")
    start: float = Field(0.0, ge=0.0, description="time of the first insertion [s]")
    stop: float | None = Field(None, gt=0.0, description="no insertion after this time [s]; default the run's end")
    total: int | None = Field(None, ge=1, description="insert at most this many particles in all; default no limit")
    interval: float = Field(0.01, gt=0.0, description="time between insertions [s]: each inserts what the rate "
                            "gives over the interval (plus what a crowded region could not take before)")
    velocity: Vec3 = Field((0.0, 0.0, 0.0), description="initial velocity of the inserted particles [m/s]")
    seed: int = Field(1, description="random seed of the sizes and places")

    @model_validator(mode="after")
    def _check(self):
        if (self.rate is None) == (self.mass_rate is None):
            raise ValueError(f"inlet {self.name!r}: give exactly one of rate [1/s] and mass_rate [kg/s]")
        for a, b, ax in zip(self.lower, self.upper, "xyz"):
            if b < a:
                raise ValueError(f"inlet {self.name!r}: upper {ax} = {b} is below lower {ax} = {a}")
        if self.stop is not None and self.stop <= self.start:
            raise ValueError(f"inlet {self.name!r}: stop = {self.stop} must be later than start = {self.start}")
        return self


class Outlet(Strict):
    """A removal region: particles whose centre lies in a box, or beyond a plane, leave the run."""

    name: str = Field("outlet", description="outlet name (probes and summary columns refer to it)")
    kind: Literal["box", "plane"] = Field(description="box: remove the centres inside lower–upper; plane: remove "
                                          "the centres behind the plane (on the side its normal points away from)")
    lower: Vec3 | None = Field(None, description="box: lower corner [m]")
    upper: Vec3 | None = Field(None, description="box: upper corner [m]")
    point: Vec3 | None = Field(None, description="plane: a point of the plane [m]")
    normal: Vec3 | None = Field(None, description="plane: normal pointing to the side where particles stay")

    @model_validator(mode="after")
    def _check(self):
        if self.kind == "box":
            if self.lower is None or self.upper is None:
                raise ValueError(f"outlet {self.name!r}: kind = 'box' needs lower and upper")
            for a, b, ax in zip(self.lower, self.upper, "xyz"):
                if not b > a:
                    raise ValueError(f"outlet {self.name!r}: upper {ax} = {b} must exceed lower {ax} = {a}")
        else:
            if self.point is None or self.normal is None:
                raise ValueError(f"outlet {self.name!r}: kind = 'plane' needs point and normal")
            if math.hypot(*self.normal) == 0:
                raise ValueError(f"outlet {self.name!r}: normal = {list(self.normal)} is zero")
        return self


class Particles(Strict):
    """The particles: species, contact laws and overrides, and how they are placed at t = 0."""

    dimensions: Literal[2, 3] = Field(3, description="2: centres move in the x-y plane, spin about z only")
    species: list[Species] = Field(min_length=1, description="the kinds of particle")
    contact: ContactLaw = Field(description="particle–particle contact law, chosen by its model key")
    pairs: list[PairContact] = Field(default_factory=list, description="per species-pair overrides")
    wall_contact: ContactLaw | None = Field(None, description="particle–wall law, the model of contact (under "
                                            "hertz_mindlin_jkr also hertz_mindlin: walls without adhesion, as "
                                            "wall shapes need); default: the particle law")
    wall_pairs: list[WallPairContact] = Field(default_factory=list, description="per species(–wall) overrides")
    placement: Placement = Field(default_factory=Placement, description="initial positions and velocities")
    force_step: Literal["split", "hoomans"] = Field(
        "split", description="how the hard-sphere engine applies gravity and the gas force over a step DT: "
        "'split', half the impulse (g + F/m) DT before the step's collision sequence (Hoomans 1996 eqs 30-32, "
        "Fig. 3) and half after it, which makes free fall exact; 'hoomans', all of it before (eqs 33-34), an "
        "energy error first order in DT (§5.1). Soft spheres integrate by velocity Verlet, a split step "
        "already, and take 'split' only")

    @field_validator("species")
    @classmethod
    def _unique(cls, v):
        names = [s.name for s in v]
        if len(set(names)) != len(names):
            raise ValueError(f"species names must be unique, got {names}")
        return v

    @model_validator(mode="after")
    def _check_pairs(self):
        names = {s.name for s in self.species}
        for pc in self.pairs:
            for s in pc.species:
                if s not in names:
                    raise ValueError(f"pairs: species {s!r} is not one of {sorted(names)}")
        for wp in self.wall_pairs:
            if wp.species not in names:
                raise ValueError(f"wall_pairs: species {wp.species!r} is not one of {sorted(names)}")
        if self.wall_contact is not None and type(self.wall_contact) is not type(self.contact):
            # an adhesive law may meet the walls with the non-adhesive law it extends (JKR on Hertz–Mindlin):
            # wall shapes take no adhesive law
            base = type(self.wall_contact)
            if not (self.contact.adhesive and not base.adhesive and isinstance(self.contact, base)):
                raise ValueError(f"wall_contact.model = {self.wall_contact.model!r} and contact.model = "
                                 f"{self.contact.model!r}: wall_contact must use the same model as contact (an "
                                 "adhesive law such as hertz_mindlin_jkr may also take the law it extends, "
                                 "hertz_mindlin, for non-adhesive walls)")
        if self.force_step == "hoomans" and not getattr(type(self.contact), "instantaneous", False):
            raise ValueError(f"force_step = 'hoomans' is the hard-sphere engine's (model = 'hard_sphere'); "
                             f"contact model {self.contact.model!r} integrates by velocity Verlet, a split step: "
                             f"use force_step = 'split' (the default)")
        return self


class Time(Strict):
    """The clock: end time and the DEM time step."""

    end: float = Field(gt=0.0, description="simulated time to reach [s]")
    dt: float | None = Field(None, gt=0.0, description="DEM time step [s]; default dt_fraction × t_c")
    dt_fraction: float = Field(0.02, gt=0.0, le=0.1, description="dt / t_c when dt is not given (Sun 2007: 1/50)")
    impact_velocity: float = Field(1.0, gt=0.0, description="impact speed for the Hertz contact time [m/s]")


class Neighbours(Strict):
    """Neighbour lists of the particle engines."""

    skin: float | None = Field(None, gt=0.0, description="Verlet skin [m]; default 0.25 × largest diameter")
    reorder_interval: int | None = Field(
        None, ge=0, description="soft spheres: renumber the particles in cell order at set-up and at the first list "
        "rebuild this many steps after the last (faster force loops; state.ids and the output keep each particle's "
        "number); 0 never; default 1000 from 1000 particles on, else 0")


class Output(Strict):
    """How often the run writes snapshots, probes, checkpoints and progress lines."""

    snapshot_interval: float | None = Field(None, gt=0.0, description="[s] simulated; default end/100")
    probe_interval: float | None = Field(None, gt=0.0, description="[s] simulated; default end/1000")
    checkpoint_interval: float | None = Field(None, gt=0.0, description="[s] simulated; default end/10")
    progress_interval: float = Field(2.0, gt=0.0, description="[s] wall time between progress lines")


class Case(Strict):
    """A complete run description in SI units."""

    name: str = Field("case", description="case name (summary.json, reports)")
    description: str = Field("", description="one line on what the case is (fluidem cases lists it)")
    gravity: Vec3 | None = Field(None, description="[m/s^2]; default −9.81 along y in 2D, along z in 3D")
    particles: Particles
    walls: list[Wall] = Field(default_factory=list, description="walls of the particles")
    inlets: list[Inlet] = Field(default_factory=list, description="insertion regions adding particles during the "
                                "run (soft spheres)")
    outlets: list[Outlet] = Field(default_factory=list, description="removal regions taking particles out of the run")
    time: Time = Field(description="end time and time step")
    neighbours: Neighbours = Field(default_factory=Neighbours, description="neighbour-list settings")
    output: Output = Field(default_factory=Output, description="what is written and how often")
    threads: int | None = Field(None, ge=1, description="compute threads; default one per 1200 particles, at most all cores")
    device: Literal["cpu", "gpu", "auto"] = Field(
        "cpu", description="where the soft-sphere particle step runs: cpu (Numba threads), gpu (an NVIDIA GPU through "
        "numba-cuda; a case the GPU engine does not support, or no GPU found, is an error), auto (the GPU where one "
        "is found and the case is supported, else the CPU)")
    gas: GasSection | None = Field(None, description="gas phase; omit for a DEM-only run")
    coupling: CouplingSection | None = Field(None, description="gas–particle exchange; default with [gas]")
    checks: ChecksSection = Field(default_factory=ChecksSection, description="health checks while the run steps")

    @model_validator(mode="after")
    def _defaults(self):
        gravity = "gravity"
        if self.gravity is None:
            g = (0.0, -9.81, 0.0) if self.particles.dimensions == 2 else (0.0, 0.0, -9.81)
            object.__setattr__(self, "gravity", g)
            gravity = f"gravity (not given: the default of particles.dimensions = {self.particles.dimensions})"
        if self.particles.dimensions == 2 and self.gravity[2] != 0.0:
            raise ValueError(f"gravity = {list(self.gravity)}: a 2D case needs gravity in the x-y plane (z = 0)")
        names = [w.name for w in self.walls]
        for j, name in enumerate(names):
            if name in names[:j]:
                raise ValueError(f"walls.{j}.name = {name!r}: wall names must be unique "
                                 f"(walls.{names.index(name)}.name is {name!r} too)")
        self._check_periodic()
        for j, w in enumerate(self.walls):
            if (w.kind in SHAPE_KINDS and w.motion is not None and w.motion.kind == "free"
                    and self.particles.contact.instantaneous):
                raise ValueError(f"walls.{j}.motion.kind = 'free': free bodies move with the soft-sphere engine only; "
                                 f"particles.contact.model = {self.particles.contact.model!r} is the event-driven "
                                 "hard-sphere engine")
            if w.kind in SHAPE_KINDS and self.particles.contact.instantaneous:
                raise ValueError(f"walls.{j}.kind = {w.kind!r}: wall shapes take soft-sphere contact laws; "
                                 f"particles.contact.model = {self.particles.contact.model!r} is event-driven, "
                                 "with planes and boxes only")
        for wp in self.particles.wall_pairs:
            if wp.wall is not None and wp.wall not in names:
                raise ValueError(f"particles.wall_pairs: wall {wp.wall!r} is not one of {names}")
        self._check_population()
        if self.gas is None and self.coupling is not None:
            raise ValueError("coupling: [coupling] needs a [gas] section; add one, or remove [coupling] "
                             "for a run without gas")
        if self.gas is not None and self.gas.grid.dimensions == 3:
            if self.coupling is None:
                object.__setattr__(self, "coupling", CouplingSection())
            self._check_gas3d(gravity)
        elif self.gas is not None:
            if self.gravity[2] != 0.0:
                raise ValueError(f"{gravity} = {list(self.gravity)}: the 2D gas grid (x-y) needs gravity in the x-y "
                                 "plane (z = 0); set gravity = [0.0, -9.81, 0.0]")
            if self.coupling is None:
                object.__setattr__(self, "coupling", CouplingSection())
            self._check_gas_covers_particles()
            check_method(self.coupling.voidage.method, 2)
        return self

    def _check_population(self) -> None:
        """Inlets name existing species; a species with count 0 needs an inlet; names are unique; in 2D an
        inlet's box holds the plane of the particles' centres."""
        species = [s.name for s in self.particles.species]
        fed = set()
        for kind, items in (("inlets", self.inlets), ("outlets", self.outlets)):
            names = [x.name for x in items]
            for j, name in enumerate(names):
                if name in names[:j]:
                    raise ValueError(f"{kind}.{j}.name = {name!r}: {kind} names must be unique")
        for j, inlet in enumerate(self.inlets):
            name = inlet.species if inlet.species is not None else species[0]
            if name not in species:
                raise ValueError(f"inlets.{j}.species = {inlet.species!r} is not one of {species}")
            fed.add(name)
        for j, sp in enumerate(self.particles.species):
            if sp.count == 0 and sp.name not in fed:
                raise ValueError(f"particles.species.{j}.count = 0: species {sp.name!r} has no particles and no inlet "
                                 "feeds it; give count >= 1 or an [[inlets]] entry with species = "
                                 f"{sp.name!r}")
        if self.inlets and self.particles.contact.instantaneous:
            raise ValueError(f"inlets: the hard-sphere engine (contact model {self.particles.contact.model!r}) keeps "
                             "a fixed set of particles; inlets need a soft-sphere contact law")
        if self.outlets and self.particles.contact.instantaneous:
            raise ValueError(f"outlets: the hard-sphere engine (contact model {self.particles.contact.model!r}) keeps "
                             "a fixed set of particles; outlets need a soft-sphere contact law")

    def _check_gas3d(self, gravity: str) -> None:
        """ValueError where a case with a 3D gas grid cannot be coupled: 2D particles, gravity off the grid
        axes, a voidage method the 3D coupling does not offer, particles outside the grid."""
        cells = list(self.gas.grid.cells)
        if self.particles.dimensions != 3:
            raise ValueError(f"gas.grid.cells = {cells} (a 3D gas grid) and particles.dimensions = 2: a 3D gas grid "
                             "takes 3D particles (particles.dimensions = 3); 2D particles take a 2D grid "
                             "(cells = [nx, ny] and a depth)")
        if sum(1 for g in self.gravity if g != 0.0) > 1:
            raise ValueError(f"{gravity} = {list(self.gravity)}: with a 3D gas grid gravity must lie along one grid "
                             "axis (one non-zero component, e.g. [0.0, 0.0, -9.81])")
        check_method(self.coupling.voidage.method, 3)
        if self.coupling.voidage.to_3d:
            raise ValueError("coupling.voidage.to_3d = true: Hoomans 1996 eq. 49 converts a 2D area voidage; a 3D gas "
                             "grid maps sphere volumes (set to_3d = false)")
        size = self.gas.grid.size
        tol = 1e-6 * max(size)
        fix = "make the gas grid cover the particles (or shrink the box)"

        def outside(lo, hi) -> str | None:
            for d, ax in enumerate("xyz"):
                if lo[d] < -tol or hi[d] > size[d] + tol:
                    return f"{ax} from {lo[d]:g} to {hi[d]:g} m is not within the gas grid's 0 to {size[d]:g} m"
            return None

        for i, w in enumerate(self.walls):
            if w.kind == "box":
                what = outside(w.lower, w.upper)
                if what:
                    raise ValueError(f"walls.{i} ({w.name!r}) lower = {list(w.lower)}, upper = {list(w.upper)} and "
                                     f"gas.grid.size = {list(size)}: {what} (the grid's corner is at the origin); "
                                     f"particles would leave the gas domain: {fix}")
        pl = self.particles.placement
        if pl.region_lower is not None and pl.region_upper is not None:
            what = outside(pl.region_lower, pl.region_upper)
            if what:
                raise ValueError(f"particles.placement.region_lower = {list(pl.region_lower)}, "
                                 f"particles.placement.region_upper = {list(pl.region_upper)} and gas.grid.size = "
                                 f"{list(size)}: {what}; particles would start outside the gas domain: {fix}")

    def _check_periodic(self) -> None:
        """ValueError where a box's ``periodic`` axes do not fit the case: z in 2D, an open top on a periodic
        axis, more than one box wall with a periodic one, or (with [gas]) gas sides on a periodic axis that
        are not periodic, or a box that does not span the gas grid along it."""
        boxes = [(i, w) for i, w in enumerate(self.walls) if w.kind == "box"]
        per = [(i, w) for i, w in boxes if w.periodic]
        if not per:
            return
        i, w = per[0]
        key = f"walls.{i}.periodic"
        if len(boxes) > 1:
            others = ", ".join(f"walls.{k} ({b.name!r})" for k, b in boxes if k != i)
            raise ValueError(f"{key} = {w.periodic}: a box with periodic sides must be the case's only box wall "
                             f"(the particles' domain), but {others} is a box too")
        if self.particles.dimensions == 2 and "z" in w.periodic:
            raise ValueError(f"{key} = {w.periodic}: particles.dimensions = 2 has no z motion, so z cannot be "
                             "periodic; allowed: x, y")
        if w.open_top:
            up = "xyz"[max(range(3), key=lambda d: abs(self.gravity[d]))]
            if up in w.periodic:
                raise ValueError(f"{key} = {w.periodic} and walls.{i}.open_top = true: the open side is on the "
                                 f"periodic axis {up}; drop one of the two")
        if self.gas is not None:
            sides = {"x": ("left", "right"), "y": ("bottom", "top"), "z": ("front", "back")}
            size = self.gas.grid.size
            for ax in w.periodic:
                d = "xyz".index(ax)
                if d >= self.gas.grid.dimensions:  # z over a 2D grid: the gas is uniform across its depth
                    continue
                for side in sides[ax]:
                    bc = self.gas.boundaries.get(side)
                    kind = getattr(bc, "kind", None)
                    if kind != "periodic":
                        raise ValueError(f"{key} = {w.periodic} and gas.boundaries.{side} = {kind!r}: particles "
                                         f"periodic along {ax} need the gas periodic there too; set "
                                         f"gas.boundaries.{side} (and its opposite side) to 'periodic', or drop "
                                         f"{ax!r} from {key}")
                tol = 1e-6 * size[d]
                if abs(w.lower[d]) > tol or abs(w.upper[d] - size[d]) > tol:
                    raise ValueError(f"{key} = {w.periodic}: walls.{i} spans {ax} from {w.lower[d]:g} to "
                                     f"{w.upper[d]:g} m, but gas.grid.size = {list(size)} spans 0 to {size[d]:g} m; "
                                     "along a periodic axis the two must be the same")

    def _check_gas_covers_particles(self) -> None:
        """ValueError where the particles' box or placement region reaches outside the gas grid (x-y, lower-left
        corner at the origin), or a box's depth (z extent) is not the grid's depth: the gas cells of a 2D grid
        hold the particles of that depth, so the two must agree."""
        size, depth = self.gas.grid.size, self.gas.grid.depth
        tol = 1e-6 * max(size)
        fix = "make the gas grid cover the particles (or shrink the box)"

        def outside(lo, hi) -> str | None:
            for d, ax in enumerate("xy"):
                if lo[d] < -tol or hi[d] > size[d] + tol:
                    return f"{ax} from {lo[d]:g} to {hi[d]:g} m is not within the gas grid's 0 to {size[d]:g} m"
            return None

        for i, w in enumerate(self.walls):
            if w.kind != "box":
                continue
            what = outside(w.lower, w.upper)
            if what:
                raise ValueError(f"walls.{i} ({w.name!r}) lower = {list(w.lower)}, upper = {list(w.upper)} and "
                                 f"gas.grid.size = {list(size)}: {what} (the grid's lower-left corner is at the "
                                 f"origin); particles would leave the gas domain: {fix}")
            extent = w.upper[2] - w.lower[2]
            if abs(extent - depth) > 1e-6 * depth:
                raise ValueError(f"gas.grid.depth = {depth:g} and walls.{i} ({w.name!r}) depth upper z - lower z = "
                                 f"{w.upper[2]:g} - {w.lower[2]:g} = {extent:g} m differ: the gas cells hold the "
                                 "particles of the box's depth, so the two must be equal")
        pl = self.particles.placement
        if pl.region_lower is not None and pl.region_upper is not None:
            what = outside(pl.region_lower, pl.region_upper)
            if what:
                raise ValueError(f"particles.placement.region_lower = {list(pl.region_lower)}, particles.placement.region_upper = "
                                 f"{list(pl.region_upper)} and gas.grid.size = {list(size)}: {what}; particles "
                                 f"would start outside the gas domain: {fix}")

    # ---------------------------------------------------------------- I/O
    def to_toml(self) -> str:
        return tomli_w.dumps(self.model_dump(mode="json", exclude_none=True))

    def with_overrides(self, overrides: dict[str, Any]) -> "Case":
        data = self.model_dump(mode="json", exclude_none=True)
        apply_overrides(data, overrides)
        return validate_case(data)


# ------------------------------------------------------------------ loading
def builtin_cases() -> dict[str, Path]:
    folder = resources.files("fluidem") / "cases"
    return {Path(p.name).stem: Path(str(p)) for p in folder.iterdir() if p.name.endswith(".toml")}


def parse_value(text: str) -> Any:
    """A --set value as TOML (numbers, booleans, arrays, quoted strings); bare words are strings."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def apply_overrides(data: dict, overrides: dict[str, Any]) -> None:
    """Set dotted keys (``a.b.0.c``) in raw case data; list items by index."""
    for key, value in overrides.items():
        parts = key.split(".")
        node: Any = data
        for depth, part in enumerate(parts):
            where = ".".join(parts[:depth])
            last = depth == len(parts) - 1
            if isinstance(node, list):
                if not part.isdigit() or int(part) >= len(node):
                    raise CaseError(f"--set {key}: {where!r} is a list and needs a list index below {len(node)}")
                if last:
                    node[int(part)] = value
                else:
                    node = node[int(part)]
            elif isinstance(node, dict):
                if last:
                    node[part] = value
                else:
                    node = node.setdefault(part, {})
            else:
                raise CaseError(f"--set {key}: {where!r} is a value, not a section (it is {node!r})")


def _models_of(ann) -> list[type[BaseModel]]:
    """The pydantic models an annotation admits (a model, a union of models, a list or dict of them, …)."""
    import typing

    if isinstance(ann, type) and issubclass(ann, BaseModel):
        return [ann]
    out = []
    for arg in typing.get_args(ann):
        out += [m for m in _models_of(arg) if m not in out]
    return out


def _tag_field(models) -> str | None:
    """The discriminator key (``model``, ``kind``) of a union of several models: the Literal field they share."""
    import typing

    if len(models) < 2:
        return None
    for name in models[0].model_fields:
        if all(name in m.model_fields and typing.get_origin(m.model_fields[name].annotation) is Literal
               for m in models):
            return name
    return None


def _resolve(loc: tuple) -> tuple[list[str], type[BaseModel] | None]:
    """The printable path of an error location (without pydantic's union tags) and the model of the section it
    ends in (None where it cannot tell)."""
    import typing

    shown: list[str] = []
    models: list = [Case]
    keyed = False  # the next part is a key of a dict of models (a gas side)
    for part in loc:
        if isinstance(part, int) or keyed:
            shown.append(str(part))
            keyed = False
            continue
        if len(models) > 1:  # a discriminated union: pydantic puts the chosen tag here
            tag = _tag_field(models)
            chosen = [m for m in models if tag and m.model_fields[tag].default == part]
            if chosen:
                models = chosen
                continue
        fields = models[0].model_fields if len(models) == 1 else {}
        shown.append(part)
        ann = fields[part].annotation if part in fields else None
        models = _models_of(ann) if ann is not None else []
        keyed = any(typing.get_origin(a) is dict for a in (ann, *typing.get_args(ann)))
    return shown, (models[0] if len(models) == 1 else None)


def format_validation_error(err: ValidationError) -> str:
    lines = []
    for e in err.errors():
        loc = tuple(x for x in e["loc"] if not (isinstance(x, str) and x.startswith("function-")))
        parts, _ = _resolve(loc)
        shown = ".".join(parts)
        ctx = e.get("ctx") or {}
        inner = ctx.get("error")
        if isinstance(inner, CaseError) and inner.problems:  # a building block that checks itself (gas sides)
            for sub, value, msg in inner.problems:
                key = ".".join([*parts, *map(str, sub)])
                lines.append(f"{key} = {value!r}: {msg}" if sub else f"{key}: {msg}")
            continue
        if e["type"] == "extra_forbidden":
            _, model = _resolve(loc[:-1])
            allowed = sorted(model.model_fields) if model is not None else None
            extra = f"; allowed keys: {', '.join(allowed)}" if allowed else ""
            lines.append(f"unknown key {shown!r} (value {e['input']!r}){extra}")
        elif e["type"] == "missing":
            lines.append(f"missing key {shown!r}")
        elif e["type"] == "union_tag_invalid":
            key = str(ctx.get("discriminator", "model")).strip("'")
            value = e["input"].get(key) if isinstance(e["input"], dict) else e["input"]
            allowed = [t.strip() for t in str(ctx.get("expected_tags", "")).replace("'", "").split(",")]
            hint = difflib.get_close_matches(str(value), allowed, n=1)
            lines.append(f"{shown}: {key} = {value!r} is not a known model; allowed: {', '.join(allowed)}"
                         + (f"; did you mean {hint[0]!r}?" if hint else ""))
        elif e["type"] == "union_tag_not_found":
            key = str(ctx.get("discriminator", "model")).strip("'")
            _, model = _resolve(loc)
            lines.append(f"{shown}: needs a {key!r} key" + _choices(loc, key))
        elif e["type"] == "finite_number":
            lines.append(f"{shown} = {e['input']!r}: must be a finite number (NaN and ±inf are not allowed)")
        else:
            msg = e["msg"].removeprefix("Value error, ")
            value = e.get("input")
            if isinstance(value, dict):
                lines.append(f"{shown or 'case'}: {msg}")
            else:
                lines.append(f"{shown} = {value!r}: {msg}")
    return "invalid case:\n  " + "\n  ".join(lines)


def _choices(loc: tuple, key: str) -> str:
    """'; allowed: a, b' — the tags of the union at ``loc`` (or nothing)."""
    models: list = [Case]
    for part in loc:
        if isinstance(part, int):
            continue
        fields = models[0].model_fields if len(models) == 1 else {}
        models = _models_of(fields[part].annotation) if part in fields else []
    tags = sorted(str(m.model_fields[key].default) for m in models if key in m.model_fields)
    return f"; allowed: {', '.join(tags)}" if tags else ""


def validate_case(data: dict) -> Case:
    try:
        return Case.model_validate(data)
    except ValidationError as err:
        raise CaseError(format_validation_error(err)) from None


def read_case_data(name_or_path: str | Path) -> dict:
    builtin = builtin_cases()
    path = Path(name_or_path)
    if str(name_or_path) in builtin and not path.exists():
        path = builtin[str(name_or_path)]
    if not path.exists():
        raise CaseError(
            f"case {str(name_or_path)!r} is neither a TOML file nor a built-in case; built-in: {', '.join(sorted(builtin))}"
        )
    if path.is_dir():
        raise CaseError(f"case {str(name_or_path)!r} is a folder; give a TOML case file or a built-in case name")
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as err:
        line = path.read_bytes()[:err.start].count(b"\n") + 1
        raise CaseError(f"case file {path}: not a text (UTF-8) file: byte {err.object[err.start]:#04x} on line {line} "
                        "cannot be decoded; a case file is TOML text") from None
    except OSError as err:
        raise CaseError(f"case file {path}: cannot be read: {err.strerror or err}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise CaseError(f"case file {path}: not valid TOML: {err}") from None
    resolve_case_paths(data, path.parent)
    return data


def resolve_case_paths(data: dict, folder: str | Path) -> None:
    """Make the relative file paths of raw case data (``particles.placement.file``, ``walls[].file``,
    ``walls[].motion.file``) absolute, taken from ``folder`` (the case file's directory), so that the case finds
    its files from any working directory and its ``case.toml`` in a run directory resumes from anywhere. Entries
    that are not of the expected types are left for validation to name."""
    folder = Path(folder)

    def fix(node) -> None:
        if isinstance(node, dict) and isinstance(node.get("file"), str) and node["file"]:
            f = Path(node["file"]).expanduser()
            node["file"] = str(f if f.is_absolute() else (folder / f).resolve())

    particles = data.get("particles")
    if isinstance(particles, dict):
        fix(particles.get("placement"))
    walls = data.get("walls")
    if isinstance(walls, list):
        for wall in walls:
            fix(wall)
            if isinstance(wall, dict):
                fix(wall.get("motion"))


def load_case(name_or_path: str | Path, overrides: dict[str, Any] | None = None) -> Case:
    """A validated Case from a built-in name or a TOML path, with dotted-key overrides applied."""
    data = read_case_data(name_or_path)
    if overrides:
        apply_overrides(data, overrides)
    return validate_case(data)
