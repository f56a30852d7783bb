"""Schedules: the next due multiple in constant time, the same as stepping to it; a scene's
schedules refused when they imply too much or cannot advance the time."""

import numpy as np
import pytest

from pdfem.errors import InputError
from pdfem.scene import parse_scene
from pdfem.schedule import SLACK, Schedule, next_index
from tests.scenes import packaged


def _stepped(k, interval, t):
    """The index by stepping, one multiple at a time."""
    while k * interval * (1 - SLACK) <= t:
        k += 1
    return k


def test_next_index_equals_stepping():
    rng = np.random.default_rng(4)
    for _ in range(20000):
        interval = 10.0 ** rng.uniform(-12, 0)
        # Times at and next to multiples, and anywhere
        j = int(rng.integers(1, 2000))
        t = j * interval * (1 - SLACK) * (1 + rng.choice([-1e-16, 0.0, 1e-16, 1e-9]))
        if rng.random() < 0.3:
            t = rng.uniform(0, 2000) * interval
        k = int(rng.integers(1, j + 1))
        assert next_index(k, interval, t) == _stepped(k, interval, t)


def test_schedule_is_constant_time_for_a_far_time():
    s = Schedule(1e-12)
    # 1e12 multiples at once: stepping would take hours
    assert s.due(1.0)
    c = 1e-12 * (1 - SLACK)
    assert s.k * c > 1.0 >= (s.k - 1) * c
    assert not s.due(1.0)


def _scene(edit):
    doc = packaged("shot912_small.toml")
    edit(doc)
    return doc


def test_ramp_below_the_advance_at_release_refused():
    def edit(doc):
        bc = next(b for b in doc["bc"] if "release" in b)
        bc["ramp_down"] = 1e-30

    with pytest.raises(InputError, match=r"bc\[1\]\.ramp_down: 1e-30 s is below the smallest "
                       "advance of the time"):
        parse_scene(_scene(edit))


def test_derived_interval_that_underflows_refused():
    # time.end 1e-306: output.interval derives as end / 20, energy and gauge intervals below
    with pytest.raises(InputError, match=r"output.energy_interval: .* s \(from output.interval "
                       r"/ 10\) is subnormal"):
        parse_scene(_scene(lambda d: (d["time"].update(end=1e-306), d.pop("output"))))


def test_packaged_scenes_pass():
    for name in ("shot912.toml", "shot912_small.toml"):
        parse_scene(packaged(name))
