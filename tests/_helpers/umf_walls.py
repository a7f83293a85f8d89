"""The measures of tests/validation/umf_walls.py (and test_umf_walls.py): the wall layers, the packing and the
fixed-bed gas force of the u_mf sweep bed (``umf_sweep``); the module docstring of umf_walls.py says what each is."""
from __future__ import annotations

import math

import numpy as np

from fluidem.analysis.fluidised import minimum_fluidisation, pressure_drop, wen_yu_umf
from fluidem.case import apply_overrides, validate_case
from fluidem.coupling.interpolation import interpolate
from fluidem.simulation import Simulation

from . import umf_sweep as T

U_PROFILE = (0.095, 0.105)  # [m/s] superficial velocities of the fixed bed where the force profile is taken
PER_AREA = 20.0  # spheres per d² of bed area, as the sweep beds (12,000 on 60 × 10 d)


def ergun_coefficients(eps, d=T.D, mu=T.MU, rho=T.RHO):
    """(a, b) of Ergun's gradient ∇p = a U + b U² [Pa/m] at voidage ``eps`` (Ergun 1952)."""
    eps = np.asarray(eps, float)
    return 150.0 * (1 - eps) ** 2 * mu / (eps**3 * d**2), 1.75 * (1 - eps) * rho / (eps**3 * d)


def solve_u(a, b, grad):
    """Superficial U [m/s] where a U + b U² = grad."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return (-a + np.sqrt(a * a + 4 * b * grad)) / (2 * b)


def ergun_umf(eps):
    """Ergun's u_mf [m/s] of a bed at voidage ``eps``: its gradient meets (1 − ε)(ρ_p − ρ) g."""
    a, b = ergun_coefficients(eps)
    return solve_u(a, b, (1 - np.asarray(eps, float)) * (T.RHO_P - T.RHO) * T.G)


def cap_volume(h, r):
    """Volume of a sphere of radius r below the plane at h from its centre (h clipped to [−r, r])."""
    h = np.clip(h, -r, r)
    return math.pi * (r * r * (h + r) - (h**3 + r**3) / 3.0)


def slab_fraction(coord, r, edges, cross_area):
    """Solids fraction of the slabs between ``edges`` along one axis: Σ sphere volume between the planes /
    (slab width × ``cross_area``), for spheres with centres at ``coord`` (N,)."""
    v = cap_volume(edges[None, :] - coord[:, None], r)
    return np.diff(v, axis=1).sum(axis=0) / (np.diff(edges) * cross_area)


def settled_profiles(pos, width, depth):
    """Voidage of the interior heights of a bed with centres ``pos`` (N, 3) in a box width × depth [m]."""
    d, r = T.D, 0.5 * T.D
    top = np.quantile(pos[:, 1], 0.99)
    lo, hi = 3 * d, top - 3 * d
    inner = (pos[:, 1] > lo) & (pos[:, 1] < hi)
    p = pos[inner]
    height = hi - lo
    out = {"interior_m": (lo, hi), "count_interior": int(inner.sum())}
    out["eps_mean"] = 1 - p.shape[0] * math.pi / 6 * d**3 / (width * depth * height)
    # core: more than 1.5 d from every wall; exact in z (where the layers are), by centre in x
    cw, cd = width - 3 * d, depth - 3 * d
    mid_x = np.abs(p[:, 0] - width / 2) < cw / 2
    core = slab_fraction(p[mid_x, 2], r, np.array([1.5 * d, depth - 1.5 * d]), cw * height)[0] if cd > 0 else math.nan
    out["eps_core"] = 1 - core
    zedges = np.linspace(0.0, depth, int(round(depth / d * 10)) + 1)
    xedges = np.linspace(0.0, width, int(round(width / d * 10)) + 1)
    out["z_edges"], out["phi_z"] = zedges, slab_fraction(p[:, 2], r, zedges, width * height)
    out["x_edges"], out["phi_x"] = xedges, slab_fraction(p[:, 0], r, xedges, depth * height)
    # the half-diameter layer at each of the four walls: measured, and the touching layer's caps
    layers = []
    for coord, lw, cross in ((p[:, 2], depth, width), (p[:, 0], width, depth)):
        for dist in (coord, lw - coord):
            meas = slab_fraction(dist, r, np.array([0.0, r]), cross * height)[0]
            touching = dist < r * 1.02  # in contact with the wall (overlaps are < 1 % of r here)
            n_a = touching.sum() / (cross * height)
            reach = (dist < 2 * r) & ~touching  # other spheres that reach into the layer
            layers.append((meas, 2.0 / 3.0 * math.pi * r * r * n_a, int(reach.sum())))
    out["wall_layers"] = layers
    return out


def parallel_umf(phi_z, phi_x, eps_mean, width, depth, channel):
    """u_mf of slabs ``channel`` [m] wide in parallel at the bed's mean gradient (Ergun in each)."""
    grad = (1 - eps_mean) * (T.RHO_P - T.RHO) * T.G  # the bed's weight per area over its height

    def mean_u(phi, n_per):
        eps = 1 - phi.reshape(-1, n_per).mean(axis=1)
        return float(np.mean(solve_u(*ergun_coefficients(eps), grad)))

    k = int(round(channel / (T.D / 10)))
    return mean_u(phi_z, k), mean_u(phi_x, k)


def cell_coefficients(grid, eps, top):
    """Ergun's (a, b) of the fixed bed [Pa/(m/s)], [Pa/(m/s)²] from the cell voidages: each row's gradient at the
    mean U over its columns, rows in series up to ``top`` [m] (the first row from the inflow face)."""
    a, b = ergun_coefficients(np.minimum(eps, 0.999))
    ys = grid.y_centres
    rows = ys - 0.5 * grid.dy < top
    return float((a.mean(axis=0)[rows] * grid.dy).sum()), float((b.mean(axis=0)[rows] * grid.dy).sum())


def measure(width_d=20.0, depth_d=5.0, count=None, overrides=None, sweep=True, echo=print) -> dict:
    """Run the sweep bed ``width_d`` × ``depth_d`` diameters (``count`` spheres, default 20 per d²) with the case
    ``overrides`` (dotted keys), print the measures (``echo``) and return them."""
    width, depth = width_d * T.D, depth_d * T.D
    n = count or int(round(PER_AREA * width_d * depth_d))
    data = T.sweep_case(n, width, depth).model_dump(mode="json", exclude_none=True)
    overrides = dict(overrides or {})
    apply_overrides(data, overrides)
    case = validate_case(data)
    wc = case.particles.wall_contact or case.particles.contact
    out = {"particle_friction": case.particles.contact.friction, "wall_friction": wc.friction}
    echo(f"bed {width_d:g} x {depth_d:g} d, {n} spheres; particle friction {case.particles.contact.friction}, "
         f"wall friction {wc.friction}; overrides {overrides or 'none'}")
    sim = Simulation(case)
    chunk = int(round(0.005 / sim.dt))
    while sim.time < T.T_SETTLE - 1e-9:
        sim.advance(chunk)
    pos = np.array(sim.state.position)
    prof = settled_profiles(pos, width, depth)
    out.update(prof)
    em, ec = prof["eps_mean"], prof["eps_core"]
    echo(f"settled at {sim.time:.3f} s: interior {prof['interior_m'][0] * 1e3:.1f}-{prof['interior_m'][1] * 1e3:.1f} mm "
         f"({prof['count_interior']} spheres); eps_mean {em:.4f}, eps_core {ec:.4f}")
    wl = (1 - (1 - em) / (1 - ec)) * depth * width / (2 * (depth + width)) if np.isfinite(ec) else math.nan
    out["wall_layer_d"] = wl / T.D
    echo(f"equivalent wall layer of voidage 1 (all four walls): delta_w = {wl / T.D:.3f} d")
    names = ("z=0 (front)", "z=L (back)", "x=0 (left)", "x=W (right)")
    for name, (meas, caps, reach) in zip(names, prof["wall_layers"]):
        echo(f"  half-diameter layer at {name}: voidage {1 - meas:.4f}; touching layer's caps (2/3) pi r^2 n_A give "
             f"{1 - caps:.4f}; other spheres reaching into it: {reach}")
    for label, edges, phi in (("depth z", prof["z_edges"], prof["phi_z"]), ("width x", prof["x_edges"], prof["phi_x"])):
        k = min(len(phi) // 2, 25)
        echo(f"  voidage across the {label}, slabs of d/10 from the wall (first {k}): "
             + " ".join(f"{1 - f:.3f}" for f in phi[:k]))
    wy = wen_yu_umf(T.D, T.RHO_P, T.RHO, T.MU, T.G)
    pz5, px5 = parallel_umf(prof["phi_z"], prof["phi_x"], em, width, depth, 0.5 * T.D)
    pz25, px25 = parallel_umf(prof["phi_z"], prof["phi_x"], em, width, depth, 0.25 * T.D)
    out.update(umf_wen_yu=wy, umf_ergun_core=float(ergun_umf(ec)), umf_ergun_mean=float(ergun_umf(em)),
               umf_parallel_depth=pz5, umf_parallel_width=px5)
    echo(f"u_mf [m/s]: Wen-Yu {wy:.4f}; Ergun at eps_core {float(ergun_umf(ec)):.4f}, at eps_mean {float(ergun_umf(em)):.4f}; "
         f"parallel slabs of d/2 across depth {pz5:.4f}, width {px5:.4f}; of d/4: {pz25:.4f}, {px25:.4f}")
    grid = sim.gas.grid
    eps_cells = np.array(sim.gas.state.voidage)
    top = np.quantile(pos[:, 1], 0.99) + 0.5 * T.D
    a_c, b_c = cell_coefficients(grid, eps_cells, top)
    eps_p = interpolate(grid, eps_cells, pos, boundary="copy")
    ic = np.clip((pos[:, 0] / grid.dx).astype(int), 0, grid.shape[0] - 1)
    jc = np.clip((pos[:, 1] / grid.dy).astype(int), 0, grid.shape[1] - 1)
    inner = (pos[:, 1] > 3 * T.D) & (pos[:, 1] < top - 4 * T.D)
    wa = weight_per_area(n, width, depth)
    out.update(eps_particles=float(eps_p[inner].mean()), eps_particle_cells=float(eps_cells[ic, jc][inner].mean()),
               umf_cells=float(solve_u(a_c, b_c, wa)))
    echo(f"cells: voidage of the bed's full rows {eps_cells[:, (grid.y_centres + 0.5 * grid.dy) < top - 2 * T.D].mean():.4f}; "
         f"at the particles (interior heights) interpolated {eps_p[inner].mean():.4f} against their cells' "
         f"{eps_cells[ic, jc][inner].mean():.4f}; Ergun from the cells: a = {a_c:.1f} Pa s/m, b = {b_c:.1f} Pa s²/m², "
         f"u_mf where a U + b U² = W/A {out['umf_cells']:.4f}")
    if not sweep:
        return out
    u, dp = [], []
    layers = np.zeros((2, 60))  # Σ gas force, Σ m g per one-diameter layer, while U is in U_PROFILE
    mg = np.asarray(sim.state.mass) * T.G
    while sim.time < case.time.end - 1e-9:
        sim.advance(chunk)
        if sim.time > T.T_SETTLE:
            u.append(T.U_MAX * (sim.time - T.T_SETTLE) / T.T_SWEEP)
            dp.append(pressure_drop(grid, sim.gas.state.p, T.H) - T.RHO * T.G * T.H)
            if U_PROFILE[0] <= u[-1] <= U_PROFILE[1]:
                y = np.asarray(sim.state.position)[:, 1]
                k = np.clip((y / T.D).astype(int), 0, layers.shape[1] - 1)
                layers[0] += np.bincount(k, sim.engine.external_force()[:, 1], layers.shape[1])
                layers[1] += np.bincount(k, mg, layers.shape[1])
    res = minimum_fluidisation(u, dp, wa)
    echo(f"sweep: W/A {wa:.2f} Pa, plateau {res['plateau_Pa'] / wa - 1:+.2%}, u_mf {res['umf']:.4f} m/s "
         f"({res['umf'] / wy - 1:+.1%} over Wen-Yu); fitted a = {res['a']:.1f}, b = {res['b']:.1f}")
    ua, da = np.array(u), np.array(dp)
    height = n * math.pi / 6 * T.D**3 / (width * depth * (1 - em))  # the bed's height at its mean voidage
    a_u, b_u = (c * height for c in ergun_coefficients(em))
    echo("fixed bed, measured dp over Ergun's (uniform eps_mean over the bed height | the cells): " + ", ".join(
        f"{lo:.3f}-{lo + 0.025:.3f} m/s {np.mean(da[m] / (a_u * ua[m] + b_u * ua[m] ** 2)):.3f} | "
        f"{np.mean(da[m] / (a_c * ua[m] + b_c * ua[m] ** 2)):.3f}"
        for lo in np.arange(0.025, 0.15, 0.025) if (m := (ua > lo) & (ua <= lo + 0.025)).any()))
    uc = 0.5 * (U_PROFILE[0] + U_PROFILE[1])
    expect = float(ergun_coefficients(em)[0] * uc + ergun_coefficients(em)[1] * uc**2) / ((1 - em) * T.RHO_P * T.G)
    echo(f"gas force / m g by layer of one diameter at U = {U_PROFILE[0]}-{U_PROFILE[1]} m/s over Ergun's at eps_mean "
         f"({expect:.3f}), from the floor: " + " ".join(f"{layers[0, k] / layers[1, k] / expect:.2f}"
                                                     for k in np.flatnonzero(layers[1])))
    height_ratio = np.array([np.mean(da[m] / (a_u * ua[m] + b_u * ua[m] ** 2))
                             for lo in (0.05, 0.1) if (m := (ua > lo) & (ua <= lo + 0.05)).any()])
    out.update(umf=res["umf"], plateau=res["plateau_Pa"] / wa, fixed_dp_over_ergun=float(height_ratio.mean()),
               layer_force_over_ergun=layers[0, layers[1] > 0] / layers[1, layers[1] > 0] / expect)
    return out


def weight_per_area(n, width, depth):
    """Buoyant weight of ``n`` spheres per bed area [Pa]."""
    return n * math.pi / 6 * T.D**3 * (T.RHO_P - T.RHO) * T.G / (width * depth)
