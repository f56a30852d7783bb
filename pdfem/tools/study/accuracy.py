"""Accuracy-cost study of a shock scene: one run per setting, measured against the converged
estimate of its ladder of meshes.

A setting is a grain mesh level (6 level^2 quads per grain), an element rule (1-point with
hourglass control, or 2x2), a time-step safety factor and a factor on the contact stiffness.
A full Cartesian grid of the four is too slow, so the study runs

1. the grid of every level x every rule at the scene's safety factor and stiffness; from its
   ladders, the converged estimate of each quantity with its uncertainty
   (:mod:`pdfem.tools.study.estimate`: Richardson extrapolation with the observed order,
   each rule, then the rules combined), against which every run's error is measured;
2. one axis at a time around a baseline (level, rule): every other safety factor, then every
   other stiffness factor. The baseline is given, or by default the cheapest grid run whose
   every error is within the tolerance (failing that, the grid run with the smallest worst
   error): the settings a user would pick are probed where they matter.

Every run goes through the normal :class:`~pdfem.solver.Simulation` and driver on the
study's communicator, so a study gives the same numbers on any number of ranks (the wall
times aside). Levels other than the bed file's use the bed re-meshed by
:func:`pdfem.prepare.relevel.relevel_bed` (same grain polygons, same mass), written once per
(level, rule) next to the run files.

The measured quantities (:mod:`pdfem.tools.study.quantities`) come from the shock analysis on
rank 0 and are broadcast, so every rank takes the same decisions.
"""

import copy
import math
import os
import time
from dataclasses import dataclass

import h5py
import numpy as np

from pdfem.errors import InputError, SimulationError
from pdfem.parallel.mpi import barrier, broadcast, global_max
from pdfem.tools.study import pareto
from pdfem.tools.study.estimate import converged
from pdfem.tools.study.quantities import MEASURED, QUANTITIES, SE_KEYS, measure

RULES = ("1pt", "2x2")


@dataclass(frozen=True)
class Setting:
    """One point of the study: mesh level, element rule, safety factor, stiffness factor.

    ``axis`` says why it runs: ``grid`` (level x rule), ``safety`` or ``kn0`` (one axis
    varied around the baseline).
    """

    level: int
    rule: str
    safety: float
    kn0_scale: float
    axis: str = "grid"

    @property
    def key(self):
        """The setting without its reason (two settings with one key are one run)."""
        return (self.level, self.rule, self.safety, self.kn0_scale)

    @property
    def label(self):
        """Short name, also the run file's: ``L2-2x2-s0.5-k1``."""
        return f"L{self.level}-{self.rule}-s{self.safety:g}-k{self.kn0_scale:g}"

    @property
    def quads(self):
        """Quads per grain, 6 level^2."""
        return 6 * self.level * self.level


def grid_settings(levels, rules, safety):
    """Every level x every rule at one safety factor and the scene's stiffness."""
    return [Setting(lv, r, safety, 1.0, "grid") for lv in levels for r in rules]


def axis_settings(base, safeties, kn0_scales):
    """One axis at a time around ``base``: the other safety factors, the other stiffnesses."""
    out = [Setting(base.level, base.rule, s, base.kn0_scale, "safety") for s in safeties
           if s != base.safety]
    out += [Setting(base.level, base.rule, base.safety, k, "kn0") for k in kn0_scales
            if k != base.kn0_scale]
    return out


def possible_settings(levels, rules, safeties, kn0_scales, safety, base=None):
    """Every setting a study may run: the grid at ``safety`` (the scene's) and the axes
    around the baseline ``base`` (level, rule) or, when it is chosen from the grid's
    results, around every grid setting."""
    grid = grid_settings(levels, rules, safety)
    bases = [Setting(base[0], base[1], safety, 1.0)] if base else grid
    out = list(grid)
    for b in bases:
        out += axis_settings(b, safeties, kn0_scales)
    return unique(out)


def unique(settings):
    """The settings without repeats (the first of each key kept, in order)."""
    seen, out = set(), []
    for s in settings:
        if s.key not in seen:
            seen.add(s.key)
            out.append(s)
    return out


def scale_contact(doc, factor):
    """Multiply every given contact stiffness (kn0, ks, and those of [contact.pairs]) of the
    scene dict ``doc`` by ``factor``, in place (a derived ks follows kn0 by itself)."""
    contact = doc.get("contact", {})
    tables = [contact] + list(contact.get("pairs", {}).values())
    for tab in tables:
        for key in ("kn0", "ks"):
            if key in tab:
                tab[key] = float(tab[key]) * factor


def bed_level(path):
    """Mesh level of a bed file; InputError when it cannot be read."""
    try:
        with h5py.File(path, "r") as f:
            return int(f.attrs["level"])
    except (OSError, KeyError) as exc:
        raise InputError(f"grains_file.path: {path}: not a readable bed file ({exc})") from None


class AccuracyStudy:
    """Runs the settings of one scene into a folder; one dict (a row) per run.

    ``doc`` is the scene as ``tomllib`` reads it, ``scene`` the checked scene (for the bed
    file and the defaults), ``folder`` where the run files and re-meshed beds go.
    """

    def __init__(self, doc, scene, folder, comm, log=print):
        self.doc, self.scene, self.folder, self.comm = doc, scene, folder, comm
        self.log = log if comm.rank == 0 else (lambda *a, **k: None)
        gf = scene.resolved.get("grains_file", {})
        path = gf.get("path", "")
        self.bed = path if path.lower().endswith((".h5", ".hdf5")) else None
        self.bed_level = bed_level(self.bed) if self.bed else None
        # Integration points per element of the bed's stresses (None: no stresses stored)
        self.bed_nip = None
        if self.bed:
            with h5py.File(self.bed, "r") as f:
                self.bed_nip = f["grains/stress"].shape[2] if "grains/stress" in f else None
        self.rows = []
        # The converged estimate of each quantity (pdfem.tools.study.estimate.converged)
        self.estimate = None

    def check_levels(self, levels):
        """Every level must be a multiple of the bed file's (InputError otherwise)."""
        if self.bed_level is None:
            return
        bad = [lv for lv in levels if lv % self.bed_level]
        if bad:
            raise InputError(f"--levels: {bad[0]} is not a multiple of the level "
                             f"{self.bed_level} of the bed file {self.bed}")

    def bed_for(self, setting):
        """The bed file of a setting's level and rule: the scene's own, or a re-meshed copy."""
        from pdfem.prepare.relevel import relevel_bed

        nip = self.bed_nip
        same_rule = nip is None or nip == (1 if setting.rule == "1pt" else 4)
        if setting.level == self.bed_level and same_rule:
            return self.bed
        path = os.path.join(self.folder, f"bed-L{setting.level}-{setting.rule}.h5")
        # Rank 0 writes it once; every rank waits for it
        if self.comm.rank == 0 and not os.path.exists(path):
            relevel_bed(self.bed, path, setting.level, setting.rule)
        barrier(self.comm)
        return path

    def scene_of(self, setting, name, written=True):
        """The checked scene of a setting: the scene dict with its element, time step,
        contact stiffness and bed replaced; no figures, no checkpoints; a driven hammer that
        is released ends the run there (the study measures the wave, not the spring-back).
        ``written=False``: the bed re-meshed in memory, as :meth:`bed_for` would write it
        (the same grains, positions and stresses; nothing written)."""
        from pdfem.scene import parse_scene

        doc = copy.deepcopy(self.doc)
        hammer = self.scene.resolved.get("shock", {}).get("hammer")
        for bc in self.scene.resolved.get("bc", []):
            if bc.get("body") == hammer and "release" in bc:
                doc["time"]["end"] = min(doc["time"]["end"], bc["release"])
        doc.setdefault("element", {}).update(rule=setting.rule, level=setting.level)
        doc.setdefault("time", {})["safety"] = setting.safety
        scale_contact(doc, setting.kn0_scale)
        if self.bed:
            bed = self.bed_for(setting) if written else self.bed
            doc["grains_file"]["path"] = os.path.abspath(bed)
        doc.setdefault("shock", {})["plots"] = "none"
        doc.setdefault("output", {}).update(checkpoint_interval=0.0, checkpoint_wall=0.0)
        scene = parse_scene(doc, self.scene.base_dir, name=name)
        if not written:
            _stresses_to_rule(scene.grains, setting)
        return scene

    def check_steps(self, plan, allow_huge=False):
        """Refuse (pdfem.limits.check_runs) a study any of whose settings in ``plan`` would
        run more than MAX_STEPS steps, before the first run; nothing is written."""
        from pdfem.limits import check_runs

        names = ((s, f"{self.scene.path} ({s.label})") for s in plan)
        check_runs(((self.scene_of(s, name, written=False), name) for s, name in names),
                   self.comm, allow_huge, remedy="shorten time.end, leave the setting out "
                   "(--levels, --safety, --kn0-scale)")

    def run(self, setting):
        """Run one setting (once: a setting already run returns its row); return the row."""
        from pdfem.driver import run as drive
        from pdfem.solver import Simulation

        for row in self.rows:
            if row["setting"].key == setting.key:
                return row
        out = os.path.join(self.folder, setting.label + ".h5")
        sc = self.scene_of(setting, f"{self.scene.path} ({setting.label})")
        # Wall time of the run itself (set-up and stepping), the slowest rank's
        t0 = time.perf_counter()
        status, steps = "ok", 0
        try:
            summary = drive(Simulation(sc, self.comm), out, quiet=True)
            steps = int(summary["steps"])
        except SimulationError as exc:
            status = f"failed: {exc}"
        wall = global_max(self.comm, time.perf_counter() - t0)
        vals = None
        if self.comm.rank == 0:
            vals = ({k: math.nan for k in MEASURED} if status != "ok"
                    else measure(out, os.path.splitext(out)[0]))
        vals = broadcast(self.comm, vals)
        row = {"setting": setting, "wall_s": wall, "steps": steps, "status": status,
               "run_file": out if status == "ok" else "", **vals}
        self.rows.append(row)
        return row

    def run_all(self, levels, rules, safeties, kn0_scales, tol, base=None):
        """Run the study (module docstring) and return its rows with their errors against
        the converged estimate (kept in ``self.estimate``) and their Pareto flags.

        ``safeties`` and ``kn0_scales`` are the values of the two axes (the grid runs at the
        scene's safety factor and stiffness); ``base`` an optional (level, rule) baseline,
        otherwise chosen with ``tol`` by :func:`baseline`. Raises
        :class:`~pdfem.errors.SimulationError` when no quantity has an estimate (every
        ladder of the grid has fewer than two runs that ended).
        """
        safety = self.scene.resolved["time"]["safety"]
        plan = grid_settings(levels, rules, safety)
        self.log(f"pdfem study accuracy: {self.scene.path} on {self.comm.size} rank(s): the "
                 f"level x rule grid ({len(plan)} runs) and its converged estimate, then "
                 "the safety factors and contact stiffnesses around a baseline", flush=True)
        # The level x rule grid and the estimate from its ladders
        for k, setting in enumerate(plan):
            self._logged(setting, f"{k + 1}/{len(plan)}")
        keys = [k for k, *_ in QUANTITIES]
        self.estimate = converged(self.rows, keys, SE_KEYS)
        if all(self.estimate[k]["combined"] is None for k in keys):
            raise SimulationError("no converged estimate: every ladder of the level x rule "
                                  "grid has fewer than two runs that reached the end")
        values = {k: (e["combined"] or {}).get("value", math.nan)
                  for k, e in self.estimate.items()}
        pareto.add_errors(self.rows, values)
        # One axis at a time around the baseline
        base = (Setting(base[0], base[1], safety, 1.0) if base else baseline(self.rows, tol))
        done = {r["setting"].key for r in self.rows}
        axes = [s for s in axis_settings(base, safeties, kn0_scales) if s.key not in done] \
            if base else []
        if axes:
            self.log(f"baseline {base.label}: {len(axes)} runs varying the safety factor and "
                     "the contact stiffness", flush=True)
        for k, setting in enumerate(axes):
            self._logged(setting, f"axis {k + 1}/{len(axes)}")
        pareto.add_errors(self.rows, values)
        pareto.mark_pareto(self.rows)
        return self.rows

    def _logged(self, setting, count):
        """Run one setting and log it on one line."""
        row = self.run(setting)
        vals = ", ".join(f"{h} {row[k] * s:.4g}{' ' + u if u else ''}"
                         for k, h, _, u, s in QUANTITIES)
        self.log(f"[{count}] {setting.label}: {row['wall_s']:.1f} s, {row['steps']} steps; "
                 + (vals if row["status"] == "ok" else row["status"]), flush=True)


def _stresses_to_rule(grains, setting):
    """A bed's stresses and state (when stored) at the setting's element rule, as
    relevel_bed writes them: the scene re-meshes a bed to another level at its rule, but at
    the bed's own level it keeps the bed's integration points."""
    from pdfem.prepare.relevel import RULE_POINTS, refine_points

    nip = RULE_POINTS[setting.rule]
    if "elem_sig" in grains and grains["elem_sig"].shape[2] != nip:
        for k in ("elem_sig", "elem_mst"):
            grains[k] = refine_points(grains[k], setting.level, setting.level, nip)


def baseline(rows, tol):
    """The grid run to vary the safety factor and stiffness around: the cheapest whose every
    error is within ``tol``, else the one with the smallest worst error (rows carry
    ``err_max``, see :func:`pdfem.tools.study.pareto.add_errors`); None without one."""
    grid = [r for r in rows if r["setting"].axis == "grid" and np.isfinite(r["err_max"])]
    if not grid:
        return None
    good = [r for r in grid if r["err_max"] <= tol]
    if good:
        return min(good, key=lambda r: r["wall_s"])["setting"]
    return min(grid, key=lambda r: r["err_max"])["setting"]
