"""A coupled run on a 3D gas grid stopped at a checkpoint and resumed equals the run made in one go, bit for bit
(the gas state with w, K_p of the gas step in progress, the phase within the gas step and the 3D solver's
state are in the restart file), and its gas snapshots open as a 3D grid."""
import numpy as np

from fluidem.case import validate_case
from fluidem.io.gas_fields import read_gas_fields

from _helpers.settling3d import settling3d_case


def test_resumed_coupled_3d_run_matches_the_uninterrupted_one(stopped_and_resumed, tmp_path):
    case = validate_case(settling3d_case(end=0.02, axis=1))
    whole, first, again = stopped_and_resumed(case, 0.0105)  # stops inside a gas step (DT = 1 ms)
    assert first.steps % first.gas.substeps != 0
    assert again.steps == whole.steps
    for k in ("position", "velocity", "omega"):
        assert np.array_equal(getattr(again.state, k), getattr(whole.state, k)), k
    for k in ("p", "rho", "u", "v", "w", "voidage"):
        assert np.array_equal(getattr(again.gas.state, k), getattr(whole.gas.state, k)), k
    assert whole.state.velocity[0, 1] < -0.05  # it has been settling along −y
    fields = read_gas_fields(tmp_path / "run")
    g = case.gas.grid
    assert fields["voidage"].shape[1:] == tuple(g.cells)  # (T, nx, ny, nz)
    assert "uz" in fields and "solids_w" in fields
    # the run's figures read the gas maps averaged along z (x–y maps of the pseudo-2D view)
    from fluidem.plotting.run import RunData

    maps = RunData(tmp_path / "run").gas["voidage"]
    assert maps.shape[1:] == (g.cells[0], g.cells[1])
    np.testing.assert_allclose(maps, fields["voidage"].mean(axis=3), rtol=1e-15)


def test_resumed_3d_run_with_the_cell_exchange_matches_the_uninterrupted_one(stopped_and_resumed, tmp_path):
    """``momentum_exchange = "cell"``: the cell β and solids velocity of the gas step in progress, which the
    sub-steps' forces read, are in the restart file (as in 2D)."""
    import h5py

    case = validate_case(settling3d_case(end=0.02, axis=1, momentum_exchange="cell"))
    whole, first, again = stopped_and_resumed(case, 0.0105)
    assert first.steps % first.gas.substeps != 0
    with h5py.File(tmp_path / "run" / "restart.h5", "r") as f:
        names = []
        f.visit(names.append)
    assert {"cell_beta", "solids_u", "solids_v", "solids_w"} <= {n.rsplit("/", 1)[-1] for n in names}, names
    assert again.steps == whole.steps
    for k in ("position", "velocity", "omega"):
        assert np.array_equal(getattr(again.state, k), getattr(whole.state, k)), k
    for k in ("p", "rho", "u", "v", "w", "voidage"):
        assert np.array_equal(getattr(again.gas.state, k), getattr(whole.gas.state, k)), k
    assert whole.state.velocity[0, 1] < -0.05
