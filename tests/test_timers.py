"""Phase timers: an inner phase pauses the one around it, so the phases add up."""

import pdfem.timers as timers


class Clock:
    """A clock that moves only when told."""

    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


def test_an_inner_phase_pauses_the_outer_one(monkeypatch):
    clock = Clock()
    monkeypatch.setattr(timers.time, "perf_counter", clock)
    t = timers.Timers()
    with t.phase("contact_forces"):
        clock.t += 2.0
        with t.phase("contact_exchange"):
            clock.t += 5.0
        clock.t += 1.0
        with t.phase("contact_exchange"):
            clock.t += 0.5
        clock.t += 0.25
    with t.phase("elements"):
        clock.t += 3.0
    assert t.seconds["contact_forces"] == 3.25
    assert t.seconds["contact_exchange"] == 5.5
    assert t.seconds["elements"] == 3.0
    assert sum(t.seconds.values()) == clock.t - 100.0
    assert (t.calls["contact_forces"], t.calls["contact_exchange"]) == (1, 2)


def test_a_phase_left_by_an_exception_is_closed(monkeypatch):
    clock = Clock()
    monkeypatch.setattr(timers.time, "perf_counter", clock)
    t = timers.Timers()
    try:
        with t.phase("halo"):
            clock.t += 1.0
            raise RuntimeError("stop")
    except RuntimeError:
        pass
    with t.phase("output"):
        clock.t += 2.0
    assert (t.seconds["halo"], t.seconds["output"]) == (1.0, 2.0)
