"""Bad input never hurts, through the real command line.

Every command on a missing file, a file that is not TOML or not HDF5, a truncated HDF5 file,
a checkpoint of another scene, negative, zero, NaN or huge values, an unknown effect name, a
run file with a dataset of strings, of the wrong shape or with ids out of range, an output
path that cannot be written and an output that exists: exit status 2, one line on
stderr naming the file or key, no traceback, and the folder exactly as it was (no file
added, none changed: nothing overwritten without --force, nothing partial left behind).
"""

import hashlib
import os
import shutil
import subprocess
import tomllib
from pathlib import Path

import h5py
import numpy as np
import pytest

from pdfem.scene.toml_out import dumps
from tests.helpers import datasets, pdfem
from tests.scenes import (
    checkpointed_grains,
    drifting_grains,
    every_field_shock,
    inline_shock,
    prep_scene,
    small_prepare,
    toml,
    write_scene,
)


def _good(edit):
    """The TOML text of checkpointed_grains() changed by ``edit(doc)``."""
    doc = checkpointed_grains()
    edit(doc)
    return toml(doc)


def _grain_axes(doc, axes):
    for g in doc["grains"]:
        g["axes"] = axes


def _prep(edit):
    """The TOML text of prep_scene() changed by ``edit(doc)``."""
    doc = prep_scene()
    edit(doc)
    return toml(doc)


def _shock_with(edit):
    """The TOML text of inline_shock() changed by ``edit(doc)``."""
    doc = inline_shock()
    edit(doc)
    return toml(doc)


# Input files written once for all cases
FILES = {
    "good.toml": toml(checkpointed_grains()),
    "other.toml": toml(drifting_grains(n=4, end=1e-7)),
    "garbage.toml": "this is = = not [[[ toml\n",
    "prep.toml": toml(prep_scene()),
    "typo.toml": _prep(lambda d: d["materials"]["hmx"].update(specfic_heat=1.0)),
    "gamma_prep.toml": _prep(lambda d: d["materials"]["hmx"].update(eos="us_up", eos_s=2.29,
                                                                     eos_gamma=1.1)),
    "fields.toml": toml(every_field_shock()),
    "shock.toml": toml(inline_shock()),
    "hugoniot_twice.toml": _shock_with(lambda d: (
        d["materials"]["hmx"].update(eos="us_up", eos_s=2.29),
        d["shock"].update(crystal_hugoniot=[2770.0, 2.29]))),
    "negative.toml": _good(lambda d: d["domain"].update(cell_size=-1.0e-3)),
    "zero.toml": _good(lambda d: _grain_axes(d, [0.0, 3.0e-4])),
    "nan.toml": _good(lambda d: d["time"].update(end=float("nan"))),
    "eos_no_s.toml": _good(lambda d: d["materials"]["grain"].update(eos="us_up")),
    "eos_s_alone.toml": _good(lambda d: d["materials"]["grain"].update(eos_s=2.0)),
    "eos_s_big.toml": _good(lambda d: d["materials"]["grain"].update(eos="us_up", eos_s=50.0)),
    "gamma_linear.toml": _good(lambda d: d["materials"]["grain"].update(eos_gamma=1.0)),
    "gamma_big.toml": _good(lambda d: d["materials"]["grain"].update(eos="us_up", eos_s=1.5,
                                                                      eos_gamma=3.0)),
    "gamma_negative.toml": _good(lambda d: d["materials"]["grain"].update(eos="us_up", eos_s=1.5,
                                                                           eos_gamma=-1.0)),
    "eos_thermal.toml": _good(lambda d: (
        d["materials"]["grain"].update(eos="us_up", eos_s=2.0, specific_heat=1000.0,
                                       expansion=1.0e-5),
        d.update(heat={}, thermoelastic={}, thermal_expansion={}))),
    "no_expansion.toml": _good(lambda d: (
        d["materials"]["grain"].update(specific_heat=1000.0),
        d.update(heat={}, thermoelastic={}, thermal_expansion={}))),
    "gamma_expansion.toml": _good(lambda d: (
        d["materials"]["grain"].update(eos="us_up", eos_s=2.0, eos_gamma=1.0,
                                       specific_heat=1000.0, expansion=1.0e-5),
        d.update(heat={}, thermoelastic={}, thermal_expansion={}))),
    "huge.toml": _good(lambda d: d["domain"].update(box=[0.0, 0.0, 1.0e9, 0.006])),
    "effect.toml": _good(lambda d: d.update(viscosityy={"coefficient": 1.0})),
    "fast.toml": _good(lambda d: d.update(blocks=[{
        "name": "b", "box": [0.0, 0.0, 0.024, 2.0e-4], "material": "grain",
        "velocity": [0.0, 1.0e300]}])),
    "prep-zero.toml": _prep(lambda d: d["prepare"].update(grains=0)),
    "one-cell.toml": _good(lambda d: d["domain"].update(cell_size=0.02)),
    "steps.toml": _good(lambda d: (d["time"].update(end=1000.0),
                                   d["output"].update(interval=10.0, energy_interval=1.0,
                                                      gauge_interval=1.0,
                                                      checkpoint_interval=10.0))),
    "mat-text.toml": "[materials]\nhmx = \"text\"\n",
    "prep-vast.toml": dumps(small_prepare(semi_axis=[1.2e296, 1.6e296])),
    "prep-thin.toml": dumps(small_prepare(height=1.0e-9)),
    "strains.csv": "exx,eyy,exy,ezz\n-0.01,0,0,0\n",
    "big-strain.csv": "exx,eyy,exy,ezz\n-0.01,0,0,0\n-5,0,0,0\n",
    "frames-1e-20.toml": _good(lambda d: d["output"].update(interval=1e-20)),
    "frames-denormal.toml": _good(lambda d: d["output"].update(interval=5e-324)),
    "frames-per-step.toml": _good(lambda d: d["output"].update(interval=1e-7 / 4.8e6)),
    "ckpt-denormal.toml": _good(lambda d: d["output"].update(checkpoint_interval=5e-324)),
    "energy-denormal.toml": _good(lambda d: d["output"].update(energy_interval=5e-324)),
    "energy-no-advance.toml": _good(lambda d: d["output"].update(energy_interval=1e-24)),
    "gauge-denormal.toml": _good(lambda d: d["output"].update(gauge_interval=5e-324)),
    "end-denormal.toml": _good(lambda d: d["time"].update(end=5e-324)),
    "visc.toml": _good(lambda d: d.update(bulk_viscosity={})),
    "stiffer.toml": _good(lambda d: d["materials"]["grain"].update(bulk=2.0e10)),
    "notafolder": "a plain file\n",
    "keep-0000.vtu": "precious\n",
    "keep.csv": "precious\n",
    "keep.h5": "precious\n",
    "side.xdmf": "precious\n",
    "stale.h5.ckpt.h5": "precious\n",
}


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """The input files, a run file with its checkpoint, a shock run with every frame field
    and its summary, and corrupted copies of that shock run (CORRUPT)."""
    d = tmp_path_factory.mktemp("badin")
    for name, text in FILES.items():
        (d / name).write_text(text)
    (d / "adir").mkdir()
    for args in (["run", "good.toml", "-o", "good.h5"], ["run", "fields.toml", "-o", "sh.h5"],
                 ["run", "visc.toml", "-o", "visc.h5"]):
        p = pdfem(args + ["--quiet"], d)
        assert p.returncode == 0, p.stderr
    for src, dst in (("good.h5", "trunc.h5"), ("good.h5.ckpt.h5", "trunc.ckpt.h5")):
        data = (d / src).read_bytes()
        (d / dst).write_bytes(data[: len(data) // 2])
    for name, edit in CORRUPT.items():
        shutil.copy(d / "sh.h5", d / name)
        with h5py.File(d / name, "r+") as f:
            edit(f)
    for name, edit in DAMAGED.items():
        shutil.copy(d / "sh.h5", d / name)
        edit(d / name)
    return d


def _replace(f, name, data):
    """Dataset ``name`` of the open file f replaced by ``data``."""
    del f[name]
    f[name] = data


def _strings(f, name):
    """Dataset ``name`` as the text of its numbers (bytes, as h5py stores str arrays)."""
    _replace(f, name, np.array([str(v) for v in f[name][()].ravel()], dtype="S").reshape(
        f[name].shape))


def _odd_float(f, name):
    """Dataset ``name`` of a 17-byte float type (sign bit 97, exponent 52-62, mantissa
    0-51) that no numpy type holds: what bytes overwritten in a datatype message can make."""
    shape = f[name].shape
    del f[name]
    t = h5py.h5t.IEEE_F64LE.copy()
    t.set_size(17)
    t.set_precision(98)
    t.set_fields(97, 52, 11, 0, 52)
    h5py.h5d.create(f.id, name.encode(), t, h5py.h5s.create_simple(shape))


def _conn_past(f):
    """One node id of /mesh/conn past the last node."""
    conn = f["mesh/conn"][()]
    conn[3, 2] = f["mesh/node_body"].shape[0]
    _replace(f, "mesh/conn", conn)


def _damage(signature, last=False):
    """An edit (of the file's bytes) spoiling the first or last HDF5 block with that signature."""
    def edit(path):
        data = path.read_bytes()
        k = data.rfind(signature) if last else data.find(signature)
        assert k >= 0, signature
        path.write_bytes(data[:k] + b"XXXX" + data[k + 4:])
    return edit


# Run files damaged on disk: the global heap holding the scene text, a group's symbol table
DAMAGED = {"heap.h5": _damage(b"GCOL"), "table.h5": _damage(b"SNOD", last=True)}


def _set(name, row, value):
    """An edit setting row ``row`` of dataset ``name`` to ``value``."""
    def edit(f):
        f[name][row] = value
    return edit


# Run files corrupted from the shock run: the dataset that each breaks
CORRUPT = {
    "time-str.h5": lambda f: _strings(f, "frames/time"),
    "conn-past.h5": _conn_past,
    "v-row.h5": lambda f: _replace(f, "frames/v", f["frames/v"][:-1]),
    "temp-node.h5": lambda f: _replace(f, "frames/temperature", f["frames/temperature"][:, 1:]),
    "gauge-str.h5": lambda f: _strings(f, "gauges/hammer/stress"),
    "time-back.h5": _set("frames/time", 2, -1.0),
    "time-zero.h5": lambda f: f["frames/time"].__setitem__(slice(None), 0.0),
    "energy-odd.h5": lambda f: _odd_float(f, "energy/total"),
    "time-nan.h5": _set("frames/time", 1, np.nan),
    "body-past.h5": _set("mesh/elem_body", 0, 99),
    "kind-float.h5": lambda f: _replace(f, "mesh/body_kind", f["mesh/body_kind"][()] * 1.0),
    "energy-row.h5": lambda f: _replace(f, "energy/total", f["energy/total"][1:]),
    "x-int.h5": lambda f: _replace(f, "frames/x", f["frames/x"][()].astype("i1")),
    "v-nan.h5": _set("frames/v", 2, np.nan),
}


# (command line, text the one error line must hold)
CASES = {
    # run
    "run missing scene": (["run", "absent.toml"], "absent.toml"),
    "run not TOML": (["run", "garbage.toml"], "garbage.toml: TOML syntax"),
    "run HDF5 as scene": (["run", "good.h5"], "good.h5: cannot read the scene file"),
    "run negative size": (["run", "negative.toml"], "domain.cell_size: must be >= 0"),
    "run zero size": (["run", "zero.toml"], "grains[0].axes[0]: must be > 0"),
    "run hugoniot typed twice": (["run", "hugoniot_twice.toml"],
                                 "shock.crystal_hugoniot: derived from materials.hmx"),
    "run nan": (["run", "nan.toml"], "time.end: must be finite"),
    "run eos without slope": (["run", "eos_no_s.toml"],
                              'materials.grain.eos_s: required with eos = "us_up"'),
    "run slope without eos": (["run", "eos_s_alone.toml"],
                              'materials.grain.eos_s: only with eos = "us_up"'),
    "run slope out of range": (["run", "eos_s_big.toml"], "materials.grain.eos_s: must be"),
    "run gamma without an EOS": (["run", "gamma_linear.toml"],
                                 'materials.grain.eos_gamma: only with eos = "us_up"'),
    "run gamma too large": (["run", "gamma_big.toml"],
                            "materials.grain.eos_gamma: must be < 2 eos_s = 3"),
    "run gamma negative": (["run", "gamma_negative.toml"], "materials.grain.eos_gamma: must be"),
    "run thermal expansion with an eos": (["run", "eos_thermal.toml"],
                                          "materials.grain.eos_gamma: [thermoelastic] needs the "
                                          "thermal pressure of an equation of state"),
    "run coupling without expansion": (["run", "no_expansion.toml"],
                                       "materials.grain.expansion: required by [thermoelastic]"),
    "run expansion with a gruneisen eos": (["run", "gamma_expansion.toml"],
                                           'materials.grain.expansion: not with eos = "us_up"'),
    "run huge": (["run", "huge.toml"], "domain.cell_size: the cell grid would have"),
    "run faster than light": (["run", "fast.toml"], "blocks[0].velocity: must be below"),
    "run unknown effect": (["run", "effect.toml"], "viscosityy: unknown table"),
    "run no folder": (["run", "good.toml", "-o", "nowhere/r.h5"], "nowhere does not exist"),
    "run parent is a file": (["run", "good.toml", "-o", "notafolder/r.h5"],
                             "notafolder is not a folder"),
    "run output is a folder": (["run", "good.toml", "-o", "adir", "--force"],
                               "adir is a folder"),
    "run existing output": (["run", "good.toml", "-o", "keep.h5"], "keep.h5 exists"),
    "run existing sidecar": (["run", "good.toml", "-o", "side.h5"], "side.xdmf exists"),
    "run existing checkpoint": (["run", "good.toml", "-o", "stale.h5"],
                                "stale.h5.ckpt.h5 exists"),
    "run restart missing": (["run", "good.toml", "-o", "r.h5", "--restart", "absent.ckpt.h5"],
                            "absent.ckpt.h5"),
    "run restart not HDF5": (["run", "good.toml", "-o", "r.h5", "--restart", "good.toml"],
                             "cannot read good.toml"),
    "run restart truncated": (["run", "good.toml", "-o", "r.h5", "--restart", "trunc.ckpt.h5"],
                              "trunc.ckpt.h5"),
    "run restart other scene": (["run", "other.toml", "-o", "r.h5", "--restart",
                                 "good.h5.ckpt.h5"], "different scene ([grains] differs"),
    "run absurdly many steps": (["run", "steps.toml", "-o", "r.h5"],
                                "steps.toml: time.end: about 4.17e+10 steps of"),
    "run restart run file": (["run", "good.toml", "-o", "r.h5", "--restart", "good.h5"],
                             "good.h5 is not a pdfem checkpoint"),
    # prepare
    "prepare missing scene": (["prepare", "absent.toml"], "absent.toml"),
    "prepare not TOML": (["prepare", "garbage.toml"], "garbage.toml: TOML syntax"),
    "prepare no table": (["prepare", "good.toml"], "prepare: the scene has no [prepare]"),
    "prepare zero grains": (["prepare", "prep-zero.toml"], "prepare.grains: must be >= 1"),
    "prepare no folder": (["prepare", "prep.toml", "-o", "nowhere/b.h5"], "nowhere"),
    "prepare existing output": (["prepare", "prep.toml", "-o", "keep.h5"], "keep.h5 exists"),
    "prepare vast grains": (["prepare", "prep-vast.toml"],
                            "prep-vast.toml: prepare.semi_axis: grains of 1.2e+296 m"),
    "prepare bed too thin": (["prepare", "prep-thin.toml", "-o", "b.h5"],
                             "prep-thin.toml: prepare.packing: grain 0 found no place"),
    "prepare name too long": (["prepare", "prep.toml", "-o", "b" * 300],
                              "prepare.output: " + "b" * 300 + ": file name longer than"),
    # material
    "material option without value": (["material", "prep.toml", "--material", "hmx",
                                       "--strain=--"], "argument --strain: expected one"),
    "material not a table": (["material", "mat-text.toml", "--material", "hmx"],
                             "mat-text.toml: materials.hmx: must be a table (got str)"),
    "material absurd nsub": (["material", "prep.toml", "--material", "hmx", "--nsub",
                              "1000000000", "--out", "m.csv"],
                             "--nsub: 1000000000 increments x 2 path segment(s)"),
    "material HDF5 as scene": (["material", "good.h5", "--material", "hmx"], "good.h5"),
    "material unknown": (["material", "prep.toml", "--material", "lead"], "materials.lead"),
    "material gruneisen": (["material", "gamma_prep.toml", "--material", "hmx"],
                           "materials.hmx.eos_gamma: the material-point driver keeps no"),
    "material nan strain": (["material", "prep.toml", "--material", "hmx", "--strain", "nan",
                             "--out", "m.csv"], "--strain"),
    "material binary path": (["material", "prep.toml", "--material", "hmx", "--path",
                              "good.h5", "--out", "m.csv"], "--path: good.h5"),
    "material no folder": (["material", "prep.toml", "--material", "hmx", "--out",
                            "nowhere/m.csv"], "--out: "),
    "material existing output": (["material", "prep.toml", "--material", "hmx", "--out",
                                  "keep.csv"], "keep.csv exists"),
    "material unknown key": (["material", "typo.toml", "--material", "hmx", "--out", "m.csv"],
                             'typo.toml: materials.hmx.specfic_heat: unknown key for model "cap"'),
    # export
    "export missing": (["export", "absent.h5"], "absent.h5: no such run file"),
    "export not HDF5": (["export", "good.toml"], "good.toml: cannot read"),
    "export truncated": (["export", "trunc.h5"], "trunc.h5: cannot read"),
    "export checkpoint": (["export", "good.h5.ckpt.h5"], "not a pdfem run file"),
    "export unknown format": (["export", "good.h5", "--format", "bogus", "-p", "e"],
                              "--format: meshio has no writer 'bogus'"),
    "export no folder": (["export", "good.h5", "-p", "nowhere/e"], "nowhere does not exist"),
    "export existing output": (["export", "good.h5", "-p", "keep"], "keep-0000.vtu exists"),
    "export over its run file": (["export", "good.h5", "--format", "xdmf", "-p", "good",
                                  "--force"], "good.h5 is the run file"),
    "export time strings": (["export", "time-str.h5"], "time-str.h5: /frames/time: holds bytes"),
    "export time strings xdmf": (["export", "time-str.h5", "--format", "xdmf"],
                                 "time-str.h5: /frames/time: holds bytes"),
    "export conn past nodes": (["export", "conn-past.h5"],
                               "conn-past.h5: /mesh/conn: node id "),
    "export frame missing": (["export", "v-row.h5", "--frames", "0"],
                             "v-row.h5: /frames/v: shape"),
    "export node missing": (["export", "temp-node.h5"], "temp-node.h5: /frames/temperature: "),
    "export time backwards": (["export", "time-back.h5"], "time-back.h5: /frames/time: decreases"),
    "export time nan": (["export", "time-nan.h5"], "time-nan.h5: /frames/time: not finite"),
    "export body past": (["export", "body-past.h5"], "body-past.h5: /mesh/elem_body: body id 99"),
    "export float ids": (["export", "kind-float.h5"], "kind-float.h5: /mesh/body_kind: holds "
                         "floats, not integer ids"),
    "export empty name": (["export", ""], "runfile: empty file name"),
    # analyse
    "analyse damaged heap": (["analyse", "heap.h5", "-p", "a"],
                             "heap.h5: no readable scene attribute (Unable to read attribute"),
    "analyse damaged table": (["analyse", "table.h5", "-p", "a"],
                              "table.h5: cannot read the run file (Can't determine"),
    "analyse integer positions": (["analyse", "x-int.h5"],
                                  "x-int.h5: /frames/x: holds integers (int8), not floats"),
    "analyse nan velocity": (["analyse", "v-nan.h5"],
                             "v-nan.h5: /frames/v: frame 2 holds a non-finite value"),
    "analyse empty name": (["analyse", ""], "runfile: empty file name"),
    "analyse missing": (["analyse", "absent.h5"], "absent.h5: no such run file"),
    "analyse truncated": (["analyse", "trunc.h5"], "trunc.h5: cannot read"),
    "analyse not a shock run": (["analyse", "good.h5"], "good.h5: no [shock] table"),
    "analyse existing output": (["analyse", "sh.h5"], "sh-summary.json exists"),
    "analyse no folder": (["analyse", "sh.h5", "-p", "nowhere/a"], "nowhere does not exist"),
    "analyse sweep missing": (["analyse", "sh.h5", "-p", "a", "--sweep", "none.json"],
                              "--sweep: none.json: cannot read"),
    "analyse sweep not json": (["analyse", "sh.h5", "-p", "a", "--sweep", "good.toml"],
                               "--sweep: good.toml: not a JSON file"),
    "analyse sweep of another kind": (["analyse", "sh.h5", "-p", "a", "--sweep",
                                       "sh-summary.json"],
                                      "--sweep: sh-summary.json: not a sweep's JSON"),
    "analyse time strings": (["analyse", "time-str.h5"], "time-str.h5: /frames/time: holds "),
    "analyse conn past nodes": (["analyse", "conn-past.h5"], "conn-past.h5: /mesh/conn: node"),
    "analyse frame missing": (["analyse", "v-row.h5"], "v-row.h5: /frames/v: shape"),
    "analyse node missing": (["analyse", "temp-node.h5"], "temp-node.h5: /frames/temperature"),
    "analyse gauge strings": (["analyse", "gauge-str.h5"],
                              "gauge-str.h5: /gauges/hammer/stress: holds bytes"),
    "analyse time backwards": (["analyse", "time-back.h5"], "/frames/time: decreases at row 2"),
    "analyse times all zero": (["analyse", "time-zero.h5"],
                               "time-zero.h5: /frames/time: repeats at row 1 (0.0 after 0.0)"),
    "analyse odd float type": (["analyse", "energy-odd.h5"], "energy-odd.h5: /energy/total: "
                               "unreadable datatype (Insufficient precision in available types"),
    "analyse body past": (["analyse", "body-past.h5"], "body-past.h5: /mesh/elem_body: body"),
    "analyse energy missing": (["analyse", "energy-row.h5"], "energy-row.h5: /energy/total: "),
    # bench
    "bench zero": (["bench", "elements", "--n", "0"], "--n: must be in [1, "),
    "bench huge": (["bench", "contact", "--sizes", "10,1000000000000"], "--sizes: must be in"),
    "bench json no folder": (["bench", "parallel", "--json", "nowhere/b.json"], "--json: "),
    # study
    "study missing scene": (["study", "accuracy", "absent.toml"], "absent.toml"),
    "study infinite scale": (["study", "accuracy", "--kn0-scale", "1,inf"], "--kn0-scale"),
    "study negative level": (["study", "accuracy", "--levels", "-1"], "--levels"),
    "study no folder": (["study", "accuracy", "shock.toml", "-p", "nowhere/s"], "nowhere"),
    "study zero size": (["study", "convergence", "--sizes", "0,8"], "--sizes"),
    # sweep
    "sweep not TOML": (["sweep", "garbage.toml"], "garbage.toml: TOML syntax"),
    "sweep nan speed": (["sweep", "shock.toml", "--velocities", "100,nan"], "--velocities"),
    "sweep not a shock scene": (["sweep", "good.toml"], "good.toml: shock"),
    "sweep no folder": (["sweep", "shock.toml", "-p", "nowhere/s"], "nowhere does not exist"),
}


def _state(folder):
    """Every file under folder with a digest of its content."""
    out = {}
    for root, _, names in os.walk(folder):
        for n in names:
            p = os.path.join(root, n)
            with open(p, "rb") as f:
                out[os.path.relpath(p, folder)] = hashlib.sha1(f.read()).hexdigest()
    return out


def _one_error_line(p, text):
    assert p.returncode == 2, (p.returncode, p.stdout, p.stderr)
    assert "Traceback" not in p.stderr + p.stdout, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("pdfem: error: "), p.stderr
    assert text in lines[0], (text, lines[0])


# Schedules, cross-scene restarts and strain paths: the line also stays under 200 characters
SHORT_CASES = {
    "run frames 1e-20": (["run", "frames-1e-20.toml", "-o", "r.h5"],
                         "output.interval: 1e-20 s over time.end = 1e-07 s implies 1e+13 frames"),
    "run frames subnormal": (["run", "frames-denormal.toml", "-o", "r.h5"],
                             "output.interval: 5e-324 s is subnormal"),
    "run frames shorter than a step": (["run", "frames-per-step.toml", "-o", "r.h5"],
                                       "implies 4.8e+06 frames, more than 1e+06"),
    "run checkpoints subnormal": (["run", "ckpt-denormal.toml", "-o", "r.h5"],
                                  "output.checkpoint_interval: 5e-324 s is subnormal"),
    "run energy subnormal": (["run", "energy-denormal.toml", "-o", "r.h5"],
                             "output.energy_interval: 5e-324 s is subnormal"),
    "run energy below the time's advance": (["run", "energy-no-advance.toml", "-o", "r.h5"],
                                            "output.energy_interval: 1e-24 s is below the "
                                            "smallest advance of the time at time.end"),
    "run gauges subnormal": (["run", "gauge-denormal.toml", "-o", "r.h5"],
                             "output.gauge_interval: 5e-324 s is subnormal"),
    "run end subnormal": (["run", "end-denormal.toml", "-o", "r.h5"],
                          "time.end: 5e-324 s is subnormal"),
    "run restart other effects": (["run", "visc.toml", "-o", "r.h5", "--restart",
                                   "good.h5.ckpt.h5"], "([bulk_viscosity] only in this scene"),
    # The checkpoint holds the viscosity's fields (qv, ewq) that this scene lacks
    "run restart checkpoint of other effects": (["run", "good.toml", "-o", "r.h5", "--restart",
                                                 "visc.h5.ckpt.h5"],
                                                "([bulk_viscosity] only in the checkpoint"),
    "run restart other material": (["run", "stiffer.toml", "-o", "r.h5", "--restart",
                                    "good.h5.ckpt.h5"], "([materials.grain] differs"),
    "material path beyond small strain": (["material", "prep.toml", "--material", "hmx",
                                           "--path", "big-strain.csv", "--out", "m.csv"],
                                          "big-strain.csv: row 3, column exx: strain -5.0"),
}


def _refused(folder, args, text):
    """The command exits 2 with one line holding text; the folder stays as it was. Returns
    its stderr."""
    before = _state(folder)
    p = pdfem(args, folder, timeout=60)
    _one_error_line(p, text)
    assert _state(folder) == before
    return p.stderr


@pytest.mark.parametrize("case", list(SHORT_CASES))
def test_schedule_restart_and_path_cases_one_short_line(folder, case):
    assert len(_refused(folder, *SHORT_CASES[case]).strip()) < 200


@pytest.mark.parametrize("case", list(CASES))
def test_bad_input_one_line_exit_2_nothing_written(folder, case):
    _refused(folder, *CASES[case])


def test_more_ranks_than_cells(folder):
    before = _state(folder)
    p = pdfem(["run", "one-cell.toml", "-o", "r.h5", "--quiet"], folder, ranks=2, timeout=60)
    _one_error_line(p, "one-cell.toml: domain.cell_size: the cell grid has 1 cell(s)")
    assert _state(folder) == before


def _in_process(args, cwd):
    """``pdfem.cli.main(args)`` in the folder cwd: (exit status, stderr)."""
    import contextlib
    import io

    from pdfem.cli import main

    err = io.StringIO()
    with contextlib.chdir(cwd), contextlib.redirect_stdout(io.StringIO()), \
            contextlib.redirect_stderr(err):
        return main(args), err.getvalue()


def test_nul_byte_in_a_file_name(folder):
    """A NUL byte (which no command line can pass, a script can) in an input or output name."""
    before = _state(folder)
    for args, text in ((["prepare", "bed\0.toml"], "bed\0.toml: cannot read the scene file"),
                       (["analyse", "sh.h5", "-p", "a\0b"], "--prefix: 'a\\x00b-summary"),
                       (["material", "bed\0.toml", "--material", "hmx"],
                        "'bed\\x00.toml': cannot read the scene file")):
        status, err = _in_process(args, folder)
        assert status == 2 and "Traceback" not in err, err
        lines = err.strip().splitlines()
        assert len(lines) == 1 and text in lines[0], (text, err)
    assert _state(folder) == before


def test_material_path_the_model_cannot_hold(folder):
    """Triaxial under tension: the held stresses stop responding; exit 3 with one line."""
    before = _state(folder)
    status, err = _in_process(["material", "prep.toml", "--material", "hmx", "--path",
                               "triaxial", "--strain", "0.005", "--out", "t.csv"], folder)
    lines = err.strip().splitlines()
    assert status == 3 and len(lines) == 1 and "singular Jacobian" in lines[0], err
    assert _state(folder) == before


def test_export_of_a_frame_given_twice(folder, tmp_path):
    """--frames 0,0 (or 1,-1 naming one frame twice) writes that frame once."""
    status, err = _in_process(["export", str(folder / "good.h5"), "--frames", "1,0,-1,1",
                               "-p", "dup"], tmp_path)
    assert status == 0, err
    assert sorted(os.listdir(tmp_path)) == ["dup-0000.vtu", "dup-0001.vtu", "dup-0004.vtu"]


def test_allow_huge_runs_what_is_refused_without_it(folder, tmp_path):
    """The 1e12-step scene runs with --allow-huge (until SIGTERM ends it with a checkpoint)."""
    import signal
    import sys

    shutil.copy(folder / "steps.toml", tmp_path / "steps.toml")
    cmd = [sys.executable, "-m", "pdfem", "run", "steps.toml", "-o", "r.h5", "--allow-huge"]
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2]))
    p = subprocess.Popen(cmd, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, env=env)
    # The first step is taken only once the run has passed the step estimate
    for line in p.stdout:
        if line.startswith("first step"):
            break
    p.send_signal(signal.SIGTERM)
    out, err = p.communicate(timeout=120)
    assert p.returncode == 0, err
    assert (tmp_path / "r.h5.ckpt.h5").exists() and not (tmp_path / "r.h5").exists()


def test_a_rank_without_grains_writes_its_share(tmp_path):
    """Two cells on two ranks, both grains in one: the rank with no bodies still takes part in
    the collective writes, and the file is the 1-rank one."""
    doc = drifting_grains(n=2, end=1e-7, frac=0.25)
    doc["domain"]["cell_size"] = 0.012
    write_scene(tmp_path / "e.toml", doc)
    for n in (1, 2):
        p = pdfem(["run", "e.toml", "-o", f"e{n}.h5", "--quiet"], tmp_path, ranks=n)
        assert p.returncode == 0, p.stderr
    a, b = datasets(tmp_path / "e1.h5"), datasets(tmp_path / "e2.h5")
    assert sorted(a) == sorted(b) and all(np.array_equal(a[k], b[k]) for k in a)


def test_material_command_knows_the_named_paths():
    """The command line lists the named strain paths without loading the material kernels."""
    from pdfem import material_point
    from pdfem.cli.material import NAMED_PATHS

    assert NAMED_PATHS == material_point.NAMED_PATHS


def test_complete_run_files_pass_the_run_file_check(folder):
    """The checker of analyse and export accepts what the run wrote, every frame field too."""
    from pdfem.io.layout import frame_layout
    from pdfem.io.runcheck import check_run_file

    for name, series in (("good.h5", False), ("sh.h5", True)):
        with h5py.File(folder / name) as f:
            got = check_run_file(f, name, series=series, n_materials=2)
            want = (f["frames/time"].shape[0], f["mesh/node_body"].shape[0],
                    f["mesh/conn"].shape[0])
            fields = set(f["frames"]) - {"time"}
        assert got == want and want[0] >= 3
    assert fields == set(frame_layout())


def test_material_accepts_every_material_of_the_packaged_scene(tmp_path):
    """A scene that run accepts is accepted by material: its thermal keys are ignored."""
    from pdfem.packaged import default_scene_path
    from pdfem.scene import load_scene

    path = default_scene_path()
    mats = load_scene(path).resolved["materials"]
    with open(path, "rb") as f:
        raw = tomllib.load(f)["materials"]
    # The premise: run accepts the scene, whose cap materials carry thermal keys
    assert set(mats) == set(raw) and "specific_heat" in raw["hmx"]
    for name in raw:
        p = pdfem(["material", str(path), "--material", name, "--out", f"{name}.csv"],
                  tmp_path, timeout=120)
        assert p.returncode == 0, p.stderr
        rows = (tmp_path / f"{name}.csv").read_text().splitlines()
        assert rows[0].startswith("step,exx") and len(rows) > 50
    # Every key the scene schema gives a cap material is known to the driver
    from pdfem.kernels import params as P
    from pdfem.material_point import cap_params_from_table
    from pdfem.scene import schema as S

    # (the equation of state's keys with values of their own: the driver applies them; a
    # Gruneisen coefficient it refuses, tested above)
    extra = {k: 1.0e-4 for k in (*S.MATERIAL_COMMON, *S.CAP) if k not in raw["hmx"]}
    extra.update(eos="us_up", eos_s=2.0, eos_gamma=0.0)
    p = cap_params_from_table({**raw["hmx"], **extra}, "materials.hmx")
    assert "softening" in extra and p[P.RHO] == raw["hmx"]["density"] and p[P.EOS_S] == 2.0


def test_many_coincident_grains_refused_with_the_first_pair(tmp_path):
    """20 000 copies of one grain (a grains file): refused at the first pair, at once (the
    overlap search stops there instead of forming all 2e8 pairs)."""
    n = 20_000
    np.savez(tmp_path / "same.npz", x=np.full(n, 3e-3), y=np.full(n, 3e-3),
             a=np.full(n, 4e-4), b=np.full(n, 3e-4), angle=np.full(n, 0.2))
    doc = drifting_grains(n=1, end=1e-7, out="same.h5")
    del doc["grains"]
    doc["grains_file"] = {"path": "same.npz", "material": "grain"}
    write_scene(tmp_path / "same.toml", doc)
    before = _state(tmp_path)
    p = pdfem(["run", "same.toml"], tmp_path, timeout=60)
    _one_error_line(p, "same.toml: grains_file: same.npz row 0 (grain 0): overlaps same.npz "
                    "row 1 (grain 1) at t=0")
    assert _state(tmp_path) == before


@pytest.mark.parametrize("args", [["prepare", "--help"], ["export", "run.h5"], []])
def test_a_missing_dependency_is_one_line_naming_the_fix(tmp_path, args):
    """A Python without the project's packages (here h5py and numpy made unimportable)
    gets one line saying to activate or install the environment, exit 2, no traceback."""
    import sys

    for name in ("h5py", "numpy"):
        (tmp_path / "block" / name).mkdir(parents=True)
        (tmp_path / "block" / name / "__init__.py").write_text(
            f"raise ModuleNotFoundError(\"No module named '{name}'\", name='{name}')\n")
    env = dict(os.environ, PYTHONPATH=f"{tmp_path / 'block'}:{Path(__file__).parents[2]}")
    p = subprocess.run([sys.executable, "-m", "pdfem", *args], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in p.stderr, p.stderr
    assert "is not installed for" in lines[0] and ". .venv/bin/activate" in lines[0]
