"""The contact pass of a bench bed against its C twin (bench/c/contact_pass.c), and the cost of
one element pair on its own.

``pass_yardstick(sim, repeat)`` takes the candidates, history and positions of a Simulation's
current step and times the numba pass (pdfem.kernels.contact.contact_pass, as the contact
effect calls it, less the adding of the forces into the force array) and the C twin on them:
CPU seconds per call (process time: the figure a shared machine distorts least), the median
of ``repeat`` calls, and whether the two give the same bits. Per-pair figures divide by the
candidates, by the element pairs evaluated (their boxes overlap this step) and by the contacts
(overlapping pairs). Then the arithmetic of a single pair: one overlapping pair, and one pair
the early out rejects, each evaluated ``REPS`` times in a row (its data in cache, its
branches predicted), numba and C.
"""

import time

import numpy as np

from pdfem.kernels.contact import C_ACTIVE, NNOD, NRES, contact_pass
from pdfem.kernels.contact_law import NPAR
from pdfem.kernels.overlap import outside_edge
from pdfem.tools.bench.timing import median_call

# Evaluations of one pair in the single-pair timing, and calls timed
REPS = 2000
CALLS = 25


def _outputs(rows):
    """The output arrays of the pass with room for rows contacts."""
    return (np.zeros(rows, np.int8), np.zeros((rows, 4), np.int64), np.zeros((rows, 2), np.int64),
            np.zeros((rows, NNOD), np.int64), np.zeros((rows, NNOD)), np.zeros((rows, NNOD, 2)),
            np.zeros(rows), np.zeros((rows, NRES)))


def _one_pair(sim, eff, pair, law, nmat, walls, dt, cfn):
    """CPU seconds of one element pair evaluated REPS times in a row, numba and C: the pair's
    two elements and their nodes alone (the pass's box of every element and its history merge
    then cost next to nothing), its history row if it has one."""
    s = sim.store
    nodes, conn = np.unique(s.conn[pair], return_inverse=True)
    conn = np.ascontiguousarray(conn.reshape(2, 4).astype(np.int64))
    e = np.asarray(pair)
    key = (s.elem_gid[e[0]], s.elem_loc[e[0]], s.elem_gid[e[1]], s.elem_loc[e[1]])
    held = np.all(s.hkey == key, axis=1)
    hkey, hval = np.ascontiguousarray(s.hkey[held]), np.ascontiguousarray(s.hval[held])
    common = (np.ascontiguousarray(s.x[nodes]), np.ascontiguousarray(sim.du[nodes]),
              np.ascontiguousarray(s.m[nodes]), conn, np.ascontiguousarray(s.ebnd[e]),
              s.elem_gid[e], s.elem_loc[e], s.elen[e], np.ascontiguousarray(s.emat[e]), law,
              nmat)
    reps = np.ascontiguousarray(np.tile([0, 1], (REPS, 1)).astype(np.int64))
    bbox = np.empty((2, 4))
    o = _outputs(REPS + 1)
    depth = tuple(np.ascontiguousarray(d[e]) for d in eff.depth)
    args = (common[:8] + depth + common[8:] + (np.zeros(0, np.int64),) + walls
            + (reps, hkey, hval, np.zeros(0), False, False, dt, bbox, np.zeros((0, 2)), 0))
    cargs = common + walls + (reps, hkey, hval, dt, bbox)
    return {"numba": median_call(contact_pass, args + o, CALLS, time.process_time) / REPS,
            "c": median_call(cfn, cargs + o, CALLS, time.process_time) / REPS}


def pass_yardstick(sim, repeat):
    """Figures of the numba pass and its C twin on sim's current step (module docstring), or
    None without a C compiler."""
    from pdfem.tools.bench.cyardstick import load

    cfn = load("contact_pass")
    if cfn is None:
        return None
    eff = [e for e in sim.effects if e.name == "contact"][0]
    s = sim.store
    # The bench bed has walls, not periodic sides: the pairs without their (zero) shifts
    cand = np.ascontiguousarray(eff.detect.step(sim.state, sim.ctx)[:, :2])
    law = np.ascontiguousarray(eff.law.reshape(-1, NPAR))
    nmat = eff.law.shape[0]
    common = (s.x, sim.du, s.m, s.conn, s.ebnd, s.elem_gid, s.elem_loc, s.elen, s.emat, law,
              nmat)
    walls = (eff._wall_p0, eff._wall_n, eff._wall_mu)
    dt = float(sim.dt)
    bbox = np.empty((s.nelem, 4))

    def numba_args(cands, hkey, hval):
        return (common[:8] + eff.depth + common[8:] + (np.zeros(0, np.int64),) + walls
                + (cands, hkey, hval, np.zeros(0), False, False, dt, bbox, np.zeros((0, 2)), 0))

    def c_args(cands, hkey, hval):
        return common + walls + (cands, hkey, hval, dt, bbox)

    rows = cand.shape[0] + 1
    outs = {"numba": _outputs(rows), "c": _outputs(rows)}
    got = {"numba": contact_pass(*numba_args(cand, s.hkey, s.hval), *outs["numba"]),
           "c": cfn(*c_args(cand, s.hkey, s.hval), *outs["c"])}
    n, _, nev = got["numba"]
    same = got["c"][:3] == got["numba"] and got["c"][3] == 0 and all(
        a[:n].tobytes() == b[:n].tobytes() for a, b in zip(outs["numba"], outs["c"],
                                                           strict=True))
    out = {"candidates": cand.shape[0], "evaluated": nev, "contacts": n, "same": same,
           "unsupported": got["c"][3],
           "numba": median_call(contact_pass, numba_args(cand, s.hkey, s.hval) + outs["numba"],
                                repeat, time.process_time),
           "c": median_call(cfn, c_args(cand, s.hkey, s.hval) + outs["c"], repeat,
                            time.process_time)}
    # One pair on its own: the first overlapping pair, and the first pair whose boxes overlap
    # that the early out rejects (A wholly outside an edge line of B)
    act = outs["numba"][0][:n]
    pair = outs["numba"][2][:n][(act == C_ACTIVE) & (outs["numba"][2][:n, 1] >= 0)][0]
    apart = None
    for a, b in cand:
        xa, xb = s.x[s.conn[a]], s.x[s.conn[b]]
        if b >= 0 and np.all(xa.min(0) <= xb.max(0)) and np.all(xb.min(0) <= xa.max(0)) and \
                outside_edge(xb, xa):
            apart = np.array([a, b])
            break
    for name, one in (("overlapping", pair), ("apart", apart)):
        if one is not None:
            out[name] = _one_pair(sim, eff, one, law, nmat, walls, dt, cfn)
    return out


def print_pass_yardstick(y, n, log=print):
    """Lines of the pass yardstick of an n-grain bed."""
    if y is None:
        log("contact pass against C: no C compiler found (gcc or cc), skipped")
        return
    per = {"candidate": y["candidates"], "evaluated pair": y["evaluated"],
           "overlapping pair": y["contacts"]}
    log(f"contact pass, numba against its C twin (gcc -O3 -march=native -ffp-contract=off), "
        f"{n} grains, CPU time, median of the calls: numba {1e6 * y['numba'] / n:.3f}, C "
        f"{1e6 * y['c'] / n:.3f} us/grain, numba/C = {y['numba'] / y['c']:.2f}; results "
        f"{'the same bits' if y['same'] else 'DIFFERENT'}"
        + (f" ({y['unsupported']} non-convex pairs outside the twin)" if y["unsupported"] else ""))
    log("  per " + ", per ".join(
        f"{k} ({v / n:.2f}/grain): numba {1e9 * y['numba'] / v:.1f} ns, C "
        f"{1e9 * y['c'] / v:.1f} ns" for k, v in per.items()))
    for name, what in (("overlapping", "an overlapping pair"),
                       ("apart", "a pair whose boxes overlap, rejected by the early out")):
        if name in y:
            log(f"  {what}, alone ({REPS} in a row, data in cache): numba "
                f"{1e9 * y[name]['numba']:.1f} ns, C {1e9 * y[name]['c']:.1f} ns")
