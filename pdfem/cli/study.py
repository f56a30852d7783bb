"""``pdfem study <name> ...``: studies of the solver.

- ``study accuracy [scene]``: what accuracy costs in time on a shock scene (grid of mesh
  levels, element rules, safety factors and contact stiffnesses against the finest run;
  CSV, Pareto figure, the settings for a 5 % answer) and the element's convergence order;
- ``study convergence``: the element's observed order on a standing elastic wave;
- ``study hard``: hard cases on 1 and N ranks;
- ``study speeds``: the packaged shot-912 piston at several speeds and mesh levels, to the
  scene's end;
- ``study width``: the shot-912 wave in beds of several widths and over seeds.

Each study is one entry of :data:`STUDIES`: a function adding its arguments and one running
it, so another study is one more entry.
"""

import math
import os
import shutil
import tomllib

from pdfem.errors import InputError
from pdfem.limits import MAX_STEPS, add_allow_huge

DEFAULT_STUDY_SCENE = "shot912_small.toml"
# Meshes of the convergence order printed after the accuracy study
CONVERGENCE_SIZES = (8, 16, 32)


def _numbers(text, option, kind=float):
    """A comma-separated list of numbers, sorted and without repeats; InputError if bad."""
    try:
        vals = sorted({kind(v) for v in text.split(",") if v.strip()})
    except ValueError:
        word = "integers" if kind is int else "numbers"
        raise InputError(f"{option}: not a list of {word}: {text!r}") from None
    if not vals:
        raise InputError(f"{option}: empty list")
    if not all(math.isfinite(v) for v in vals):
        raise InputError(f"{option}: not a list of finite numbers: {text!r}")
    return vals


def _check(vals, ok, option, what):
    """Every value must pass ``ok``; InputError naming the option and the range."""
    bad = [v for v in vals if not ok(v)]
    if bad:
        raise InputError(f"{option}: {bad[0]!r} is not {what}")
    return vals


def _levels(text):
    """The --levels list: grain mesh levels 1 to 10."""
    return _check(_numbers(text, "--levels", int), lambda v: 1 <= v <= 10, "--levels",
                  "a level in [1, 10]")


def _output_args(p, prefix, writes):
    """-p/--prefix (default ``prefix``; ``writes`` says what it names), --force and
    --allow-huge of a study that runs scenes."""
    p.add_argument("-p", "--prefix", default=prefix, help=f"writes {writes} and the runs in "
                   f"<prefix>-runs/ (default {prefix})")
    p.add_argument("--force", action="store_true", help="overwrite existing output")
    add_allow_huge(p, f"a run of more than {MAX_STEPS:.0e} steps")


def _rules(text):
    """The --rules list: 1pt and/or 2x2, in that order."""
    from pdfem.tools.study.accuracy import RULES

    names = {v.strip() for v in text.split(",") if v.strip()}
    bad = sorted(names - set(RULES))
    if bad or not names:
        raise InputError(f"--rules: expected 1pt and/or 2x2 (got {text!r})")
    return [r for r in RULES if r in names]


def _baseline(text, rules):
    """--baseline LEVEL,RULE, or None for auto."""
    if text == "auto":
        return None
    parts = text.split(",")
    if len(parts) != 2 or not parts[0].strip().isdigit() or parts[1].strip() not in rules:
        raise InputError(f"--baseline: expected auto or LEVEL,RULE with RULE in --rules "
                         f"(got {text!r})")
    return int(parts[0]), parts[1].strip()


def _accuracy_args(p):
    p.add_argument("scene", nargs="?", default=None, help="shock scene with a [shock] table "
                   f"(default: the packaged {DEFAULT_STUDY_SCENE})")
    p.add_argument("--levels", default="1,2,3,4", help="grain mesh levels, 6 level^2 quads per "
                   "grain; multiples of the bed file's level (default 1,2,3,4)")
    p.add_argument("--rules", default="1pt,2x2", help="element rules (default 1pt,2x2)")
    p.add_argument("--speed", type=float, default=None, help="the driven hammer at this speed "
                   "[m/s]: its velocity set, the scene's times scaled by its own speed over "
                   "this one and the piston held until the slowest front has crossed the bed, "
                   "as study speeds does (default: the scene as written)")
    p.add_argument("--safety", default="0.9,0.5,0.25", help="time.safety factors; the grid "
                   "runs at the scene's, the others around the baseline (default 0.9,0.5,0.25)")
    p.add_argument("--kn0-scale", default="0.1,1,10", help="factors on the contact stiffness "
                   "(kn0, ks and the pairs'); 1 = the scene's (default 0.1,1,10)")
    p.add_argument("--baseline", default="auto", help="LEVEL,RULE around which the safety "
                   "factor and stiffness vary; auto = the cheapest grid run within --tol")
    p.add_argument("--tol", type=float, default=0.05, help="accuracy asked of the "
                   "recommended settings, relative (default 0.05)")
    p.add_argument("-p", "--prefix", default="study-accuracy", help="writes <prefix>.csv, "
                   "<prefix>.json (the converged estimate), <prefix>.png and the runs in "
                   "<prefix>-runs/ (default study-accuracy)")
    p.add_argument("--force", action="store_true", help="overwrite existing output")
    p.add_argument("--no-convergence", action="store_true", help="skip the element "
                   "convergence order printed at the end")
    add_allow_huge(p, f"a run of more than {MAX_STEPS:.0e} steps")


def _convergence_args(p):
    from pdfem.tools.study.convergence import SIZES

    p.add_argument("--sizes", default=",".join(map(str, SIZES)), help="meshes n x n of the "
                   "block; orders between successive sizes (default "
                   f"{','.join(map(str, SIZES))})")
    p.add_argument("--rules", default="1pt,2x2", help="element rules (default 1pt,2x2)")


def _scene_path(args):
    """The scene argument or the packaged small shot-912 scene."""
    from importlib import resources

    return args.scene or str(resources.files("pdfem") / "scenes" / DEFAULT_STUDY_SCENE)


def _outputs(prefix, force, exts=(".csv", ".png")):
    """Check the output files (``exts``) and runs folder of a prefix; return the folder's
    path."""
    from pdfem.cli.paths import check_output_path

    for ext in exts:
        check_output_path(prefix + ext, force, "--prefix")
    folder = prefix + "-runs"
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise InputError(f"--prefix: {folder} exists and is not a folder")
    if os.path.isdir(folder) and os.listdir(folder) and not force:
        raise InputError(f"--prefix: {folder} holds files (use --force to overwrite)")
    return folder


def _accuracy(args):
    from pdfem.parallel.mpi import barrier, world
    from pdfem.scene import check_ranks, load_scene
    from pdfem.tools.study import accuracy as acc
    from pdfem.tools.study import pareto

    comm = world()
    # Options
    levels = _levels(args.levels)
    rules = _rules(args.rules)
    safeties = _check(_numbers(args.safety, "--safety"), lambda v: 0.0 < v <= 1.0,
                      "--safety", "a safety factor in (0, 1]")
    scales = _check(_numbers(args.kn0_scale, "--kn0-scale"), lambda v: v > 0.0,
                    "--kn0-scale", "a factor > 0")
    base_given = _baseline(args.baseline, rules)
    if not 0.0 < args.tol < 1.0:
        raise InputError(f"--tol: must be in (0, 1) (got {args.tol!r})")
    # The scene: a shock scene, its dict for the edits
    path = _scene_path(args)
    scene = load_scene(path)
    if "shock" not in scene.resolved:
        raise InputError(f"{path}: shock: the accuracy study needs a scene with a [shock] table")
    check_ranks(scene, comm.size)
    if "contact" not in scene.resolved and scales != [1.0]:
        raise InputError(f"{path}: contact: --kn0-scale needs a scene with a [contact] table")
    with open(path, "rb") as fh:
        doc = tomllib.load(fh)
    if args.speed is not None:
        doc, scene = _at_speed(doc, scene, path, args.speed)
    folder = _outputs(args.prefix, args.force, (".csv", ".json", ".png"))
    study = acc.AccuracyStudy(doc, scene, folder, comm)
    study.check_levels(levels)
    if base_given and base_given[0] not in levels:
        raise InputError(f"--baseline: level {base_given[0]} is not in --levels")
    # Every run the study may start, its step count before the first one
    study.check_steps(acc.possible_settings(levels, rules, safeties, scales,
                                            scene.resolved["time"]["safety"], base_given),
                      args.allow_huge)
    # The runs folder, emptied of an earlier study's files with --force
    if comm.rank == 0:
        if os.path.isdir(folder) and args.force:
            shutil.rmtree(folder)
        os.makedirs(folder, exist_ok=True)
    barrier(comm)
    rows = study.run_all(levels, rules, safeties, scales, args.tol, base_given)
    # The files, the table and the recommendation
    if comm.rank == 0:
        from pdfem.tools.study.plots import accuracy_plot

        pareto.write_csv(rows, args.prefix + ".csv")
        _write_estimate(study.estimate, args.prefix + ".json", comm.size, path, args.speed)
        accuracy_plot(rows, args.tol, args.prefix + ".png", study.estimate,
                      _figure_header(comm.size))
        print("", *pareto.table_lines(rows), "", sep="\n")
        print("errors in % against the converged estimate; * = on the Pareto front of worst "
              "error versus wall time")
        print("converged estimate (Richardson extrapolation of each rule's levels):")
        print("\n".join("  " + line for line in pareto.estimate_lines(study.estimate)))
        print(pareto.recommendation_line(rows, args.tol,
                                         scene.resolved.get("contact", {}).get("kn0")))
        print(f"pdfem study accuracy: {args.prefix}.csv, {args.prefix}.json, "
              f"{args.prefix}.png, runs in "
              f"{folder}/; {sum(r['wall_s'] for r in rows):.0f} s of runs", flush=True)
    barrier(comm)
    if not args.no_convergence:
        _print_convergence(comm, CONVERGENCE_SIZES, rules)
    return 0


def _at_speed(doc, scene, path, speed):
    """The scene dict and checked scene with the driven hammer at ``speed``
    (pdfem.tools.study.speeds.rung_doc, scaled from the hammer condition's own speed);
    InputError when the scene has no hammer driven at a constant velocity."""
    from pdfem.scene import parse_scene
    from pdfem.tools.study.speeds import rung_doc

    if not 0.0 < speed < 1.0e5:
        raise InputError(f"--speed: {speed!r} is not a speed in (0, 1e5) m/s")
    hammer = scene.resolved["shock"].get("hammer")
    driven = [bc for bc in scene.resolved.get("bc", [])
              if bc.get("body") == hammer and bc.get("type") == "velocity"]
    own = math.hypot(*driven[0]["velocity"]) if driven else 0.0
    if not own > 0.0:
        raise InputError(f"{path}: bc: --speed needs the shock hammer driven by a velocity "
                         "condition")
    element = scene.resolved["element"]
    doc = rung_doc(doc, speed, element["rule"], element["level"], written_for=own,
                   base_dir=scene.base_dir)
    return doc, parse_scene(doc, scene.base_dir, name=f"{path} at {speed:g} m/s",
                            path=scene.path)


def _figure_header(ranks):
    """The line over a study's figure: date, commit, machine and the command that made it."""
    import sys

    from pdfem.tools.provenance import provenance

    p = provenance(ranks)
    command = " ".join(["python -m pdfem", *sys.argv[1:]])
    return f"{p['date']}, commit {p['commit']}, {p['machine']}: {command}"


def _write_estimate(estimate, path, ranks, scene, speed):
    """The converged estimate and where it came from (provenance, the scene file and the
    --speed it ran at, null for the scene's own), as JSON (written atomically)."""
    import json

    from pdfem.tools.analysis.jsontext import plain, write_atomic
    from pdfem.tools.provenance import provenance

    body = {"provenance": provenance(ranks), "scene": scene, "speed": speed,
            "estimate": estimate}
    write_atomic(path, json.dumps(plain(body), indent=1) + "\n")


def _print_convergence(comm, sizes, rules):
    """The element's convergence order, computed serially on rank 0."""
    from pdfem.parallel.mpi import barrier
    from pdfem.tools.study.convergence import observed_orders, report_lines

    if comm.rank == 0:
        print("\n".join(report_lines(observed_orders(sizes, rules))), flush=True)
    barrier(comm)


def _convergence(args):
    from pdfem.parallel.mpi import world

    sizes = _check(_numbers(args.sizes, "--sizes", int), lambda v: 2 <= v <= 512,
                   "--sizes", "a mesh size in [2, 512]")
    if len(sizes) < 2:
        raise InputError("--sizes: need at least two meshes for an order")
    _print_convergence(world(), sizes, _rules(args.rules))
    return 0


def _hard_args(p):
    from pdfem.tools.study.hard_cases import CASES, LADDER_CASES, LADDERS, LARGE_ONLY

    p.add_argument("--size", choices=("ci", "large"), default="large", help="ci: the "
                   "seconds-long versions the test suite runs; large: the study's (default)")
    singles = [c for c in CASES if c not in LADDER_CASES]
    large = ", ".join(c for c in LARGE_ONLY if c in singles)
    ladders = "; ".join(k + " = " + ", ".join(v) for k, v in LADDERS.items())
    p.add_argument("--case", default="all", help="comma-separated case names or all "
                   f"(the cases: {', '.join(singles)}; {large} only with --size large; the "
                   f"ladders, --size large and only by name: {ladders})")
    p.add_argument("-p", "--prefix", default="study-hard", help="runs go to <prefix>-runs/, "
                   "the table to <prefix>.json (default study-hard)")
    p.add_argument("--force", action="store_true", help="overwrite existing output")


def _hard(args):
    import json

    from pdfem.parallel.mpi import barrier, world
    from pdfem.tools.study.hard import print_rows, run_case
    from pdfem.tools.study.hard_cases import CASES, LADDER_CASES, LADDERS, LARGE_ONLY

    comm = world()
    if comm.size < 2:
        raise InputError("study hard: start it under mpirun with 2 or more ranks (each case "
                         "runs on 1 rank and on all of them)")
    names = [c for c in CASES if args.size == "large" or c not in LARGE_ONLY]
    if args.case != "all":
        asked = [c.strip() for c in args.case.split(",") if c.strip()]
        # A ladder's name stands for its rungs
        asked = [r for c in asked for r in (LADDERS[c] if c in LADDERS else [c])]
        bad = [c for c in asked if c not in names]
        if bad or not asked:
            raise InputError(f"--case: {bad[0] if bad else args.case!r} is not a case of "
                             f"--size {args.size} ({', '.join(names)})")
        names = asked
    else:
        names = [c for c in names if c not in LADDER_CASES]
    from pdfem.cli.paths import check_output_path

    check_output_path(args.prefix + ".json", args.force, "--prefix")
    folder = args.prefix + "-runs"
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise InputError(f"--prefix: {folder} exists and is not a folder")
    rows = []
    for name in names:
        row = run_case(name, os.path.join(folder, name), args.size, comm)
        if comm.rank == 0:
            rows.append(row)
            print_rows([row])
    if comm.rank == 0:
        print("\nall cases:")
        print_rows(rows)
        tmp = args.prefix + ".json.part"
        with open(tmp, "w") as f:
            json.dump(rows, f, indent=1)
        os.replace(tmp, args.prefix + ".json")
        passed = sum(r["passed"] for r in rows)
        print(f"pdfem study hard: {passed} of {len(rows)} cases pass on 1 and {comm.size} "
              f"ranks; {args.prefix}.json, runs in {folder}/", flush=True)
    barrier(comm)
    return 0


def _width_args(p):
    p.add_argument("--widths", default="4,8,16,32", help="bed widths in grains (0.25 mm "
                   "each, the packaged bed's 4 mm for 16) (default 4,8,16,32)")
    p.add_argument("--seeds", type=int, default=5, help="seeds of the bed at --seed-width, "
                   "the packaged one first (default 5)")
    p.add_argument("--seed-width", type=float, default=16.0, help="width in grains of the "
                   "seed beds (default 16)")
    p.add_argument("-p", "--prefix", default="study-width", help="the table to "
                   "<prefix>.json, beds and runs in <prefix>-runs/ (default study-width)")
    p.add_argument("--force", action="store_true", help="overwrite existing output")
    add_allow_huge(p, "a bed beyond the preparation's limits, a run of more than "
                   f"{MAX_STEPS:.0e} steps")


def _width(args):
    import json

    from pdfem.cli.paths import check_output_path
    from pdfem.parallel.mpi import barrier, world
    from pdfem.tools.study import width as ws

    widths = _check(_numbers(args.widths, "--widths"), lambda v: 1.0 <= v <= 4096.0,
                    "--widths", "a width in [1, 4096] grains")
    if not 1 <= args.seeds <= 100:
        raise InputError(f"--seeds: must be in [1, 100] (got {args.seeds})")
    if not 1.0 <= args.seed_width <= 4096.0:
        raise InputError(f"--seed-width: must be in [1, 4096] grains (got {args.seed_width})")
    check_output_path(args.prefix + ".json", args.force, "--prefix")
    folder = args.prefix + "-runs"
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise InputError(f"--prefix: {folder} exists and is not a folder")
    # Every bed's size before the first one is prepared
    ws.check_sizes(ws.plan(widths, args.seeds, args.seed_width), folder, args.allow_huge)
    comm = world()
    if comm.rank == 0:
        if os.path.isdir(folder) and args.force:
            shutil.rmtree(folder)
        os.makedirs(folder, exist_ok=True)
    barrier(comm)
    rows = ws.run_study(widths, args.seeds, args.seed_width, folder, comm,
                        lambda s: print(s, flush=True), args.allow_huge)
    if comm.rank == 0:
        from pdfem.tools.analysis.jsontext import plain

        table, found = ws.table_lines(rows), ws.conclusions(rows)
        print("", *table, "", *found, sep="\n")
        with open(args.prefix + ".json.part", "w") as f:
            json.dump(plain({"rows": rows, "conclusions": found}), f, indent=1)
        os.replace(args.prefix + ".json.part", args.prefix + ".json")
        print(f"pdfem study width: {args.prefix}.json, beds and runs in {folder}/", flush=True)
    barrier(comm)
    return 0


def _hotspots_args(p):
    from pdfem.cli.hotspots import add_threshold_options

    p.add_argument("scene", nargs="?", default=None, help="shock scene with a [shock] table, "
                   "run as its thermal variant when it has no [heat] (default: the packaged "
                   f"{DEFAULT_STUDY_SCENE})")
    p.add_argument("--levels", default="1,2,3,4", help="grain mesh levels, 6 level^2 quads per "
                   "grain; multiples of the bed file's level (default 1,2,3,4)")
    p.add_argument("--rule", default=None, help="element rule of every run, 1pt or 2x2 "
                   "(default: the scene's)")
    add_threshold_options(p)
    _output_args(p, "study-hotspots", "<prefix>.csv, <prefix>.json")


def _hotspots(args):
    import json

    from pdfem.cli.hotspots import thresholds_of
    from pdfem.cli.paths import check_output_path
    from pdfem.parallel.mpi import barrier, world
    from pdfem.scene import check_ranks, load_scene, parse_scene
    from pdfem.tools.study import hotspots as hs

    comm = world()
    levels = _levels(args.levels)
    thresholds, spot = thresholds_of(args)
    path = _scene_path(args)
    scene = load_scene(path)
    if "shock" not in scene.resolved:
        raise InputError(f"{path}: shock: the hot-spot study needs a scene with a [shock] "
                         "table (the front tells the shocked material)")
    rule = args.rule or scene.resolved["element"]["rule"]
    if rule not in ("1pt", "2x2"):
        raise InputError(f"--rule: expected 1pt or 2x2 (got {rule!r})")
    with open(path, "rb") as fh:
        doc = hs.thermal_variant(tomllib.load(fh))
    thermal = parse_scene(doc, scene.base_dir, name=f"{path} (thermal variant)")
    check_ranks(thermal, comm.size)
    for ext in (".csv", ".json"):
        check_output_path(args.prefix + ext, args.force, "--prefix")
    folder = args.prefix + "-runs"
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise InputError(f"--prefix: {folder} exists and is not a folder")
    study = hs.HotspotStudy(doc, thermal, folder, comm, rule)
    study.check_levels(levels)
    study.check_steps(levels, args.allow_huge)
    if comm.rank == 0:
        if os.path.isdir(folder) and args.force:
            shutil.rmtree(folder)
        os.makedirs(folder, exist_ok=True)
        print(f"pdfem study hotspots: {path} (thermal variant) at levels "
              f"{','.join(map(str, levels))}, rule {rule}, on {comm.size} rank(s)", flush=True)
    barrier(comm)
    rows, chg = study.run_all(levels, thresholds, spot)
    if comm.rank == 0:
        from pdfem.tools.analysis.jsontext import plain

        print("", *hs.table_lines(rows, chg), sep="\n")
        with open(args.prefix + ".csv.part", "w") as f:
            f.write(hs.csv_text(rows))
        os.replace(args.prefix + ".csv.part", args.prefix + ".csv")
        with open(args.prefix + ".json.part", "w") as f:
            json.dump(plain({"scene": path, "rows": rows, "changes": chg}), f, indent=1)
        os.replace(args.prefix + ".json.part", args.prefix + ".json")
        print(f"pdfem study hotspots: {args.prefix}.csv, {args.prefix}.json, runs in "
              f"{folder}/", flush=True)
    barrier(comm)
    return 0


def _speeds_args(p):
    from pdfem.tools.study.speeds import BEDS, SPEEDS

    p.add_argument("--bed", choices=tuple(BEDS), default="small", help="the packaged bed: "
                   "small (shot912_small.toml, 29 grains) or default (shot912.toml, 218 grains; "
                   "default small)")
    p.add_argument("--rule", choices=("1pt", "2x2"), default="2x2", help="element rule "
                   "(default 2x2, the packaged scenes')")
    p.add_argument("--levels", default="2", help="grain mesh levels (default 2)")
    p.add_argument("--mesh", choices=("kite", "ring"), default=None, help="grain mesh "
                   "(default the packaged scenes', kite)")
    p.add_argument("--speeds", default=",".join(f"{v:g}" for v in SPEEDS),
                   help="piston speeds [m/s] (default %(default)s)")
    p.add_argument("--sides", choices=("periodic", "walls"), default="periodic", help="the "
                   "bed's sides: periodic, as in the packaged scenes (domain.periodic = \"x\"), "
                   "or frictionless side walls (default periodic)")
    _output_args(p, "study-speeds", "<prefix>.json")


def _speeds(args):
    import json

    from pdfem.cli.paths import check_output_path
    from pdfem.limits import check_runs
    from pdfem.parallel.mpi import barrier, world
    from pdfem.scene import check_ranks, parse_scene
    from pdfem.tools.study import speeds as sp

    comm = world()
    levels = _levels(args.levels)
    speeds = _check(_numbers(args.speeds, "--speeds"), lambda v: 0.0 < v < 1.0e5, "--speeds",
                    "a speed in (0, 1e5) m/s")
    doc = sp.packaged_doc(args.bed)
    doc = sp.periodic_doc(doc) if args.sides == "periodic" else sp.walls_doc(doc)
    rungs = []
    for level in levels:
        for v in speeds:
            rung = {"bed": args.bed, "rule": args.rule, "level": level, "velocity": v,
                    "sides": args.sides}
            scene = parse_scene(sp.rung_doc(doc, v, args.rule, level, args.mesh), ".",
                                name=f"{sp.BEDS[args.bed]} ({sp.rung_name(rung)})")
            rungs.append((rung, scene))
    check_ranks(rungs[0][1], comm.size)
    check_output_path(args.prefix + ".json", args.force, "--prefix")
    folder = args.prefix + "-runs"
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise InputError(f"--prefix: {folder} exists and is not a folder")
    check_runs([(sc, sc.name) for _, sc in rungs], comm, args.allow_huge, key="--speeds",
               remedy="faster pistons or lower --levels")
    if comm.rank == 0:
        if os.path.isdir(folder) and args.force:
            shutil.rmtree(folder)
        os.makedirs(folder, exist_ok=True)
    barrier(comm)
    rows, stops = sp.run_rungs(rungs, folder, comm, log=lambda m: print(m, flush=True))
    if comm.rank == 0:
        from pdfem.tools.analysis.jsontext import plain
        from pdfem.tools.provenance import provenance

        print("", *sp.table_lines(rows), sep="\n")
        with open(args.prefix + ".json.part", "w") as f:
            json.dump(plain({"bed": args.bed, "rule": args.rule, "mesh": args.mesh or "kite",
                              "sides": args.sides, "provenance": provenance(comm.size),
                              "rows": rows}), f, indent=1)
        os.replace(args.prefix + ".json.part", args.prefix + ".json")
        lost = sum(1 for r in rows if r["runs"] and r["escaped"])
        print(f"pdfem study speeds: {len(rows) - stops} of {len(rows)} runs reach the scene's "
              f"end" + (f", {lost} with grain material gone past the anvil or the hammer (the "
                        "column escape)" if lost else "")
              + f"; {args.prefix}.json, runs in {folder}/", flush=True)
    barrier(comm)
    return 3 if stops else 0


# Study name -> (help, add its arguments, run it)
STUDIES = {
    "accuracy": ("what accuracy costs in time on a shock scene: mesh level, element rule, "
                 "safety factor and contact stiffness against the finest run",
                 _accuracy_args, _accuracy),
    "convergence": ("observed convergence order of the element on a standing elastic wave",
                    _convergence_args, _convergence),
    "hard": ("hard cases (fast hammers, stiff contact, needle grains, sheared meshes, fast "
             "migration, squeezing, tight conduction, long settling) on 1 and N ranks: "
             "energy balance, finiteness, Jacobians, bit-identity (under mpirun)",
             _hard_args, _hard),
    "speeds": ("the packaged shot-912 piston at several speeds and grain mesh levels, each to "
               "the scene's end: stability (energy balance, folded meshes) and the answer "
               "against the bound of the compacted bed", _speeds_args, _speeds),
    "width": ("the shot-912 wave in beds of several widths and seeds: Us and arrival against "
              "width, their spread over seeds", _width_args, _width),
    "hotspots": ("mesh convergence of hot spots: the thermal variant of a shock scene at "
                 "several grain mesh levels, the hot-spot census of each", _hotspots_args,
                 _hotspots),
}


def add_parser(sub):
    p = sub.add_parser("study", help="studies of the solver: accuracy (accuracy against "
                       "cost on a shock scene), convergence (element order), hard (hard "
                       "cases), speeds (the piston from 100 m/s to 2 km/s), width (bed width "
                       "and seed), hotspots (hot spots against mesh)")
    studies = p.add_subparsers(dest="study", metavar="STUDY", required=True)
    for name, (text, add_args, _) in STUDIES.items():
        add_args(studies.add_parser(name, help=text, description=text))


def run(args):
    return STUDIES[args.study][2](args)
