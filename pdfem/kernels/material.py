"""Material dispatch: one material point update chosen by the model id column of the table.

Status codes returned by ``material_update``:
    0   success
    -1  unknown model id (the element kernels then report the element)
    > 0 the cap return failed (pdfem.kernels.cap status codes)
"""

from numba import njit

from pdfem.kernels.cap import cap_initial_state, cap_update
from pdfem.kernels.elastic import elastic_update
from pdfem.kernels.params import (
    BULK,
    CAP,
    CAP_A,
    CAP_C,
    ELASTIC,
    MODEL,
    SHEAR,
    SOFT_K,
    SOFT_Y,
    T_REF,
)

MAT_OK = 0
MAT_UNKNOWN_MODEL = -1
# Moduli and strength never soften below this fraction of their reference value
SOFT_FLOOR = 0.05


@njit(cache=True)
def material_update(p, sig, deps, st, dt=0.0):
    """Update stress sig (4,) in place for strain increment deps (4,) and state row st over a
    step of duration dt (used only by a rate-dependent cap, p[CAP_TAU] > 0).

    Returns (status, dwp): status 0 on success or a negative code (see module docstring);
    dwp is the plastic work density increment [J/m^3]. The stress is left untouched when
    the model id is unknown.
    """
    model = int(p[MODEL])
    # Isotropic hypo-elasticity
    if model == ELASTIC:
        return MAT_OK, elastic_update(p, sig, deps, st)
    # Sandler-Rubin cap plasticity (state row of CAP_NST values)
    if model == CAP:
        return cap_update(p, sig, deps, st, dt)
    return MAT_UNKNOWN_MODEL, 0.0


@njit(cache=True)
def material_initial_state(mst, emat, mat_params):
    """Initial internal state of every integration point of every element (cap: kappa_0)."""
    if mst.shape[2] == 0:
        return
    for e in range(mst.shape[0]):
        p = mat_params[emat[e]]
        if int(p[MODEL]) == CAP:
            for q in range(mst.shape[1]):
                cap_initial_state(p, mst[e, q])


@njit(cache=True)
def softened(p, t, out):
    """Parameter row p at temperature t into out: moduli and strength scaled linearly.

    K, G <- K, G max(SOFT_FLOOR, 1 - p[SOFT_K] (t - p[T_REF])); the cap envelope constants
    A, C <- A, C max(SOFT_FLOOR, 1 - p[SOFT_Y] (t - p[T_REF])).
    """
    for i in range(p.shape[0]):
        out[i] = p[i]
    fk = max(SOFT_FLOOR, 1.0 - p[SOFT_K] * (t - p[T_REF]))
    fy = max(SOFT_FLOOR, 1.0 - p[SOFT_Y] * (t - p[T_REF]))
    out[BULK] = p[BULK] * fk
    out[SHEAR] = p[SHEAR] * fk
    out[CAP_A] = p[CAP_A] * fy
    out[CAP_C] = p[CAP_C] * fy
