"""Material dispatch: one material point update chosen by the model id column of the table.

Status codes returned by ``material_update``:
    0   success
    -1  unknown or not-yet-wired model id (the element kernels then report the element)
"""

from numba import njit

from pdfem.kernels.elastic import elastic_update
from pdfem.kernels.params import ELASTIC, MODEL

MAT_OK = 0
MAT_UNKNOWN_MODEL = -1


@njit(cache=True)
def material_update(p, sig, deps, st):
    """Update stress sig (4,) in place for strain increment deps (4,) and state row st.

    Returns (status, dwp): status 0 on success or a negative code (see module docstring);
    dwp is the plastic work density increment [J/m^3]. The stress is left untouched when
    the model id is unknown.
    """
    model = int(p[MODEL])
    # Isotropic hypo-elasticity
    if model == ELASTIC:
        return MAT_OK, elastic_update(p, sig, deps, st)
    # CAP: lead wires `if model == CAP: return MAT_OK, cap_update(p, sig, deps, st)` here
    return MAT_UNKNOWN_MODEL, 0.0
