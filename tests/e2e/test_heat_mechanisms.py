"""Heat by mechanism: the per-element fields add up to what the sources put in, each equals
its paying mechanical term, and the run files are the same on 1 and 2 ranks."""

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from pdfem.effects.heat import MECHANISMS
from pdfem.io.contacts import COLUMNS
from tests.helpers import datasets, pdfem
from tests.scenes import packaged, write_scene

# The heat-by-mechanism frame fields
HEAT_FIELDS = tuple(f"heat_{m}" for m in MECHANISMS)

BETA, GAMMA, FRACTION = 0.9, 0.8, 0.7


def thermal_shot(end=4.0e-7):
    """The packaged small piston shot with every heat effect on, viscous heating included (the
    crystal's linear bulk, which the thermo-elastic coupling needs)."""
    doc = packaged("shot912_small.toml")
    for key in ("eos", "eos_s"):
        doc["materials"]["hmx"].pop(key)
    doc["time"]["end"] = end
    for name in ("heat", "thermoelastic", "thermal_expansion", "conduction"):
        doc[name] = {}
    doc["dissipation_heating"] = {"beta": BETA}
    doc["viscous_heating"] = {"fraction": GAMMA}
    doc["friction_heating"] = {"fraction": FRACTION}
    doc["contact_conductance"] = {"h": 1.0e8}
    doc.pop("shock")
    doc["output"].update(path="hot.h5", interval=end / 4, energy_interval=end / 4,
                         fields=["x", "v", "stress", "kappa", "plastic_strain", "temperature",
                                 "element_temperature", *HEAT_FIELDS, "contacts"])
    return doc


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The thermal shot on 1 rank, and on 2 ranks with checkpoints: (folder, h1, h2)."""
    d = tmp_path_factory.mktemp("hot")
    doc = thermal_shot()
    write_scene(d / "hot.toml", doc)
    doc["output"]["checkpoint_interval"] = 1.5e-7
    write_scene(d / "hot_ckpt.toml", doc)
    for n, scene in ((1, "hot.toml"), (2, "hot_ckpt.toml")):
        p = pdfem(["run", scene, "-o", f"h{n}.h5", "--quiet"], d, ranks=n)
        assert p.returncode == 0, p.stderr
    return d, datasets(d / "h1.h5"), datasets(d / "h2.h5")


def test_heat_by_mechanism_sums_to_the_sources_and_is_rank_count_free(runs):
    d, one, two = runs
    # ParaView's sidecar shows every frame field the effects declare
    grid = ET.parse(d / "h1.xdmf").getroot().find(".//Grid[@GridType='Uniform']")
    names = {a.get("Name") for a in grid.findall("Attribute")}
    assert {"temperature", "element_temperature", "kappa", *HEAT_FIELDS} <= names
    assert sorted(one) == sorted(two)
    for k in one:
        assert np.array_equal(one[k], two[k]), f"{k} differs on 2 ranks"
    # Every frame: the mechanisms sum to the heat the sources put in (frames coincide with
    # energy samples here), and each equals its share of the term that pays for it
    t, et = one["frames/time"], one["energy/time"]
    assert len(t) == 5 and all(f"frames/{f}" in one for f in HEAT_FIELDS)
    for k in range(len(t)):
        j = int(np.argmin(abs(et - t[k])))
        assert et[j] == pytest.approx(t[k], rel=1e-9, abs=1e-15)
        mech = {f: one[f"frames/{f}"][k].sum() for f in HEAT_FIELDS}
        src = one["energy/heat_sources"][j]
        scale = max(abs(src), 1e-30)
        assert abs(sum(mech.values()) - src) <= 1e-12 * scale, (k, mech, src)
        assert mech["heat_plastic"] == pytest.approx(BETA * one["energy/plastic"][j],
                                                     rel=1e-10, abs=1e-14)
        assert mech["heat_viscous"] == pytest.approx(GAMMA * one["energy/viscous"][j],
                                                     rel=1e-10, abs=1e-14)
        assert mech["heat_friction"] == pytest.approx(FRACTION * one["energy/friction"][j],
                                                      rel=1e-10, abs=1e-14)
        # Conductance only moves heat between elements
        assert abs(mech["heat_conducted"]) <= 1e-10 * scale
    # By the end each mechanism has heated the bed, and the balance closes with every source
    # paid: beta D_plastic + gamma D_viscous + fraction D_friction
    last = {f: one[f"frames/{f}"][-1].sum() for f in HEAT_FIELDS}
    assert min(last["heat_plastic"], last["heat_viscous"], last["heat_friction"]) > 0.0
    assert last["heat_thermoelastic"] != 0.0
    paid = (BETA * one["energy/plastic"] + GAMMA * one["energy/viscous"]
            + FRACTION * one["energy/friction"])
    assert np.allclose(one["energy/heat_paid"], paid, rtol=1e-12, atol=1e-12 * paid.max())
    assert one["energy/balance_error"].max() < 1e-3


def test_restart_continues_the_heat_by_mechanism(runs):
    """The 2-rank run's last checkpoint continued on 1 rank: the heat fields of the later
    frames equal the uninterrupted run's (they are part of the checkpointed state)."""
    d, one, _ = runs
    p = pdfem(["run", "hot_ckpt.toml", "--restart", "h2.h5.ckpt.h5", "-o", "r.h5", "--quiet"],
              d, ranks=1)
    assert p.returncode == 0, p.stderr
    r = datasets(d / "r.h5")
    nb = r["frames/time"].shape[0] - 1
    assert nb >= 1
    for k in ("frames/time", "frames/temperature") + tuple(f"frames/{f}" for f in HEAT_FIELDS):
        assert np.array_equal(one[k][-nb:], r[k][1:]), k
    # The contacts of the later frames too (the restart's first frame has none: no step yet)
    n1 = one["frames/time"].shape[0]
    assert r["contacts/000000/key"].shape[0] == 0
    for j in range(1, nb + 1):
        for name, _, _ in COLUMNS:
            assert np.array_equal(one[f"contacts/{n1 - nb - 1 + j:06d}/{name}"],
                                  r[f"contacts/{j:06d}/{name}"]), (j, name)


def test_per_contact_output(runs):
    """/contacts/<frame>: every frame, keys in order and matching /mesh, unit normals,
    overlaps below delta_max, forces within the Coulomb bound (at it where the contact
    dissipates: dissipation = |F_s| slip rate), heat passed across the grain contacts."""
    d, one, _ = runs
    doc = thermal_shot()
    mu, dmax = doc["contact"]["friction"], doc["contact"]["delta_max"]
    nf = one["frames/time"].shape[0]
    assert sorted({k.split("/")[1] for k in one if k.startswith("contacts/")}) == \
        [f"{k:06d}" for k in range(nf)]
    ebody = one["mesh/elem_body"]
    hot = 0
    for k in range(1, nf):
        c = {name: one[f"contacts/{k:06d}/{name}"] for name, _, _ in COLUMNS}
        key, el = c["key"], c["element"]
        assert key.shape[0] > 0
        order = np.lexsort((key[:, 3], key[:, 2], key[:, 1], key[:, 0]))
        assert np.array_equal(order, np.arange(key.shape[0]))
        assert np.array_equal(ebody[el[:, 0]], key[:, 0])
        pair = key[:, 2] >= 0
        assert np.array_equal(ebody[el[pair, 1]], key[pair, 2])
        assert (el[~pair, 1] == -1).all()
        assert np.allclose(np.hypot(*c["normal"].T), 1.0)
        assert (c["overlap"] > 0).all() and (c["overlap"] < dmax).all()
        fn, fs = np.abs(c["force"][:, 0]), np.abs(c["force"][:, 1])
        walls = ~pair
        assert (fs[pair] <= mu * fn[pair] * (1 + 1e-12)).all()
        slip = c["dissipation"] > 0
        assert np.allclose(c["dissipation"][slip], fs[slip] * c["slip_rate"][slip],
                           rtol=1e-12)
        assert (c["slip_rate"][walls & ~slip] == 0).all()
        # Conductance (h > 0) passes heat across the grain contacts
        hot += int((c["heat"][pair] != 0.0).sum())
    assert hot > 0
