"""Compiled pass of the run-time health checks (``checks``): one loop over the particles, read-only."""
import math

from numba import njit


@njit(cache=True, error_model="numpy")
def particle_scan(position, velocity, omega, radius, mass, inertia, wall_point, wall_normal, lower, upper, up,
                  margin):
    """What the health checks need of the particles, in one pass.

    position, velocity, omega : (N, 3) float64 [m, m/s, rad/s]; radius, mass, inertia : (N,) float64
    wall_point, wall_normal : (W, 3) float64, a point of each wall plane now [m] and its inward unit normal
    lower, upper : (3,) float64, bounds of a box [m] (±inf: none on that side)
    up : (3,) float64, the unit vector against gravity (zeros: none)
    margin : how far a centre may lie beyond a wall plane or a bound, in its diameters [-]

    Returns (first_bad, kinetic, excess, excess_i, excess_where, wall_rel, wall_i, wall_w, height_lo, height_hi,
    mass_total):
    first_bad — the first particle with a non-finite position, velocity or spin (−1: none; the other figures
    leave such particles out); kinetic — Σ ½ (m v² + I ω²) [J]; excess — how far the centre furthest out lies
    beyond its limit, margin × diameter behind a wall plane or outside a bound [m] (> 0: out; 0 if none),
    excess_i its particle, excess_where the wall (>= 0) or −1 − (2 axis + side) for a bound (side 0 lower,
    1 upper); wall_rel — the deepest particle–wall overlap over the particle's diameter [-] (−inf without
    walls), wall_i, wall_w its particle and wall; height_lo, height_hi — the range of position · up [m];
    mass_total [kg].
    """
    n = position.shape[0]
    nw = wall_normal.shape[0]
    first_bad = -1
    kinetic = 0.0
    excess, excess_i, excess_where = 0.0, -1, 0
    wall_rel, wall_i, wall_w = -math.inf, -1, -1
    h_lo, h_hi = math.inf, -math.inf
    mass_total = 0.0
    for i in range(n):
        mass_total += mass[i]
        px, py, pz = position[i, 0], position[i, 1], position[i, 2]
        vx, vy, vz = velocity[i, 0], velocity[i, 1], velocity[i, 2]
        wx, wy, wz = omega[i, 0], omega[i, 1], omega[i, 2]
        # one test: a NaN or an infinity carries to the sum (finite fields of a particle do not reach 1e308)
        if not math.isfinite(px + py + pz + vx + vy + vz + wx + wy + wz):
            if first_bad < 0:
                first_bad = i
            continue
        kinetic += 0.5 * (mass[i] * (vx * vx + vy * vy + vz * vz) + inertia[i] * (wx * wx + wy * wy + wz * wz))
        d = 2.0 * radius[i]
        inv_d = 1.0 / d
        limit = margin * d
        for w in range(nw):
            gap = ((px - wall_point[w, 0]) * wall_normal[w, 0] + (py - wall_point[w, 1]) * wall_normal[w, 1]
                   + (pz - wall_point[w, 2]) * wall_normal[w, 2])
            beyond = -gap - limit
            if beyond > excess:
                excess, excess_i, excess_where = beyond, i, w
            rel = (radius[i] - gap) * inv_d
            if rel > wall_rel:
                wall_rel, wall_i, wall_w = rel, i, w
        for k in range(3):
            beyond = lower[k] - position[i, k] - limit  # −inf without a bound
            if beyond > excess:
                excess, excess_i, excess_where = beyond, i, -1 - 2 * k
            beyond = position[i, k] - upper[k] - limit
            if beyond > excess:
                excess, excess_i, excess_where = beyond, i, -2 - 2 * k
        h = px * up[0] + py * up[1] + pz * up[2]
        h_lo = min(h_lo, h)
        h_hi = max(h_hi, h)
    return first_bad, kinetic, excess, excess_i, excess_where, wall_rel, wall_i, wall_w, h_lo, h_hi, mass_total
