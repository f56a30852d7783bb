"""``python -m pdfem material SCENE --material NAME --path PATH --out out.csv``.

Drives one point of the cap material ``[materials.NAME]`` of a scene file through a strain
path (a named path or a CSV file of target strain tensors) and writes the stress history as
CSV with columns step, exx, eyy, exy, ezz, sxx, syy, sxy, szz, I1, sqrtJ2, kappa, epv, wp
(SI units, tension positive).
"""

import os
import tomllib

from pdfem.errors import InputError
from pdfem.material_point import (
    NAMED_PATHS,
    cap_params_from_table,
    named_path,
    read_path_csv,
    run_path,
    write_csv,
)


def add_parser(subparsers):
    """Register the ``material`` command."""
    sp = subparsers.add_parser(
        "material", help="drive one cap material point through a strain path",
        description=__doc__.split("\n\n")[1])
    sp.add_argument("scene", help="scene TOML file with a [materials.NAME] table")
    sp.add_argument("--material", required=True, metavar="NAME", help="material name")
    sp.add_argument("--path", default="uniaxial",
                    help=f"named path ({', '.join(NAMED_PATHS)}) or CSV file with columns "
                    "exx, eyy, exy, ezz (default uniaxial)")
    sp.add_argument("--strain", type=float, default=-0.01,
                    help="peak strain of a named path (default -0.01, compression)")
    sp.add_argument("--axial", type=float, default=None,
                    help="extra axial strain of the triaxial path (default 4 x strain)")
    sp.add_argument("--nsub", type=int, default=50,
                    help="increments per path segment (default 50)")
    sp.add_argument("--out", default="material.csv", help="output CSV (default material.csv)")
    return sp


def _material_table(fname, name):
    """[materials.NAME] of a TOML file, or InputError."""
    try:
        with open(fname, "rb") as f:
            doc = tomllib.load(f)
    except OSError as exc:
        raise InputError(f"{fname}: {exc.strerror}") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{fname}: {exc}") from None
    mats = doc.get("materials", {})
    if name not in mats:
        have = ", ".join(sorted(mats)) or "none"
        raise InputError(f"materials.{name}: no such table in {fname} (have: {have})")
    return mats[name]


def run(args):
    """Run the material point and write the CSV; returns 0."""
    tbl = _material_table(args.scene, args.material)
    p = cap_params_from_table(tbl, where=f"materials.{args.material}")
    # Named path (an unknown name raises, listing the choices), or a file of target strains
    if args.path in NAMED_PATHS or not os.path.exists(args.path):
        path, held = named_path(args.path, args.strain, args.axial)
    else:
        path, held = read_path_csv(args.path), None
    res = run_path(p, path, args.nsub, held)
    write_csv(args.out, res)
    return 0
