"""How wide a bed must be, and how much the answer moves with the seed: the shot-912 wave
in beds of several widths and, at one width, several seeds.

Each bed is the packaged geometric preparation (``shot912_prepare.toml``: 0.65 of HMX at
1900 kg/m^3, 4 mm deep) at another width and seed, and each run the packaged impact scene
(``shot912.toml``) on it, with its chamber, hammer and bottom as wide as the bed, between
frictionless side walls as the bed was packed (the scene's periodic sides need a bed at least
three contact cells wide, just over 1.0 mm with these grains, and the study starts at 4
grains, 1 mm). A width is
counted in grains: the packaged bed's width per grain (4 mm for 16, NOMINAL), close to its
mean grain diameter (0.245 mm). Runs end when the piston is released: the study measures
the wave, not the spring-back.
"""

import copy
import math
import os
import tomllib
from importlib import resources

import numpy as np

from pdfem.parallel.mpi import barrier
from pdfem.scene.toml_out import dumps
from pdfem.tools.study.speeds import walls_doc

PREP, SCENE = "shot912_prepare.toml", "shot912.toml"
# Bed width per grain of the packaged bed (4 mm, 16 grains)
NOMINAL = 0.25e-3
# Row keys printed by table_lines: (key, heading, scale, format)
COLUMNS = (("grains_wide", "wide", 1, ".0f"), ("seed", "seed", 1, "d"),
           ("grains", "grains", 1, "d"), ("us", "Us m/s", 1, ".0f"), ("us_se", "+-", 1, ".0f"),
           ("precursor", "precursor m/s", 1, ".0f"), ("arrival", "arrival us", 1e6, ".2f"),
           ("arrival_gauge", "gauge rise us", 1e6, ".2f"), ("up", "up m/s", 1, ".1f"),
           ("rho1", "rho1", 1, ".0f"), ("mass_strain_closure", "strain closure %", 100, ".1f"),
           ("wall_s", "wall s", 1, ".0f"))


def _packaged(name):
    """A packaged scene file as tomllib reads it, and its folder."""
    path = resources.files("pdfem") / "scenes" / name
    with open(path, "rb") as f:
        return tomllib.load(f), str(path.parent)


def _widen(doc, width):
    """The domain and every block of ``doc`` made ``width`` wide (blocks keep their element
    width)."""
    old = doc["domain"]["box"][2] - doc["domain"]["box"][0]
    doc["domain"]["box"][2] = doc["domain"]["box"][0] + width
    for b in doc.get("blocks", []):
        b["box"][2] = b["box"][0] + width
        b["nx"] = max(1, round(b.get("nx", 3) * width / old))


def scenes(width, seed, folder):
    """The preparation and impact scenes of one bed ``width`` wide from ``seed``, their files
    in ``folder``: (preparation path, impact scene dict, its base folder, preparation dict,
    tag)."""
    prep, _ = _packaged(PREP)
    shot, base = _packaged(SCENE)
    shot = walls_doc(shot)
    tag = f"w{width / NOMINAL:g}-s{seed}"
    bed = os.path.abspath(os.path.join(folder, f"bed-{tag}.h5"))
    _widen(prep, width)
    prep["prepare"].update(seed=seed, output=bed)
    prep_path = os.path.join(folder, f"prepare-{tag}.toml")
    _widen(shot, width)
    shot["grains_file"]["path"] = bed
    hammer = shot["shock"]["hammer"]
    release = [bc["release"] for bc in shot["bc"] if bc.get("body") == hammer
               and "release" in bc]
    if release:
        shot["time"]["end"] = min(shot["time"]["end"], release[0])
    shot["shock"]["plots"] = "none"
    shot["output"] = dict(shot["output"], path=os.path.join(folder, f"run-{tag}.h5"),
                          checkpoint_interval=0.0, checkpoint_wall=0.0)
    return prep_path, copy.deepcopy(shot), base, prep, tag


def row(width, seed, summary, wall):
    """One row of the study from a run's analysis summary."""
    f, p, h = summary["front"], summary["precursor"], summary["shocked"]
    return {"width": width, "grains_wide": width / NOMINAL, "seed": seed,
            "grains": summary["bed"]["n_grains"], "us": f["us"], "us_se": f["se"],
            "us_fit": f["us_fit"],
            "steadiness": f["steadiness"], "note": f["note"], "precursor": p["us"],
            "arrival": f["arrival_fit"], "arrival_gauge": f["arrival_gauge"], "up": h["up"],
            "rho1": h["rho1"], "rho0": summary["bed"]["rho0"],
            "mass_strain_closure": summary["jump"]["mass_strain_closure"], "wall_s": wall}


def _num(v):
    return math.nan if v is None else float(v)


def table_lines(rows):
    """The rows as a plain-text table."""
    head = " ".join(f"{h:>14}" for _, h, _, _ in COLUMNS)
    out = [head]
    for r in rows:
        cells = []
        for key, _, scale, fmt in COLUMNS:
            v = r[key]
            cells.append(f"{'n/a':>14}" if v is None or (isinstance(v, float)
                                                       and not math.isfinite(v))
                         else f"{v * scale if fmt != 'd' else v:>14{fmt}}")
        out.append(" ".join(cells) + ("" if r["steadiness"] == "steady"
                                      else f"  ({r['note']})"))
    return out


def conclusions(rows, tol=0.05):
    """Lines: each width's Us and arrival against the widest bed's, the seeds' mean and
    spread, and the narrowest width whose Us and arrival are within ``tol`` of the widest's."""
    lines = []
    widths = sorted({r["width"] for r in rows})
    first = {w: next(r for r in rows if r["width"] == w) for w in widths}
    ref = first[widths[-1]]
    ok = []
    for w in widths:
        r = first[w]
        dus = abs(_num(r["us"]) - _num(ref["us"])) / _num(ref["us"])
        darr = abs(_num(r["arrival"]) - _num(ref["arrival"])) / _num(ref["arrival"])
        lines.append(f"{r['grains_wide']:g} grains wide: Us {_num(r['us']):.0f} m/s "
                     f"({100 * dus:.1f} % from the widest), arrival "
                     f"{1e6 * _num(r['arrival']):.2f} us ({100 * darr:.1f} %)")
        ok.append(w if dus <= tol and darr <= tol else None)
    # The narrowest width from which every wider one is within tol too
    good = None
    for w, flag in zip(reversed(widths), reversed(ok), strict=True):
        if flag is None:
            break
        good = w
    if good is not None:
        lines.append(f"within {tol:.0%} of the widest bed from {good / NOMINAL:g} grains wide "
                     "on")
    for w in widths:
        seeds = [r for r in rows if r["width"] == w]
        us = np.array([_num(r["us"]) for r in seeds])
        if len(seeds) > 1 and np.isfinite(us).all():
            arr = np.array([_num(r["arrival"]) for r in seeds])
            lines.append(f"{len(seeds)} seeds at {w / NOMINAL:g} grains wide: Us mean "
                         f"{us.mean():.0f} m/s, standard deviation {us.std(ddof=1):.0f} m/s "
                         f"({100 * us.std(ddof=1) / us.mean():.1f} %), range "
                         f"{us.min():.0f}-{us.max():.0f}; arrival mean {1e6 * arr.mean():.2f} "
                         f"us, standard deviation {1e6 * arr.std(ddof=1):.2f} us")
    return lines


def plan(widths, seeds, seed_width):
    """The (width in grains, seed) of every bed of the study: each width at the packaged
    seed, then ``seeds`` - 1 more seeds at ``seed_width``."""
    base_seed = _packaged(PREP)[0]["prepare"]["seed"]
    return [(w, base_seed) for w in widths] + [(seed_width, base_seed + k)
                                               for k in range(1, seeds)]


def check_sizes(beds, folder, allow_huge=False):
    """Refuse (pdfem.prepare.size.check_size) a study any of whose beds is beyond the
    preparation's limits, before the first one is prepared; nothing is written."""
    from pdfem.prepare.size import check_size
    from pdfem.scene import parse_scene

    for wide, seed in beds:
        _, _, base, prep, tag = scenes(wide * NOMINAL, seed, folder)
        name = f"{PREP} ({tag})"
        check_size(parse_scene(prep, base, name=name).resolved, name, allow_huge)


def run_study(widths, seeds, seed_width, folder, comm, log, allow_huge=False):
    """Prepare and run every bed (widths in grains; ``seeds`` seeds at ``seed_width``, the
    packaged seed first); return the rows (rank 0; None elsewhere). A bed or run beyond the
    limits (pdfem.limits) is refused unless ``allow_huge``."""
    import time

    from pdfem.driver import run as drive
    from pdfem.limits import check_step_count
    from pdfem.prepare import prepare
    from pdfem.scene import check_ranks, parse_scene
    from pdfem.solver import Simulation
    from pdfem.tools.analysis import analyse

    rows = []
    for wide, seed in plan(widths, seeds, seed_width):
        width = wide * NOMINAL
        prep_path, shot, base, prep, tag = scenes(width, seed, folder)
        if comm.rank == 0:
            with open(prep_path, "w") as f:
                f.write(dumps(prep))
            log(f"pdfem study width: {wide:g} grains wide ({width * 1e3:g} mm), seed {seed}")
        barrier(comm)
        prepare(prep_path, shot["grains_file"]["path"], comm, log=lambda s: None,
                allow_huge=allow_huge)
        sc = parse_scene(shot, base, name=f"{SCENE} ({tag})")
        check_ranks(sc, comm.size)
        t0 = time.perf_counter()
        sim = Simulation(sc, comm)
        check_step_count(sim, f"{SCENE} ({tag})", allow_huge)
        drive(sim, shot["output"]["path"], quiet=True)
        wall = time.perf_counter() - t0
        if comm.rank == 0:
            out = shot["output"]["path"]
            s = analyse(out, os.path.splitext(out)[0])
            rows.append(row(width, seed, s, wall))
            log("  " + table_lines(rows[-1:])[1])
    return rows if comm.rank == 0 else None
