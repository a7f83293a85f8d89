"""The polydisperse drag of a coupled run against the DEM book 2012 two-phase chapter, eqs 7-12.

A frozen bidisperse bed on the tsuji-jet-background grid: every cell of its lower rows holds one small and one
large sphere (so every cell, and the bed, has the same Sauter mean D̄, eq. 10), the gas flows
uniformly through it at a uniform voidage. Then each particle of species i must feel
f_di = y_i² f̄_d (eq. 12), f̄_d the law's drag on a sphere of diameter D̄ (Reynolds number with D̄)
and y_i = D_i/D̄ (eq. 11), in each exchange mode; and the whole bed the drag of the same solids volume
made of spheres of diameter D̄ (eqs 7-8). A bed of one size is left as it was.
"""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

import fluidem as fd
from fluidem.coupling.exchange import GasCoupling
from fluidem.gas.solver import GasState

D_SMALL, D_LARGE = 1.5e-3, 3.0e-3  # [m]
EPS, SLIP, RHO_G = 0.55, 1.3, 1.2  # bed voidage [-], gas velocity through the resting bed [m/s], [kg/m³]
ROWS = 10  # cell rows holding the bed


def frozen_bed(drag="beetstra", exchange="cell_beta", diameters=(D_SMALL, D_LARGE), polydisperse=None):
    """GasCoupling of a resting bed: in each cell of the lower ROWS rows one particle of each diameter, placed
    symmetrically about the cell centre; uniform gas (v = SLIP, u = 0, ε = EPS, ρ = RHO_G, uniform p)."""
    overrides = {"coupling.drag": drag, "coupling.momentum_exchange": exchange,
                 "coupling.pressure_gradient_force": False}
    if polydisperse is not None:
        overrides["coupling.polydisperse"] = polydisperse
    case = fd.load_case("tsuji-jet-background").with_overrides(overrides)
    grid = case.gas.build(case.gravity).grid
    nx = grid.shape[0]
    pos, radius = [], []
    for i in range(nx):
        for j in range(ROWS):
            xc, yc = (i + 0.5) * grid.dx, (j + 0.5) * grid.dy
            for k, d in enumerate(diameters):
                pos.append([xc + (0.25 if k else -0.25) * grid.dx, yc, 0.002])
                radius.append(0.5 * d)
    pos, radius = np.array(pos), np.array(radius)
    n = len(radius)
    vel = np.zeros((n, 3))
    state = SimpleNamespace(position=pos, radius=radius, velocity=vel, force=np.zeros_like(pos), n=n)
    engine = SimpleNamespace(state=state, dt=1e-5, steps=0, time=0.0, dim2=True, ext_force=np.zeros_like(pos))
    cpl = GasCoupling(case, engine)
    c = grid.shape
    cpl.state = GasState(p=np.full(c, 1.013e5), rho=np.full(c, RHO_G), u=np.zeros(grid.u_shape),
                         v=np.full(grid.v_shape, SLIP), voidage=np.full(c, EPS))
    return cpl


def sauter(diameters):
    """D̄ of one particle of each diameter (eq. 10 with x_i the volume fractions)."""
    d = np.asarray(diameters)
    v = d**3
    return v.sum() / (v / d).sum()


def drag_forces(cpl, exchange):
    """The drag on each particle [N] (y components; the gas flows along y) as the exchange mode computes it."""
    if exchange == "particle":
        voidage = np.full(cpl.grid.shape, EPS)
        cpl._deposit(voidage)
        return cpl._kp * SLIP  # K_p (v_g − v_p)
    return cpl.particle_forces()[:, 1]


@pytest.mark.parametrize("exchange", ["particle", "cell", "cell_beta"])
@pytest.mark.parametrize("drag", ["beetstra", "gidaspow", "di_felice", "koch_hill"])
def test_each_species_feels_y_squared_times_the_drag_at_the_sauter_mean(drag, exchange):
    cpl = frozen_bed(drag, exchange)
    assert cpl.polydisperse == "sauter_y2"  # the default for more than one size
    mu = cpl.solver.props.viscosity
    dbar = sauter((D_SMALL, D_LARGE))
    f_bar = cpl.drag.force_coefficient(EPS, SLIP, dbar, RHO_G, mu) * SLIP  # f̄_d: the law at D̄ [N]
    forces = drag_forces(cpl, exchange)
    d = 2.0 * cpl.engine.state.radius
    want = (d / dbar) ** 2 * f_bar  # eq. 12 with y_i = D_i/D̄ (eq. 11)
    np.testing.assert_allclose(forces, want, rtol=1e-12)
    # the small spheres feel less than their own monodisperse drag would be at this slip, the large more
    own = cpl.drag.force_coefficient(EPS, SLIP, d, RHO_G, mu) * SLIP
    small = d == D_SMALL
    assert np.all(forces[small] != own[small]) and np.all(forces[~small] != own[~small])


@pytest.mark.parametrize("drag", ["beetstra", "gidaspow"])
def test_the_bed_feels_the_drag_of_its_solids_volume_made_of_sauter_mean_spheres(drag):
    """Σ_i N_i y_i² f̄_d = V_s f̄_d / V̄ (eqs 7-8 with 10-12): the pressure drop of the mixture is that of a
    bed of diameter D̄ at the same voidage."""
    cpl = frozen_bed(drag, "particle")
    mu = cpl.solver.props.viscosity
    d = 2.0 * cpl.engine.state.radius
    solids = (math.pi / 6.0 * d**3).sum()
    dbar = sauter((D_SMALL, D_LARGE))
    mixture = solids / (math.pi / 6.0 * dbar**3) * cpl.drag.force_coefficient(EPS, SLIP, dbar, RHO_G, mu) * SLIP
    total = drag_forces(cpl, "particle").sum()
    assert total == pytest.approx(mixture, rel=1e-12)
    # and the gas takes it back: Σ_faces V_f β_f (v_f − v_s,f) over the y-faces is the same total
    beta_v, sv = cpl._face_beta[1], cpl._face_solids[1]
    face_volume = cpl._face_volumes[1] if cpl._fold else cpl.grid.cell_volume
    assert (face_volume * beta_v * (SLIP - sv)).sum() == pytest.approx(total, rel=1e-12)
    # without the mixture rule the same bed feels another total (size ratio 2: 2.9 % more with beetstra,
    # 1.8 % more with gidaspow): the rule is what makes the totals agree
    plain = frozen_bed(drag, "particle", polydisperse="none")
    assert drag_forces(plain, "particle").sum() / mixture - 1.0 > 0.01


@pytest.mark.parametrize("exchange", ["particle", "cell", "cell_beta"])
def test_a_bed_of_one_size_is_unchanged(exchange):
    """One size: the default is no mixture rule (y = 1 exactly: the law itself); asking for the rule changes
    the forces by round-off only (y = 1 up to the sums of eq. 10). That the built-in beds, all of one size,
    keep their results bit for bit is checked on their restart files."""
    one = frozen_bed("beetstra", exchange, diameters=(D_LARGE, D_LARGE))
    assert one.polydisperse == "none"
    mu = one.solver.props.viscosity
    d = 2.0 * one.engine.state.radius
    np.testing.assert_allclose(drag_forces(one, exchange), one.drag.force_coefficient(EPS, SLIP, d, RHO_G, mu) * SLIP,
                               rtol=1e-14)
    rule = frozen_bed("beetstra", exchange, diameters=(D_LARGE, D_LARGE), polydisperse="sauter_y2")
    np.testing.assert_allclose(drag_forces(rule, exchange), drag_forces(one, exchange), rtol=1e-14)


def test_the_rule_is_refused_with_a_law_giving_the_total_gas_force():
    with pytest.raises(fd.CaseError, match="polydisperse = 'sauter_y2'.*hoomans1996_total"):
        fd.load_case("hoomans-orifice").with_overrides({"coupling.drag": "hoomans1996_total",
                                                        "coupling.pressure_gradient_force": False,
                                                        "coupling.momentum_exchange": "cell_beta",
                                                        "coupling.polydisperse": "sauter_y2"})
