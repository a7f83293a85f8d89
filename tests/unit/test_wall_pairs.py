"""Per species–wall contact parameters (particles.wall_pairs), Hoomans 1996 keeps e_w, μ_w apart."""
import numpy as np
import pytest

from fluidem.case import validate_case
from fluidem.errors import CaseError
from fluidem.particles.softsphere import SoftSphereEngine


def case_dict(tmp_path, wall_pairs):
    csv = tmp_path / "p.csv"
    # species a falls onto the floor at 1 m/s; species b sits far away
    csv.write_text("x,y,z,diameter,species,vx,vy,vz\n"
                   "0.01,0.0025,0.002,0.004,a,0,-1.0,0\n"
                   "0.05,0.0100,0.002,0.004,b,0,0,0\n")
    return {
        "name": "wall-pairs",
        "gravity": [0.0, 0.0, 0.0],
        "particles": {
            "dimensions": 2,
            "species": [{"name": "a", "diameter": 0.004, "density": 2700.0, "count": 1},
                        {"name": "b", "diameter": 0.004, "density": 2700.0, "count": 1}],
            "contact": {"model": "linear_spring_dashpot", "stiffness": 800.0, "restitution": 0.9, "friction": 0.3},
            "wall_pairs": wall_pairs,
            "placement": {"method": "file", "file": str(csv)},
        },
        "walls": [{"name": "box", "kind": "box", "lower": [0, 0, 0], "upper": [0.1, 0.1, 0.004]}],
        "time": {"end": 0.01},
    }


def test_species_wall_restitution_is_measured(tmp_path):
    case = validate_case(case_dict(tmp_path, [{"species": "a", "wall": "box", "restitution": 0.5}]))
    eng = SoftSphereEngine(case)
    # one wall collision lasts t_c ≈ 1 ms; run 4 ms, the particle has left the floor by then
    eng.advance(int(4e-3 / eng.dt))
    # 1 % as for every restitution test: the linear law meets e exactly up to the time-step error
    assert eng.state.velocity[0, 1] == pytest.approx(0.5, rel=0.01)
    # the table of species b keeps the default restitution 0.9; a's differs
    assert not np.array_equal(eng.pw[0, 0], eng.pw[1, 0])
    assert np.array_equal(eng.pw[1, 0], eng.pw[1, 1])


def test_wall_pairs_name_unknown_species_and_walls(tmp_path):
    with pytest.raises(CaseError, match="wall_pairs.*'c'"):
        validate_case(case_dict(tmp_path, [{"species": "c", "restitution": 0.5}]))
    with pytest.raises(CaseError, match="wall_pairs: wall 'lid'"):
        validate_case(case_dict(tmp_path, [{"species": "a", "wall": "lid", "restitution": 0.5}]))
