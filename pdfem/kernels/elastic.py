"""Isotropic hypo-elastic material point update (plane strain, sigma_zz carried).

Sign convention: tension positive, compression negative. Stress and strain-increment vectors
are ordered (xx, yy, xy, zz); the xy entry of a strain increment is the tensor component
d_xy = (du_x/dy + du_y/dx)/2, not the engineering shear.

Every material model has the same point signature ``update(p, sig, deps, st) -> dwp``:
p is one row of the material table (see params.py), sig the (4,) stress updated in place,
deps the (4,) strain increment, st the (nst,) internal state row, and the return value the
plastic work density increment [J/m^3].
"""

from numba import njit

from pdfem.kernels.params import BULK, SHEAR


@njit(cache=True)
def elastic_increment(p, d0, d1, d2, d3):
    """Stress increment C:deps (4 scalars) of the strain increment (d0, d1, d2, d3).

    d sigma = lambda tr(deps) I + 2 G deps with lambda = K - 2G/3, K = p[BULK], G = p[SHEAR].
    """
    # Lame constants from bulk and shear moduli
    g2 = 2.0 * p[SHEAR]
    lam = p[BULK] - g2 / 3.0
    dv = d0 + d1 + d3
    return lam * dv + g2 * d0, lam * dv + g2 * d1, g2 * d2, lam * dv + g2 * d3


@njit(cache=True)
def elastic_update(p, sig, deps, st):
    """Add C:deps to sig in place (elastic_increment); return 0.0 plastic work.

    deps[3] (zz) is honoured even though plane strain normally passes 0. st is unused
    (elastic has no state).
    """
    # Hypo-elastic increment, component by component
    i0, i1, i2, i3 = elastic_increment(p, deps[0], deps[1], deps[2], deps[3])
    sig[0] += i0
    sig[1] += i1
    sig[2] += i2
    sig[3] += i3
    return 0.0


@njit(cache=True)
def elastic_energy_density(p, sig):
    """Complementary elastic energy density 0.5 sig:C^-1:sig [J/m^3] of a stress (4,).

    Closed form for isotropic C: tr(sig)^2 / (18 K) + s:s / (4 G), s the 3-D deviator
    (sigma_zz included, xy counted twice). A zero shear modulus drops the deviatoric term.
    """
    # Volumetric part
    tr = sig[0] + sig[1] + sig[3]
    e = tr * tr / (18.0 * p[BULK])
    # Deviatoric part (3-D deviator, symmetric xy counted twice)
    if p[SHEAR] > 0.0:
        m = tr / 3.0
        sx = sig[0] - m
        sy = sig[1] - m
        sz = sig[3] - m
        ss = sx * sx + sy * sy + sz * sz + 2.0 * sig[2] * sig[2]
        e += ss / (4.0 * p[SHEAR])
    return e
