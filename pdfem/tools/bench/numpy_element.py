"""Plain-numpy twins of the element force kernels (elastic only), for ``pdfem bench elements``.

Same arguments, same algorithm and the same operation order as
pdfem.kernels.element.q4_forces_1pt / q4_forces_2x2, vectorised over elements with an
np.add.at scatter (which adds in element order, as the numba loop does). Only the ELASTIC
model is supported; any other model id raises ValueError.
"""

import time

import numpy as np

from pdfem.kernels.params import BULK, ELASTIC, EOS_S, MODEL, SHEAR

_XI = np.array([-1.0, 1.0, 1.0, -1.0])
_ETA = np.array([-1.0, -1.0, 1.0, 1.0])
_HG = np.array([1.0, -1.0, 1.0, -1.0])
_GP = 0.5773502691896257


def _elastic_params(mat_params, emat):
    """(K, G) per element; refuse anything but the elastic model with a linear bulk."""
    p = mat_params[emat]
    if np.any(p[:, MODEL].astype(np.int64) != ELASTIC) or np.any(p[:, EOS_S] > 0.0):
        raise ValueError("numpy element reference supports the ELASTIC model only, without "
                         "an equation of state")
    return p[:, BULK], p[:, SHEAR]


def _bvec(xe):
    """Area (n,) and centroid gradients bx, by (n,4) of quads xe (n,4,2)."""
    a = 0.5 * ((xe[:, 2, 0] - xe[:, 0, 0]) * (xe[:, 3, 1] - xe[:, 1, 1])
               - (xe[:, 3, 0] - xe[:, 1, 0]) * (xe[:, 2, 1] - xe[:, 0, 1]))
    with np.errstate(divide="ignore"):
        r = 1.0 / (2.0 * a)
    nxt = [1, 2, 3, 0]
    prv = [3, 0, 1, 2]
    bx = (xe[:, nxt, 1] - xe[:, prv, 1]) * r[:, None]
    by = (xe[:, prv, 0] - xe[:, nxt, 0]) * r[:, None]
    return a, bx, by


def _ip_grad(xe, xi, eta):
    """det J (n,) and shape function gradients dx, dy (n,4) at (xi, eta)."""
    dxi = 0.25 * _XI * (1.0 + _ETA * eta)
    deta = 0.25 * _ETA * (1.0 + _XI * xi)
    j11 = j12 = j21 = j22 = 0.0
    for i in range(4):
        j11 = j11 + dxi[i] * xe[:, i, 0]
        j12 = j12 + deta[i] * xe[:, i, 0]
        j21 = j21 + dxi[i] * xe[:, i, 1]
        j22 = j22 + deta[i] * xe[:, i, 1]
    det = j11 * j22 - j12 * j21
    with np.errstate(divide="ignore"):
        r = 1.0 / det
    dx = (j22[:, None] * dxi - j21[:, None] * deta) * r[:, None]
    dy = (j11[:, None] * deta - j12[:, None] * dxi) * r[:, None]
    return det, dx, dy


def _stress_points(s, ue, dx, dy, kb, gs):
    """Objective elastic update of stresses s (n,4) in place; returns the work density."""
    gxx = gxy = gyx = gyy = 0.0
    for i in range(4):
        gxx = gxx + ue[:, i, 0] * dx[:, i]
        gxy = gxy + ue[:, i, 0] * dy[:, i]
        gyx = gyx + ue[:, i, 1] * dx[:, i]
        gyy = gyy + ue[:, i, 1] * dy[:, i]
    w = 0.5 * (gxy - gyx)
    d = 1.0 / (1.0 + 0.25 * w * w)
    c = (1.0 - 0.25 * w * w) * d
    sn = w * d
    sxx, syy, sxy = s[:, 0].copy(), s[:, 1].copy(), s[:, 2].copy()
    s[:, 0] = c * c * sxx + 2.0 * c * sn * sxy + sn * sn * syy
    s[:, 1] = sn * sn * sxx - 2.0 * c * sn * sxy + c * c * syy
    s[:, 2] = c * sn * (syy - sxx) + (c * c - sn * sn) * sxy
    dep = np.stack([gxx, gyy, 0.5 * (gxy + gyx), np.zeros_like(gxx)], axis=1)
    sold = s.copy()
    g2 = 2.0 * gs
    lam = kb - g2 / 3.0
    dv = dep[:, 0] + dep[:, 1] + dep[:, 3]
    s[:, 0] += lam * dv + g2 * dep[:, 0]
    s[:, 1] += lam * dv + g2 * dep[:, 1]
    s[:, 2] += g2 * dep[:, 2]
    s[:, 3] += lam * dv + g2 * dep[:, 3]
    wd = 0.5 * ((sold[:, 0] + s[:, 0]) * dep[:, 0] + (sold[:, 1] + s[:, 1]) * dep[:, 1]
                + 2.0 * (sold[:, 2] + s[:, 2]) * dep[:, 2] + (sold[:, 3] + s[:, 3]) * dep[:, 3])
    return wd


def _first_bad(ok, e0, e1):
    """Elements to process and the return code: stop before the first failing element."""
    bad = np.flatnonzero(~ok)
    if bad.size == 0:
        return e1, -1
    return e0 + int(bad[0]), e0 + int(bad[0])


def _scatter(f, c, fe):
    """f -= fe node by node in element order."""
    np.add.at(f, (c.ravel(), 0), -fe[:, :, 0].ravel())
    np.add.at(f, (c.ravel(), 1), -fe[:, :, 1].ravel())


def _hg_gamma(xe, bx, by):
    """Flanagan-Belytschko hourglass vectors (n,4)."""
    hx = hy = 0.0
    for i in range(4):
        hx = hx + _HG[i] * xe[:, i, 0]
        hy = hy + _HG[i] * xe[:, i, 1]
    return 0.25 * (_HG - hx[:, None] * bx - hy[:, None] * by)


def hourglass_reference(x, conn, hg_coef):
    """numpy twin of pdfem.kernels.element_1pt.hourglass_reference: (ne, 6) hourglass
    vectors, geometric factors and areas in the configuration x."""
    xe = x[conn]
    a, bx, by = _bvec(xe)
    hg = np.empty((conn.shape[0], 6))
    hg[:, :4] = _hg_gamma(xe, bx, by)
    hg[:, 0] = -(hg[:, 1] + hg[:, 2] + hg[:, 3])
    bb = 0.0
    for i in range(4):
        bb = bb + (bx[:, i] * bx[:, i] + by[:, i] * by[:, i])
    hg[:, 4] = hg_coef * np.maximum(a, 0.0) * bb
    hg[:, 5] = a
    return hg


def numpy_forces_1pt(x, du, conn, emat, mat_params, sig, mstate, hg, hg_model, e0, e1, f, ewint,
                     ewp, eth=None):
    """numpy twin of q4_forces_1pt (elastic only); returns -1 or the first bad element."""
    am, _, _ = _bvec(x[conn[e0:e1]] - 0.5 * du[conn[e0:e1]])
    ac, _, _ = _bvec(x[conn[e0:e1]])
    stop, rc = _first_bad((am > 0.0) & (ac > 0.0), e0, e1)
    c = conn[e0:stop]
    kb, gs = _elastic_params(mat_params, emat[e0:stop])
    xc = x[c]
    ue = du[c]
    xm = xc - 0.5 * ue
    # Stress update at mid-step
    am, bx, by = _bvec(xm)
    s = sig[e0:stop, 0].copy()
    wd = _stress_points(s, ue, bx, by, kb, gs)
    sig[e0:stop, 0] = s
    # Forces at the current configuration
    a, bx, by = _bvec(xc)
    ewint[e0:stop] += wd * a
    ewp[e0:stop] += 0.0 * a
    fe = np.empty((stop - e0, 4, 2))
    fe[:, :, 0] = a[:, None] * (s[:, 0, None] * bx + s[:, 2, None] * by)
    fe[:, :, 1] = a[:, None] * (s[:, 2, None] * bx + s[:, 1, None] * by)
    if hg.shape[0] > 0:
        # The hourglass mode of the current and the last positions, its energy's change (a
        # linear bulk: the spring's modulus does not change with the area)
        m = {1: 8.0 * gs * (3.0 * kb + gs) / (3.0 * (3.0 * kb + 4.0 * gs)),
             2: 2.0 * (kb + 7.0 * gs / 3.0) / 3.0}.get(hg_model, kb + 4.0 * gs / 3.0)
        g, k = hg[e0:stop, :4], hg[e0:stop, 4] * m
        q0 = q1 = p0 = p1 = 0.0
        for i in range(1, 4):
            q0 = q0 + g[:, i] * (xc[:, i, 0] - xc[:, 0, 0])
            q1 = q1 + g[:, i] * (xc[:, i, 1] - xc[:, 0, 1])
        for i in range(1, 4):
            p0 = p0 + g[:, i] * (ue[:, i, 0] - ue[:, 0, 0])
            p1 = p1 + g[:, i] * (ue[:, i, 1] - ue[:, 0, 1])
        p0, p1 = q0 - p0, q1 - p1
        ewint[e0:stop] += 0.5 * k * ((q0 * q0 + q1 * q1) - (p0 * p0 + p1 * p1))
        fe[:, :, 0] += (k * q0)[:, None] * g
        fe[:, :, 1] += (k * q1)[:, None] * g
    _scatter(f, c, fe)
    return rc


def numpy_forces_2x2(x, du, conn, emat, mat_params, sig, mstate, hg, hg_model, e0, e1, f, ewint,
                     ewp, eth=None):
    """numpy twin of q4_forces_2x2 (elastic only); returns -1 or the first bad element."""
    xc = x[conn[e0:e1]]
    xm = xc - 0.5 * du[conn[e0:e1]]
    ok = np.ones(e1 - e0, dtype=bool)
    for ip in range(4):
        ok &= _ip_grad(xm, _GP * _XI[ip], _GP * _ETA[ip])[0] > 0.0
        ok &= _ip_grad(xc, _GP * _XI[ip], _GP * _ETA[ip])[0] > 0.0
    stop, rc = _first_bad(ok, e0, e1)
    c = conn[e0:stop]
    kb, gs = _elastic_params(mat_params, emat[e0:stop])
    xc = x[c]
    ue = du[c]
    xm = xc - 0.5 * ue
    fe = np.zeros((stop - e0, 4, 2))
    for ip in range(4):
        xi = _GP * _XI[ip]
        eta = _GP * _ETA[ip]
        # Stress update at mid-step, forces and work at the current configuration
        _, dx, dy = _ip_grad(xm, xi, eta)
        s = sig[e0:stop, ip].copy()
        wd = _stress_points(s, ue, dx, dy, kb, gs)
        sig[e0:stop, ip] = s
        dv, dx, dy = _ip_grad(xc, xi, eta)
        ewint[e0:stop] += wd * dv
        ewp[e0:stop] += 0.0 * dv
        fe[:, :, 0] += dv[:, None] * (s[:, 0, None] * dx + s[:, 2, None] * dy)
        fe[:, :, 1] += dv[:, None] * (s[:, 2, None] * dx + s[:, 1, None] * dy)
    _scatter(f, c, fe)
    return rc


def bench_mesh(nx, ny, jitter=0.2, seed=0):
    """A jittered nx x ny grid of unit-size quads: (x (nn,2), conn (ne,4) int64)."""
    rng = np.random.default_rng(seed)
    gx, gy = np.meshgrid(np.arange(nx + 1.0), np.arange(ny + 1.0), indexing="xy")
    x = np.stack([gx.ravel(), gy.ravel()], axis=1)
    inner = (gx.ravel() > 0) & (gx.ravel() < nx) & (gy.ravel() > 0) & (gy.ravel() < ny)
    x[inner] += rng.uniform(-jitter, jitter, size=(int(inner.sum()), 2))
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="xy")
    n0 = (j * (nx + 1) + i).ravel()
    conn = np.stack([n0, n0 + 1, n0 + nx + 2, n0 + nx + 1], axis=1).astype(np.int64)
    return x, conn


def bench_elements(nx=200, ny=200, reps=5, rule="1pt"):
    """Seconds per call of the numba kernel and its numpy twin on a bench_mesh (dict)."""
    from pdfem.kernels.element import q4_forces_2x2
    from pdfem.kernels.element_1pt import q4_forces_1pt
    from pdfem.kernels.params import NPAR, RHO

    x, conn = bench_mesh(nx, ny)
    ne = conn.shape[0]
    nip = 1 if rule == "1pt" else 4
    mat = np.zeros((1, NPAR))
    mat[0, [MODEL, RHO, BULK, SHEAR]] = [ELASTIC, 2000.0, 1e10, 6e9]
    du = np.random.default_rng(1).uniform(-1e-6, 1e-6, size=x.shape)
    emat = np.zeros(ne, dtype=np.int32)
    out = {"elements": ne, "rule": rule}
    hg = hourglass_reference(x, conn, 0.1) if rule == "1pt" else np.zeros((0, 6))
    kernels = {"1pt": (q4_forces_1pt, numpy_forces_1pt), "2x2": (q4_forces_2x2, numpy_forces_2x2)}
    for name, fn in zip(("numba", "numpy"), kernels[rule], strict=True):
        sig = np.zeros((ne, nip, 4))
        args = (x + du, du, conn, emat, mat, sig, np.zeros((ne, nip, 0)), hg, 0, 0, ne,
                np.zeros_like(x), np.zeros(ne), np.zeros(ne), np.zeros((0, 3)))
        fn(*args)  # warm-up (numba compile / cache load)
        t0 = time.perf_counter()
        for _ in range(reps):
            fn(*args)
        out[name] = (time.perf_counter() - t0) / reps
    return out
