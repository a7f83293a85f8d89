"""The data layout that the 3D gas solver (``solver3d.py``) shares with its compiled kernels.

The integer codes (face kinds, ghost rules, step inputs) are those of the 2D layout (``_layout.py``),
re-exported here; the stacks and parameter vectors are laid out for three axes. Every face quantity
is kept for the three directions in one stack, axis ``a`` (0: x, 1: y, 2: z) at index ``a``, each
direction using the leading part of the stack's extent (``n + 1`` along its own axis, ``n`` across).
Index conventions of the padded arrays (``grid.py``): centre arrays ``(nx + 2, ny + 2, nz + 2)`` with
cell (i, j, k) at ``[i + 1, j + 1, k + 1]``; the velocity stack ``W`` ``(3, nx + 5, ny + 5, nz + 5)``
with face (i, j, k) of axis a at ``W[a, i + 2, j + 2, k + 2]`` (two layers of ghost faces).
"""
from ._layout import (  # noqa: F401  (the codes of both layouts are one set)
    COPY,
    FIXED,
    OUTFLOW_FACE,
    R_COPY,
    R_FIXED,
    R_NONE,
    R_WRAP,
    SOLVED,
)

# C (N_C, nx + 2, ny + 2, nz + 2) float64, centre arrays with one ring of boundary cells:
#   C_P         pressure relative to the reference pressure p_ref [Pa]
#   C_RHO       gas density ρ_g [kg/m^3]
#   C_E         voidage ε [-] (at t while the step's explicit terms are made, then at t + dt)
#   C_PFIX      prescribed pressure of the boundary cells at t + dt, relative to p_ref [Pa]
#   C_PFIX_OLD  the same at t [Pa]
#   C_EFIX      prescribed voidage of the boundary cells (influx cells) [-]
#   C_RO_OLD    (ερ) at t [kg/m^3]
C_P, C_RHO, C_E, C_PFIX, C_PFIX_OLD, C_EFIX, C_RO_OLD = range(7)
N_C = 7
# F (N_F, 3, nx + 1, ny + 1, nz + 1) float64, face arrays per direction, without ghost faces:
#   F_OLD   velocity at t [m/s]
#   F_EX    explicit momentum terms: convection and viscous stress [N/m^3]
#   F_BETA  interphase coefficient β [kg m^-3 s^-1]
#   F_RHS   β u_s + momentum source [N/m^3] (a body force of immersed boundaries is one more source here)
#   F_FIX   prescribed velocity of fixed faces [m/s]
#   F_WOUT  share of the outflow of each continuous-outflow face [-]
#   F_FLUX  mass flux A (ερ)_f w along +x / +y / +z [kg/s]
#   F_EF    face voidage ε_f at t + dt [-]
#   F_X1    w_old/dt + g [m/s^2]
#   F_X2    explicit terms + β u_s + source [N/m^3]
#   F_EP    voidage ε_p,f of the pressure term −ε_p,f ∂p/∂x: ε_f
F_OLD, F_EX, F_BETA, F_RHS, F_FIX, F_WOUT, F_FLUX, F_EF, F_X1, F_X2, F_EP = range(11)
N_F = 11
# K (2, 3, nx + 1, ny + 1, nz + 1) int8:
#   K_KIND  face kind (SOLVED, FIXED, OUTFLOW_FACE, COPY)
#   K_SIGN  inward sign: +1 on a low boundary face, -1 on a high one, else 0
K_KIND, K_SIGN = 0, 1
# RULES (2, 9) int64, ghost rule (R_*) per cell flag: RULE_P of the pressure, RULE_E of the voidage
RULE_P, RULE_E = 0, 1
# fpar (N_FPAR,) float64:
#   FP_G         gravity (gx, gy, gz) [m/s^2], slots FP_G .. FP_G + 2
#   FP_H         cell sides (dx, dy, dz) [m], slots FP_H .. FP_H + 2
#   FP_A         face areas (dy dz, dx dz, dx dy) [m^2], slots FP_A .. FP_A + 2
#   FP_DT        time step [s]
#   FP_VOL       cell volume [m^3]
#   FP_COMP      compressibility dρ/dp = M/(RT) [s^2/m^2], 0 for constant density
#   FP_RHOC      the constant density [kg/m^3], 0 for the ideal gas
#   FP_PREF      reference pressure p_ref [Pa]
#   FP_MU        viscosity μ_g [Pa s]
FP_G, FP_H, FP_A = 0, 3, 6
FP_DT, FP_VOL, FP_COMP, FP_RHOC, FP_PREF, FP_MU = range(9, 15)
N_FPAR = 15
# ipar (N_IPAR,) int64:
#   I_N       cells (nx, ny, nz), slots I_N .. I_N + 2
#   I_SCHEME  convection scheme (``_operators.UPWIND``, ``TVD``)
#   I_PIN     position of the diagonal entry of row 0 when the pressure level is pinned, else -1
#   I_THREADS Numba threads in use, set every step: above 1 the kernels' passes over the grid run on them
I_N = 0
I_SCHEME, I_PIN, I_THREADS = 3, 4, 5
N_IPAR = 6
# out (N_OUT,) float64, diagnostics of the last residual:
#   O_RES, O_QREF, O_IN, O_OUT, O_ACC, O_MASS as in ``_layout.py``
O_RES, O_QREF, O_IN, O_OUT, O_ACC, O_MASS = range(6)
N_OUT = 6
