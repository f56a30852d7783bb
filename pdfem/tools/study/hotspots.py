"""Mesh convergence of hot spots: one thermal shock scene at several grain mesh levels.

Each level runs the scene's bed re-meshed at that level (:func:`pdfem.prepare.relevel.relevel_bed`,
the same grain polygons and mass, as ``study accuracy`` does) through the normal solver, to
the hammer's release (the study measures the wave, not the spring-back), and the hot-spot
census (:func:`pdfem.tools.analysis.hotcensus.census`) of its last frame gives the statistics of
the level: over the material behind the compaction front, the mass-weighted mean, 99th and
99.9th percentile and peak element temperature, the hot area fractions and the spot count;
over the whole bed, the heat each mechanism put into the grains. A scene without ``[heat]``
is run as its thermal variant (:func:`thermal_variant`).

Convergence is judged on the temperature rise above the initial temperature, not on the
absolute temperature (a 30 K change on a 100 K rise is 30 %, not 8 % of 390 K): the change
from one level to the next over the rise at the finer level.
"""

import copy
import math

import h5py
import numpy as np

from pdfem.effects.heat import MECHANISMS
from pdfem.effects.thermal import check_coupled_materials
from pdfem.errors import SceneError
from pdfem.parallel.mpi import broadcast
from pdfem.tools.study.accuracy import AccuracyStudy, Setting

NAN = float("nan")
# Statistics of the region behind the front compared between levels (census keys)
COMPARED = (("mean", "mean"), ("p99", "99th percentile"), ("p99.9", "99.9th percentile"),
            ("max", "peak"))


def thermal_variant(doc):
    """The scene dict with every heat effect it can have, when it has no [heat]: heat,
    conduction, dissipation heating, thermo-elastic coupling with thermal expansion when every
    material can take it (a linear bulk with its expansion, or an equation of state with a
    Gruneisen coefficient and no expansion), and, where their owner is present, viscous heating
    ([bulk_viscosity]) and friction heating ([contact]). A scene with [heat] keeps its own
    heat effects. Either way a given output.fields gains element_temperature and the heat_*
    fields the census reads."""
    out = copy.deepcopy(doc)
    fields = out.get("output", {}).get("fields")
    if fields is not None:
        # The census reads the element temperatures and the heat by mechanism
        heat = ["element_temperature"] + [f"heat_{m}" for m in MECHANISMS]
        out["output"]["fields"] = list(dict.fromkeys(list(fields) + heat))
    if "heat" in out:
        return out
    for name in ("heat", "conduction", "dissipation_heating"):
        out[name] = {}
    # The thermo-elastic coupling where every material can take it (a linear bulk with its
    # expansion, an equation of state with its Gruneisen coefficient and no expansion:
    # pdfem.effects.thermal.check_coupled_materials)
    try:
        check_coupled_materials(out.get("materials", {}), "thermoelastic")
    except SceneError:
        pass
    else:
        out["thermoelastic"] = {}
        out["thermal_expansion"] = {}
    if "bulk_viscosity" in out:
        out["viscous_heating"] = {}
    if "contact" in out:
        out["friction_heating"] = {}
    return out


def mechanism_heat(path):
    """{mechanism: heat [J/m] the grains received by the last frame} from the run's
    heat_<mechanism> fields (grain elements only)."""
    with h5py.File(path, "r") as f:
        grain = f["mesh/body_kind"][()][f["mesh/elem_body"][()]] == 0
        return {name.removeprefix("heat_"): float(f[f"frames/{name}"][-1][grain].sum())
                for name in (f"heat_{m}" for m in MECHANISMS) if f"frames/{name}" in f}


def level_row(row, result, heat, t_initial):
    """The study's row of one level: its run (wall time, steps), the census of its last
    frame behind the front and over the whole bed, and the heat by mechanism."""
    last = result["frames"][-1]
    shocked = last.get("shocked", last["whole"])
    out = {"level": row["setting"].level, "rule": row["setting"].rule,
           "quads_per_grain": row["setting"].quads, "wall_s": row["wall_s"],
           "steps": row["steps"], "status": row["status"], "time": last["time"],
           "t_initial": t_initial, "n_spots": shocked["n_spots"],
           "whole_max": last["whole"]["max"],
           "area_fraction": shocked["area_fraction"], "heat": heat}
    out.update({key: shocked[key] for key, _ in COMPARED})
    return out


def changes(rows):
    """Per pair of successive levels and compared statistic: the change of the temperature
    rise, (T_fine - T_coarse) / (T_fine - T_initial), NaN where the rise is not positive."""
    out = []
    for a, b in zip(rows, rows[1:], strict=False):
        ch = {"levels": (a["level"], b["level"])}
        for key, _ in COMPARED:
            rise = b[key] - b["t_initial"]
            ch[key] = (b[key] - a[key]) / rise if rise > 0 else NAN
        out.append(ch)
    return out


class HotspotStudy:
    """Runs one thermal scene at several levels into a folder; one row per level.

    ``doc`` is the scene dict (its thermal variant is taken), ``scene`` the checked scene of
    that variant, ``rule`` the element rule of every run.
    """

    def __init__(self, doc, scene, folder, comm, rule, log=print):
        self.runs = AccuracyStudy(doc, scene, folder, comm, log)
        self.scene, self.comm, self.rule = scene, comm, rule
        self.log = log if comm.rank == 0 else (lambda *a, **k: None)

    def check_levels(self, levels):
        """Every level must be a multiple of the bed file's (InputError otherwise)."""
        self.runs.check_levels(levels)

    def check_steps(self, levels, allow_huge=False):
        """Refuse (pdfem.limits.check_runs) a study any of whose levels would run more than
        MAX_STEPS steps, before the first run; nothing is written."""
        safety = self.scene.resolved["time"]["safety"]
        self.runs.check_steps([Setting(lv, self.rule, safety, 1.0, "grid") for lv in levels],
                              allow_huge)

    def run_all(self, levels, thresholds, spot_threshold):
        """Run every level, take the census of each on rank 0 and return (rows, changes),
        the same on every rank."""
        from pdfem.tools.analysis.hotcensus import census

        safety = self.scene.resolved["time"]["safety"]
        t_initial = self.scene.resolved["heat"]["initial"]
        rows = []
        for k, level in enumerate(levels):
            setting = Setting(level, self.rule, safety, 1.0, "grid")
            row = self.runs.run(setting)
            out = None
            if self.comm.rank == 0:
                if row["status"] == "ok":
                    result, _ = census(row["run_file"], thresholds, spot_threshold)
                    out = level_row(row, result, mechanism_heat(row["run_file"]), t_initial)
                else:
                    out = {"level": level, "rule": self.rule, "status": row["status"],
                           "wall_s": row["wall_s"], "steps": row["steps"]}
            out = broadcast(self.comm, out)
            rows.append(out)
            self.log(f"[{k + 1}/{len(levels)}] {setting.label}: {row['wall_s']:.1f} s, "
                     f"{row['steps']} steps; " + (_summary(out) if out["status"] == "ok"
                                                   else out["status"]), flush=True)
        ok = [r for r in rows if r["status"] == "ok"]
        return rows, changes(ok)


def _summary(row):
    """One line of a level's statistics."""
    vals = ", ".join(f"{name} {row[key]:.1f} K" for key, name in COMPARED)
    return f"behind the front: {vals}; {row['n_spots']} spot(s)"


def table_lines(rows, chg):
    """The study's table: one line per level, then the changes between levels."""
    mechs = list(MECHANISMS)
    head = (f"{'level':>5} {'quads':>5} {'wall s':>7} {'mean K':>7} {'p99 K':>7} "
            f"{'p99.9 K':>8} {'peak K':>7} {'spots':>5} | heat [J/m]: "
            + " ".join(f"{m:>13}" for m in mechs))
    lines = [head]
    for r in rows:
        if r["status"] != "ok":
            lines.append(f"{r['level']:>5} {'':>5} {r['wall_s']:>7.1f}  {r['status']}")
            continue
        lines.append(f"{r['level']:>5} {r['quads_per_grain']:>5} {r['wall_s']:>7.1f} "
                     f"{r['mean']:>7.1f} {r['p99']:>7.1f} {r['p99.9']:>8.1f} {r['max']:>7.1f} "
                     f"{r['n_spots']:>5} | {'':>11}"
                     + " ".join(f"{r['heat'].get(m, NAN):>13.3f}" for m in mechs))
    lines.append("change of the temperature rise between levels, (T_fine - T_coarse) / "
                 "(T_fine - T_initial):")
    for c in chg:
        lines.append(f"  {c['levels'][0]} -> {c['levels'][1]}: "
                     + ", ".join(f"{name} {_pct(c[key])}" for key, name in COMPARED))
    return lines


def _pct(v):
    return "n/a" if not math.isfinite(v) else f"{100.0 * v:+.1f} %"


def csv_text(rows):
    """One CSV line per level."""
    mechs = list(MECHANISMS)
    keys = [k for k, _ in COMPARED]
    lines = [",".join(["level", "rule", "quads_per_grain", "status", "wall_s", "steps", "time"]
                      + keys + ["n_spots"] + [f"heat_{m}" for m in mechs])]
    for r in rows:
        ok = r["status"] == "ok"
        vals = [r["level"], r["rule"], r.get("quads_per_grain", ""), r["status"].replace(",", ";"),
                f"{r['wall_s']:.2f}", r["steps"], f"{r['time']:.6e}" if ok else ""]
        vals += [f"{r[k]:.4f}" if ok else "" for k in keys]
        vals += [r["n_spots"] if ok else ""]
        vals += [f"{r['heat'].get(m, np.nan):.6g}" if ok else "" for m in mechs]
        lines.append(",".join(str(v) for v in vals))
    return "\n".join(lines) + "\n"
