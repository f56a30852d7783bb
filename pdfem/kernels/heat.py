"""Heat in the bodies (report eqs. 48-73): conduction, sources, explicit update, stable step.

Temperatures are nodal [K]; heat quantities are per unit thickness (J/m), as every energy of
this plane-strain code. The lumped heat capacity of node I is C_I = sum_e rho_e c_e int N_I dA
(the lumped mass with rho c in place of rho), so the thermal energy sum_I C_I T_I changes
only through the sources: conduction within a body and conductance across a contact move heat
without creating any (every element's conduction flows sum to zero).

Update (forward Euler on the lumped system, the explicit form of eqs. 61, 69, 73):
    T_I <- T_I + (dt q_I + Q_I) / C_I,  q_I = -sum_e int k grad N_I . grad T dA  (2x2 Gauss)
with Q_I the heat [J/m] the step's sources put on node I. Conduction always uses 2x2 Gauss,
whatever the mechanical rule, so a checkerboard temperature is never a zero-energy mode.

Stable step of conduction per element: dt_e = rho c L_e^2 / (2 k), L_e = area / longest
diagonal (the length of the mechanical limit); for a square of side h this is h^2 rho c/(4 k),
half the exact limit h^2 rho c / (2 k) of the lumped bilinear element.

Sign convention (stress only enters through the thermo-elastic source): tension positive,
compression negative, pressure p = -(s_xx + s_yy + s_zz) / 3 positive in compression; a rise
of the pressure of an expanding material heats it.
"""

import numpy as np
from numba import njit

from pdfem.kernels.broad_phase import element_corners
from pdfem.kernels.element import ETA, GP, XI, _ip_grad
from pdfem.kernels.eos import point_compression
from pdfem.kernels.material import softened
from pdfem.kernels.params import ALPHA, COND, CP, EOS_G, RHO, SOFT_K
from pdfem.kernels.stable import element_length


@njit(cache=True)
def conduction_flows(x, temp, conn, emat, mat_params, e0, e1, q):
    """q[I] += -int k grad N_I . grad T dA over elements [e0, e1) (2x2 Gauss) [W/m].

    Each element adds its four flows node by node, in element order; they sum to zero.
    Returns -1, or the first element with a non-positive Jacobian.
    """
    xc = np.empty((4, 2))
    dx = np.empty(4)
    dy = np.empty(4)
    for e in range(e0, e1):
        k = mat_params[emat[e], COND]
        if k == 0.0:
            continue
        element_corners(x, conn, e, xc)
        for ip in range(4):
            dv = _ip_grad(xc, GP * XI[ip], GP * ETA[ip], dx, dy)
            if dv <= 0.0:
                return e
            # Temperature gradient at the point, then the flows -k dv grad N . grad T
            gx = 0.0
            gy = 0.0
            for i in range(4):
                t = temp[conn[e, i]]
                gx += dx[i] * t
                gy += dy[i] * t
            for i in range(4):
                q[conn[e, i]] -= k * dv * (dx[i] * gx + dy[i] * gy)
    return -1


@njit(cache=True)
def conduction_stable_dt(x, conn, emat, mat_params, e0, e1):
    """Min over conducting elements of rho c L_e^2 / (2 k) (module docstring); inf if none."""
    dt = np.inf
    for e in range(e0, e1):
        p = mat_params[emat[e]]
        if p[COND] <= 0.0:
            continue
        a, le = element_length(x, conn, e)
        if a <= 0.0:
            return 0.0
        dt = min(dt, p[RHO] * p[CP] * le * le / (2.0 * p[COND]))
    return dt


@njit(cache=True)
def element_to_nodes(x, conn, e0, e1, val, out):
    """Spread element quantities val[e] over its nodes by int N_I dA / A: out[I] += ...

    Exact for any quad (2x2 Gauss of the bilinear weights); the four shares sum to val[e].
    """
    xc = np.empty((4, 2))
    dx = np.empty(4)
    dy = np.empty(4)
    w = np.empty(4)
    for e in range(e0, e1):
        v = val[e]
        if v == 0.0:
            continue
        element_corners(x, conn, e, xc)
        tot = 0.0
        for i in range(4):
            w[i] = 0.0
        for ip in range(4):
            xi = GP * XI[ip]
            eta = GP * ETA[ip]
            det = _ip_grad(xc, xi, eta, dx, dy)
            for i in range(4):
                s = 0.25 * (1.0 + XI[i] * xi) * (1.0 + ETA[i] * eta) * det
                w[i] += s
                tot += s
        for i in range(4):
            out[conn[e, i]] += v * w[i] / tot


@njit(cache=True)
def _area2(x, conn, e):
    """Twice the area of element e (shoelace)."""
    a = 0.0
    for i in range(4):
        n = conn[e, i]
        m = conn[e, (i + 1) % 4]
        a += x[n, 0] * x[m, 1] - x[m, 0] * x[n, 1]
    return a


@njit(cache=True)
def _tau(x, conn, sig, e):
    """p A of element e: the mean pressure of its integration points, p = -(s_xx + s_yy +
    s_zz) / 3, times its current area (shoelace)."""
    a = _area2(x, conn, e)
    nip = sig.shape[1]
    p = 0.0
    for q in range(nip):
        p -= (sig[e, q, 0] + sig[e, q, 1] + sig[e, q, 3]) / (3.0 * nip)
    return p * 0.5 * a


@njit(cache=True)
def kirchhoff_pressure(x, conn, sig, e0, e1, out):
    """out[e] = p_e A_e (:func:`_tau`) for elements [e0, e1) [J/m]."""
    for e in range(e0, e1):
        out[e] = _tau(x, conn, sig, e)


@njit(cache=True)
def element_areas(x, conn, e0, e1, out):
    """out[e] = the area of element e in [e0, e1) (shoelace) [m^2]."""
    for e in range(e0, e1):
        out[e] = 0.5 * _area2(x, conn, e)


@njit(cache=True)
def _eos_compression(p, sig, mst, e):
    """The mean over the points of element e of their Mie-Gruneisen compression eta
    (pdfem.kernels.eos.point_compression; the energy is the last value of a point's state)."""
    nip = sig.shape[1]
    last = mst.shape[2] - 1
    c = 0.0
    for q in range(nip):
        c += point_compression(p, sig[e, q, 0], sig[e, q, 1], sig[e, q, 3],
                               mst[e, q, last]) / nip
    return c


@njit(cache=True)
def _coupled(x, conn, p, sig, mst, eth, e, pbuf):
    """The state the thermo-elastic heat of element e (material row p) follows: p_e A_e
    (:func:`_tau`) of a linear bulk, the mean compression eta of a Mie-Gruneisen material's
    points (eos_gamma > 0; its row softened at the element temperature eth[e, 1] as in the
    element update, into pbuf)."""
    if not p[EOS_G] > 0.0:
        return _tau(x, conn, sig, e)
    if p[SOFT_K] != 0.0:
        softened(p, eth[e, 1], pbuf)
        p = pbuf
    return _eos_compression(p, sig, mst, e)


@njit(cache=True)
def coupling_state(x, conn, emat, mat_params, sig, mst, eth, e0, e1, out):
    """out[e] = the state the thermo-elastic heat follows (:func:`_coupled`) for elements
    [e0, e1)."""
    pbuf = np.empty(mat_params.shape[1])
    for e in range(e0, e1):
        out[e] = _coupled(x, conn, mat_params[emat[e]], sig, mst, eth, e, pbuf)


# Columns of the per-element heat by mechanism (cumulative since t = 0) [J/m]
H_PLASTIC = 0  # beta x plastic work
H_VISCOUS = 1  # fraction x bulk-viscosity work
H_THERMOELASTIC = 2  # 3 alpha T d(p A), or Gamma0 rho0 c T d(eta) A0 with an EOS
H_FRICTION = 3  # fraction x frictional dissipation at the element's contacts
H_CONDUCTED = 4  # net heat received across its contacts (conductance; sums to zero)
NHEAT = 5


@njit(cache=True)
def element_heat(x, temp, conn, emat, mat_params, sig, mst, eth, area_ref, ewp, ewp_prev, ewq,
                 ewq_prev, tau_prev, beta, gamma, thermoelastic, e0, e1, out, eheat):
    """Heat [J/m] this step's sources put into each element e in [e0, e1): out[e] = ...

    beta (ewp[e] - ewp_prev[e])                 dissipation heating (plastic work, eq. 48)
    3 alpha T_e (tau_e - tau_prev[e])           thermo-elastic coupling of a linear bulk
    Gamma0 rho0 c T_e (eta_e - tau_prev[e]) A0  thermo-elastic coupling of a Mie-Gruneisen
                                                material (eos_gamma > 0)
    gamma (ewq[e] - ewq_prev[e])                viscous heating (bulk-viscosity work)
    with T_e the mean nodal temperature, tau = p A (:func:`kirchhoff_pressure`, from the
    stress just updated), eta_e the mean compression of the element's points and A0 =
    area_ref[e] its reference area (:func:`coupling_state`). For a small elastic change,
    tau - tau_prev = -K A d(eps_v,elastic) + p dA, so the first coupling is eq. 48's
    -3 K alpha T dV with the elastic volume change, plus the pressure's share that makes
    -3 alpha T p A the coupling's energy (see pdfem.effects.heat). The second is the
    adiabatic heating dT = Gamma0 T d(eta) of the form's thermal pressure Gamma0 rho0 c dT,
    its energy already in the stress work (its heat is the coupling's energy, negative).
    ewp_prev, ewq_prev and tau_prev are then set to the new values. beta = 0 skips the first
    term, thermoelastic = False the couplings, gamma = 0 the viscous term (their arrays may
    then be empty). Each term is also added to its column of eheat[e] (H_PLASTIC, ...).
    """
    pbuf = np.empty(mat_params.shape[1])
    for e in range(e0, e1):
        h = 0.0
        if beta > 0.0:
            hp = beta * (ewp[e] - ewp_prev[e])
            h += hp
            eheat[e, H_PLASTIC] += hp
            ewp_prev[e] = ewp[e]
        if thermoelastic:
            te = 0.0
            for i in range(4):
                te += 0.25 * temp[conn[e, i]]
            p = mat_params[emat[e]]
            c = _coupled(x, conn, p, sig, mst, eth, e, pbuf)
            if p[EOS_G] > 0.0:
                # The adiabatic heat of the Mie-Gruneisen form's compression
                ht = p[EOS_G] * (p[RHO] * p[CP]) * te * (c - tau_prev[e]) * area_ref[e]
            else:
                # The linear solid's: 3 alpha T d(p A)
                ht = 3.0 * p[ALPHA] * te * (c - tau_prev[e])
            tau_prev[e] = c
            h += ht
            eheat[e, H_THERMOELASTIC] += ht
        if gamma > 0.0:
            hv = gamma * (ewq[e] - ewq_prev[e])
            h += hv
            eheat[e, H_VISCOUS] += hv
            ewq_prev[e] = ewq[e]
        out[e] = h


@njit(cache=True)
def advance_temperature(temp, q, src, cap, dt, n1, partner):
    """T_I += (dt q_I + src_I) / C_I for nodes [0, n1); q and src are then cleared.

    partner (np,) ties node i < np to node partner[i] (-1: none; periodic sides: a block's
    left and right columns): both take the increment of their summed heat over their summed
    capacity, added in the order of the lower index, so that they keep one temperature and
    each books C_I of the pair's heat. Shape (0,): no ties.
    """
    ntied = partner.shape[0]
    for i in range(n1):
        p = partner[i] if i < ntied else -1
        if p >= 0:
            lo, hi = min(i, p), max(i, p)
            c = cap[lo] + cap[hi]
            if c > 0.0:
                temp[i] += (dt * (q[lo] + q[hi]) + (src[lo] + src[hi])) / c
        elif cap[i] > 0.0:
            temp[i] += (dt * q[i] + src[i]) / cap[i]
    # Cleared once every node has read its partner's heat
    for i in range(n1):
        q[i] = 0.0
        src[i] = 0.0


@njit(cache=True)
def hold_temperature(temp, cap, fixed, tfix, node_body, n1, acc, col):
    """Reset the fixed nodes (fixed[I] = 1) to tfix[I]; acc[b, col] += the heat this took."""
    for i in range(n1):
        if fixed[i]:
            acc[node_body[i], col] += cap[i] * (tfix[i] - temp[i])
            temp[i] = tfix[i]


@njit(cache=True)
def element_thermal_state(temp, temp_prev, conn, e0, e1, eth):
    """eth[e] = (mean nodal temperature increment since temp_prev, mean temperature)."""
    for e in range(e0, e1):
        dt = 0.0
        t = 0.0
        for i in range(4):
            n = conn[e, i]
            dt += 0.25 * (temp[n] - temp_prev[n])
            t += 0.25 * temp[n]
        eth[e, 0] = dt
        eth[e, 1] = t


@njit(cache=True)
def thermal_energy(temp, t0, cap, node_body, n1, out):
    """out[b] = sum over nodes of body b of C_I (T_I - t0) [J/m] (in node order)."""
    for b in range(out.shape[0]):
        out[b] = 0.0
    for i in range(n1):
        out[node_body[i]] += cap[i] * (temp[i] - t0)


@njit(cache=True)
def contact_heat(active, nodes, weights, res, temp, h, fraction, dt, width_col, diss_col,
                 qa, qb, fa, fb):
    """Heat [J/m] of each active contact p on its side A (qa) and side B (qb) this step, and
    the friction part of each (fa, fb).

    Conductance: h w (T_B - T_A) dt flows from B to A (w the contact width res[p, width_col],
    T_A, T_B the temperatures at the contact point of the two sides: weights[p, 0:4] and
    weights[p, 4:8] over nodes[p, 0:4] and nodes[p, 4:8]; a wall side (nodes[p, 4] < 0) has no
    temperature and exchanges nothing). Friction: fraction x the step's frictional
    dissipation res[p, diss_col], half to each side (all of it to A at a wall).
    """
    for p in range(active.shape[0]):
        qa[p] = 0.0
        qb[p] = 0.0
        fa[p] = 0.0
        fb[p] = 0.0
        if active[p] != 1:
            continue
        # Friction heat, split between the sides
        fr = fraction * res[p, diss_col]
        if nodes[p, 4] < 0:
            qa[p] += fr
            fa[p] = fr
            continue
        qa[p] += 0.5 * fr
        qb[p] += 0.5 * fr
        fa[p] = 0.5 * fr
        fb[p] = 0.5 * fr
        # Conductance across the contact
        if h > 0.0:
            ta = 0.0
            tb = 0.0
            for k in range(4):
                ta += weights[p, k] * temp[nodes[p, k]]
                tb += weights[p, 4 + k] * temp[nodes[p, 4 + k]]
            flow = h * res[p, width_col] * (tb - ta) * dt
            qa[p] += flow
            qb[p] -= flow


@njit(cache=True)
def accumulate_element_heat_sorted(order, active, elems, qa, qb, fa, fb, n_owned, eheat):
    """eheat[e, H_FRICTION] += fa and eheat[e, H_CONDUCTED] += qa - fa for the element e =
    elems[p, 0] of side A (fb, qb - fb for elems[p, 1] of side B), contacts in the given order.

    Only owned elements 0 <= e < n_owned receive heat (-1 marks a side that is not added
    here); pass contacts sorted by global key.
    """
    for i in range(order.shape[0]):
        p = order[i]
        if active[p] != 1:
            continue
        e = elems[p, 0]
        if 0 <= e < n_owned:
            eheat[e, H_FRICTION] += fa[p]
            eheat[e, H_CONDUCTED] += qa[p] - fa[p]
        e = elems[p, 1]
        if 0 <= e < n_owned:
            eheat[e, H_FRICTION] += fb[p]
            eheat[e, H_CONDUCTED] += qb[p] - fb[p]


@njit(cache=True)
def accumulate_heat_sorted(order, active, nodes, weights, qa, qb, n_owned, out):
    """out[node] += w qa (side A nodes, k < 4) or w qb (side B), contacts in the given order.

    Only owned nodes 0 <= node < n_owned receive heat; pass contacts sorted by global key.
    """
    for i in range(order.shape[0]):
        p = order[i]
        if active[p] != 1:
            continue
        for k in range(nodes.shape[1]):
            nd = nodes[p, k]
            if nd < 0 or nd >= n_owned or weights[p, k] == 0.0:
                continue
            out[nd] += weights[p, k] * (qa[p] if k < 4 else qb[p])
