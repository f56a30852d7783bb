"""The ``guards.cap_contact = "element"`` remedy: contact laws no stiffer than the elements allow.

A penalty contact stiffness far above what the grains' own elements carry makes the contact,
not the material, set the time step. The remedy lowers kn0, ks and the hardening of every
contact law of the [contact] table, once at set-up, so that a contact over a whole boundary
edge of the initial meshes keeps the elements' initial stable step
(pdfem.kernels.contact_law.contact_dt >= that step), and says so in the run log.
"""

import math

import numpy as np

from pdfem.build import joint_masses
from pdfem.kernels import contact_law as L
from pdfem.kernels.contact_law import DT_FACTOR
from pdfem.kernels.stable import q4_stable_dt
from pdfem.parallel.mpi import global_min


def contact_stiffness_cap(st, ctx, contact, kcap=None):
    """The ``cap_contact = "element"`` remedy: lower kn0 and the hardening of every contact law
    so that a contact over a whole boundary edge of the initial meshes is no stiffer than the
    elements' initial stable step allows (contact_law.contact_dt >= that step). Returns
    (cap, log line or None when no law needed it); the same on every rank (global minima).
    A restart passes the cap its run started with (kcap) so that it continues bit-identically."""
    s, n = st.store, st.store.ne_own
    if kcap is not None:
        return kcap, _apply_cap(contact, kcap, None)
    dt_el = global_min(ctx.comm, q4_stable_dt(s.x, s.conn, s.emat, ctx.mat_params, s.sig,
                                                   0, n))
    # Stiffness limit of each boundary edge: contact_dt(m, rigid, k L) >= dt_el (a tied pair
    # of block nodes moves with their joint mass)
    mass = joint_masses(s.m, ctx.partner)
    kcap = math.inf
    for k in range(4):
        on = s.ebnd[:n, k] != 0
        a, b = s.conn[:n, k][on], s.conn[:n, (k + 1) % 4][on]
        if a.shape[0]:
            le = np.hypot(s.x[b, 0] - s.x[a, 0], s.x[b, 1] - s.x[a, 1])
            m = np.minimum(mass[a], mass[b])
            kcap = min(kcap, float(((2.0 * DT_FACTOR) ** 2 * m / (dt_el * dt_el * le)).min()))
    kcap = global_min(ctx.comm, kcap)
    if not math.isfinite(kcap):
        return None, None
    return kcap, _apply_cap(contact, kcap, dt_el)


def _apply_cap(contact, kcap, dt_el):
    """Lower the contact laws to the stiffness cap; the log line (None when nothing changed)."""
    law = contact.law
    changed = False
    kn0_old = float(law[:, :, L.P_KN0].max())
    for i in range(law.shape[0]):
        for j in range(law.shape[1]):
            row = law[i, j]
            for c in (L.P_KN0, L.P_KS):
                if row[c] > kcap:
                    row[c] = kcap
                    changed = True
            # The hardening stops where the tangent stiffness kn0/(1 - r)^2 reaches the cap
            rc = 1.0 - math.sqrt(row[L.P_KN0] / kcap)
            if rc < row[L.P_RCAP]:
                row[L.P_RCAP] = rc
                changed = True
    contact.kn0_max = float(law[:, :, L.P_KN0].max())
    if not changed or dt_el is None:
        return None
    return (f"guard: remedy cap_contact: contact stiffness capped at {kcap:.4g} Pa/m (kn0 "
            f"{kn0_old:.4g} -> {contact.kn0_max:.4g}, hardening stops at delta/delta_max = "
            f"{float(law[:, :, L.P_RCAP].min()):.4g}) so that contacts keep the elements' "
            f"stable step {dt_el:.4g} s")
