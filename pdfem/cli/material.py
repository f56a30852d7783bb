"""``python -m pdfem material SCENE --material NAME --path PATH --out out.csv``.

Drives one point of the cap material ``[materials.NAME]`` of a scene file through a strain
path (a named path or a CSV file of target strain tensors) and writes the stress history as
CSV with columns step, exx, eyy, exy, ezz, sxx, syy, sxy, szz, I1, sqrtJ2, kappa, epv, wp
(SI units, tension positive).
"""

import os
import tomllib

from pdfem.errors import InputError

# The built-in strain paths (pdfem.material_point.NAMED_PATHS; that module loads numba, which
# the command line imports only when the command runs)
NAMED_PATHS = ("uniaxial", "hydrostatic", "triaxial", "load-unload")


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
    sp.add_argument("--strain-rate", type=float, default=None, metavar="RATE",
                    help="strain rate [1/s]: each increment lasts its largest strain component "
                    "over RATE (needed by a material with relaxation_time > 0)")
    sp.add_argument("--out", default="material.csv", help="output CSV (default material.csv)")
    sp.add_argument("--force", action="store_true", help="overwrite an existing output CSV")
    return sp


def _material_table(fname, name):
    """[materials.NAME] of a TOML file, or InputError."""
    try:
        with open(fname, "rb") as f:
            doc = tomllib.load(f)
    except OSError as exc:
        raise InputError(f"{fname}: cannot read the scene file: {exc.strerror}") from None
    except (UnicodeDecodeError, ValueError) as exc:
        # ValueError: a NUL byte in the name
        raise InputError(f"{fname!r}: cannot read the scene file: {exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{fname}: TOML syntax: {exc}") from None
    mats = doc.get("materials", {})
    if not isinstance(mats, dict):
        raise InputError(f"{fname}: materials: must be a table of materials")
    if name not in mats:
        have = ", ".join(sorted(mats)) or "none"
        raise InputError(f"materials.{name}: no such table in {fname} (have: {have})")
    if not isinstance(mats[name], dict):
        raise InputError(f"{fname}: materials.{name}: must be a table (got "
                         f"{type(mats[name]).__name__})")
    return mats[name]


def _strain(value, option):
    """A strain from the command line: finite, at most 1 in magnitude."""
    if value is not None and not abs(value) <= 1.0:
        raise InputError(f"{option}: must be a strain in [-1, 1] (got {value!r})")
    return value


def run(args):
    """Run the material point and write the CSV; returns 0."""
    from pdfem.cli.paths import check_output_path
    from pdfem.material_point import (
        cap_params_from_table,
        named_path,
        read_path_csv,
        run_path,
        write_csv,
    )

    tbl = _material_table(args.scene, args.material)
    p = cap_params_from_table(tbl, where=f"{args.scene}: materials.{args.material}")
    # Named path (an unknown name raises, listing the choices), or a file of target strains
    strain, axial = _strain(args.strain, "--strain"), _strain(args.axial, "--axial")
    if args.path in NAMED_PATHS or not os.path.exists(args.path):
        path, held = named_path(args.path, strain, axial)
    else:
        path, held = read_path_csv(args.path), None
    check_output_path(args.out, args.force, "--out")
    res = run_path(p, path, args.nsub, held, args.strain_rate)
    write_csv(args.out, res)
    return 0
