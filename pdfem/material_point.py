"""Drive one material point through a prescribed strain path (no mesh, no MPI).

Used by ``python -m pdfem material`` and by the cap model tests. Sign convention: tension
positive, compression negative; tensors are ordered (xx, yy, xy, zz) with the tensor (not
engineering) shear xy. A path is a sequence of target total strain tensors, reached from
zero strain by ``nsub`` linear increments per segment. A segment may hold some stress
components at their value at the segment start (mixed control, e.g. the constant lateral
stress of a triaxial test); their strains are then found by Newton at every increment.
"""

import math
import os

import numpy as np

from pdfem.errors import InputError, SimulationError
from pdfem.kernels import params as P
from pdfem.kernels.cap import (
    CAP_NST,
    cap_check_params,
    cap_initial_state,
    cap_update,
)
from pdfem.kernels.eos import eos_row
from pdfem.scene import schema as S
from pdfem.scene.cap import CAP_COLUMNS, CAP_OPTIONAL, envelope_apex, strength_rule

COLUMNS = ("step", "exx", "eyy", "exy", "ezz", "sxx", "syy", "sxy", "szz", "I1", "sqrtJ2",
           "kappa", "epv", "wp")
NAMED_PATHS = ("uniaxial", "hydrostatic", "triaxial", "load-unload")
# Most increments of one material-point run, and the seconds one takes (measured, one core)
MAX_INCREMENTS = 10**7
INCREMENT_S = 3.0e-5

# [materials.NAME] key -> parameter column, for model = "cap": the elastic moduli and the
# cap's own (pdfem.scene.cap)
CAP_KEYS = {"density": P.RHO, "bulk": P.BULK, "shear": P.SHEAR, **CAP_COLUMNS}
# Keys a scene's cap material may hold that this isothermal driver does not use (thermal and
# temperature-dependence keys): the scene schema's keys of the cap model less the ones above
# The equation of state's keys, which the driver applies (pdfem.kernels.eos)
EOS_KEYS = ("eos", "eos_s", "eos_gamma")
IGNORED_KEYS = tuple(k for k in (*S.MATERIAL_COMMON, *S.CAP)
                     if k != "model" and k not in CAP_KEYS and k not in EOS_KEYS)


def _number(tbl, key, where):
    """tbl[key] as a finite float, or InputError naming where.key."""
    v = tbl[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise InputError(f"{where}.{key}: must be a finite number (got {v!r})")
    return float(v)


def cap_params_from_table(tbl, where="materials.NAME", strict=True):
    """Parameter row (NPAR,) of a ``[materials.NAME]`` table with ``model = "cap"`` (SI units).

    Keys: model, density, bulk, shear, A, B, C, D, R, W, kappa0 and the optional
    tension_cutoff (default: envelope apex ln(A/C)/B when B, C > 0, else 0) and tol (default
    1e-8). The other keys a scene accepts for a cap material (:data:`IGNORED_KEYS`: specific
    heat, conductivity, expansion, softening) are ignored: the driver is isothermal. ``where``
    prefixes error messages; ``strict`` rejects keys that are neither.
    Raises InputError('where.KEY: ...') on a missing, mistyped or out-of-range value.
    """
    # Model and key set
    if tbl.get("model", "cap") != "cap":
        raise InputError(f"{where}.model: expected \"cap\" (got {tbl.get('model')!r})")
    if strict:
        for key in tbl:
            if key != "model" and key not in CAP_KEYS and key not in IGNORED_KEYS \
                    and key not in EOS_KEYS:
                raise InputError(f"{where}.{key}: unknown key for model \"cap\"")
    for key in CAP_KEYS:
        if key not in CAP_OPTIONAL and key not in tbl:
            raise InputError(f"{where}.{key}: required key missing")
    # Values into the row
    p = np.zeros(P.NPAR)
    p[P.MODEL] = P.CAP
    for key, col in CAP_KEYS.items():
        if key in tbl:
            p[col] = _number(tbl, key, where)
    # Per-key ranges, then the combined check of the kernel
    for key in ("density", "bulk", "shear", "A", "D", "R"):
        if p[CAP_KEYS[key]] <= 0.0:
            raise InputError(f"{where}.{key}: must be > 0 (got {p[CAP_KEYS[key]]:g})")
    for key in ("B", "C"):
        if p[CAP_KEYS[key]] < 0.0:
            raise InputError(f"{where}.{key}: must be >= 0 (got {p[CAP_KEYS[key]]:g})")
    why = strength_rule(p[P.CAP_A], p[P.CAP_C])
    if why:
        raise InputError(f"{where}.C: {why}")
    if not 0.0 < p[P.CAP_W] < 1.0:
        raise InputError(f"{where}.W: must be in (0, 1) (got {p[P.CAP_W]:g})")
    if "tension_cutoff" not in tbl:
        p[P.CAP_T] = envelope_apex(p[P.CAP_A], p[P.CAP_B], p[P.CAP_C])
    if p[P.CAP_TAU] < 0.0:
        raise InputError(f"{where}.relaxation_time: must be >= 0 (got {p[P.CAP_TAU]:g})")
    if "tol" in tbl and not 0.0 < p[P.CAP_TOL] < 1e-2:
        raise InputError(f"{where}.tol: must be in (0, 1e-2) (got {p[P.CAP_TOL]:g})")
    _eos_into(tbl, where, p)
    reason = cap_check_params(p)
    if reason:
        key = "tension_cutoff" if "tension" in reason else "kappa0" if "X(kappa0)" in reason \
            else "A"
        raise InputError(f"{where}.{key}: {reason}")
    return p


def _eos_into(tbl, where, p):
    """The Us-up equation of state of the table into the row (eos_s exactly with it)."""
    eos = tbl.get("eos", "linear")
    if eos not in ("linear", "us_up"):
        raise InputError(f'{where}.eos: must be "linear" or "us_up" (got {eos!r})')
    if (eos == "us_up") != ("eos_s" in tbl):
        raise InputError(f'{where}.eos_s: given exactly when eos = "us_up"')
    if eos == "us_up":
        p[P.EOS_S] = _number(tbl, "eos_s", where)
        if not 0.0 < p[P.EOS_S] <= 10.0:
            raise InputError(f"{where}.eos_s: must be in (0, 10] (got {p[P.EOS_S]:g})")
    if tbl.get("eos_gamma", 0.0) != 0.0:
        raise InputError(f"{where}.eos_gamma: the material-point driver keeps no internal "
                         "energy; it drives the Hugoniot alone (eos_gamma = 0)")


def named_path(name, strain=-0.01, axial=None):
    """(targets (nseg, 4), held (nseg, 4) bool) of a built-in path.

    uniaxial     eps_xx to ``strain``, back to 0
    hydrostatic  eps_xx = eps_yy = eps_zz to ``strain``, back to 0
    triaxial     hydrostatic to ``strain``, then eps_xx by ``axial`` (default 4 strain) more
                 with sigma_yy and sigma_zz held at their hydrostatic value
    load-unload  uniaxial strain to strain, strain/2, 3 strain/2, 0
    """
    s = float(strain)
    if name == "uniaxial":
        t = [[s, 0, 0, 0], [0, 0, 0, 0]]
    elif name == "hydrostatic":
        t = [[s, s, 0, s], [0, 0, 0, 0]]
    elif name == "triaxial":
        a = 4.0 * s if axial is None else float(axial)
        t = [[s, s, 0, s], [s + a, s, 0, s]]
        held = np.zeros((2, 4), bool)
        held[1, [1, 3]] = True
        return np.array(t, float), held
    elif name == "load-unload":
        t = [[s, 0, 0, 0], [0.5 * s, 0, 0, 0], [1.5 * s, 0, 0, 0], [0, 0, 0, 0]]
    else:
        raise InputError(f"--path: unknown path {name!r} (named paths: "
                         f"{', '.join(NAMED_PATHS)}, or a CSV file)")
    t = np.array(t, float)
    return t, np.zeros(t.shape, bool)


def read_path_csv(fname):
    """Targets (n, 4) from a CSV file with header exx, eyy, exy, ezz ('#' lines skipped)."""
    try:
        with open(fname) as f:
            lines = [ln.strip() for ln in f if ln.strip() and not ln.lstrip().startswith("#")]
    except OSError as exc:
        raise InputError(f"--path: cannot read {fname}: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise InputError(f"--path: {fname}: not a text (CSV) file") from None
    if not lines:
        raise InputError(f"--path: {fname} is empty")
    head = [h.strip() for h in lines[0].split(",")]
    want = ["exx", "eyy", "exy", "ezz"]
    if any(w not in head for w in want):
        raise InputError(f"--path: {fname}: header must name columns {', '.join(want)}")
    cols = [head.index(w) for w in want]
    rows = []
    for i, ln in enumerate(lines[1:], start=2):
        try:
            vals = [float(v) for v in ln.split(",")]
            rows.append([vals[c] for c in cols])
        except (ValueError, IndexError):
            raise InputError(f"--path: {fname}: bad row {i}: {ln!r}") from None
    t = np.array(rows, float).reshape(-1, 4)
    if not np.all(np.isfinite(t)):
        raise InputError(f"--path: {fname}: non-finite strain")
    # A small-strain driver: every component within [-1, 1], as for --strain
    bad = np.argwhere(np.abs(t) > 1.0)
    if bad.size:
        r, c = bad[0]
        raise InputError(f"--path: {fname}: row {r + 2}, column {want[c]}: strain "
                         f"{float(t[r, c])!r} outside [-1, 1] (the material point is a "
                         "small-strain driver)")
    return t


def _update(p, sig, st, d, dt):
    """cap_update on copies over an increment of duration dt; returns (sig, st, status, dwp)."""
    s = sig.copy()
    t = st.copy()
    p = eos_row(p, s[0], s[1], s[3], d[0] + d[1] + d[3], np.empty(p.shape[0]))
    status, dwp = cap_update(p, s, d, t, dt)
    return s, t, status, dwp


def _mixed_increment(p, sig, st, d, held, target, dt=0.0):
    """Increment d with the held components' strains chosen so their stress stays at target.

    Returns (sig, st, status, dwp, d) for the strain increment d actually applied (over a
    duration dt: a rate-dependent material's).
    """
    h = np.flatnonzero(held)
    if h.size == 0:
        return (*_update(p, sig, st, d, dt), d)
    # Elastic guess: hold the stress of the held components under the prescribed others
    kb, g2 = p[P.BULK], 2.0 * p[P.SHEAR]
    lam = kb - g2 / 3.0
    cm = np.array([[lam + g2, lam, 0, lam], [lam, lam + g2, 0, lam], [0, 0, g2, 0],
                   [lam, lam, 0, lam + g2]])
    f = np.flatnonzero(~held)
    d = d.copy()
    d[h] = np.linalg.solve(cm[np.ix_(h, h)], target - sig[h] - cm[np.ix_(h, f)] @ d[f])
    # Newton with a finite-difference Jacobian
    scale = p[P.CAP_A] + np.abs(sig).max()
    for _ in range(40):
        s, t, status, dwp = _update(p, sig, st, d, dt)
        r = s[h] - target
        if status != 0 or np.abs(r).max() <= 1e-10 * scale:
            return s, t, status, dwp, d
        jac = np.empty((h.size, h.size))
        eps = 1e-7 * max(np.abs(d).max(), 1e-9)
        for k, c in enumerate(h):
            dd = d.copy()
            dd[c] += eps
            jac[:, k] = (_update(p, sig, st, dd, dt)[0][h] - s[h]) / eps
        try:
            d[h] -= np.linalg.solve(jac, r)
        except np.linalg.LinAlgError:
            raise SimulationError("stress-controlled increment: singular Jacobian (the held "
                                  "stresses do not respond to their strains)") from None
    raise SimulationError(f"stress-controlled increment did not converge (residual "
                          f"{np.abs(r).max():.3g})")


def run_path(p, path, nsub, held=None, strain_rate=None):
    """Drive a cap material point (row p) from zero strain and stress through ``path``.

    path: (nseg, 4) target total strains (xx, yy, xy, zz), each reached in nsub equal
    increments; held: optional (nseg, 4) bool, stress components held at their value at the
    segment start (their path strains are ignored); strain_rate [1/s]: an increment lasts its
    largest prescribed strain component over it (required by a rate-dependent material,
    p[CAP_TAU] > 0; ignored otherwise). Returns a dict of 1-D arrays keyed by COLUMNS; row 0
    is the initial state, wp the cumulative plastic work density.
    """
    path = np.asarray(path, float).reshape(-1, 4)
    held = np.zeros(path.shape, bool) if held is None else np.asarray(held, bool)
    nsub = int(nsub)
    if nsub < 1:
        raise InputError(f"--nsub: must be >= 1 (got {nsub})")
    if strain_rate is not None and not (math.isfinite(strain_rate) and strain_rate > 0.0):
        raise InputError(f"--strain-rate: must be a rate > 0 in 1/s (got {strain_rate!r})")
    if p[P.CAP_TAU] > 0.0 and strain_rate is None:
        raise InputError("--strain-rate: needed by a material with relaxation_time > 0 (a "
                         "rate-dependent point has no answer without the time of its path)")
    # More than MAX_INCREMENTS is a typo, not a material test (refused before any work)
    total = nsub * path.shape[0]
    if total > MAX_INCREMENTS:
        raise InputError(f"--nsub: {nsub} increments x {path.shape[0]} path segment(s) = "
                         f"{total:.3g} increments (about {total * INCREMENT_S / 3600:.2g} h), "
                         f"more than {MAX_INCREMENTS:.0e}")
    # Initial state
    sig = np.zeros(4)
    st = np.zeros(CAP_NST)
    cap_initial_state(p, st)
    eps = np.zeros(4)
    wp = 0.0
    rows = [_row(0, eps, sig, st, wp)]
    for iseg, tgt in enumerate(path):
        hold = held[iseg]
        target = sig[hold].copy()
        d = (tgt - eps) / nsub
        d[hold] = 0.0
        dt = np.abs(d).max() / strain_rate if strain_rate else 0.0
        for _ in range(nsub):
            sig_new, st_new, status, dwp, d_used = _mixed_increment(p, sig, st, d, hold, target,
                                                                    dt)
            if status != 0:
                raise SimulationError(f"cap update failed with status {status} at step "
                                      f"{len(rows)} (strain {eps.tolist()})")
            if dwp < -1e-12 * (p[P.CAP_A] + np.abs(sig_new).max()) * np.abs(d_used).max():
                raise SimulationError(f"negative plastic work {dwp:g} at step {len(rows)}")
            eps = eps + d_used
            sig, st = sig_new, st_new
            wp += dwp
            rows.append(_row(len(rows), eps, sig, st, wp))
    return {c: np.array([r[i] for r in rows]) for i, c in enumerate(COLUMNS)}


def _row(step, eps, sig, st, wp):
    """One output row in COLUMNS order."""
    i1 = sig[0] + sig[1] + sig[3]
    m = i1 / 3.0
    j2 = 0.5 * ((sig[0] - m) ** 2 + (sig[1] - m) ** 2 + (sig[3] - m) ** 2) + sig[2] ** 2
    return (step, *eps, *sig, i1, math.sqrt(j2), st[0], st[1], wp)


def write_csv(fname, res):
    """Write a run_path result with a header line of COLUMNS (``fname.part``, then renamed)."""
    data = np.column_stack([res[c] for c in COLUMNS])
    fmt = ["%d"] + ["%.10g"] * (len(COLUMNS) - 1)
    tmp = f"{fname}.part"
    np.savetxt(tmp, data, fmt=fmt, delimiter=",", header=",".join(COLUMNS), comments="")
    os.replace(tmp, fname)
