"""Whole-element measures of the 4-node quad: lumped mass and stored elastic energy.

Same element as :mod:`pdfem.kernels.element` (node order, natural coordinates, 2x2 points,
1-point hourglass springs); these kernels read a state and never change it.
"""

import numpy as np
from numba import njit

from pdfem.kernels.elastic import elastic_energy_density
from pdfem.kernels.element import ETA, GP, XI, _bvec, _ip_grad
from pdfem.kernels.element_1pt import HG_POINTS, _tangent_bulk, hourglass_modulus
from pdfem.kernels.hourglass_points import points_energy
from pdfem.kernels.params import RHO, SHEAR


@njit(cache=True)
def q4_lumped_mass(x, conn, emat, mat_params, e0, e1, m):
    """Add the row-sum lumped mass rho int N_I dA (2x2 Gauss, exact) of [e0, e1) to m (nn,).

    Call once on the initial configuration: mass is then conserved by construction.
    """
    xc = np.empty((4, 2))
    dx = np.empty(4)
    dy = np.empty(4)
    for e in range(e0, e1):
        rho = mat_params[emat[e], RHO]
        for i in range(4):
            xc[i, 0] = x[conn[e, i], 0]
            xc[i, 1] = x[conn[e, i], 1]
        for ip in range(4):
            xi = GP * XI[ip]
            eta = GP * ETA[ip]
            # Weight of node i at this point: rho N_i det J
            det = _ip_grad(xc, xi, eta, dx, dy)
            for i in range(4):
                nn = 0.25 * (1.0 + XI[i] * xi) * (1.0 + ETA[i] * eta)
                m[conn[e, i]] += rho * nn * det


@njit(cache=True)
def q4_strain_energy(x, conn, emat, mat_params, sig, hg, hg_model, e0, e1, out):
    """out[e] = stored elastic energy of element e in [e0, e1) [J/m].

    Sum over points of elastic_energy_density(sig) x point volume (current configuration);
    for the 1-point rule with hg.shape[0] > 0 also the hourglass energy k (q.q) / 2 of
    pdfem.kernels.element_1pt (with the element's own material row and the spring's modulus
    hg_model). A
    non-positive area / Jacobian contributes its (non-positive) volume as is.
    """
    nip = sig.shape[1]
    hb = np.empty(8)
    xc = np.empty((4, 2))
    dx = np.empty(4)
    dy = np.empty(4)
    for e in range(e0, e1):
        p = mat_params[emat[e]]
        for i in range(4):
            xc[i, 0] = x[conn[e, i], 0]
            xc[i, 1] = x[conn[e, i], 1]
        en = 0.0
        if nip == 1:
            # Centroid rule plus the hourglass spring energy
            a = _bvec(xc, dx, dy)
            en = elastic_energy_density(p, sig[e, 0]) * a
            if hg.shape[0] > 0 and hg_model == HG_POINTS:
                k, _ = _tangent_bulk(p, 1.0 - a / hg[e, 5])
                eh, _, _ = points_energy(hg[e, 6], hg[e, 7], hg[e, 8], hg[e, 9], hg[e, 10],
                                         hg[e, 11], xc[1, 0] - xc[0, 0], xc[1, 1] - xc[0, 1],
                                         xc[2, 0] - xc[0, 0], xc[2, 1] - xc[0, 1],
                                         xc[3, 0] - xc[0, 0], xc[3, 1] - xc[0, 1],
                                         k - 2.0 * p[SHEAR] / 3.0, p[SHEAR], hb)
                en += eh
            elif hg.shape[0] > 0:
                q0, q1 = 0.0, 0.0
                for i in range(1, 4):
                    q0 += hg[e, i] * (xc[i, 0] - xc[0, 0])
                    q1 += hg[e, i] * (xc[i, 1] - xc[0, 1])
                m, _ = hourglass_modulus(p, 1.0 - a / hg[e, 5], hg_model)
                en += 0.5 * hg[e, 4] * m * (q0 * q0 + q1 * q1)
        else:
            # 2x2 Gauss points
            for ip in range(4):
                dv = _ip_grad(xc, GP * XI[ip], GP * ETA[ip], dx, dy)
                en += elastic_energy_density(p, sig[e, ip]) * dv
        out[e] = en
