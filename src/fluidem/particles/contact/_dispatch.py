"""Compiled dispatch over contact models and the shared tangential-history update.

``coefficients`` is written from the ``contact_models`` registry (``registry.compiled_switch``): for the
model code in slot 0 of a packed row it calls the ``coefficients`` kernel of the module that registered
that model. A force-based model's module defines ``CODE`` (a unique integer) and
``coefficients(p, overlap, m_eff, r_eff)``; nothing here names a model.

``contact_force`` is the one place where a contact's force is assembled from a
model's coefficients: normal spring + dashpot (Sun 2007 eq. 21), tangential
spring + dashpot with history (eqs 19–20, 22) truncated at the Coulomb limit.

``contact_force_full`` is the same for every law, adhesive ones included, and adds the rolling-resistance
torque; the kernels use it where a table has rolling friction, an adhesive law or a variant code of a law
(slots 8 and 10 of ``base.py``), so that the plain code, and its results, stay as they are everywhere else.

``contact_force`` is written without data-dependent branches: the rescaling of the
rotated spring, the Coulomb truncation and the spring reset on slip are computed for
every contact and chosen by conditional expressions (selects). The values are those
of the branchy form (a factor 1.0 where it does nothing), and the same code then
serves the scalar wall contacts and the pair forces vectorised over chunks of
contacts (``_pair_kernels``), where LLVM turns each select into a blend across four
contacts.
"""
import math
import sys

from numba import njit

from ...registry import compiled_switch
from .base import ROLLING_EPSD, contact_models

TINY = 1e-300  # guards a division whose result a select then drops (no inf or NaN is formed)


def _force_laws(full: bool) -> dict:
    """{code: coefficients kernel} of the registered force-based contact models: with ``full``, every code of
    every model (its ``code`` and its ``extra_codes``), else the ``code`` of each non-adhesive model only (the
    plain code's laws, as they were before variants and adhesive laws existed)."""
    laws = {}
    for name in contact_models.names():
        cls = contact_models.get(name)
        if cls.instantaneous or (cls.adhesive and not full):
            continue
        module = sys.modules[cls.__module__]
        for code, kernel_name in ((cls.code, "coefficients"), *(cls.extra_codes.items() if full else ())):
            kernel = getattr(module, kernel_name, None)
            if kernel is None:
                raise TypeError(f"contact model {name!r}: its module {cls.__module__} defines no {kernel_name}() kernel")
            if code in laws:
                raise ValueError(f"contact model {name!r}: code {code} is taken by another model")
            laws[code] = kernel
    return laws


def _pull_offs() -> dict:
    """{CODE: pull_off kernel} of every registered adhesive contact model."""
    out = {}
    for name in contact_models.names():
        cls = contact_models.get(name)
        if cls.adhesive:
            kernel = getattr(sys.modules[cls.__module__], "pull_off", None)
            if kernel is None:
                raise TypeError(f"contact model {name!r}: an adhesive law needs a pull_off(p, r_eff) kernel")
            out[cls.code] = kernel
    return out


# (elastic normal force [N], η_n [N s/m], k_t [N/m], η_t [N s/m]) of the model coded in p[0]: the plain pair and
# wall code (vectorised over contacts) sees the main code of each non-adhesive law only (a further branch changes
# the vector code LLVM makes of the others, and with fastmath their round-off); ``contact_force_full`` sees all
coefficients = compiled_switch("coefficients", _force_laws(False), ("p", "overlap", "m_eff", "r_eff"), "int(p[0])",
                               "0.0, 0.0, 0.0, 0.0", __name__, __file__, error_model="numpy", inline="always")
full_coefficients = compiled_switch("full_coefficients", _force_laws(True), ("p", "overlap", "m_eff", "r_eff"),
                                    "int(p[0])", "0.0, 0.0, 0.0, 0.0", __name__, __file__, error_model="numpy",
                                    inline="always")
# (pull-off force F_c [N], pull-off distance |δ_c| [m]) of an adhesive law; (0, 0) for the others
pull_off = compiled_switch("pull_off", _pull_offs(), ("p", "r_eff"), "int(p[0])", "0.0, 0.0", __name__, __file__,
                           error_model="numpy", inline="always")


@njit(cache=True, error_model="numpy", inline="always")
def _tangential(flim, k_t, eta_t, vn, nx, ny, nz, vx, vy, vz, wx, wy, wz, dt, hx, hy, hz, update):
    """Tangential force on i and the new spring of a contact (Sun 2007 eqs 19–20, 22), limited to flim [N]."""
    # relative tangential velocity of the contact point, Sun 2007 eq. 19
    cx = wy * nz - wz * ny
    cy = wz * nx - wx * nz
    cz = wx * ny - wy * nx
    tx = vx - vn * nx - cx
    ty = vy - vn * ny - cy
    tz = vz - vn * nz - cz
    # keep the history in the current tangent plane with its magnitude (rigid rotation, eq. 20)
    hn = hx * nx + hy * ny + hz * nz
    h2 = hx * hx + hy * hy + hz * hz
    hx -= hn * nx
    hy -= hn * ny
    hz -= hn * nz
    h2p = hx * hx + hy * hy + hz * hz
    s = math.sqrt(h2 / max(h2p, TINY))
    s = s if h2p > 0.0 else 1.0
    du = dt if update else 0.0
    hx = hx * s + tx * du
    hy = hy * s + ty * du
    hz = hz * s + tz * du
    ftx = -k_t * hx - eta_t * tx  # Sun 2007 eq. 22
    fty = -k_t * hy - eta_t * ty
    ftz = -k_t * hz - eta_t * tz
    # Coulomb limit: on slip the force is scaled to flim and the spring reset to match it
    ft2 = ftx * ftx + fty * fty + ftz * ftz
    slip = ft2 > flim * flim
    s = flim / math.sqrt(max(ft2, TINY))
    s = s if slip else 1.0
    ftx *= s
    fty *= s
    ftz *= s
    kt = max(k_t, TINY)
    keep = 1.0 if k_t > 0.0 else 0.0  # a spring without stiffness holds nothing
    gx = -(ftx + eta_t * tx) / kt * keep
    gy = -(fty + eta_t * ty) / kt * keep
    gz = -(ftz + eta_t * tz) / kt * keep
    hx = gx if slip else hx
    hy = gy if slip else hy
    hz = gz if slip else hz
    return ftx, fty, ftz, hx, hy, hz


@njit(cache=True, error_model="numpy", inline="always")
def contact_force(p, overlap, nx, ny, nz, vx, vy, vz, wx, wy, wz, m_eff, r_eff, dt, hx, hy, hz, update):
    """Force on body i of a contact, and the updated tangential history.

    Parameters
    ----------
    p : (8,) float64 packed parameters (see ``base.py``)
    overlap : δ > 0 [m]
    n : unit normal from j to i
    v : v_i − v_j [m/s] (translational)
    w : a_i ω_i + a_j ω_j [m/s] (rotational part of the contact-point velocity, Sun 2007 eq. 19)
    h : tangential spring displacement u_t [m] before the step
    update : if False the history is returned unchanged (force evaluation for analysis)

    Returns
    -------
    (fn, ftx, fty, ftz, hx, hy, hz): signed normal force magnitude [N] along n
    (positive = repulsive), tangential force on i [N], new history [m].
    """
    fel, eta_n, k_t, eta_t = coefficients(p, overlap, m_eff, r_eff)
    vn = vx * nx + vy * ny + vz * nz
    fn = fel - eta_n * vn  # Sun 2007 eq. 21 (unclamped, as eqs 25-26 assume)
    ftx, fty, ftz, hx, hy, hz = _tangential(p[7] * max(fn, 0.0), k_t, eta_t, vn, nx, ny, nz, vx, vy, vz, wx, wy, wz,
                                            dt, hx, hy, hz, update)
    return fn, ftx, fty, ftz, hx, hy, hz


@njit(cache=True, error_model="numpy", inline="always")
def _rolling_spring(p, load, k_t, r_eff, i_r, nx, ny, nz, rx, ry, rz, dt, gx, gy, gz, update):
    """Rolling torque on i [N m] and the new spring torque of an ``epsd`` contact (slot 9 = ROLLING_EPSD).

    The elastic–plastic spring–dashpot of Ai, Chen, Rotter & Ooi (2011, model C, eqs 13-18), with the rolling
    stiffness k_r = k_t R*² of Iwashita & Oda (1998) (LIGGGHTS ``rolling_friction epsd2``; k_t the law's
    tangential stiffness at this overlap):

        M_k ← M_k − k_r Δθ_r,   Δθ_r = ω_r,t Δt                       (Ai 2011 eq. 13)
        |M_k| ≤ M_m = μ_r R* F   (full mobilisation: M_k scaled to M_m)  (eq. 14)
        M_d = −C_r ω_r,t below the limit, 0 at it (f = 0),
        C_r = η_r 2 sqrt(I_r k_r)                                       (eqs 17-18)

    ω_r,t: the relative spin ω_i − ω_j without its part along n (torsion is not resisted); the stored M_k is
    first turned into the current tangent plane with its magnitude kept, as the tangential spring (Sun 2007
    eq. 20). I_r [kg m²]: the rolling inertia of the contact, 1/(1/(I_i + m_i a_i²) + 1/(I_j + m_j a_j²))
    (Ai 2011 eq. 18; I_i + m_i a_i² against a wall). F = max(F_n + 2 F_c, 0) [N], the load.
    Returns (mx, my, mz, gx, gy, gz): the torque M_k + M_d on i, and M_k (history; unchanged in magnitude
    without ``update``).
    """
    rn = rx * nx + ry * ny + rz * nz
    tx = rx - rn * nx
    ty = ry - rn * ny
    tz = rz - rn * nz
    gn = gx * nx + gy * ny + gz * nz
    g2 = gx * gx + gy * gy + gz * gz
    gx -= gn * nx
    gy -= gn * ny
    gz -= gn * nz
    g2p = gx * gx + gy * gy + gz * gz
    s = math.sqrt(g2 / g2p) if g2p > 0.0 else 1.0
    k_r = k_t * r_eff * r_eff
    du = dt if update else 0.0
    gx = gx * s - k_r * tx * du
    gy = gy * s - k_r * ty * du
    gz = gz * s - k_r * tz * du
    limit = p[8] * r_eff * load
    g2 = gx * gx + gy * gy + gz * gz
    if g2 > limit * limit:  # full mobilisation: the spring slips at the limit, no damping (f = 0)
        s = limit / math.sqrt(g2)
        gx *= s
        gy *= s
        gz *= s
        return gx, gy, gz, gx, gy, gz
    c_r = p[11] * 2.0 * math.sqrt(i_r * k_r)
    return gx - c_r * tx, gy - c_r * ty, gz - c_r * tz, gx, gy, gz


@njit(cache=True, error_model="numpy", inline="always")
def contact_force_full(p, overlap, nx, ny, nz, vx, vy, vz, wx, wy, wz, rx, ry, rz, m_eff, r_eff, i_r, dt, hx, hy, hz,
                       gx, gy, gz, update):
    """``contact_force`` for every law, adhesive ones included, with rolling resistance.

    As ``contact_force``, and: ``overlap`` may be negative for an adhesive law (a formed contact pulled
    apart, down to its pull-off distance); r : ω_i − ω_j [rad/s], the relative spin (ω_i against a wall);
    i_r : the contact's rolling inertia [kg m²] (``_rolling_spring``; read by the ``epsd`` damping only);
    g : the rolling spring torque [N m] of an ``epsd`` contact before the step (zeros for the other models).

    Returns
    -------
    (fn, ftx, fty, ftz, hx, hy, hz, reach, mx, my, mz, gx, gy, gz): as ``contact_force``; reach: the pull-off
    distance |δ_c| [m] of an adhesive law (0 otherwise), down to which the contact lasts; m: rolling-resistance
    torque on i [N m] (−m on j); g: the new rolling spring torque (``epsd``; g as given otherwise). The model
    in slot 9: ROLLING_CDT, the constant directional torque −μ_r R* F ω_r/|ω_r| (Ai et al. 2011 model A;
    LIGGGHTS ``rolling_friction cdt``); ROLLING_EPSD, the spring–dashpot of ``_rolling_spring``. The load
    F = max(F_n + 2 F_c, 0) also sets the Coulomb limit μ F (F_c the pull-off force, Thornton & Yin 1991;
    F = max(F_n, 0) for a non-adhesive law).
    """
    fel, eta_n, k_t, eta_t = full_coefficients(p, overlap, m_eff, r_eff)
    f_c, reach = pull_off(p, r_eff)
    vn = vx * nx + vy * ny + vz * nz
    fn = fel - eta_n * vn  # Sun 2007 eq. 21
    load = max(fn + 2.0 * f_c, 0.0)
    ftx, fty, ftz, hx, hy, hz = _tangential(p[7] * load, k_t, eta_t, vn, nx, ny, nz, vx, vy, vz, wx, wy, wz,
                                            dt, hx, hy, hz, update)
    if p[9] == ROLLING_EPSD:
        mx, my, mz, gx, gy, gz = _rolling_spring(p, load, k_t, r_eff, i_r, nx, ny, nz, rx, ry, rz, dt, gx, gy, gz,
                                                 update)
        return fn, ftx, fty, ftz, hx, hy, hz, reach, mx, my, mz, gx, gy, gz
    spin = math.sqrt(rx * rx + ry * ry + rz * rz)
    mr = p[8] * r_eff * load / max(spin, TINY)
    mr = mr if spin > 0.0 else 0.0
    return fn, ftx, fty, ftz, hx, hy, hz, reach, -mr * rx, -mr * ry, -mr * rz, gx, gy, gz
