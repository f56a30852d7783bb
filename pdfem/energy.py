"""The energy balance: per-body terms summed exactly, identical on any number of ranks.

Each rank evaluates every term per owned body (global bodies on rank 0 only); rank 0
gathers the rows and sums each column with math.fsum, whose correctly rounded result does
not depend on the order of the rows. U_strain is the internal energy of explicit codes: the
stress work done on the elements (hourglass included) less its plastic part D_plastic, from
the stored energy at t = 0. (The stored-energy function sigma:C^-1:sigma/2 x volume of the
hypoelastic update is not the integral of that work once volumes change by a few per cent:
at 1000 m/s it was 20 % short in the compressed grains.) Balance:
    E = K + U_strain + U_contact + V_gravity + D_damping + D_plastic + D_friction
        + D_contact_damping + D_viscous - W_bc
        + E_thermal - Q_paid - Q_bc + E_coupling
stays equal to its initial value. The contacts' normal force is the gradient of their
stored energy, so the work their forces do on the bodies equals the loss of U_contact, D_friction
and D_contact_damping up to the time discretisation; L_contact, minus that work less the growth
of the three since t = 0 (the work accumulated by the integrator exactly as it moves the nodes),
measures what is left. It is reported as a diagnostic and is not part of E: any energy the
contacts create or destroy shows in the error. D_viscous is the work of the bulk
viscosity. The error is |E - E0| over the largest term now or at t = 0 (never below
energy_floor). With [heat], every heat source is counted once, on the mechanical side
(pdfem.effects.heat): E_thermal = sum C (T - T_initial) is whatever heat is in the bodies;
Q_paid is the part of D_plastic and D_friction that the scene turns into heat (beta and the
friction heating fraction times those terms, not what the sources added); Q_bc is what the
held nodes took; E_coupling = -sum 3 alpha T p A is the thermo-elastic energy, which pays for
the thermo-elastic heat and for the stress work on the thermal strain. A heat source that no
mechanical term pays for therefore shows in the error. What the sources put on the nodes
(heat_sources) and the thermal-strain work (thermal_work) are reported as diagnostics.
Without [heat] they are zero.

Between the samples the drift guard checks the balance every ``guards.energy_steps`` steps
without a gather (:func:`fixed_point_terms`): one allreduce finds each term's largest magnitude
M over the bodies, every body's value is rounded to a multiple of the power of two
q = 2^(e - 62 + ceil(log2 n)) (M < 2^e, n bodies), and a second allreduce sums the integer
multiples, exactly and in any order, in int64. The sums are within n q / 2 of the exact ones
(relative to M: 2^-29 at 10^5 bodies, 2^-23 at 10^6) and, being integers, the same on any rank
count, so every rank count takes the same decision at the same step.
"""

import math

import numpy as np

from pdfem.kernels.element_measures import q4_strain_energy
from pdfem.kernels.fixed_point import column_extent, column_multiples
from pdfem.kernels.integrate import ACC_BC, ACC_DAMP, body_sums
from pdfem.parallel.mpi import array_max, broadcast, gather_rows, global_sum_exact

# The terms every run has, with their role in the balance: +1 a part of E, -1 subtracted
# from it (work done on the bodies, heat that left them), 0 a diagnostic reported with the
# terms and not part of E. Effects declare theirs (pdfem.effects.base.Effect.energy); a run's
# terms are the core terms and those of its effects (run_terms)
CORE_TERMS = (("kinetic", 1), ("strain", 1), ("plastic", 1), ("damping", 1), ("bc_work", -1))
ROLES = dict(CORE_TERMS)


def declare_terms(owner, pairs):
    """Add an owner's (name, role) terms to :data:`ROLES`; a name may not change its role."""
    for name, role in pairs:
        if role not in (-1, 0, 1):
            raise ValueError(f"energy term {name!r} of {owner}: role {role!r} is not -1, 0 or 1")
        if ROLES.get(name, role) != role:
            raise ValueError(f"energy term {name!r} of {owner}: role {role} differs from the "
                             f"declared {ROLES[name]}")
        ROLES[name] = role


def run_terms(effects):
    """The energy terms of a run: the core terms, then each effect's (in the effects'
    order), each once."""
    names = [n for n, _ in CORE_TERMS]
    for eff in effects:
        names += [n for n, _ in eff.energy if n not in names]
    return tuple(names)


# Per-step drift check: each body's multiples of the quantum stay below 2^QBITS / n_bodies,
# so that their int64 sum cannot overflow
QBITS = 62
# The balance's scale is never below this times M c^2 (total mass, fastest P-wave speed): in a
# scene at rest every term is of rounding size and their ratios mean nothing
FLOOR = 1e-12


def body_terms(st, ctx):
    """(nb, len(ctx.terms)) array of per-body energy terms of the owned bodies of this rank
    (global bodies on rank 0 only), in the order of the run's terms."""
    s = st.store
    nb = s.nb_own
    col = {t: i for i, t in enumerate(ctx.terms)}
    rows = np.zeros((nb, len(col)))
    rows[:, col["kinetic"]] = st.kin[:nb]
    # Internal energy of the elements: the stress work done on them (hourglass included)
    # less its plastic part, from the stored energy at t = 0 (see initial_strain_work)
    work = np.empty(nb)
    body_sums(s.ewint[: s.ne_own] - s.ewp[: s.ne_own], s.estart[:nb], s.ne[:nb], work)
    rows[:, col["strain"]] = work
    body_sums(s.ewp, s.estart[:nb], s.ne[:nb], work)
    rows[:, col["plastic"]] = work
    rows[:, col["damping"]] = s.acc[:nb, ACC_DAMP]
    rows[:, col["bc_work"]] = s.acc[:nb, ACC_BC]
    # The effects' terms (gravity potential, contact energy, heat, ...), each effect's added
    for eff in ctx.effects:
        extra = {}
        eff.energy_terms(st, ctx, extra)
        for name, vals in extra.items():
            if name not in col:
                raise KeyError(f"effect {eff.name!r} gives the energy term {name!r}, which it "
                               "does not declare (Effect.energy)")
            rows[:, col[name]] += vals[:nb]
    # Global bodies are counted once, on rank 0
    if ctx.comm.rank != 0:
        rows = rows[s.isglobal[:nb] == 0]
    return rows


def initial_strain_work(st, ctx):
    """Start the elements' stress-work accumulators at their stored elastic energy (a
    prepared bed starts stressed), so that the strain term is that energy plus the work since."""
    s = st.store
    ee = np.zeros(s.ne_own)
    q4_strain_energy(s.x, s.conn, s.emat, ctx.mat_params, s.sig, s.hourglass,
                     ctx.hg_model, 0, s.ne_own, ee)
    s.ewint[: s.ne_own] += ee


def energy_floor(st, ctx):
    """FLOOR x total mass x the largest squared P-wave speed of the materials [J/m], the same
    on every rank and any rank count (per-body masses summed exactly on rank 0)."""
    from pdfem.kernels.params import BULK, RHO, SHEAR

    s = st.store
    nb = s.nb_own
    mass = np.empty(nb)
    body_sums(s.m[: s.nn_own], s.nstart[:nb], s.nn[:nb], mass)
    if ctx.comm.rank != 0:
        mass = mass[s.isglobal[:nb] == 0]
    rows = gather_rows(ctx.comm, mass.reshape(-1, 1))
    out = None
    if rows is not None:
        p = ctx.mat_params
        c2 = float(np.max((p[:, BULK] + 4.0 * p[:, SHEAR] / 3.0) / p[:, RHO]))
        out = FLOOR * math.fsum(rows[:, 0]) * c2
    return broadcast(ctx.comm, out)


def global_terms(st, ctx):
    """{term: exact global sum} on rank 0 (None elsewhere)."""
    rows = gather_rows(ctx.comm, body_terms(st, ctx))
    if rows is None:
        return None
    return {t: math.fsum(rows[:, i]) for i, t in enumerate(ctx.terms)}


def balance(terms, ref, floor=0.0):
    """Total energy and the balance error relative to the largest term (ref: t=0 terms), or
    to ``floor`` (energy_floor) when that is larger."""
    # Correctly rounded sums (math.fsum): the same whatever the order of the run's terms
    parts = [t for t in terms if ROLES[t] != 0]
    total = math.fsum(ROLES[t] * terms[t] for t in parts)
    total0 = math.fsum(ROLES[t] * ref[t] for t in parts)
    scale = balance_scale(terms, ref, floor)
    err = abs(total - total0) / scale if scale > 0 else 0.0
    return total, err


def balance_scale(terms, ref, floor=0.0):
    """The balance's scale: the largest term now or at t = 0 (potential relative to t = 0),
    never below ``floor``."""
    parts = [t for t in terms if ROLES[t] != 0]
    return max([abs(v[t] - (ref[t] if t == "potential" else 0.0)) for t in parts
                for v in (terms, ref)] + [floor])


def fixed_point_terms(st, ctx):
    """{term: global sum} on every rank, from integer multiples of a per-term quantum (see
    the module note), or None when a value is not finite."""
    sums = fixed_point_sums(body_terms(st, ctx), ctx.comm, ctx.layout.nbody)
    return None if sums is None else dict(zip(ctx.terms, sums, strict=True))


def fixed_point_sums(rows, comm, nbody):
    """Column sums of the rows (nb, nt) of every rank of comm, nbody rows in all: each value
    rounded to a multiple of its column's quantum q = 2^(e - QBITS + ceil(log2 nbody)) (the
    column's largest magnitude < 2^e), the multiples summed exactly in int64; a list on every
    rank, the same for any split of the rows over any ranks, or None if a value is not finite."""
    rows = np.ascontiguousarray(rows, np.float64)
    nt = rows.shape[1]
    # Largest magnitude of each column over all ranks, and a flag for a non-finite value
    top = np.empty(nt + 1)
    column_extent(rows, top)
    gtop = array_max(comm, top)
    if gtop[nt]:
        return None
    # Integer multiples of a power of two per column: nbody of them cannot overflow int64
    q, k = np.empty(nt), np.empty(nt, np.int64)
    column_multiples(rows, gtop, (max(int(nbody), 1) - 1).bit_length(), QBITS, q, k)
    tot = global_sum_exact(comm, k)
    return [float(int(tot[i])) * float(q[i]) for i in range(nt)]
