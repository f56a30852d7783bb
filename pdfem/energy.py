"""The energy balance: per-body terms summed exactly, identical on any number of ranks.

Each rank evaluates every term per owned body (global bodies on rank 0 only); rank 0
gathers the rows and sums each column with math.fsum, whose correctly rounded result does
not depend on the order of the rows. Balance:
    E = K + U_strain + U_contact + V_gravity + D_damping + D_plastic + D_friction - W_bc
        + (E_thermal - Q_sources - Q_bc) + W_thermal_strain
stays equal to its initial value; the error is |E - E0| over the largest term now or at
t = 0. With [heat], E_thermal = sum C (T - T_initial) grows by what the sources
(dissipation, friction, thermo-elastic coupling) and the held nodes put in, so the bracket
checks that the heat update
conserves energy while the dissipated terms stay counted once; W_thermal_strain is the work
of the stress on the thermal strain (thermal expansion). Without [heat] they are zero.
"""

import math

import numpy as np

from pdfem.kernels.element import q4_strain_energy
from pdfem.kernels.integrate import ACC_BC, ACC_DAMP, ACC_FRIC, body_sums
from pdfem.parallel.mpi import gather_rows

TERMS = ("kinetic", "strain", "contact", "potential", "damping", "plastic", "friction",
         "bc_work", "thermal", "heat_sources", "heat_bc", "thermal_work")
SIGN = {"bc_work": -1.0, "heat_sources": -1.0, "heat_bc": -1.0}


def body_terms(sim):
    """(nb, len(TERMS)) array of per-body energy terms of the owned bodies of this rank."""
    s = sim.store
    nb = s.nb_own
    rows = np.zeros((nb, len(TERMS)))
    rows[:, TERMS.index("kinetic")] = sim.kin[:nb]
    # Stored elastic energy of the elements (and hourglass modes), summed per body
    ee = np.zeros(s.ne_own)
    q4_strain_energy(s.x, s.conn, s.emat, sim.mat_params, s.sig, s.hgq, sim.hg_coef, 0,
                     s.ne_own, ee)
    col = np.empty(nb)
    body_sums(ee, s.estart[:nb], s.ne[:nb], col)
    rows[:, TERMS.index("strain")] = col
    body_sums(s.ewp, s.estart[:nb], s.ne[:nb], col)
    rows[:, TERMS.index("plastic")] = col
    rows[:, TERMS.index("damping")] = s.acc[:nb, ACC_DAMP]
    rows[:, TERMS.index("bc_work")] = s.acc[:nb, ACC_BC]
    rows[:, TERMS.index("friction")] = s.acc[:nb, ACC_FRIC]
    # Terms owned by effects (gravity potential, contact energy, ...)
    extra = {}
    for eff in sim.effects:
        eff.energy_terms(sim, extra)
    for name, vals in extra.items():
        rows[:, TERMS.index(name)] += vals[:nb]
    # Global bodies are counted once, on rank 0
    if sim.comm.rank != 0:
        rows = rows[s.isglobal[:nb] == 0]
    return rows


def global_terms(sim):
    """{term: exact global sum} on rank 0 (None elsewhere)."""
    rows = gather_rows(sim.comm, body_terms(sim))
    if rows is None:
        return None
    return {t: math.fsum(rows[:, i]) for i, t in enumerate(TERMS)}


def balance(terms, ref):
    """Total energy and the balance error relative to the largest term (ref: t=0 terms)."""
    total = sum(SIGN.get(t, 1.0) * v for t, v in terms.items())
    total0 = sum(SIGN.get(t, 1.0) * v for t, v in ref.items())
    # Scale: the largest term now or at t = 0 (potential relative to t = 0)
    scale = max([abs(v[t] - (ref[t] if t == "potential" else 0.0)) for t in terms
                 for v in (terms, ref)] + [0.0])
    err = abs(total - total0) / scale if scale > 0 else 0.0
    return total, err
