"""The effect contract: the worked example of docs/developer.md, registered and run.

The code block of the page's "adding an effect" section is executed as it stands, the class
registered with pdfem.effects.register (on copies of the registry and the schema's lists, so
no other test sees it), and a free grain run under it against the closed form.
"""

import re

import h5py
import numpy as np
import pytest
from mpi4py import MPI

import pdfem.effects as effects
from pdfem.driver import run
from pdfem.errors import InputError
from pdfem.scene import parse_scene
from pdfem.scene import schema as S
from pdfem.solver import Simulation
from tests.helpers import ROOT
from tests.scenes import drifting_grains


def _example():
    """The Push class of the first python block after docs/developer.md's contract heading."""
    text = (ROOT / "docs" / "developer.md").read_text()
    section = text.split("## The effect contract and adding an effect", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    space = {}
    exec(compile(code, "docs/developer.md", "exec"), space)
    return space["Push"]


@pytest.fixture
def push(monkeypatch):
    """The example effect registered on copies of the registry and the schema's lists."""
    monkeypatch.setattr(effects, "REGISTRY", dict(effects.REGISTRY))
    monkeypatch.setattr(S, "EFFECT_SECTIONS", [])
    return effects.register(_example())


def test_the_example_effect_runs_against_its_closed_form(push, tmp_path):
    a = np.array([1.0e4, -2.0e4])
    doc = drifting_grains(n=1, end=4e-6, extra={"push": {"acceleration": a.tolist()}})
    sim = Simulation(parse_scene(doc, str(tmp_path)), MPI.COMM_SELF)
    assert sim.effect_names == ["push"]
    user = [hook for hook, effs in sim.hooks.items() if any(e.name == "push" for e in effs)]
    assert user == ["body_force"]
    s = sim.store
    x0 = (s.m[:, None] * s.x).sum(0) / s.m.sum()
    # The set-up took the first half step: v is v(dt/2) = v(0) + a dt / 2
    v0 = (s.m[:, None] * s.v).sum(0) / s.m.sum() - 0.5 * a * sim.dt
    summary = run(sim, str(tmp_path / "push.h5"), quiet=True)
    s = sim.store
    x = (s.m[:, None] * s.x).sum(0) / s.m.sum()
    # Constant acceleration: central differences are exact, whatever the steps
    expect = x0 + v0 * sim.t + 0.5 * a * sim.t**2
    assert np.allclose(x - x0, expect - x0, rtol=1e-9, atol=0.0)
    assert summary["balance_error"] < 1e-6
    # The same run under the built-in [gravity] with g = a: the same motion and energy
    doc = drifting_grains(n=1, end=4e-6, extra={"gravity": {"g": a.tolist()}})
    ref = Simulation(parse_scene(doc, str(tmp_path)), MPI.COMM_SELF)
    ref_summary = run(ref, str(tmp_path / "gravity.h5"), quiet=True)
    assert np.allclose(sim.store.x, ref.store.x, rtol=0.0, atol=1e-15)
    assert summary["balance_error"] == pytest.approx(ref_summary["balance_error"], rel=1e-6)
    with h5py.File(tmp_path / "push.h5") as f, h5py.File(tmp_path / "gravity.h5") as g:
        assert f.attrs["effects"] == "push"
        assert np.allclose(f["energy/potential"][()], g["energy/potential"][()], rtol=1e-12)


def test_the_example_table_is_checked(push, tmp_path):
    from pdfem.errors import InputError

    doc = drifting_grains(n=1, extra={"push": {}})
    with pytest.raises(InputError, match=r"push\.acceleration"):
        parse_scene(doc, str(tmp_path))
    doc = drifting_grains(n=1, extra={"push": {"acceleration": [1.0, float("nan")]}})
    with pytest.raises(InputError, match=r"push\.acceleration"):
        parse_scene(doc, str(tmp_path))
    # Without the registration the table is unknown
    effects.REGISTRY.pop("push")
    S.EFFECT_SECTIONS.clear()
    with pytest.raises(InputError, match="unknown table"):
        parse_scene(drifting_grains(n=1, extra={"push": {"acceleration": [1.0, 0.0]}}),
                    str(tmp_path))


def test_a_registered_effect_declares_what_a_scene_needs(push, monkeypatch, tmp_path):
    """requires and material_keys of an added effect are checked like the built-in ones'."""
    monkeypatch.setattr(push, "requires", ("gravity",))
    monkeypatch.setattr(push, "material_keys", ("specific_heat",))
    doc = drifting_grains(n=1, end=1e-6, extra={"push": {"acceleration": [1.0, 0.0]}})
    with pytest.raises(InputError, match=r"push: needs the \[gravity\] table"):
        parse_scene(doc, str(tmp_path))
    doc["gravity"] = {"g": [0.0, 0.0]}
    with pytest.raises(InputError, match=r"materials\.\w+\.specific_heat: required by \[push\]"):
        parse_scene(doc, str(tmp_path))
