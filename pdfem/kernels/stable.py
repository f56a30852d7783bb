"""Critical time step of explicit central differences for 4-node quads.

For element e:  dt_e = L_e / c_p  with
    L_e = A_e / max(|x_3 - x_1|, |x_4 - x_2|)   (area over the longest diagonal),
    c_p = sqrt((K + 4G/3) / rho)                 (plane-strain P-wave speed, table density;
                                                 K at the element's pressure with an EOS).
A unit square gives L_e = 1/sqrt(2). The value carries no safety factor: the caller applies
its Courant number. The table density rho0 is used (no current volume is kept), which is
conservative under compression.
"""

import numpy as np
from numba import njit

from pdfem.kernels.eos import wave_speed


@njit(cache=True)
def element_length(x, conn, e):
    """(area, L_e) of element e: L_e = area / longest diagonal (module docstring)."""
    n1 = conn[e, 0]
    n2 = conn[e, 1]
    n3 = conn[e, 2]
    n4 = conn[e, 3]
    # Diagonals and area (half their cross product)
    d1x = x[n3, 0] - x[n1, 0]
    d1y = x[n3, 1] - x[n1, 1]
    d2x = x[n4, 0] - x[n2, 0]
    d2y = x[n4, 1] - x[n2, 1]
    a = 0.5 * (d1x * d2y - d2x * d1y)
    if a <= 0.0:
        return a, 0.0
    return a, a / np.sqrt(max(d1x * d1x + d1y * d1y, d2x * d2x + d2y * d2y))


@njit(cache=True)
def q4_stable_dt(x, conn, emat, mat_params, sig, e0, e1):
    """Min over elements [e0, e1) of L_e / c_p (see module docstring); +inf if the range is empty.

    sig (ne, nip, 4): the elements' stresses, whose pressures set the bulk modulus of a
    material with an equation of state (pdfem.kernels.eos.wave_speed).

    An element with non-positive area gives 0.0, so a caller's dt guard trips on it.
    """
    dt = np.inf
    for e in range(e0, e1):
        a, le = element_length(x, conn, e)
        if a <= 0.0:
            return 0.0
        # P-wave speed of the element's material
        cp = wave_speed(mat_params[emat[e]], sig, e)
        dt = min(dt, le / cp)
    return dt
