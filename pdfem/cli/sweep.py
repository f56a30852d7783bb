"""``pdfem sweep [scene.toml] --velocities 100,200,...``: the bed's compaction Hugoniot.

The shock scene's hammer is driven as a piston at each speed until the slowest steady front
the bed allows has crossed it (:mod:`pdfem.tools.study.hugoniot`); each run is analysed
(steady fronts only are fitted) and checked against the bound of a bed compacted to its
grains' own compression at the measured stress. Writes the runs ``<prefix>-v<speed>.h5``
with their summaries, ``<prefix>.json`` (one row per speed) and ``<prefix>.png``: Us-up with
the precursor, the snowplow speed and the crystal's Hugoniot; stress-density with the same
and, with ``--static``, the bed's static compression curve (``<prefix>-static.h5``).
``--level`` meshes the grains at another level than the scene's.

A speed whose run stops on a guard is kept as a marked row (no front, the guard's message)
and the sweep goes on to the next speed; it then exits with status 3.
"""

import json
import math
import os
import sys
import tomllib
from itertools import pairwise

from pdfem.errors import InputError, SimulationError
from pdfem.limits import MAX_STEPS, add_allow_huge

DEFAULT_SPEEDS = "100,200,288,400,500,700,1000,1500,2000"


def add_parser(sub):
    p = sub.add_parser("sweep", help="the bed's compaction Hugoniot: a piston at several "
                       "speeds (Us-up, stress-density, snowplow bound, crystal Hugoniot)")
    p.add_argument("scene", nargs="?", default=None, help="scene with a [shock] table "
                   "(default: the packaged shot912.toml)")
    p.add_argument("--velocities", default=DEFAULT_SPEEDS,
                   help=f"piston speeds [m/s], comma separated (default {DEFAULT_SPEEDS})")
    p.add_argument("--static", action="store_true", help="also compress the bed "
                   "quasi-statically and draw its stress-density curve beside the Hugoniot")
    p.add_argument("--level", type=int, default=None, help="grain mesh level for every run "
                   "(a multiple of the bed file's; default: the scene's element.level)")
    p.add_argument("-p", "--prefix", default="sweep", help="prefix of the run files, "
                   "<prefix>.json and <prefix>.png (default: sweep)")
    p.add_argument("--force", action="store_true", help="overwrite existing run files")
    add_allow_huge(p, f"a run of more than {MAX_STEPS:.0e} steps")


def _speeds(text):
    """The --velocities list: positive floats."""
    try:
        vals = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise InputError(f"--velocities: not a list of numbers: {text!r}") from None
    if not vals or any(not 0.0 < v < math.inf for v in vals):
        raise InputError(f"--velocities: need speeds > 0 m/s, finite (got {text!r})")
    return vals


def _point(v, s, summary):
    """One row of the sweep from a run's analysis summary."""
    f, p, h, j, b = s["front"], s["precursor"], s["shocked"], s["jump"], s["bed"]
    return {"velocity": v, "us": f["us"], "us_se": f["se"], "us_fit": f["us_fit"],
            "steady": f["steady"], "steadiness": f["steadiness"], "note": f["note"],
            "precursor": p["us"],
            "precursor_fit": p["us_fit"], "up": h["up"], "sigma": h["sigma"],
            "sigma_source": h["sigma_source"], "sigma_bed": h["sigma_bed"],
            "rho0": b["rho0"], "rho1": h["rho1"], "solid_density": b["solid_density"],
            "snowplow_us": s["snowplow"]["us"], "snowplow_sigma": s["snowplow"]["sigma"],
            "mass_closure": j["mass_closure"], "mass_strain_closure": j["mass_strain_closure"],
            "momentum_closure": j["momentum_closure"],
            "crystal_hugoniot": s["hugoniot"]["crystal"],
            "rho1_max": s["bound"]["rho1_max"], "us_min": s["bound"]["us_min"],
            "bound_kept": s["bound"]["kept"], "folded": s["mesh"]["folded_max"],
            "balance_error": summary["balance_error"], "wall_s": summary["wall_s"]}


def _stopped(v, exc, bed, snowplow_us):
    """The row of a speed whose run stopped on a guard: no front, the guard's message."""
    return {"velocity": v, "us": None, "us_se": None, "us_fit": None, "steady": False,
            "steadiness": None, "note": f"run stopped: {exc}", "stopped": str(exc),
            "precursor": None, "precursor_fit": None, "up": None, "sigma": None,
            "sigma_source": None, "sigma_bed": None, "rho0": bed["rho0"], "rho1": None,
            "solid_density": bed["solid_density"], "snowplow_us": snowplow_us,
            "snowplow_sigma": None, "mass_closure": None, "mass_strain_closure": None,
            "momentum_closure": None, "crystal_hugoniot": None, "rho1_max": None,
            "us_min": None, "bound_kept": None, "folded": None, "balance_error": None,
            "wall_s": None}


def _f(v, scale=1.0):
    """A number for the log line, or n/a."""
    return "n/a" if v is None or v != v else f"{v * scale:.1f}"


def run(args):
    from pdfem.cli.paths import check_output_path
    from pdfem.cli.run import run_outputs
    from pdfem.packaged import default_scene_path
    from pdfem.scene import check_ranks, load_scene, parse_scene
    from pdfem.tools.study import hugoniot as hg

    # The input first (a bad one is reported before MPI and the solver load)
    speeds = _speeds(args.velocities)
    path = args.scene or default_scene_path()
    scene = load_scene(path)
    hg.check_scene(scene, path)
    with open(path, "rb") as fh:
        doc = tomllib.load(fh)
    if args.level is not None:
        if not 1 <= args.level <= 16:
            raise InputError(f"--level: need a grain mesh level from 1 to 16 (got {args.level})")
        doc["element"] = dict(doc.get("element", {}), level=args.level)
        scene = parse_scene(doc, scene.base_dir, name=f"{path} (--level {args.level})",
                            path=path)
    sh = scene.resolved["shock"]
    H0, phi0, width = hg.bed_figures(scene)
    outs = [f"{args.prefix}-v{v:g}.h5" for v in speeds]
    files = [f for o in outs for f in run_outputs(o, scene, plots="none")]
    extra = [args.prefix + s for s in (".json", ".png")]
    if args.static:
        extra += [f for f in run_outputs(args.prefix + "-static.h5", scene, plots="none")
                  if "summary" not in f]
    for out in files + extra:
        check_output_path(out, args.force, "--prefix")
    mat = hg.grain_material(scene.resolved)
    rho_s = sh["solid_density"]
    slowest = [hg.slowest_front(v, phi0 * rho_s, rho_s, mat) for v in speeds]
    for v, us in zip(speeds, slowest, strict=True):
        if not us > 0:
            raise InputError(f"--velocities: at {v:g} m/s the wave's stress would crush the "
                             "grains past any density this bed can hold")
    docs = [parse_scene(hg.shock_doc(doc, sh["hammer"], v, H0, us), scene.base_dir,
                        name=f"{path} (piston at {v:g} m/s)")
            for v, us in zip(speeds, slowest, strict=True)]
    static = _static_scene(scene, doc, sh, H0, phi0) if args.static else None
    from pdfem.driver import run as drive
    from pdfem.limits import check_runs
    from pdfem.parallel.mpi import barrier, world
    from pdfem.solver import Simulation
    from pdfem.tools.analysis import analyse
    from pdfem.tools.analysis.plots import sweep_plot
    from pdfem.tools.analysis.report import bound_word

    comm = world()
    check_ranks(scene, comm.size)
    # Every run's step count before the first one starts
    plan = [(sc, f"{path} (piston at {v:g} m/s)") for v, sc in zip(speeds, docs, strict=True)]
    check_runs(plan, comm, args.allow_huge, key="--velocities",
               remedy="faster pistons (a run lasts the snowplow transit time) or a scene "
               "with a longer stable step")
    if static is not None:
        check_runs([(static[0], f"{path} (static compression)")], comm, args.allow_huge,
                   key="--static", remedy="a scene with a longer stable step, no --static")
    points, stops = [], 0
    bed = {"rho0": phi0 * rho_s, "solid_density": rho_s}
    for v, sc, out in zip(speeds, docs, outs, strict=True):
        if comm.rank == 0:
            print(f"pdfem sweep: piston at {v:g} m/s for {sc.resolved['time']['end'] * 1e6:.2f}"
                  f" us -> {out}", flush=True)
        # A guard stops every rank together: the speed becomes a marked row
        try:
            summary = drive(Simulation(sc, comm), out, quiet=True)
        except SimulationError as exc:
            stops += 1
            if comm.rank == 0:
                points.append(_stopped(v, exc, bed, v / (1.0 - phi0)))
                print(f"  stopped: {exc}", flush=True)
            continue
        if summary["stopped"]:
            # Stopped by a signal: the run file is not finished and no speed after it starts
            if comm.rank == 0:
                print(f"pdfem sweep: the run at {v:g} m/s was stopped by a signal at "
                      f"t={summary['time']:.6e} s (step {summary['steps']}); its checkpoint is "
                      f"{summary['checkpoint']}; the speeds after it were not run and no table "
                      "was written", flush=True)
            barrier(comm)
            return 3
        if comm.rank == 0:
            s = analyse(out, os.path.splitext(out)[0])
            points.append(_point(v, s, summary))
            p = points[-1]
            print(f"  Us {_f(p['us'])} m/s" + (f" ({p['note']})" if p["note"] else "")
                  + f", precursor {_f(p['precursor'])} m/s, up {_f(p['up'])} m/s, rho1 "
                  f"{_f(p['rho1'])} kg/m3, stress {_f(p['sigma'], 1e-6)} MPa; bound of the "
                  f"compacted crystal Us >= {_f(p['us_min'])} m/s, rho1 <= {_f(p['rho1_max'])} "
                  f"kg/m3: {bound_word(p['bound_kept'])}", flush=True)
    static = _static(args, static, sh, H0, phi0, width, comm) if args.static else None
    if static is STOPPED:
        barrier(comm)
        return 3
    if comm.rank == 0:
        from pdfem.tools.analysis.jsontext import plain
        from pdfem.tools.provenance import provenance

        checks = _checks(points)
        for line in checks:
            print(f"pdfem sweep: {line}", flush=True)
        body = {"provenance": provenance(comm.size), "points": points, "checks": checks,
                "static": None if static is None else {k: v for k, v in static.items()}}
        with open(args.prefix + ".json.part", "w") as fh:
            json.dump(plain(body), fh, indent=1)
        os.replace(args.prefix + ".json.part", args.prefix + ".json")
        sweep_plot(points, args.prefix + ".png", static=static)
        print(f"pdfem sweep: {args.prefix}.json, {args.prefix}.png", flush=True)
        if stops:
            print(f"pdfem sweep: {stops} of {len(speeds)} runs stopped on a guard (marked rows; "
                  "exit status 3)", file=sys.stderr, flush=True)
    barrier(comm)
    return 3 if stops else 0


# What _static returns for a static run stopped by a signal
STOPPED = object()


def _static_scene(scene, doc, sh, H0, phi0):
    """The checked scene of the static compression run and its snowplow stress floor."""
    from pdfem.scene import parse_scene
    from pdfem.tools.study import hugoniot as hg

    d, floor = hg.static_doc(doc, sh["hammer"], H0, phi0)
    return parse_scene(d, scene.base_dir, name=f"{scene.path} (static compression)"), floor


def _static(args, static, sh, H0, phi0, width, comm):
    """The static compression run of ``static`` (its scene and stress floor) and its curve
    (rank 0; None elsewhere; STOPPED on every rank when a signal stopped it)."""
    from pdfem.driver import run as drive
    from pdfem.solver import Simulation
    from pdfem.tools.study import hugoniot as hg

    sc, floor = static
    out = args.prefix + "-static.h5"
    if comm.rank == 0:
        print(f"pdfem sweep: static compression (densities x {hg.STATIC_SCALE:g}, piston at "
              f"{hg.STATIC_SPEED:g} m/s, snowplow floor {floor * 1e-6:.2f} MPa) -> {out}",
              flush=True)
    summary = drive(Simulation(sc, comm), out, quiet=True)
    if summary["stopped"]:
        if comm.rank == 0:
            print(f"pdfem sweep: the static compression was stopped by a signal at "
                  f"t={summary['time']:.6e} s (step {summary['steps']}); its checkpoint is "
                  f"{summary['checkpoint']}; no table was written", flush=True)
        return STOPPED
    if comm.rank != 0:
        return None
    rho_s = sh["solid_density"]
    c = hg.static_curve(out, sh["hammer_gauge"], sh["anvil_gauge"], H0, phi0 * rho_s, width,
                        hg.STATIC_SPEED, floor)
    c.update(floor=floor, wall_s=summary["wall_s"], scale=hg.STATIC_SCALE,
             speed=hg.STATIC_SPEED)
    print(f"  the bed jams at {c['jamming_density']:.0f} kg/m3 (packing "
          f"{c['jamming_density'] / rho_s:.3f}); kinetic energy gained / piston work at the end "
          f"{c['kinetic_over_work']:.3g}; {summary['wall_s']:.0f} s", flush=True)
    return c


def _checks(points):
    """Lines on the Hugoniot's shape: fronts fitted, monotone Us(up) and stress(density),
    every front against the snowplow speed and the bound of the compacted crystal, meshes that
    fold."""
    from pdfem.tools.analysis.report import FOLDED_LIMIT

    ok = [p for p in points if p["us"] is not None and p["us"] == p["us"]]
    lines = [f"{len(ok)} of {len(points)} speeds have a steady front"]
    stopped = [p for p in points if p.get("stopped")]
    if stopped:
        lines.append("stopped on a guard (no front): " + ", ".join(
            f"{p['velocity']:g} m/s" for p in stopped))
    ok.sort(key=lambda p: p["up"])
    us_up = all(b["us"] > a["us"] for a, b in pairwise(ok))
    sig_rho = all(b["sigma"] > a["sigma"] and b["rho1"] > a["rho1"] for a, b in pairwise(ok))
    lines.append(f"Us rises with up: {'yes' if us_up else 'no'}; stress rises with density: "
                 f"{'yes' if sig_rho else 'no'}")
    below = [p for p in ok if not p["us"] >= p["snowplow_us"]]
    lines.append("every steady front at or above its snowplow speed (rigid grains)" if not below
                 else "below the snowplow speed (rigid grains; no bound for grains that compress): "
                 + ", ".join(f"{p['velocity']:g} m/s (Us {p['us']:.0f} < "
                             f"{p['snowplow_us']:.0f})" for p in below))
    broken = [p for p in ok if p["bound_kept"] is False]
    lines.append("every steady front keeps the bound of the bed compacted to its grains' own "
                 "compression" if not broken else "the bound of the bed compacted to its "
                 "grains' own compression is broken (not a state of this bed): " + ", ".join(
                     f"{p['velocity']:g} m/s (Us {p['us']:.0f}, bound {p['us_min']:.0f}; rho1 "
                     f"{p['rho1']:.0f}, bound {p['rho1_max']:.0f})" for p in broken))
    folded = [p for p in points if p["folded"] is not None and p["folded"] > FOLDED_LIMIT]
    if folded:
        lines.append(f"grain meshes folded over themselves (more than {100 * FOLDED_LIMIT:g} % "
                     "of their area in folded corners; the answer is the mesh's): " + ", ".join(
                         f"{p['velocity']:g} m/s ({100 * p['folded']:.1f} %)" for p in folded))
    return lines
