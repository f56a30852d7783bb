"""Bad input never hurts, beyond ``run``: mutated inputs of prepare, material, export, analyse,
hotspots.

Each example mutates one input once and runs the command in process through
``pdfem.cli.main``. The command either succeeds (the mutant was still valid: its outputs are
complete) or exits 2 with exactly one line on stderr naming the input file (or the option) and
no traceback, the folder exactly as it was: nothing changed, nothing partial (``*.part``, a
half-written VTU, summary or figure) left behind. The classes:

- prepare: a small geometric preparation scene through the scene mutator of
  tests/test_fuzz_scenes.py (deleted, retyped, scaled, unknown, truncated, garbage keys);
  every prepare is bounded by an alarm (a hang fails the example), and a valid bed beyond a
  few seconds' work is refused by the preparation's limits, lowered to this test's budget
  (LIMITS);
- material: the material tables through the same mutator, and the command's options
  (--material, --strain, --axial, --nsub, --path as a name, a folder, a missing file or a
  mutated CSV, --out); a material path the model cannot follow exits 3 with one line;
- export, analyse and hotspots: a real run file and a real shock run file (built once) copied
  and one dataset, group or attribute deleted, replaced by strings, a group, another dtype or shape,
  one value made NaN, infinite, negative or huge, the scene attribute replaced by garbage,
  the file truncated, or bytes overwritten in place (damaged metadata can hang or crash the
  HDF5 library: the commands walk it in a child process first, pdfem.io.probe, whose time
  limit LIMITS lowers);
- any of these commands: garbage, huge or missing option values and output paths that are
  folders, missing or files;
- cross-scene restarts: ``run --restart`` of a real checkpoint with its own scene mutated once
  (tests/fuzz.py's mutator, schedule keys included), with only the keys a restart may change
  changed, or with another scene altogether: it continues (the change was allowed), stops on a
  guard, or exits 2 with one line of under 200 characters that names the scene or the
  checkpoint (and, for another scene, the table that differs).

``PDFEM_FUZZ_EXAMPLES=2000 pytest tests/test_fuzz_commands.py`` runs the long mode (that
many examples per test instead of the few that keep the suite's run near a minute).
"""

import contextlib
import hashlib
import io
import math
import os
import shutil
import tempfile
from pathlib import Path

import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pdfem.cli import main
from pdfem.scene.toml_out import dumps
from tests.fuzz import alarm, mutants
from tests.scenes import (
    checkpointed_grains,
    drifting_grains,
    every_field_shock,
    inline_shock,
    shock_materials,
    small_prepare,
    toml,
)

# Examples per test: the quick default of the suite, or the long mode's count
LONG = int(os.environ.get("PDFEM_FUZZ_EXAMPLES", "0"))
# Seconds a valid prepare of the small bed may take before it counts as a hang
PREPARE_LIMIT = 60
# The limits of the commands, set to this test's budget (module, name, value): a step of the
# metadata walk of a run file (pdfem.io.probe.TIMEOUT, 10 s, is sized for large files on a
# loaded machine; these walk in tens of milliseconds, and each hang costs this), and the
# grains and grain-sweeps of a geometric bed (pdfem.prepare.size: 1e6 and 1e9, about an
# hour; a valid mutant 1 m wide holds 13 700 grains and takes a minute or more, here it is
# refused with its estimate like a bed beyond the default limits)
LIMITS = (("pdfem.io.probe", "TIMEOUT", 3), ("pdfem.prepare.size", "MAX_GEOMETRIC_GRAINS", 2000),
          ("pdfem.prepare.size", "MAX_GRAIN_SWEEPS", 10**6))


@pytest.fixture(autouse=True, scope="module")
def _test_limits():
    import importlib

    old = []
    for module, name, value in LIMITS:
        mod = importlib.import_module(module)
        old.append((mod, name, getattr(mod, name)))
        setattr(mod, name, value)
    yield
    for mod, name, value in old:
        setattr(mod, name, value)


def _settings(n):
    """Derandomised hypothesis settings with n examples (the long mode's count if set)."""
    return settings(max_examples=LONG or n, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.too_slow,
                                           HealthCheck.function_scoped_fixture])


def _cli(args):
    """``pdfem.cli.main(args)`` in process: (exit status, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main([str(a) for a in args])
    return status, out.getvalue(), err.getvalue()


def _state(folder):
    """Every entry under folder with a digest of a file's content (None for a folder)."""
    out = {}
    for root, dirs, names in os.walk(folder):
        for n in dirs:
            out[os.path.relpath(os.path.join(root, n), folder)] = None
        for n in names:
            p = os.path.join(root, n)
            with open(p, "rb") as f:
                out[os.path.relpath(p, folder)] = hashlib.sha1(f.read()).hexdigest()
    return out


def _refused_cleanly(status, err, names, what, before, folder, codes=(2,)):
    """An exit in ``codes`` with one error line holding one of ``names``, the folder as it was."""
    assert "Traceback" not in err, (what, err)
    assert status in codes, (what, status, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("pdfem: error: "), (what, err)
    message = lines[0].removeprefix("pdfem: error: ")
    assert any(str(n) in message for n in names if str(n)), (what, names, lines[0])
    assert _state(folder) == before, (what, sorted(set(_state(folder)) ^ set(before)))


def _no_partial(folder, what):
    """No ``.part`` file or export scratch folder under folder."""
    left = [n for n in _state(folder) if n.endswith(".part") or ".pdfem-export-" in n]
    assert not left, (what, left)


# ---------------------------------------------------------------- prepare


def _prepare_base():
    """The small geometric preparation cut to a 1 mm x 1 mm bed (13 grains, under a second)."""
    doc = small_prepare("bed.h5", height=1.0e-3)
    doc["domain"]["box"] = [0.0, 0.0, 1.0e-3, 1.3e-3]
    return dumps(doc)


PREPARE = _prepare_base()


def test_the_prepare_base_prepares():
    with tempfile.TemporaryDirectory() as d:
        Path(d, "p.toml").write_text(PREPARE)
        status, _, err = _cli(["prepare", Path(d, "p.toml"), "-o", Path(d, "bed.h5")])
        assert status == 0, err
        with h5py.File(Path(d, "bed.h5")) as f:
            assert f["grains/x"].shape[0] >= 10


@_settings(150)
@given(mutants(PREPARE))
def test_mutated_prepare_scene_prepares_or_exits_2(mutant):
    data, what = mutant
    with tempfile.TemporaryDirectory() as d:
        scene, bed = Path(d, "p.toml"), Path(d, "bed.h5")
        scene.write_bytes(data)
        before = _state(d)
        with alarm(PREPARE_LIMIT):
            status, _, err = _cli(["prepare", scene, "-o", bed])
        if status == 0:
            # Still a valid preparation: a complete bed file
            with h5py.File(bed) as f:
                assert f["grains/x"].shape[0] >= 1, what
            _no_partial(d, what)
            return
        _refused_cleanly(status, err, [scene, "prepare.output"], what, before, d)


# ---------------------------------------------------------------- material

MATERIAL = toml({"materials": shock_materials()})
# Strain-path CSV files: valid, and broken in one way each
CSV = {"good": "exx,eyy,exy,ezz\n-0.01,0,0,0\n0,0,0,0\n",
       "empty": "", "header only": "exx,eyy,exy,ezz\n", "no header": "-0.01,0,0,0\n",
       "short row": "exx,eyy,exy,ezz\n-0.01,0\n", "nan": "exx,eyy,exy,ezz\nnan,0,0,0\n",
       "text": "exx,eyy,exy,ezz\na,b,c,d\n", "huge": "exx,eyy,exy,ezz\n-1e300,0,0,0\n",
       "binary": "\x00\x01\x02\xff",
       "columns": "ezz,exy,eyy,exx,extra\n0,0,0,-0.01,7\n",
       "many rows": "exx,eyy,exy,ezz\n" + "-0.001,0,0,0\n" * 200}
# Strains outside what the small-strain driver can mean (|strain| > 1), put at one row and
# column of a valid path: refused with one line naming the file, the row and the column
OUT_OF_RANGE = [-5.0, 5.0, 1.0000001, -1.5, 1.0e3, -1.0e300]
PATH_COLUMNS = ["exx", "eyy", "exy", "ezz"]
# Option values: numbers out of range or not numbers at all, and valid ones
NUMBERS = ["nan", "inf", "-inf", "1e400", "-2", "2", "abc", "", "0", "-0.02", "0.005", "1e-300",
           "-1", "10", "1000000000", "3.5", "0x10", "--", "-"]
OPTIONS = ["--strain", "--axial", "--nsub"]
PATH_NAMES = ["uniaxial", "hydrostatic", "triaxial", "load-unload", "bogus", "Uniaxial", ""]


@st.composite
def material_calls(draw):
    """(scene bytes, extra arguments, CSV text or None, what) of a material command."""
    kind = draw(st.sampled_from(["table", "option", "option", "path", "csv", "range", "out",
                                 "name"]))
    args, csv = [], None
    if kind == "table":
        data, what = draw(mutants(MATERIAL))
        return data, ["--material", draw(st.sampled_from(["hmx", "steel"]))], None, what
    data = MATERIAL.encode()
    name = "hmx"
    if kind == "option":
        opt, val = draw(st.sampled_from(OPTIONS)), draw(st.sampled_from(NUMBERS))
        args = [f"{opt}={val}", "--path", draw(st.sampled_from(PATH_NAMES[:4]))]
        what = f"{opt}={val}"
    elif kind == "path":
        path = draw(st.sampled_from(PATH_NAMES + ["<folder>", "<missing>.csv"]))
        args, what = ["--path", path], f"--path {path}"
    elif kind == "csv":
        key = draw(st.sampled_from(sorted(CSV)))
        csv, args, what = CSV[key], ["--path", "<csv>"], f"csv {key}"
    elif kind == "range":
        row, col = draw(st.integers(0, 2)), draw(st.integers(0, 3))
        value = draw(st.sampled_from(OUT_OF_RANGE))
        rows = [[-0.01, 0.0, 0.0, 0.0], [-0.02, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]]
        rows[row][col] = value
        csv = ",".join(PATH_COLUMNS) + "\n" + "".join(",".join(map(repr, r)) + "\n" for r in rows)
        args = ["--path", "<csv>"]
        what = f"range row {row + 2} {PATH_COLUMNS[col]} = {value!r}"
    elif kind == "out":
        out = draw(st.sampled_from(["<folder>", "<missing>/m.csv", "<file>/m.csv", "", "m.csv"]))
        args, what = ["--out", out], f"--out {out}"
    else:
        name = draw(st.sampled_from(["lead", "", "hmx.x", "materials", "HMX"]))
        what = f"--material {name!r}"
    return data, ["--material", name] + args, csv, what


def _placeholders(args, d):
    """The arguments with <folder>, <missing>, <file> and <csv> made paths in folder d."""
    out = []
    for a in args:
        a = a.replace("<folder>", os.path.join(d, "adir")).replace(
            "<missing>", os.path.join(d, "absent")).replace(
            "<file>", os.path.join(d, "plain.txt")).replace("<csv>", os.path.join(d, "path.csv"))
        out.append(a)
    return out


def _folder_with_inputs(d):
    """A folder ``adir`` and a plain file ``plain.txt`` in d."""
    os.mkdir(os.path.join(d, "adir"))
    Path(d, "plain.txt").write_text("a plain file\n")


@_settings(300)
@given(material_calls())
def test_mutated_material_call_runs_or_exits_2(call):
    data, args, csv, what = call
    with tempfile.TemporaryDirectory() as d:
        _folder_with_inputs(d)
        scene = Path(d, "m.toml")
        scene.write_bytes(data)
        if csv is not None:
            Path(d, "path.csv").write_bytes(csv.encode("utf-8", "surrogateescape"))
        args = _placeholders(args, d)
        if "--out" not in args:
            args += ["--out", os.path.join(d, "out.csv")]
        before = _state(d)
        with alarm(PREPARE_LIMIT), contextlib.chdir(d):
            status, _, err = _cli(["material", scene] + args)
        out = args[args.index("--out") + 1]
        if what.startswith("range "):
            # Out of range: always refused, naming the file, the row and the column
            _, _, row, col, *_ = what.split()
            _refused_cleanly(status, err, [f"path.csv: row {row}, column {col}"], what,
                             before, d)
            return
        if status == 0:
            rows = Path(d, out).read_text().splitlines()
            assert rows[0].startswith("step,exx") and len(rows) >= 2, what
            _no_partial(d, what)
            return
        # A path the model cannot follow ends the point with exit 3, naming the step
        names = [scene, "--", "materials."] if status == 2 else ["step", "increment"]
        _refused_cleanly(status, err, names, what, before, d, codes=(2, 3))


# ---------------------------------------------------------------- export and analyse


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """A real run file (run.h5) and a shock run with every frame field (shock.h5)."""
    d = tmp_path_factory.mktemp("fuzzruns")
    for name, doc in (("run", checkpointed_grains()), ("shock", every_field_shock())):
        (d / f"{name}.toml").write_text(toml(doc))
        status, _, err = _cli(["run", d / f"{name}.toml", "-o", d / f"{name}.h5", "--quiet"])
        assert status == 0, err
    return d


def _members(path):
    """(datasets, groups, (object, attribute) pairs) of an HDF5 file, sorted."""
    dsets, groups, attrs = [], [], []
    with h5py.File(path) as f:
        attrs += [("/", a) for a in f.attrs]

        def visit(name, obj):
            (dsets if isinstance(obj, h5py.Dataset) else groups).append(name)
            attrs.extend((name, a) for a in obj.attrs)
        f.visititems(visit)
    return sorted(dsets), sorted(groups), sorted(attrs)


# Values one element of a dataset is set to
ODD = [math.nan, math.inf, -math.inf, -1, 2**40, -(2**40), 1.0e300, -1.0e300, 0, 1.0e-300]
# Text that replaces an attribute (the scene attribute among them)
GARBAGE_TEXT = ["", "[[[", "this is = = not toml", np.bytes_(b"\x00\x01"),
                "[shock]\nplots = 'png'\n", "[time]\nend = 1.0\n", "é" * 10]


def _resize(a, how):
    """Array a of another shape: a row less, a column less, an axis more, a scalar, empty."""
    if how == "row" and a.ndim >= 1 and a.shape[0] > 0:
        return a[:-1]
    if how == "column" and a.ndim >= 2 and a.shape[1] > 0:
        return a[:, 1:]
    if how == "axis":
        return a[..., None]
    if how == "scalar":
        return a.ravel()[0] if a.size else np.float64(0.0)
    return a[:0]


def _mutate(path, data, members):
    """Mutate the HDF5 file at path once (drawing from ``data``); returns what was done."""
    dsets, groups, attrs = members
    kinds = ["delete", "strings", "dtype", "shape", "value", "value", "group", "delete group",
             "attribute", "delete attribute", "truncate", "overwrite"]
    kind = data.draw(st.sampled_from(kinds))
    if kind in ("truncate", "overwrite"):
        size = os.path.getsize(path)
        k = data.draw(st.integers(0, size - 1))
        with open(path, "r+b") as fh:
            if kind == "truncate":
                fh.truncate(k)
            else:
                fh.seek(k)
                fh.write(data.draw(st.sampled_from([b"\x00" * 64, b"\xff" * 8, b"garbage!"])))
        return f"{kind} at byte {k}"
    with h5py.File(path, "r+") as f:
        if kind in ("attribute", "delete attribute"):
            obj, name = data.draw(st.sampled_from(attrs))
            if kind == "delete attribute":
                del f[obj].attrs[name]
                return f"delete attribute {obj}:{name}"
            value = data.draw(st.sampled_from(GARBAGE_TEXT + [np.arange(3), 1.0e300]))
            f[obj].attrs[name] = value
            return f"attribute {obj}:{name} = {value!r}"
        if kind == "delete group":
            name = data.draw(st.sampled_from(groups))
            del f[name]
            return f"delete group /{name}"
        name = data.draw(st.sampled_from(dsets))
        a = f[name][()]
        what = f"{kind} /{name}"
        if kind == "value":
            a = np.array(a)
            if a.size == 0:
                return what + " (empty: unchanged)"
            v = data.draw(st.sampled_from(ODD))
            k = data.draw(st.integers(0, a.size - 1))
            if a.dtype.kind in "iu" and not (isinstance(v, int)
                                             and np.iinfo(a.dtype).min <= v
                                             <= np.iinfo(a.dtype).max):
                v = -1 if a.dtype.kind == "i" else np.iinfo(a.dtype).max
            a.flat[k] = v
            f[name][...] = a
            return f"{what} element {k} = {v}"
        del f[name]
        if kind == "strings":
            f[name] = np.array([str(v).encode() for v in np.ravel(a)], dtype="S").reshape(
                np.shape(a))
        elif kind == "dtype":
            dt = data.draw(st.sampled_from(["i1", "u8", "f4", "f8", "c16", "?", "i8"]))
            with np.errstate(invalid="ignore"):
                f[name] = np.asarray(a).astype(dt)
            what += f" as {dt}"
        elif kind == "shape":
            how = data.draw(st.sampled_from(["row", "column", "axis", "scalar", "empty"]))
            f[name] = _resize(np.asarray(a), how)
            what += f" ({how})"
        else:
            f.create_group(name)
    return what


def _export_or_analyse(data, runs, command):
    """Mutate a copy of a run file and run ``command`` on it; check the outcome."""
    src = data.draw(st.sampled_from(["run.h5", "shock.h5"])) if command == "export" \
        else "shock.h5"
    with tempfile.TemporaryDirectory() as d:
        path = Path(d, "m.h5")
        shutil.copy(runs / src, path)
        what = f"{src}: " + _mutate(path, data, _members(runs / src))
        args = [command, path]
        if command == "hotspots":
            # Figures in one example of three (their drawing is most of an example's time)
            args += ["--plots", data.draw(st.sampled_from(["none", "none", "png"]))]
        if command == "export":
            args += ["--format", data.draw(st.sampled_from(["vtu", "vtu", "xdmf", "vtk"]))]
            args += ["--frames", data.draw(st.sampled_from(["all", "last", "0", "1,-1"]))]
        before = _state(d)
        with alarm(PREPARE_LIMIT):
            status, _, err = _cli(args)
        if status == 0:
            _no_partial(d, what)
            made = sorted(set(_state(d)) - set(before))
            assert made, (what, "nothing written")
            return
        _refused_cleanly(status, err, [path], what, before, d)


@_settings(320)
@given(data=st.data())
def test_mutated_run_file_exports_or_exits_2(runs, data):
    _export_or_analyse(data, runs, "export")


@_settings(230)
@given(data=st.data())
def test_mutated_shock_run_analyses_or_exits_2(runs, data):
    _export_or_analyse(data, runs, "analyse")


@_settings(150)
@given(data=st.data())
def test_mutated_thermal_run_hotspots_or_exits_2(runs, data):
    _export_or_analyse(data, runs, "hotspots")


# ---------------------------------------------------------------- command-line arguments

# Arguments of each command (a placeholder in <>: a path in the example's folder)
COMMAND_ARGS = {
    "export": ["<run>", "--format", "--frames", "-p", "--force"],
    "analyse": ["<shock>", "-p", "--force"],
    "hotspots": ["<shock>", "-o", "--thresholds", "--spot-threshold", "--contact-tol",
                 "--corner-angle", "--plots", "--force"],
    "prepare": ["<prepare>", "-o", "--force"],
    "material": ["<material>", "--material", "--strain", "--axial", "--nsub", "--path",
                 "--out"],
}
# Values an option is given: garbage numbers and text, huge values, paths of every kind
VALUES = NUMBERS + ["<folder>", "<missing>/x", "<file>", "<file>/x", "<folder>/x", "last",
                    "all", "0,0,0", "99", "-99", "1,", "vtu", "bogus", "xdmf", "\x00", "a" * 300]


@st.composite
def command_lines(draw):
    """(command, argument list with placeholders, what) of a command with one odd option."""
    command = draw(st.sampled_from(sorted(COMMAND_ARGS)))
    given_args = COMMAND_ARGS[command]
    args = [given_args[0]] + (["--material", "hmx"] if command == "material" else [])
    opt = draw(st.sampled_from(given_args[1:] + ["--bogus", "<positional>"]))
    value = draw(st.sampled_from(VALUES))
    if opt == "<positional>":
        args = [value] + args[1:]
    elif opt == "--force":
        args.append(opt)
    else:
        args += [opt, value]
    return command, args, f"{command} {' '.join(args)!r}"


@_settings(300)
@given(command_lines())
def test_odd_command_line_runs_or_exits_2(runs, call):
    command, args, what = call
    with tempfile.TemporaryDirectory() as d:
        _folder_with_inputs(d)
        for name in ("run", "shock"):
            shutil.copy(runs / f"{name}.h5", Path(d, f"{name}.h5"))
        Path(d, "prepare.toml").write_text(PREPARE)
        Path(d, "material.toml").write_text(MATERIAL)
        inputs = {"<run>": "run.h5", "<shock>": "shock.h5", "<prepare>": "prepare.toml",
                  "<material>": "material.toml"}
        args = [os.path.join(d, inputs[a]) if a in inputs else a for a in args]
        args = _placeholders(args, d)
        # Outputs inside the example's folder unless the option under test moves them
        defaults = {"export": ["-p", "e"], "analyse": ["-p", "a"], "prepare": ["-o", "bed.h5"],
                    "material": ["--out", "m.csv"], "hotspots": ["-o", "h"]}[command]
        if defaults[0] not in args:
            args += [defaults[0], os.path.join(d, defaults[1])]
        before = _state(d)
        # Relative paths (an odd value taken as a prefix) land in the example's folder
        with alarm(PREPARE_LIMIT), contextlib.chdir(d):
            status, _, err = _cli([command] + args)
        if status == 0:
            _no_partial(d, what)
            assert sorted(set(_state(d)) - set(before)), (what, "nothing written")
            return
        codes = (2, 3) if command == "material" else (2,)
        # The message names an input or output path, an option, or the odd value itself
        names = ["step", "increment"] if status == 3 else [a.split("=")[0] for a in args] + \
            ["runfile: empty", "scene file", "--prefix", "prepare.output", "required: "]
        _refused_cleanly(status, err, names, what, before, d, codes)


# ---------------------------------------------------------------- cross-scene restarts

def _restart_base():
    """The checkpointed scene with time.max_steps bounding a mutated end (a restart may change
    it): a few hundred steps past the checkpoint at most."""
    doc = checkpointed_grains()
    doc["time"]["max_steps"] = 1000
    return doc


RESTART_BASE = toml(_restart_base())
# Scenes a restart of the checkpoint must refuse, and what their message must name
OTHER_SCENES = {"three grains": (drifting_grains(n=3, end=1e-7), "[grains] differs"),
                "a shock scene": (inline_shock(), "differs"),
                "the shock scene with heat": (every_field_shock(), "differs")}


@st.composite
def restart_calls(draw):
    """(scene bytes, kind, what) of a restart of the checkpoint of RESTART_BASE."""
    kind = draw(st.sampled_from(["allowed", "mutant", "mutant", "other"]))
    if kind == "other":
        name = draw(st.sampled_from(sorted(OTHER_SCENES)))
        return toml(OTHER_SCENES[name][0]).encode(), kind, name
    if kind == "allowed":
        doc = _restart_base()
        key, value = draw(st.sampled_from([("end", 1.5e-7), ("safety", 0.3),
                                           ("max_steps", 10**6), ("dt_min", 1.0e-20)]))
        doc["time"][key] = value
        return toml(doc).encode(), kind, f"time.{key} = {value!r}"
    data, what = draw(mutants(RESTART_BASE))
    return data, kind, what


@_settings(60)
@given(call=restart_calls())
def test_restart_of_another_scene_continues_or_exits_2(runs, call):
    data, kind, what = call
    with tempfile.TemporaryDirectory() as d:
        scene, ckpt, out = Path(d, "s.toml"), Path(d, "c.ckpt.h5"), Path(d, "out.h5")
        scene.write_bytes(data)
        shutil.copy(runs / "run.h5.ckpt.h5", ckpt)
        before = _state(d)
        with alarm(PREPARE_LIMIT):
            status, _, err = _cli(["run", scene, "-o", out, "--restart", ckpt, "--quiet"])
        assert "Traceback" not in err, (what, err)
        if kind == "allowed":
            assert status == 0, (what, err)
        if status == 0:
            with h5py.File(out) as f:
                assert f["frames/time"].shape[0] >= 1, what
            _no_partial(d, what)
            return
        if status == 3:
            assert err.strip().splitlines()[-1].startswith("pdfem: error: step "), (what, err)
            return
        _refused_cleanly(status, err, [scene, ckpt], what, before, d)
        # A refused restart (not a refused scene, whose lists of known keys may be longer)
        assert "--restart" not in err or len(err.strip()) < 200, (what, err)
        if kind == "other":
            assert "different scene" in err and OTHER_SCENES[what][1] in err, (what, err)
