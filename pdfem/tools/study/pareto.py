"""Errors against the converged estimate, the Pareto front of error versus wall time, the
choice for a given tolerance, and the study's CSV file, table and estimate in words.

A row is a dict made by :class:`pdfem.tools.study.accuracy.AccuracyStudy` (its ``setting``, wall
time, steps, status and the measured :data:`~pdfem.tools.study.quantities.QUANTITIES`).
"""

import csv
import math
import os

from pdfem.tools.study.quantities import QUANTITIES, SE_KEYS


def add_errors(rows, ref):
    """Add ``err_<q>`` (relative error |q - q_ref| / |q_ref| against ``ref``, a mapping of the
    quantities' keys to their reference values; NaN when either is missing) and ``err_max``
    (the worst; +inf when any is missing) to every row, in place."""
    for row in rows:
        worst = 0.0
        for key, *_ in QUANTITIES:
            q, q0 = row[key], ref[key]
            e = abs(q - q0) / abs(q0) if math.isfinite(q) and math.isfinite(q0) and q0 else math.nan
            row["err_" + key] = e
            worst = max(worst, e) if math.isfinite(e) else math.inf
        row["err_max"] = worst


def mark_pareto(rows):
    """Set ``pareto`` on every row: True when no run at most as long has a smaller or equal
    worst error."""
    done = sorted((r for r in rows if math.isfinite(r["err_max"])),
                  key=lambda r: (r["wall_s"], r["err_max"]))
    best = math.inf
    for r in rows:
        r["pareto"] = False
    for r in done:
        if r["err_max"] < best:
            r["pareto"], best = True, r["err_max"]


def recommend(rows, tol):
    """The cheapest run whose every error is <= ``tol``; None if no such run."""
    ok = [r for r in rows if r["err_max"] <= tol]
    return min(ok, key=lambda r: r["wall_s"]) if ok else None


def describe(setting, kn0):
    """A setting in words: level (quads per grain), rule, safety factor, contact stiffness."""
    return (f"level {setting.level} ({setting.quads} quads per grain), rule {setting.rule}, "
            f"time.safety {setting.safety:g}, contact kn0 x{setting.kn0_scale:g}"
            + (f" ({kn0 * setting.kn0_scale:.3g} Pa/m)" if kn0 else ""))


def worst_name(row):
    """Words for the quantity with the largest error of a row."""
    key = max((k for k, *_ in QUANTITIES), key=lambda k: _finite(row["err_" + k]))
    return {k: w for k, _, w, *_ in QUANTITIES}[key]


def recommendation_line(rows, tol, kn0=None):
    """The sentence printed at the end of the study."""
    pick = recommend(rows, tol)
    pct = f"{tol * 100:g} %"
    done = [r for r in rows if math.isfinite(r["err_max"])]
    if pick is None:
        best = min(done, key=lambda r: r["err_max"]) if done else None
        return (f"no run of the study has every error <= {pct} against the converged "
                "estimate" + (f"; the closest is {describe(best['setting'], kn0)} "
                              f"(largest {best['err_max'] * 100:.1f} %, {worst_name(best)}, "
                              f"{best['wall_s']:.1f} s)" if best else ""))
    dearest = max(done, key=lambda r: r["wall_s"])
    return (f"for a {pct} answer choose {describe(pick['setting'], kn0)}: every error <= "
            f"{pct} against the converged estimate (largest {pick['err_max'] * 100:.1f} %, "
            f"{worst_name(pick)}) in {pick['wall_s']:.1f} s, "
            f"{dearest['wall_s'] / pick['wall_s']:.0f} x faster than the dearest run of the "
            f"study ({dearest['setting'].label}, {dearest['wall_s']:.1f} s)")


def _finite(v):
    return v if math.isfinite(v) else math.inf


def csv_row(r):
    """One row of the CSV file: the setting, cost, values (SI) and their standard errors
    where measured, relative errors, flags."""
    s = r["setting"]
    out = {"run": s.label, "axis": s.axis, "level": s.level, "quads_per_grain": s.quads,
           "rule": s.rule, "safety": s.safety, "kn0_scale": s.kn0_scale,
           "wall_s": r["wall_s"], "steps": r["steps"]}
    out.update({k: r[k] for k, *_ in QUANTITIES})
    out.update({se: r.get(se, math.nan) for se in SE_KEYS.values()})
    out.update({"err_" + k: r["err_" + k] for k, *_ in QUANTITIES})
    out.update(err_max=r["err_max"], pareto=int(r["pareto"]), status=r["status"],
               run_file=r["run_file"])
    return out


def write_csv(rows, path):
    """The study's table as CSV (SI units; relative errors as fractions), atomically."""
    tmp = path + ".part"
    with open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        for k, r in enumerate(rows):
            row = csv_row(r)
            if k == 0:
                w.writerow(list(row))
            w.writerow([_cell(v) for v in row.values()])
    os.replace(tmp, path)


def _cell(v):
    """A CSV cell: floats to 6 significant digits, NaN and inf as written by Python."""
    return f"{v:.6g}" if isinstance(v, float) else v


def table_lines(rows):
    """The study as a markdown table: the setting, wall time, steps and the errors in %."""
    head = ["run", "quads/grain", "rule", "safety", "kn0 x", "wall [s]", "steps"]
    head += [h for _, h, *_ in QUANTITIES]
    head += ["worst", "Pareto"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        s = r["setting"]
        errs = [_pct(r["err_" + k]) for k, *_ in QUANTITIES] + [_pct(r["err_max"])]
        cells = [s.label, str(s.quads), s.rule, f"{s.safety:g}", f"{s.kn0_scale:g}",
                 f"{r['wall_s']:.1f}", str(r["steps"]) if r["status"] == "ok" else "failed"]
        lines.append("| " + " | ".join(cells + errs + ["*" if r["pareto"] else ""]) + " |")
    return lines


def _pct(e):
    """A relative error as a percentage for the table."""
    return f"{e * 100:.1f}" if math.isfinite(e) else "n/a"


def estimate_lines(estimate):
    """The converged estimate in words, one line per quantity: the combined value and its
    uncertainty, then each rule's extrapolation (pdfem.tools.study.estimate)."""
    lines = []
    for key, _, words, unit, scale in QUANTITIES:
        e = estimate.get(key) or {}
        c = e.get("combined")
        u = f" {unit}" if unit else ""
        if c is None:
            lines.append(f"{words}: no estimate (fewer than two levels ran for every rule)")
            continue
        rel = abs(c["uncertainty"] / c["value"]) * 100 if c["value"] else math.inf
        parts = []
        for rule, r in e["rules"].items():
            if r is not None:
                lv = "-".join(map(str, r["levels"]))
                parts.append(f"{rule} levels {lv}: {r['value'] * scale:.4g} +- "
                             f"{r['uncertainty'] * scale:.2g} ({r['how']})")
        flag = "" if c["agree"] else "; the rules disagree beyond their bands"
        lines.append(f"{words}: {c['value'] * scale:.4g} +- {c['uncertainty'] * scale:.2g}{u} "
                     f"({rel:.1f} %{flag}); " + "; ".join(parts))
    return lines

