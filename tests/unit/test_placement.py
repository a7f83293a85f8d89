"""Initial placement: random fill and lattice give non-overlapping particles inside the box; files
(CSV, HDF5) are read as given; overlaps, wall crossings and over-full regions are CaseErrors that
name the particles."""
from __future__ import annotations

import copy
import re

import h5py
import numpy as np
import pytest

from fluidem.case import validate_case
from fluidem.errors import CaseError
from fluidem.particles.placement import place
from fluidem.particles.walls import build_walls

D = 0.004  # m, particle diameter of the small test cases


def make_case(dimensions=2, species=None, placement=None, box=None, **top):
    """A small validated case: one box wall, linear springs, the given species and placement."""
    if box is None:
        box = [0.08, 0.08, D] if dimensions == 2 else [0.04, 0.04, 0.04]
    data = {
        "name": "placement-test",
        "particles": {
            "dimensions": dimensions,
            "species": species or [{"name": "a", "diameter": D, "density": 2500.0, "count": 100}],
            "contact": {"model": "linear_spring_dashpot", "stiffness": 800.0},
            "placement": placement or {"method": "random"},
        },
        "walls": [{"name": "box", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": list(box)}],
        "time": {"end": 0.01},
    }
    data.update(top)
    return validate_case(copy.deepcopy(data))


def placed(case):
    return place(case, build_walls(case))


def assert_no_overlap(pos, diam, rel_tol=1e-12):
    r = 0.5 * diam
    dist = np.linalg.norm(pos[:, None, :] - pos[None, :, :], axis=-1)
    contact = r[:, None] + r[None, :]
    np.fill_diagonal(dist, np.inf)
    gap = dist - contact
    i, j = np.unravel_index(np.argmin(gap / contact), gap.shape)
    assert gap[i, j] >= -rel_tol * contact[i, j], f"particles {i} and {j} overlap by {-gap[i, j]:.3g} m"


def assert_inside_box(pos, diam, lo, hi, dimensions):
    r = 0.5 * diam
    for d in range(dimensions):
        assert np.all(pos[:, d] - r >= lo[d] - 1e-15), f"a particle crosses the lower {'xyz'[d]} wall"
        assert np.all(pos[:, d] + r <= hi[d] + 1e-15), f"a particle crosses the upper {'xyz'[d]} wall"
    if dimensions == 2:
        # 2D: every centre in the mid-plane of the box depth
        assert np.all(pos[:, 2] == 0.5 * (lo[2] + hi[2]))


def simulation(case):
    """A Simulation without a run folder: builds the engine and checks the initial particles."""
    from fluidem.simulation import Simulation

    return Simulation(case)


def pair_in_message(msg):
    m = re.search(r"particles (\d+) and (\d+)", msg)
    assert m, f"message does not name two particles: {msg}"
    return {int(m.group(1)), int(m.group(2))}


# ---------------------------------------------------------------- random fill
@pytest.mark.parametrize("dimensions", [2, 3])
def test_random_fill_monodisperse(dimensions):
    case = make_case(dimensions, species=[{"name": "a", "diameter": D, "density": 2500.0, "count": 150}])
    pos, vel, diam, spec = placed(case)
    assert pos.shape == (150, 3) and vel.shape == (150, 3)
    assert np.all(diam == D) and np.all(spec == 0)
    assert np.all(vel == 0.0)
    assert_no_overlap(pos, diam)
    box = case.walls[0]
    assert_inside_box(pos, diam, box.lower, box.upper, dimensions)


@pytest.mark.parametrize("dimensions", [2, 3])
def test_random_fill_polydisperse_uniform(dimensions):
    species = [
        {"name": "small", "diameter": 0.003, "density": 2500.0, "count": 150,
         "size_distribution": {"kind": "uniform", "min": 0.002, "max": 0.004}},
        {"name": "big", "diameter": 0.006, "density": 2500.0, "count": 20},
    ]
    case = make_case(dimensions, species=species)
    pos, vel, diam, spec = placed(case)
    assert pos.shape == (170, 3)
    small = spec == 0
    assert small.sum() == 150 and (spec == 1).sum() == 20
    assert np.all((diam[small] >= 0.002) & (diam[small] <= 0.004))
    assert np.ptp(diam[small]) > 0.001, "a uniform distribution should give a spread of diameters"
    assert np.all(diam[~small] == 0.006)
    assert_no_overlap(pos, diam)
    box = case.walls[0]
    assert_inside_box(pos, diam, box.lower, box.upper, dimensions)
    simulation(case)  # and the engine's own initial check agrees


def test_random_fill_dense_2d_pour_case():
    """The built-in pour case: 500 discs, a fill of about 0.34 of the box area."""
    from fluidem.case import load_case

    case = load_case("pour")
    pos, _, diam, _ = placed(case)
    assert pos.shape == (500, 3)
    assert_no_overlap(pos, diam)
    box = case.walls[0]
    assert_inside_box(pos, diam, box.lower, box.upper, 2)


def test_random_fill_is_reproducible_from_the_seed():
    a = placed(make_case(placement={"method": "random", "seed": 3}))
    b = placed(make_case(placement={"method": "random", "seed": 3}))
    c = placed(make_case(placement={"method": "random", "seed": 4}))
    for x, y in zip(a, b):
        assert np.array_equal(x, y)
    assert not np.array_equal(a[0], c[0])


def test_random_fill_in_a_region_and_with_initial_velocity():
    case = make_case(placement={"method": "random", "region_lower": [0.0, 0.04, 0.0],
                                "region_upper": [0.08, 0.08, D], "velocity": [0.1, -0.2, 0.3]},
                     species=[{"name": "a", "diameter": D, "density": 2500.0, "count": 40}])
    pos, vel, diam, _ = placed(case)
    assert_inside_box(pos, diam, (0.0, 0.04, 0.0), (0.08, 0.08, D), 2)
    assert np.all(vel == [0.1, -0.2, 0.0])  # 2D: no z velocity


def test_random_fill_too_many_particles():
    case = make_case(species=[{"name": "a", "diameter": D, "density": 2500.0, "count": 1000}])
    with pytest.raises(CaseError) as info:
        placed(case)
    msg = str(info.value)
    assert "particles.placement" in msg
    assert "of 1000 particles" in msg


def test_region_without_box_wall_needs_explicit_region():
    case = make_case(walls=[])
    with pytest.raises(CaseError, match="region_lower and region_upper"):
        placed(case)


# ---------------------------------------------------------------- lattice
@pytest.mark.parametrize("dimensions", [2, 3])
@pytest.mark.parametrize("spacing, perturbation", [(1.05, 0.02), (1.0, 0.0), (1.2, 0.1)])
def test_lattice_has_no_overlaps(dimensions, spacing, perturbation):
    case = make_case(dimensions, placement={"method": "lattice", "spacing": spacing, "perturbation": perturbation},
                     species=[{"name": "a", "diameter": D, "density": 2500.0, "count": 180}])
    pos, _, diam, _ = placed(case)
    assert pos.shape == (180, 3)
    assert_no_overlap(pos, diam)
    box = case.walls[0]
    assert_inside_box(pos, diam, box.lower, box.upper, dimensions)
    # filled from the floor up (against gravity): the lowest layer sits near the floor
    up = 1 if dimensions == 2 else 2
    assert np.min(pos[:, up] - 0.5 * diam) < 0.5 * D
    simulation(case)


def test_lattice_polydisperse():
    species = [{"name": "a", "diameter": 0.003, "density": 2500.0, "count": 100,
                "size_distribution": {"kind": "uniform", "min": 0.002, "max": 0.004}}]
    case = make_case(3, species=species, placement={"method": "lattice"})
    pos, _, diam, _ = placed(case)
    assert_no_overlap(pos, diam)
    box = case.walls[0]
    assert_inside_box(pos, diam, box.lower, box.upper, 3)


def test_lattice_too_many_particles():
    case = make_case(placement={"method": "lattice"},
                     species=[{"name": "a", "diameter": D, "density": 2500.0, "count": 1000}])
    with pytest.raises(CaseError) as info:
        placed(case)
    msg = str(info.value)
    assert "particles.placement" in msg and "1000" in msg and "lattice" in msg


# ---------------------------------------------------------------- files
FILE_ROWS = np.array([
    # x, y, z, diameter, vx, vy, vz
    [0.010, 0.010, 0.002, 0.004, 0.0, -0.1, 0.0],
    [0.020, 0.010, 0.002, 0.004, 0.5, 0.0, 0.0],
    [0.030, 0.020, 0.002, 0.006, 0.0, 0.0, 0.0],
    [0.050, 0.050, 0.002, 0.002, 0.0, 0.2, 0.0],
])
TWO_SPECIES = [{"name": "glass", "diameter": 0.004, "density": 2500.0, "count": 3},
               {"name": "steel", "diameter": 0.002, "density": 7800.0, "count": 1}]
SPECIES_COL = ["glass", "glass", "glass", "steel"]


def write_csv(path, rows, species=None, velocity=True):
    cols = ["x", "y", "z", "diameter"] + (["species"] if species is not None else []) + (
        ["vx", "vy", "vz"] if velocity else [])
    lines = [",".join(cols)]
    for k, r in enumerate(rows):
        vals = [repr(float(v)) for v in r[:4]]
        if species is not None:
            vals.append(str(species[k]))
        if velocity:
            vals += [repr(float(v)) for v in r[4:7]]
        lines.append(",".join(vals))
    path.write_text("\n".join(lines) + "\n")
    return path


def file_case(path, dimensions=2, species=None, box=None):
    return make_case(dimensions, species=species or TWO_SPECIES, placement={"method": "file", "file": str(path)},
                     box=box)


def test_file_placement_csv_with_species_names_and_velocities(tmp_path):
    path = write_csv(tmp_path / "p.csv", FILE_ROWS, species=SPECIES_COL)
    pos, vel, diam, spec = placed(file_case(path))
    assert np.array_equal(pos, FILE_ROWS[:, :3])
    assert np.array_equal(diam, FILE_ROWS[:, 3])
    assert np.array_equal(vel, FILE_ROWS[:, 4:7])
    assert spec.tolist() == [0, 0, 0, 1]


def one_species(count):
    """One species of ``count`` particles: the file has no species column, so every row is this species."""
    return [{"name": "a", "diameter": 0.004, "density": 2500.0, "count": count}]


def test_file_placement_csv_minimal_columns(tmp_path):
    path = write_csv(tmp_path / "p.csv", FILE_ROWS, velocity=False)
    pos, vel, diam, spec = placed(file_case(path, species=one_species(4)))
    assert np.array_equal(pos, FILE_ROWS[:, :3])
    assert np.all(vel == 0) and np.all(spec == 0)


def test_file_placement_csv_species_indices(tmp_path):
    path = write_csv(tmp_path / "p.csv", FILE_ROWS, species=[0, 0, 0, 1])
    _, _, _, spec = placed(file_case(path))
    assert spec.tolist() == [0, 0, 0, 1]


def test_file_placement_csv_single_row(tmp_path):
    path = write_csv(tmp_path / "p.csv", FILE_ROWS[:1])
    pos, _, diam, _ = placed(file_case(path, species=one_species(1)))
    assert pos.shape == (1, 3) and np.array_equal(pos[0], FILE_ROWS[0, :3])


def test_file_placement_hdf5_position_dataset(tmp_path):
    path = tmp_path / "p.h5"
    with h5py.File(path, "w") as f:
        f["position"] = FILE_ROWS[:, :3]
        f["diameter"] = FILE_ROWS[:, 3]
        f["species"] = np.array([0, 0, 0, 1], dtype=np.int32)
        f["vx"], f["vy"], f["vz"] = FILE_ROWS[:, 4], FILE_ROWS[:, 5], FILE_ROWS[:, 6]
    pos, vel, diam, spec = placed(file_case(path))
    assert np.array_equal(pos, FILE_ROWS[:, :3])
    assert np.array_equal(diam, FILE_ROWS[:, 3])
    assert np.array_equal(vel, FILE_ROWS[:, 4:7])
    assert spec.tolist() == [0, 0, 0, 1]


def test_file_placement_hdf5_xyz_datasets(tmp_path):
    path = tmp_path / "p.hdf5"
    with h5py.File(path, "w") as f:
        for k, name in enumerate("xyz"):
            f[name] = FILE_ROWS[:, k]
        f["diameter"] = FILE_ROWS[:, 3]
    pos, vel, diam, spec = placed(file_case(path, species=one_species(4)))
    assert np.array_equal(pos, FILE_ROWS[:, :3])
    assert np.all(vel == 0) and np.all(spec == 0)


def test_file_placement_runs_through_the_engine(tmp_path):
    path = write_csv(tmp_path / "p.csv", FILE_ROWS, species=SPECIES_COL)
    sim = simulation(file_case(path))
    assert sim.state.n == 4
    assert np.array_equal(sim.state.position, FILE_ROWS[:, :3])
    assert np.array_equal(sim.state.radius, 0.5 * FILE_ROWS[:, 3])


@pytest.mark.parametrize("suffix", [".csv", ".h5"])
@pytest.mark.parametrize("dimensions", [2, 3])
def test_overlapping_particles_in_file_name_both_indices(tmp_path, suffix, dimensions):
    rows = FILE_ROWS.copy()
    rows[:, 2] = 0.002 if dimensions == 2 else 0.02
    rows[3, :4] = [0.033, 0.021, rows[3, 2], 0.002]  # particle 3 inside particle 2 (d = 6 mm at 0.030, 0.020)
    path = tmp_path / f"p{suffix}"
    if suffix == ".csv":
        write_csv(path, rows)
    else:
        with h5py.File(path, "w") as f:
            f["position"] = rows[:, :3]
            f["diameter"] = rows[:, 3]
    case = file_case(path, dimensions, species=[{"name": "a", "diameter": 0.004, "density": 2500.0, "count": 4}],
                     box=[0.08, 0.08, 0.004 if dimensions == 2 else 0.04])
    with pytest.raises(CaseError) as info:
        simulation(case)
    msg = str(info.value)
    assert "overlap" in msg
    assert pair_in_message(msg) == {2, 3}


def test_overlap_message_counts_all_pairs(tmp_path):
    rows = np.array([[0.010, 0.010, 0.002, 0.004], [0.013, 0.010, 0.002, 0.004],
                     [0.040, 0.040, 0.002, 0.004], [0.040, 0.0435, 0.002, 0.004]])
    case = file_case(write_csv(tmp_path / "p.csv", rows, velocity=False),
                     species=[{"name": "a", "diameter": 0.004, "density": 2500.0, "count": 4}])
    with pytest.raises(CaseError) as info:
        simulation(case)
    msg = str(info.value)
    assert "2 pair(s)" in msg
    assert pair_in_message(msg) == {0, 1}  # the worst pair (1 mm overlap) is named


def test_touching_particles_are_not_an_overlap(tmp_path):
    rows = np.array([[0.010, 0.010, 0.002, 0.004], [0.014, 0.010, 0.002, 0.004]])
    case = file_case(write_csv(tmp_path / "p.csv", rows, velocity=False),
                     species=[{"name": "a", "diameter": 0.004, "density": 2500.0, "count": 2}])
    simulation(case)


@pytest.mark.parametrize("dimensions", [2, 3])
@pytest.mark.parametrize("where, wall", [((0.001, 0.03), "box.xmin"), ((0.03, 0.079), "box.ymax")])
def test_particle_crossing_a_wall(tmp_path, dimensions, where, wall):
    z = 0.002 if dimensions == 2 else 0.02
    rows = np.array([[0.02, 0.02, z, 0.004], [where[0], where[1], z, 0.004]])
    case = file_case(write_csv(tmp_path / "p.csv", rows, velocity=False), dimensions,
                     species=[{"name": "a", "diameter": 0.004, "density": 2500.0, "count": 2}],
                     box=[0.08, 0.08, 0.004 if dimensions == 2 else 0.04])
    with pytest.raises(CaseError) as info:
        simulation(case)
    msg = str(info.value)
    assert wall in msg
    assert "particle 1" in msg


def test_particle_crossing_a_plane_wall(tmp_path):
    rows = np.array([[0.02, 0.02, 0.002, 0.004], [0.03, 0.0105, 0.002, 0.004]])
    case = make_case(placement={"method": "file", "file": str(write_csv(tmp_path / "p.csv", rows, velocity=False))},
                     species=one_species(2), walls=[{"name": "floor", "kind": "plane", "point": [0.0, 0.011, 0.0], "normal": [0.0, 1.0, 0.0]}])
    with pytest.raises(CaseError) as info:
        simulation(case)
    assert "floor" in str(info.value) and "particle 1" in str(info.value)


def test_missing_file(tmp_path):
    with pytest.raises(CaseError) as info:
        placed(file_case(tmp_path / "nope.csv"))
    assert "particles.placement.file" in str(info.value) and "nope.csv" in str(info.value)


def test_missing_column(tmp_path):
    path = tmp_path / "p.csv"
    path.write_text("x,y,diameter\n0.01,0.01,0.004\n")
    with pytest.raises(CaseError) as info:
        placed(file_case(path))
    assert "'z'" in str(info.value) and "p.csv" in str(info.value)


def test_non_positive_diameter_in_file(tmp_path):
    rows = FILE_ROWS.copy()
    rows[2, 3] = -0.001
    with pytest.raises(CaseError) as info:
        placed(file_case(write_csv(tmp_path / "p.csv", rows, velocity=False)))
    assert "row 2" in str(info.value) and "-0.001" in str(info.value)


def test_unknown_species_name_in_file(tmp_path):
    path = write_csv(tmp_path / "p.csv", FILE_ROWS, species=["glass", "glass", "brass", "steel"])
    with pytest.raises(CaseError) as info:
        placed(file_case(path))
    assert "'brass'" in str(info.value) and "glass" in str(info.value) and "steel" in str(info.value)


def test_species_index_out_of_range_in_file(tmp_path):
    path = write_csv(tmp_path / "p.csv", FILE_ROWS, species=[0, 0, 2, 1])
    with pytest.raises(CaseError, match="species index"):
        placed(file_case(path))


def test_file_method_needs_a_file():
    with pytest.raises(CaseError) as info:
        make_case(placement={"method": "file"})
    assert "placement.file" in str(info.value)
