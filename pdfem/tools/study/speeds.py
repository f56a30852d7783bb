"""``pdfem study speeds``: the packaged shot-912 scene's piston at several speeds and grain mesh
levels, each run to the scene's end, analysed and checked against the bound of its bed.

A rung is the packaged scene (``shot912_small.toml`` or ``shot912.toml``) with only the piston
changed, as a user would change it: the hammer block's velocity and its ``[[bc]]`` velocity set
to V, and the scene's end, the piston's release and ramp-down and the output intervals scaled
by 288 m/s / V; ``[element]`` takes the rung's rule and level and keeps the scene's other keys.
The piston is then held at V at least until the slowest steady front the bed allows has crossed
it (:func:`crossing_time`, the sweep's bound), the release and the end moved later where the
scaled release would bring it to rest sooner: a front is measured only while its piston drives
it. The packaged scenes hold the piston that long at 288 m/s; scaled by 288/V alone, the
release would come before that crossing from 500 m/s on (by 24 % of it at 2000 m/s).

Every rung runs on all ranks of the command (the same bits on any number); a rung that stops on
a guard is a row with the guard's message and the study goes on. A row holds what the stability
of a hard impact is judged by (to the end or not, the largest energy-balance error, the share of
the grains' area in folded corners, the grain nodes that ended inside another grain's interior
elements) and what its answer is checked with (Us, up, the piston's stress, rho1, the bound of the
bed compacted to its grains' own compression at that stress, the anvil gauge's arrival, the final
compaction).
"""

import copy
import os
import tomllib
from importlib import resources

from pdfem.errors import InputError
from pdfem.tools.analysis.report import bound_word

# The packaged beds and the speed their times are written for [m/s]
BEDS = {"small": "shot912_small.toml", "default": "shot912.toml"}
SCENE_SPEED = 288.0
SPEEDS = (100.0, 288.0, 500.0, 1000.0, 1500.0, 2000.0)


def packaged_doc(bed):
    """The packaged scene of ``bed`` as a dict, its bed file's path made absolute."""
    folder = resources.files("pdfem") / "scenes"
    doc = tomllib.loads((folder / BEDS[bed]).read_text())
    doc["grains_file"]["path"] = str(folder / doc["grains_file"]["path"])
    return doc


def periodic_doc(doc):
    """``doc`` with periodic sides in x instead of its side walls: domain.periodic = "x", no
    left or right contact wall, no condition on those walls (``doc`` is not changed)."""
    d = copy.deepcopy(doc)
    d["domain"]["periodic"] = "x"
    walls = d.get("walls", {})
    for side in ("left", "right"):
        walls.pop(side, None)
    d["bc"] = [b for b in d.get("bc", []) if b.get("wall") not in ("left", "right")]
    return d


def walls_doc(doc):
    """``doc`` between side walls instead of periodic sides: frictionless contact walls left
    and right with roller conditions on them, as the packaged scenes had (``doc`` is not
    changed)."""
    d = copy.deepcopy(doc)
    d["domain"].pop("periodic", None)
    d["walls"] = {**d.get("walls", {}), "left": "frictionless", "right": "frictionless"}
    rollers = [{"wall": side, "type": "roller"} for side in ("left", "right")]
    d["bc"] = [b for b in d.get("bc", []) if b.get("wall") not in ("left", "right")] + rollers
    return d


def piston_doc(doc, speed, rule, level, mesh=None, hold=0.0, written_for=SCENE_SPEED):
    """A rung: ``doc`` with the piston at ``speed`` (hammer block and velocity condition),
    its end, release, ramp-down and output intervals scaled by written_for / speed (the
    piston speed the scene's times are written for), and the element rule and level (and
    mesh, when given) of the rung; a release that would start bringing the piston to rest
    before ``hold`` [s] moves to hold + ramp-down, and the end by as much. ``doc`` is not
    changed."""
    d = copy.deepcopy(doc)
    f = written_for / speed
    for b in d.get("blocks", []) + d.get("bc", []):
        if "velocity" in b:
            b["velocity"] = [0.0, -speed]
        for key in ("release", "ramp_down"):
            if key in b:
                b[key] *= f
    d["time"]["end"] *= f
    # Held until hold: the release later, the time after it kept
    released = [b for b in d.get("bc", []) if "release" in b]
    shift = max([hold + b.get("ramp_down", 0.0) - b["release"] for b in released], default=0.0)
    if shift > 0.0:
        for b in released:
            b["release"] += shift
        d["time"]["end"] += shift
    for key in ("interval", "energy_interval", "gauge_interval"):
        if key in d.get("output", {}):
            d["output"][key] *= f
    d["element"] = {**d.get("element", {}), "rule": rule, "level": level,
                    **({"mesh": mesh} if mesh else {})}
    return d


def crossing_time(scene, speed):
    """Seconds the slowest steady front the bed of a shock ``scene`` allows at particle speed
    ``speed`` takes to cross it (pdfem.tools.study.hugoniot.slowest_front: the bed compacted
    to its grains' own compression under the front's stress; the bed's height and packing of
    the scene's meshes); InputError when no density the bed can hold carries that stress."""
    from pdfem.tools.study import hugoniot as hg

    H0, phi0, _ = hg.bed_figures(scene)
    rho_s = scene.resolved["shock"]["solid_density"]
    us = hg.slowest_front(speed, phi0 * rho_s, rho_s, hg.grain_material(scene.resolved))
    if not us > 0.0:
        raise InputError(f"--speeds: at {speed:g} m/s the front's stress would crush the grains "
                         "past any density this bed can hold")
    return H0 / us


def rung_doc(doc, speed, rule, level, mesh=None, written_for=SCENE_SPEED, base_dir="."):
    """:func:`piston_doc` with the piston held until the slowest front has crossed the bed
    (:func:`crossing_time` of the rung's own meshes; relative paths from ``base_dir``)."""
    from pdfem.scene import parse_scene

    first = parse_scene(piston_doc(doc, speed, rule, level, mesh, written_for=written_for),
                        base_dir,
                        name=f"{doc.get('output', {}).get('path', 'scene')} at {speed:g} m/s")
    return piston_doc(doc, speed, rule, level, mesh, hold=crossing_time(first, speed),
                      written_for=written_for)


def rung_name(rung):
    """The file stem of a rung's run (a dict of bed, rule, level, velocity and sides)."""
    sides = "-walls" if rung.get("sides") == "walls" else ""
    return f"{rung['bed']}-{rung['rule']}-l{rung['level']}-v{rung['velocity']:g}{sides}"


def row_of(rung, summary, wall_s, steps):
    """A table row from a rung (bed, rule, level, speed) and its run's analysis summary."""
    f, h, bd, m = summary["front"], summary["shocked"], summary["bound"], summary["mesh"]
    return {**rung, "runs": True, "wall_s": wall_s, "steps": steps,
            "energy_error": summary["energy"]["balance_error_max"], "us": f["us"],
            "us_se": f["se"], "steady": f["steady"], "up": h["up"], "sigma": h["sigma"],
            "rho1": h["rho1"], "rho1_max": bd["rho1_max"], "us_min": bd["us_min"],
            "bound_kept": bd["kept"], "arrival": f["arrival_gauge"],
            "compaction": summary["compaction"]["final"], "folded": m["folded_max"],
            "interpenetrated": m["interpenetrated_end"],
            "escape": max(m["escape"]["below_anvil"], m["escape"]["above_hammer"]),
            "escaped": m["escape"]["escaped"], "escaped_mass": m["escape"]["mass"],
            "momentum_closure": summary["jump"]["momentum_closure"]}


def stopped_row(rung, message):
    """The row of a rung whose run stopped on a guard."""
    return {**rung, "runs": False, "stopped": message}


def _pct(v, digits=2):
    return f"{100.0 * v:.{digits}f} %" if v == v else "-"


def table_lines(rows):
    """The printed table: one line per rung."""
    out = ["bed      rule level  V [m/s]  result           energy err  folded   Us [m/s]"
           "          up [m/s]  sigma [GPa]  rho1 (max) [kg/m3]  Us bound  bound   arrival "
           "[us]  compaction  interpenetrated  escape [um] (grain mass past)"]
    for r in rows:
        head = f"{r['bed']:8s} {r['rule']:4s} {r['level']:5d}  {r['velocity']:7g}  "
        if not r["runs"]:
            out.append(head + "stopped: " + r["stopped"])
            continue
        out.append(head + f"runs ({r['wall_s']:6.0f} s)  {_pct(r['energy_error'], 3):>10s}  "
                   f"{_pct(r['folded']):>7s}  {r['us']:7.1f} +- {r['us_se']:5.1f}  "
                   f"{r['up']:8.1f}  {r['sigma'] * 1e-9:11.3f}  {r['rho1']:7.0f} "
                   f"({r['rho1_max']:5.0f})    {r['us_min']:8.0f}  "
                   f"{bound_word(r['bound_kept'], none='n/a'):6s}  {r['arrival'] * 1e6:12.4f}  "
                   f"{r['compaction']:10.3f}  {_pct(r['interpenetrated']):>15s}  "
                   f"{r['escape'] * 1e6:7.1f}"
                   + (f" ({_pct(r['escaped_mass'], 3)}) ESCAPED" if r["escaped"] else ""))
    return out


def run_rungs(rungs, folder, comm, log=print):
    """Run every rung (a list of (rung dict, checked scene)) on ``comm`` into ``folder`` and
    analyse it on rank 0; the rows (rank 0; None elsewhere) and the number that stopped. A
    rung stopped by SIGTERM or SIGUSR1 (its checkpoint written) ends the study there."""
    from pdfem.driver import run as drive
    from pdfem.errors import SimulationError
    from pdfem.solver import Simulation
    from pdfem.tools.analysis import analyse

    rows, stops = [], 0
    for rung, scene in rungs:
        out = os.path.join(folder, rung_name(rung) + ".h5")
        if comm.rank == 0:
            log(f"pdfem study speeds: {rung['bed']} bed, {rung['rule']}, level {rung['level']}, "
                f"piston at {rung['velocity']:g} m/s to {scene.resolved['time']['end'] * 1e6:.3f}"
                f" us -> {out}")
        try:
            summary = drive(Simulation(scene, comm), out, quiet=True)
        except SimulationError as exc:
            stops += 1
            if comm.rank == 0:
                rows.append(stopped_row(rung, str(exc)))
                log(f"  stopped: {exc}")
            continue
        if summary["stopped"]:
            # Stopped by a signal: the run file is not finished and no rung after it starts
            stops += 1
            msg = (f"stopped by a signal at t={summary['time']:.6e} s (step {summary['steps']}); "
                   f"its checkpoint is {summary['checkpoint']}; the rungs after it were not run")
            if comm.rank == 0:
                rows.append(stopped_row(rung, msg))
                log(f"  {msg}")
            break
        if comm.rank == 0:
            s = analyse(out, os.path.splitext(out)[0])
            rows.append(row_of(rung, s, summary["wall_s"], summary["steps"]))
            log(table_lines(rows[-1:])[1])
    return (rows if comm.rank == 0 else None), stops
