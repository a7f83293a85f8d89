"""Compiled finite-volume operators of the staggered grid, named for where their result lives.

Small ``@njit`` functions of arrays and scalars, inlined into the solver kernels:
face values of a transported quantity (first-order upwind or TVD), the stresses of
Hoomans 1996 eq. 48 at cell centres and cell corners, and interpolations from
centres to faces. Index conventions are those of the padded solver arrays (see
``grid.py``): a centre array has one ring of boundary cells (cell (i, j) at
``[i + 1, j + 1]``), a face array two layers of ghost faces (face (i, j) at
``[i + 2, j + 2]``).
"""
from numba import njit

UPWIND, TVD = 0, 1  # convection schemes


@njit(cache=True, error_model="numpy", inline="always")
def van_leer(r):
    """Van Leer limiter ψ(r) = (r + |r|) / (1 + |r|): TVD, second order where the field is smooth."""
    a = abs(r)
    return (r + a) / (1.0 + a)


@njit(cache=True, error_model="numpy", inline="always")
def face_value(flux, q_mm, q_m, q_p, q_pp, scheme):
    """Value of q carried across a face by ``flux`` (> 0 from the minus side to the plus side).

    ``q_m``, ``q_p`` are the values either side of the face, ``q_mm``, ``q_pp`` the
    next ones out. UPWIND: the donor value. TVD: q_C + ψ(r) (q_D − q_C) / 2 with
    r = (q_C − q_U) / (q_D − q_C) and the van Leer limiter ψ.
    """
    pos = flux >= 0.0
    c = q_m if pos else q_p  # selects, not branches: the sign of the flux is unpredictable
    if scheme == UPWIND:
        return c
    u = q_mm if pos else q_pp
    d = q_p if pos else q_m
    dd = d - c
    if dd == 0.0:
        return c
    return c + 0.5 * van_leer((c - u) / dd) * dd


@njit(cache=True, error_model="numpy", inline="always")
def normal_stresses_at_centre(U, V, E, mu, dx, dy, ci, cj):
    """(σ_xx, σ_yy) [Pa] of ε τ_g at the centre of cell (ci, cj), Hoomans 1996 eq. 48 with λ_g = 0.

    σ_xx = ε μ (2 ∂u/∂x − 2/3 ∇·u), σ_yy = ε μ (2 ∂v/∂y − 2/3 ∇·u); the sign is that of
    the stress acting on the gas (minus the τ_g of eq. 48).
    """
    dudx = (U[ci + 3, cj + 2] - U[ci + 2, cj + 2]) * (1.0 / dx)  # 1/dx: hoisted out of the callers' loops
    dvdy = (V[ci + 2, cj + 3] - V[ci + 2, cj + 2]) * (1.0 / dy)
    em = E[ci + 1, cj + 1] * mu
    third = (2.0 / 3.0) * (dudx + dvdy)
    return em * (2.0 * dudx - third), em * (2.0 * dvdy - third)


@njit(cache=True, error_model="numpy", inline="always")
def shear_stress_at_corner(U, V, E, mu, dx, dy, i, j):
    """ε μ (∂u/∂y + ∂v/∂x) [Pa] at the corner (x_i, y_j) where x-face line i meets y-face line j.

    Hoomans 1996 eq. 48 (off-diagonal); ε is the mean of the four cells around the corner.
    """
    dudy = (U[i + 2, j + 2] - U[i + 2, j + 1]) * (1.0 / dy)
    dvdx = (V[i + 2, j + 2] - V[i + 1, j + 2]) * (1.0 / dx)
    ec = 0.25 * (E[i, j] + E[i + 1, j] + E[i, j + 1] + E[i + 1, j + 1])
    return ec * mu * (dudy + dvdx)


@njit(cache=True, error_model="numpy")
def centre_to_x_faces(q, periodic, out):
    """out (nx + 1, ny) = q (nx, ny) averaged onto x-faces; boundary faces take the adjacent cell
    (or, ``periodic``, the mean of the two cells the face joins)."""
    nx, ny = q.shape
    for j in range(ny):
        for i in range(1, nx):
            out[i, j] = 0.5 * (q[i - 1, j] + q[i, j])
        if periodic:
            out[0, j] = out[nx, j] = 0.5 * (q[nx - 1, j] + q[0, j])
        else:
            out[0, j] = q[0, j]
            out[nx, j] = q[nx - 1, j]


@njit(cache=True, error_model="numpy")
def centre_to_y_faces(q, periodic, out):
    """out (nx, ny + 1) = q (nx, ny) averaged onto y-faces; boundary faces as in ``centre_to_x_faces``."""
    nx, ny = q.shape
    for i in range(nx):
        for j in range(1, ny):
            out[i, j] = 0.5 * (q[i, j - 1] + q[i, j])
        if periodic:
            out[i, 0] = out[i, ny] = 0.5 * (q[i, ny - 1] + q[i, 0])
        else:
            out[i, 0] = q[i, 0]
            out[i, ny] = q[i, ny - 1]
