"""The geometric route to a bed file: pack (pdfem.prepare.geometric) on rank 0, measure the
packing and the gaps, check them against ``prepare.packing``, write the bed."""

import time

import numpy as np

from pdfem.errors import InputError
from pdfem.io.bedfile import write_bed
from pdfem.parallel.mpi import barrier, broadcast
from pdfem.prepare import packing
from pdfem.prepare.geometric import pack


def bed_box(r):
    """[x0, floor, x1, floor + height] of a geometric preparation: between the domain's side
    walls, from the highest block top (or the domain bottom) up by prepare.height."""
    pr, box = r["prepare"], r["domain"]["box"]
    floor = max([box[1]] + [b["box"][3] for b in r["blocks"]
                            if b["name"] != pr.get("weight")])
    top = floor + pr["height"]
    if top > box[3]:
        raise InputError(f"prepare.height: the bed would reach y = {top:g} m, above the domain "
                         f"box (top {box[3]:g} m)")
    return [box[0], floor, box[2], top]


def _make(path, scene, out, log):
    """Rank 0's work: the bed, its figures, the check, the file; returns its attributes."""
    t0 = time.perf_counter()
    r = scene.resolved
    pr, level = r["prepare"], r["element"]["level"]
    box = bed_box(r)
    rows, nodes, figs = pack(pr, box, level, log)
    polys = packing.outlines(nodes, level)
    prof = packing.profile(polys, box[0], box[2], box[1], box[3])
    gaps = packing.gaps(polys)
    for line in packing.report(prof, pr["packing"], gaps):
        log(f"prepare: {line}")
    bad = packing.check(prof, pr["packing"], pr["tolerance"], pr["slice_tolerance"],
                        "prepare.packing")
    if bad:
        raise InputError(bad)
    rho = r["materials"][pr["material"]]["density"]
    attrs = {"level": level, "method": "geometric", "phase": "geometric", "seed": pr["seed"],
             "converged": True, "scene": scene.to_toml_string(),
             **packing.attributes(prof, pr["packing"], rho), **gaps,
             **{f"geometric_{k}": v for k, v in figs.items()},
             "wall_s": time.perf_counter() - t0}
    write_bed(out, rows, nodes, np.zeros_like(nodes), attrs)
    log(f"prepare: bed {out}: {rows.shape[0]} grains, bed density {attrs['bed_density']:.1f} "
        f"kg/m^3 ({pr['material']} at {rho:g} kg/m^3 x packing {prof['whole']:.4f}), height "
        f"{box[3] - box[1]:.4g} m; wall time {attrs['wall_s']:.1f} s")
    return attrs


def prepare_geometric(path, scene, out, comm, log):
    """Make the geometric bed on rank 0 (the same on any number of ranks); every rank raises
    the same InputError when it fails."""
    result, err = None, None
    if comm.rank == 0:
        try:
            result = _make(path, scene, out, log)
        except InputError as exc:
            err = str(exc)
    err = broadcast(comm, err)
    if err:
        raise InputError(err)
    barrier(comm)
    return result
