"""Scene files: parsing, defaults, round trip, one-line errors naming the key, geometry."""

import copy
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from pdfem.errors import InputError
from pdfem.scene import geometry as geo
from pdfem.scene import load_scene, parse_scene
from pdfem.scene.reference import pages
from pdfem.scene.toml_out import dumps

ROOT = Path(__file__).resolve().parents[1]

MINIMAL = """
[domain]
box = [0.0, 0.0, 0.01, 0.01]

[time]
end = 1e-5

[materials.glass]
density = 2500.0
bulk = 4.0e10
shear = 3.0e10

[[grains]]
center = [0.005, 0.005]
axes = [0.001, 0.0005]
material = "glass"
"""


def full_scene(out_dir):
    """A scene using every table, as a dict (what tomllib makes of a file)."""
    return {
        "domain": {"box": [0.0, 0.0, 0.02, 0.02], "partition": "strips", "rebalance": 1.5},
        "time": {"end": 2e-5, "safety": 0.4, "dt_max": 1e-7, "dt_min": 1e-12,
                 "max_steps": 100000},
        "element": {"rule": "2x2", "hourglass": 0.1, "level": 2},
        "gravity": {"g": [0.0, -9.81]},
        "damping": {"gamma": 10.0},
        "materials": {
            "glass": {"density": 2500.0, "bulk": 4e10, "shear": 3e10},
            "hmx": {"model": "cap", "density": 1900.0, "bulk": 1.2e10, "shear": 5e9,
                    "A": 2e8, "B": 2e-9, "C": 1e8, "D": 1e-9, "R": 2.5, "W": 0.2,
                    "kappa0": -5e7},
        },
        "grains": [
            {"center": [0.004, 0.004], "axes": [0.001, 0.0008], "material": "glass"},
            {"center": [0.007, 0.004], "axes": [0.0012, 0.0006], "angle": 0.7,
             "material": "hmx", "velocity": [1.0, -2.0]},
        ],
        "blocks": [
            {"name": "anvil", "box": [0.0, 0.0, 0.02, 0.002], "material": "glass"},
            {"name": "piston", "box": [0.0, 0.015, 0.02, 0.02], "nx": 8, "ny": 2,
             "material": "glass", "velocity": [0.0, -50.0]},
        ],
        "bc": [
            {"body": "anvil", "nodes": "bottom", "type": "fixed"},
            {"body": "piston", "type": "velocity", "velocity": [0.0, -50.0]},
            {"wall": "left", "type": "roller"},
            {"body": "piston", "nodes": "top", "type": "roller"},
        ],
        "walls": {"left": "frictionless", "right": "frictional", "friction": 0.2},
        "contact": {"kn0": 1e13, "delta_max": 1e-5, "friction": 0.1,
                    "pairs": {"glass:hmx": {"friction": 0.3}, "hmx:hmx": {"kn0": 2e13}}},
        "output": {"path": str(out_dir / "run.h5"), "interval": 1e-6, "fields": ["x", "v"]},
        "run": {"seed": 7},
    }


def write(tmp_path, doc, name="bed.toml"):
    """Write a scene dict as TOML (our writer) and return the file's path."""
    path = tmp_path / name
    path.write_text(dumps(doc) if isinstance(doc, dict) else doc)
    return path


# ---------------------------------------------------------------- valid scenes
def test_minimal_scene_defaults(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    s = load_scene(write(tmp_path, MINIMAL))
    r = s.resolved
    assert r["time"] == {"end": 1e-5, "safety": 0.5, "dt_max": math.inf, "dt_min": 0.0,
                         "max_steps": 0}
    assert r["element"] == {"rule": "1pt", "hourglass_stiffness": "coefficient",
                            "hourglass": 0.05, "level": 1, "skip_rest": True,
                            "mesh": "kite"}
    assert r["materials"]["glass"]["model"] == "elastic"
    assert r["grains"][0]["angle"] == 0.0 and r["grains"][0]["velocity"] == [0.0, 0.0]
    # Auto skin = 0.1 x smallest minor diameter; auto cell = largest diameter + skin
    assert r["domain"]["skin"] == pytest.approx(0.1 * 2 * 0.0005)
    assert r["domain"]["cell_size"] == pytest.approx(2 * 0.001 + 1e-4)
    assert r["domain"]["partition"] == "rcb" and r["domain"]["rebalance"] == 0.0
    assert r["output"] == {"path": "pdfem-run.h5", "interval": 1e-5 / 20,
                           "fields": ["x", "v", "stress"], "energy_interval": 1e-5 / 20 / 10,
                           "gauge_interval": 1e-5 / 20 / 10 / 10, "checkpoint_interval": 0.0,
                           "checkpoint_wall": 3600.0}
    assert r["run"] == {"seed": 0}
    assert r["blocks"] == [] and r["bc"] == []
    # Effects exist only when their tables do
    for name in ("gravity", "damping", "contact", "walls", "grains_file"):
        assert name not in r
    # Arrays
    assert s.n_grains == 1 and s.materials == {"glass": 0}
    assert s.grains["center"].shape == (1, 2) and s.grains["angle"].shape == (1,)
    assert s.grains["material"].dtype.kind == "i"
    assert s.path == tmp_path / "bed.toml" and s.base_dir == tmp_path


def test_full_scene(tmp_path):
    s = load_scene(write(tmp_path, full_scene(tmp_path)))
    r = s.resolved
    assert list(s.materials) == ["glass", "hmx"] and s.materials["hmx"] == 1
    np.testing.assert_array_equal(s.grains["material"], [0, 1])
    np.testing.assert_array_equal(s.grains["velocity"], [[0, 0], [1, -2]])
    # Cap defaults: the envelope apex as tension cut-off, tolerance
    hmx = r["materials"]["hmx"]
    assert hmx["tension_cutoff"] == pytest.approx(math.log(2.0) / 2e-9)
    assert hmx["tol"] == 1e-8
    # Boundary conditions: dof defaults and nodes default
    assert [b["dof"] for b in s.bcs] == ["xy", "xy", "x", "y"]
    assert s.bcs[1]["nodes"] == "all" and "nodes" not in s.bcs[2]
    # Contact: ks = kn0/2, pairs inherit and override
    c = r["contact"]
    assert c["ks"] == 5e12
    assert c["pairs"]["glass:hmx"] == {"kn0": 1e13, "delta_max": 1e-5, "ks": 5e12,
                                       "friction": 0.3, "damping": 0.0}
    assert c["pairs"]["hmx:hmx"]["ks"] == 1e13
    assert [b["nx"] for b in s.blocks] == [3, 8]
    assert r["output"]["energy_interval"] == pytest.approx(1e-7)
    assert r["gravity"]["g"] == [0.0, -9.81] and r["damping"]["gamma"] == 10.0


def test_round_trip(tmp_path):
    s = load_scene(write(tmp_path, full_scene(tmp_path)))
    text = s.to_toml_string()
    again = parse_scene(text, "/nonexistent")
    assert again.resolved == s.resolved
    assert again.to_toml_string() == text
    for k in s.grains:
        np.testing.assert_array_equal(again.grains[k], s.grains[k])


def test_toml_writer_round_trip():
    doc = {"top": [], "a": {"s": 'q"uo\\te \u00e9 \t\x7f', "f": [0.1, -1e-300, math.inf, 5e20],
                          "i": -3, "b": True},
           "t": {"x:y": {"k": 1}, "empty": {}}, "arr": [{"n": 1, "sub": {"m": 2}}, {"n": 2}]}
    assert tomllib.loads(dumps(doc)) == doc


def test_grains_csv(tmp_path):
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "g.csv").write_text(
        "x, y, a, b, angle, vx, material\n"
        "# a comment line\n"
        "0.004, 0.011, 0.001, 0.0008, 0.5, 1.0, hmx\n"
        "\n"
        "0.008, 0.011, 0.001, 0.0008, , , \n")
    doc = full_scene(tmp_path)
    doc["grains_file"] = {"path": "data/g.csv", "material": "glass", "velocity": [3.0, 4.0]}
    doc["grains"][1]["center"] = [0.004, 0.008]
    s = load_scene(write(tmp_path, doc))
    g = s.grains
    assert s.n_grains == 4
    np.testing.assert_array_equal(g["material"], [0, 1, 1, 0])
    np.testing.assert_array_equal(g["velocity"][2:], [[1.0, 4.0], [3.0, 4.0]])
    np.testing.assert_array_equal(g["angle"][2:], [0.5, 0.0])
    # The resolved scene holds the absolute path: it reads back from anywhere
    assert s.resolved["grains_file"]["path"] == str((tmp_path / "data" / "g.csv").resolve())
    assert parse_scene(s.to_toml_string(), "/").resolved == s.resolved


def test_grains_npz(tmp_path):
    np.savez(tmp_path / "g.npz", x=[0.004, 0.008], y=[0.01, 0.01], a=[1e-3, 1e-3],
             b=[5e-4, 5e-4], material=np.array(["hmx", "glass"]))
    doc = full_scene(tmp_path)
    doc["grains_file"] = {"path": "g.npz"}
    s = load_scene(write(tmp_path, doc))
    np.testing.assert_array_equal(s.grains["material"], [0, 1, 1, 0])


def test_reference_doc_is_current():
    """docs/scene/ is generated (python -m pdfem.scene.reference --out docs/scene): every page
    on disk is the generated one, and there is no page the schema does not generate."""
    folder = ROOT / "docs" / "scene"
    generated = pages()
    assert sorted(p.name for p in folder.iterdir()) == sorted(generated)
    for name, text in generated.items():
        assert (folder / name).read_text() == text, f"docs/scene/{name} is out of date"


def test_reference_pages_cover_the_schema():
    """One page per table of the schema, and each page lists every key of its table."""
    from pdfem.scene import schema as S

    generated = pages()
    for sec in S.SECTIONS:
        page = generated[f"{sec.name}.md"]
        for key in sec.keys:
            assert f"| `{key}` |" in page, (sec.name, key)
        assert f"({sec.name}.md)" in generated["README.md"]


# ---------------------------------------------------------------- mistakes
def _set(path, value):
    """A mistake that sets the key at ``path`` (a tuple of keys/indices) to ``value``."""
    def edit(doc, tmp_path):
        tbl = doc
        for k in path[:-1]:
            tbl = tbl[k]
        tbl[path[-1]] = value
        return doc
    return edit


def _delete(path):
    """A mistake that removes the key at ``path``."""
    def edit(doc, tmp_path):
        tbl = doc
        for k in path[:-1]:
            tbl = tbl[k]
        del tbl[path[-1]]
        return doc
    return edit


def _text(old, new):
    """A mistake made in the TOML text of the minimal scene."""
    def edit(doc, tmp_path):
        assert old in MINIMAL
        return MINIMAL.replace(old, new)
    return edit


def _grains_file(name, content, spec=None):
    """A mistake in a grains file: write it next to the scene and point to it."""
    def edit(doc, tmp_path):
        if name.endswith(".npz"):
            np.savez(tmp_path / name, **content)
        elif content is not None:
            (tmp_path / name).write_text(content)
        doc["grains_file"] = dict(spec or {"path": name, "material": "glass"})
        return doc
    return edit


def _rename_material(new):
    def edit(doc, tmp_path):
        doc["materials"] = {new: doc["materials"]["glass"]}
        return doc
    return edit


def _add_bc(bc):
    def edit(doc, tmp_path):
        doc["bc"].append(bc)
        return doc
    return edit


def _output_nowhere(doc, tmp_path):
    doc["output"]["path"] = str(tmp_path / "no-such-dir" / "run.h5")
    return doc


CSV_BAD = "x,y,a,b\n0.004,0.011,0.001,0.0008\n0.008,abc,0.001,0.0008\n"

MISTAKES = [
    ("unknown table", _set(("gravitty",), {}), "gravitty: unknown table"),
    ("unknown key", _set(("time", "ende"), 1.0), "time.ende: unknown key"),
    ("wrong type", _set(("time", "end"), "1e-5"), "time.end: expected a number"),
    ("bool for number", _set(("damping", "gamma"), True), "damping.gamma: expected a number"),
    ("float for int", _set(("time", "max_steps"), 1.5), "time.max_steps: expected an integer"),
    ("int for bool", _set(("element", "skip_rest"), 1),
     "element.skip_rest: expected true or false (got 1)"),
    ("short vector", _set(("gravity", "g"), [0.0]), "gravity.g: expected [x, y]"),
    ("negative density", _set(("materials", "glass", "density"), -1),
     "materials.glass.density: must be > 0 (got -1.0)"),
    ("nan literal", _text("end = 1e-5", "end = nan"), "time.end: must be finite (got nan)"),
    ("minus inf", _set(("time", "dt_max"), -math.inf), "time.dt_max: must be finite"),
    ("safety above 1", _set(("time", "safety"), 1.5),
     "time.safety: must be in (0, 1] (got 1.5): a larger step is above the stable limit"),
    ("dt_min above dt_max", _set(("time", "dt_min"), 1e-6), "time.dt_min: must be < time.dt_max"),
    ("bad choice", _set(("domain", "partition"), "metis"),
     'domain.partition: must be one of "rcb", "strips"'),
    ("missing table", _delete(("time",)), "time: required table [time] missing"),
    ("missing material key", _delete(("materials", "glass", "bulk")),
     "materials.glass.bulk: required key missing"),
    ("unknown material", _set(("grains", 1, "material"), "steel"),
     "grains[1].material: unknown material 'steel'"),
    ("no materials", _set(("materials",), {}), "materials: at least one"),
    ("bad material name", _rename_material("1glass"), "materials.1glass: bad material name"),
    ("bad material name quoted", _rename_material("my glass"),
     'materials."my glass": bad material name'),
    ("cap missing key", _delete(("materials", "hmx", "W")),
     "materials.hmx.W: required key missing"),
    ("cap C >= A", _set(("materials", "hmx", "C"), 3e8), "materials.hmx.C: must be < A"),
    ("elastic with cap key", _set(("materials", "glass", "A"), 1e8),
     'materials.glass.A: unknown key for model "elastic"'),
    ("level out of range", _set(("element", "level"), 11),
     "element.level: must be in [1, 10] (got 11)"),
    ("coefficient with bending", _set(("element",), {"hourglass_stiffness": "bending",
                                                     "hourglass": 0.1}),
     'element.hourglass: only with hourglass_stiffness = "coefficient"'),
    ("unknown hourglass stiffness", _set(("element",), {"hourglass_stiffness": "stiff"}),
     'element.hourglass_stiffness: must be one of "coefficient", "bending", "full"'),
    ("cell_size too small", _set(("domain", "cell_size"), 1e-4),
     "domain.cell_size: must be >= "),
    ("grain outside box", _set(("grains", 0, "center"), [0.0005, 0.01]),
     "grains[0]: outside the domain box"),
    ("overlapping grains", _set(("grains", 1, "center"), [0.0045, 0.004]),
     "grains[0]: overlaps grains[1] at t=0"),
    ("grain overlaps block", _set(("grains", 0, "center"), [0.004, 0.0025]),
     "grains[0]: overlaps blocks[0] (anvil) at t=0"),
    ("blocks overlap", _set(("blocks", 1, "box"), [0.0, 0.001, 0.02, 0.003]),
     "blocks[0]: overlaps blocks[1]"),
    ("block outside box", _set(("blocks", 1, "box"), [0.0, 0.015, 0.03, 0.02]),
     "blocks[1].box: outside the domain box"),
    ("duplicate block name", _set(("blocks", 1, "name"), "anvil"),
     "blocks[1].name: duplicate block name 'anvil'"),
    ("grains file missing", _grains_file("nope.csv", None), "grains_file.path: file not found"),
    ("bad csv row", _grains_file("g.csv", CSV_BAD),
     "grains_file: g.csv line 3: y: not a number (got 'abc')"),
    ("bad npz row", _grains_file("g.npz", {"x": [0.004, 0.008], "y": [0.011, 0.011],
                                           "a": [1e-3, 1e-3], "b": [5e-4, -5e-4]}),
     "grains_file: g.npz row 1: b: must be > 0"),
    ("unknown bc body", _set(("bc", 0, "body"), "hammer"), "bc[0].body: unknown block 'hammer'"),
    ("velocity bc without velocity", _delete(("bc", 1, "velocity")),
     "bc[1].velocity: required for type velocity"),
    ("velocity on fixed bc", _set(("bc", 0, "velocity"), [0.0, 1.0]),
     "bc[0].velocity: only for type velocity"),
    ("bc body and wall", _set(("bc", 0, "wall"), "left"), "bc[0]: give exactly one of"),
    ("roller on all nodes", _add_bc({"body": "piston", "type": "roller"}),
     'bc[4].dof: required for a roller on nodes = "all"'),
    ("release on a fixed bc", _set(("bc", 0, "release"), 1e-6),
     "bc[0].release: only for type velocity on a body"),
    ("ramp_down without release", _set(("bc", 1, "ramp_down"), 1e-7),
     "bc[1].ramp_down: needs release >= ramp_down"),
    ("ramp_down past release", _add_bc({"body": "piston", "type": "velocity",
                                        "velocity": [0.0, -1.0], "release": 1e-7,
                                        "ramp_down": 2e-7}),
     "bc[4].ramp_down: needs release >= ramp_down"),
    ("frictional wall", _set(("walls", "friction"), 0.0), "walls.friction: must be > 0"),
    ("contact pair material", _set(("contact", "pairs", "glass:steel"), {}),
     'contact.pairs."glass:steel": expected "mat1:mat2"'),
    ("output directory", _output_nowhere, "output.path: directory"),
    ("toml syntax", _text("[time]", "[time"), "TOML syntax:"),
]


@pytest.mark.parametrize("edit, expected", [m[1:] for m in MISTAKES],
                         ids=[m[0] for m in MISTAKES])
def test_mistake(tmp_path, edit, expected):
    scene = edit(copy.deepcopy(full_scene(tmp_path)), tmp_path)
    path = write(tmp_path, scene)
    with pytest.raises(InputError) as info:
        load_scene(path)
    msg = str(info.value)
    assert "\n" not in msg
    assert msg.startswith(f"{path}: ")
    assert expected in msg, msg


def test_missing_scene_file(tmp_path):
    with pytest.raises(InputError, match="bed.toml: cannot read the scene file"):
        load_scene(tmp_path / "bed.toml")


# ---------------------------------------------------------------- geometry
def _polygon(c, ax, ang):
    t = np.arange(geo.NPOLY) * 2 * np.pi / geo.NPOLY
    p = np.stack([ax[0] * np.cos(t), ax[1] * np.sin(t)], 1) * (1 + geo.INFLATE)
    cs, sn = np.cos(ang), np.sin(ang)
    return c + p @ np.array([[cs, sn], [-sn, cs]])


def _sat(p, q):
    """Brute-force separating axis test of two convex polygons."""
    for r in (p, q):
        e = np.roll(r, -1, 0) - r
        for n in np.stack([-e[:, 1], e[:, 0]], 1):
            if (p @ n).max() < (q @ n).min() or (q @ n).max() < (p @ n).min():
                return False
    return True


def test_overlap_matches_brute_force():
    rng = np.random.default_rng(0)
    n = 400
    c = rng.uniform(0, 10, (n, 2))
    ax = rng.uniform(0.1, 0.6, (n, 2))
    ang = rng.uniform(0, np.pi, n)
    lo, hi = geo.ellipse_aabb(c, ax, ang)
    i, j = geo.candidate_pairs(lo, hi)
    # Candidates are exactly the pairs whose boxes intersect
    ii, jj = np.triu_indices(n, 1)
    box = np.all((lo[ii] <= hi[jj]) & (lo[jj] <= hi[ii]), axis=1)
    assert set(zip(i.tolist(), j.tolist(), strict=True)) == set(
        zip(ii[box].tolist(), jj[box].tolist(), strict=True))
    # Closed-form SAT equals explicit polygons
    got = geo.grains_overlap(c, ax, ang, i, j)
    want = [_sat(_polygon(c[a], ax[a], ang[a]), _polygon(c[b], ax[b], ang[b]))
            for a, b in zip(i, j, strict=True)]
    assert got.tolist() == want and any(want) and not all(want)


def test_touching_grains_overlap():
    c = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0 + 1e-6]])
    ax = np.ones((3, 2))
    assert geo.first_grain_overlap(c, ax, np.zeros(3)) == (0, 1)
    assert geo.first_grain_overlap(c[[0, 2]], ax[:2], np.zeros(2)) is None


def _first_of_all_pairs(c, ax, ang):
    """The first overlapping pair in (i, j) order, testing every pair i < j."""
    ii, jj = np.triu_indices(c.shape[0], 1)
    hit = np.flatnonzero(geo.grains_overlap(c, ax, ang, ii, jj))
    return (int(ii[hit[0]]), int(jj[hit[0]])) if hit.size else None


def test_first_overlap_blockwise_is_the_full_search_first_pair():
    """Blocks of any size find the pair that the test of every pair finds first: sparse sets
    (the first overlap anywhere, or none), a few big grains among small ones, copies."""
    rng = np.random.default_rng(5)
    found = set()
    for _ in range(150):
        n = int(rng.integers(2, 90))
        c = rng.uniform(0.0, rng.uniform(3.0, 40.0), (n, 2))
        ax = rng.uniform(0.1, 0.7, (n, 2)) * np.where(rng.random((n, 1)) < 0.05, 6.0, 1.0)
        ang = rng.uniform(0.0, np.pi, n)
        # Sometimes a copy of an earlier grain further down the list
        if n > 3 and rng.random() < 0.3:
            k, m = sorted(rng.choice(n, 2, replace=False))
            c[m], ax[m], ang[m] = c[k], ax[k], ang[k]
        want = _first_of_all_pairs(c, ax, ang)
        found.add(want if want is None else min(want[0], 9))
        for block in (1, 3, 40, geo._BLOCK_PAIRS):
            assert geo.first_grain_overlap(c, ax, ang, block_pairs=block) == want, (n, block)
    # The sets cover no overlap and first overlaps late in the list
    assert None in found and 9 in found and 0 in found


def test_first_overlap_of_coincident_grains_forms_one_block_of_pairs(monkeypatch):
    """20 000 copies of one grain (2e8 overlapping pairs): the search forms the candidates of
    one block of grains, finds the first pair in it and stops."""
    n = 20_000
    c, ax, ang = np.full((n, 2), 0.5), np.tile([1e-3, 6e-4], (n, 1)), np.full(n, 0.3)
    formed = []
    real = geo.BoxGrid.pairs

    def counting(grid, entries, start, stop):
        i, j = real(grid, entries, start, stop)
        formed.append(i.size)
        return i, j

    monkeypatch.setattr(geo.BoxGrid, "pairs", counting)
    assert geo.first_grain_overlap(c, ax, ang) == (0, 1)
    assert len(formed) == 1 and n - 1 <= formed[0] <= geo._BLOCK_PAIRS


def test_a_bed_of_1e5_grains_loads_whole_and_one_overlap_in_it_is_found(tmp_path):
    """A hexagonal bed of ~1e5 ellipses from a grains file (npz): every grain is loaded, in
    the file's order, with the file's values; the same bed with one grain moved onto its
    neighbour is refused naming those two rows."""
    rng = np.random.default_rng(1)
    nx, ny, h = 316, 317, 1e-3
    ix, iy = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    x = ((ix + 0.5 + 0.5 * (iy % 2)) * h).ravel()
    y = ((iy * np.sqrt(3) / 2 + 0.5) * h).ravel()
    a = rng.uniform(0.45, 0.495, x.size) * h
    b = a * rng.uniform(0.6, 1.0, x.size)
    angle = rng.uniform(0, np.pi, x.size)
    np.savez(tmp_path / "bed.npz", x=x, y=y, a=a, b=b, angle=angle)
    doc = {"domain": {"box": [0.0, 0.0, (nx + 1) * h, (ny + 1) * h]}, "time": {"end": 1e-3},
           "materials": {"glass": {"density": 2500.0, "bulk": 4e10, "shear": 3e10}},
           "grains_file": {"path": "bed.npz", "material": "glass"},
           "output": {"path": str(tmp_path / "run.h5")}}
    s = parse_scene(doc, tmp_path)
    assert s.n_grains == nx * ny
    assert np.array_equal(s.grains["center"], np.stack([x, y], 1))
    assert np.array_equal(s.grains["axes"], np.stack([a, b], 1))
    # Grain k moved onto the centre of grain k + ny, its neighbour in the row; every other
    # centre is a spacing h away, more than two semi-axes (< 0.495 h each)
    k = nx * ny // 2
    assert y[k] == y[k + ny] and x[k + ny] - x[k] == pytest.approx(h)
    x[k] = x[k + ny]
    np.savez(tmp_path / "bed.npz", x=x, y=y, a=a, b=b, angle=angle)
    with pytest.raises(InputError, match=rf"grains_file: bed\.npz row {k} \(grain {k}\): "
                                         rf"overlaps bed\.npz row {k + ny} \(grain {k + ny}\)"):
        parse_scene(doc, tmp_path)


def test_packaged_default_scene_and_bed_load():
    import h5py

    from pdfem.packaged import default_scene_path

    sc = load_scene(default_scene_path())
    r = sc.resolved
    # The geometric bed: 16 grains wide, stress-free, at 0.65 of the crystal's density
    assert sc.n_grains > 200 and "nodes" in sc.grains and "elem_sig" not in sc.grains
    with h5py.File(r["grains_file"]["path"]) as f:
        assert f.attrs["method"] == "geometric" and f.attrs["packing_target"] == 0.65
        assert abs(f.attrs["packing_fraction"] - 0.65) <= 0.01
    assert r["materials"]["hmx"]["density"] == 1900.0 and r["shock"]["solid_density"] == 1900.0
    assert r["domain"]["box"][2] - r["domain"]["box"][0] >= 16 * 0.245e-3
    assert r["materials"]["hmx"]["model"] == "cap" and r["shock"]["hammer"] == "hammer"
    assert [g["name"] for g in r["gauges"]] == ["hammer", "bottom"]


def test_restart_scene_comparison_takes_keys_added_since_at_their_default():
    """A checkpoint written before element.mesh and a material's eos existed restarts a
    scene that holds them at their defaults, and not one that sets them otherwise."""
    from pdfem.errors import InputError
    from pdfem.scene.toml_out import dumps
    from pdfem.setup import same_scene

    old = {"element": {"rule": "1pt", "hourglass": 0.05, "level": 1},
           "materials": {"g": {"model": "elastic", "density": 1900.0, "bulk": 1e10,
                               "shear": 4e9}}}
    new = {"element": dict(old["element"], mesh="kite"),
           "materials": {"g": dict(old["materials"]["g"], eos="linear")}}
    same_scene("c.h5", dumps(old), dumps(new))
    for edit in ({"element": dict(new["element"], mesh="ring")},
                 {"materials": {"g": dict(new["materials"]["g"], eos="us_up", eos_s=2.0)}}):
        with pytest.raises(InputError, match="was written for a different scene"):
            same_scene("c.h5", dumps(old), dumps({**new, **edit}))


def test_the_crystal_hugoniot_is_the_grain_materials_own():
    """[shock] crystal_hugoniot: derived from a grain material with eos = "us_up" (and then
    refused when typed again), as given for grains without an equation of state."""
    from tests.scenes import inline_shock

    sc = load_scene(Path(__file__).resolve().parents[1] / "pdfem" / "scenes" / "shot912.toml")
    hmx = sc.resolved["materials"]["hmx"]
    assert sc.resolved["shock"]["crystal_hugoniot"] == [
        math.sqrt(hmx["bulk"] / hmx["density"]), hmx["eos_s"]]
    doc = inline_shock()
    assert "crystal_hugoniot" not in parse_scene(doc, ".").resolved["shock"]
    doc["shock"]["crystal_hugoniot"] = [2770.0, 2.29]
    assert parse_scene(doc, ".").resolved["shock"]["crystal_hugoniot"] == [2770.0, 2.29]
    doc["materials"]["hmx"].update(eos="us_up", eos_s=2.0)
    with pytest.raises(InputError, match="shock.crystal_hugoniot: derived from materials.hmx"):
        parse_scene(doc, ".")
    del doc["shock"]["crystal_hugoniot"]
    c0 = math.sqrt(doc["materials"]["hmx"]["bulk"] / doc["materials"]["hmx"]["density"])
    assert parse_scene(doc, ".").resolved["shock"]["crystal_hugoniot"] == [c0, 2.0]
